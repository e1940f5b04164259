//! A large model's ODE for diffsol, with a sparse Jacobian and a sparse LU.
//!
//! The implicit methods solve with `I - hγJ` at every Newton step. Stored dense, that matrix takes `8n²` bytes and
//! its LU `n³/3` multiply-adds: 94 % of a 2,000-state run went to the dense factorisation, and 20,000 states do
//! not fit in memory. The equations' Jacobian has a few entries per row, known symbolically before the run, so a
//! large model hands diffsol that pattern (plus the diagonal) and fills the values in one pass per assembly;
//! diffsol factorises it with faer's sparse LU. Nothing is probed: diffsol's own sparsity detection for closures
//! evaluates `n` products on an `n × n` batch.

use diffsol::matrix::sparsity::MatrixSparsity;
use diffsol::{
    ConstantOp, FaerSparseMat, FaerVec, Matrix, MatrixCommon, NonLinearOp, NonLinearOpJacobian,
    OdeEquations, OdeEquationsRef, Op, UnitCallable, Vector, VectorIndex,
};

type M = FaerSparseMat<f64>;
type V = FaerVec<f64>;
type C = <M as MatrixCommon>::C;
type Index = <V as Vector>::Index;

/// `ẏ = f(y, t)` written into the last argument.
pub(super) type Rates<'a> = dyn Fn(&[f64], f64, &mut [f64]) + 'a;
/// The Jacobian's entries at `(y, t)`, in the order of the pattern given to [`SparseOde::new`].
pub(super) type JacobianValues<'a> = dyn Fn(&[f64], f64, &mut [f64]) + 'a;

/// The ODE of a segment: rates, Jacobian values and their pattern, and the initial state.
pub(super) struct SparseOde<'a> {
    rates: &'a Rates<'a>,
    values: &'a JacobianValues<'a>,
    y0: Vec<f64>,
    /// The entries the values closure writes, then the diagonal entries it does not (kept at zero).
    pattern: Vec<(usize, usize)>,
    /// How many of `pattern`'s entries the values closure writes.
    written: usize,
    sparsity: <M as Matrix>::Sparsity,
    /// Where each entry of `pattern` is stored in the matrix's values.
    destination: Index,
    source: Index,
    no_params: V,
    ctx: C,
}

impl<'a> SparseOde<'a> {
    /// The ODE with the Jacobian's entries at `pattern` (rows and columns below `y0.len()`, each once).
    pub fn new(
        rates: &'a Rates<'a>,
        values: &'a JacobianValues<'a>,
        y0: &[f64],
        pattern: &[(usize, usize)],
    ) -> Result<SparseOde<'a>, String> {
        let n = y0.len();
        let ctx = C::default();
        let mut full = pattern.to_vec();
        let written = full.len();
        let mut on_diagonal = vec![false; n];
        for &(r, c) in pattern {
            if r >= n || c >= n {
                return Err(format!("Jacobian entry ({r}, {c}) outside the {n} states"));
            }
            if r == c {
                on_diagonal[r] = true;
            }
        }
        full.extend((0..n).filter(|&i| !on_diagonal[i]).map(|i| (i, i)));
        let mut sorted = full.clone();
        sorted.sort_unstable_by_key(|&(r, c)| (c, r));
        let sparsity =
            <<M as Matrix>::Sparsity as MatrixSparsity<M>>::try_from_indices(n, n, sorted)
                .map_err(|e| format!("the Jacobian's pattern: {e}"))?;
        let destination = MatrixSparsity::<M>::get_index(&sparsity, &full, ctx);
        let source = Index::from_vec((0..full.len()).collect(), ctx);
        Ok(SparseOde {
            rates,
            values,
            y0: y0.to_vec(),
            pattern: full,
            written,
            sparsity,
            destination,
            source,
            no_params: V::zeros(0, ctx),
            ctx,
        })
    }

    fn dim(&self) -> usize {
        self.y0.len()
    }

    /// The values of all of `pattern`'s entries at `(x, t)`.
    fn entries(&self, x: &V, t: f64) -> V {
        let mut data = V::zeros(self.pattern.len(), self.ctx);
        let written = self.written;
        data.for_each_batch_host([x], |vals, [x], _| {
            (self.values)(x, t, &mut vals[..written]);
        });
        data
    }
}

/// diffsol's `Op` for a type that reaches the ODE through `ode()`: square, `dim` states, no parameters.
macro_rules! op_of_ode {
    ($ty:ty) => {
        impl Op for $ty {
            type T = f64;
            type V = V;
            type M = M;
            type C = C;
            fn context(&self) -> &C {
                &self.ode().ctx
            }
            fn nstates(&self) -> usize {
                self.ode().dim()
            }
            fn nout(&self) -> usize {
                self.ode().dim()
            }
            fn nparams(&self) -> usize {
                0
            }
        }
    };
}

/// The right-hand side as diffsol's operator.
pub(super) struct Rhs<'b, 'a> {
    ode: &'b SparseOde<'a>,
}

/// The initial state as diffsol's operator.
pub(super) struct Init<'b, 'a> {
    ode: &'b SparseOde<'a>,
}

impl<'a> Rhs<'_, 'a> {
    fn ode(&self) -> &SparseOde<'a> {
        self.ode
    }
}

impl<'a> Init<'_, 'a> {
    fn ode(&self) -> &SparseOde<'a> {
        self.ode
    }
}

impl<'a> SparseOde<'a> {
    fn ode(&self) -> &SparseOde<'a> {
        self
    }
}

op_of_ode!(Rhs<'_, '_>);
op_of_ode!(Init<'_, '_>);
op_of_ode!(SparseOde<'_>);

impl NonLinearOp for Rhs<'_, '_> {
    fn call_inplace(&self, x: &V, t: f64, y: &mut V) {
        y.for_each_batch_host([x], |y, [x], _| (self.ode.rates)(x, t, y));
    }
}

impl NonLinearOpJacobian for Rhs<'_, '_> {
    fn jac_mul_inplace(&self, x: &V, t: f64, v: &V, y: &mut V) {
        let entries = self.ode.entries(x, t).clone_as_vec();
        let v = v.clone_as_vec();
        let mut product = vec![0.0; self.ode.dim()];
        for (&(r, c), value) in self.ode.pattern.iter().zip(entries) {
            product[r] += value * v[c];
        }
        y.for_each_batch_host([], |y, [], _| y.copy_from_slice(&product));
    }

    fn jacobian_inplace(&self, x: &V, t: f64, y: &mut M) {
        let data = self.ode.entries(x, t);
        y.set_data_with_indices(&self.ode.destination, &self.ode.source, &data);
    }

    fn jacobian_sparsity(&self) -> Option<<M as Matrix>::Sparsity> {
        Some(self.ode.sparsity.clone())
    }
}

impl ConstantOp for Init<'_, '_> {
    fn call_inplace(&self, _t: f64, y: &mut V) {
        y.for_each_batch_host([], |y, [], _| y.copy_from_slice(&self.ode.y0));
    }
}

impl<'b, 'a> OdeEquationsRef<'b> for SparseOde<'a> {
    type Mass = UnitCallable<M>;
    type Rhs = Rhs<'b, 'a>;
    type Root = UnitCallable<M>;
    type Init = Init<'b, 'a>;
    type Out = UnitCallable<M>;
    type Reset = UnitCallable<M>;
}

impl<'a> OdeEquations for SparseOde<'a> {
    fn rhs(&self) -> Rhs<'_, 'a> {
        Rhs { ode: self }
    }

    fn mass(&self) -> Option<UnitCallable<M>> {
        None
    }

    fn init(&self) -> Init<'_, 'a> {
        Init { ode: self }
    }

    fn set_params(&mut self, _p: &V) {}

    fn get_params(&self, p: &mut V) {
        p.copy_from(&self.no_params);
    }
}
