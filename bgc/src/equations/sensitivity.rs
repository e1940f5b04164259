//! The Jacobians of the rates and outputs at a point with respect to the states and to chosen parameters, for
//! the forward sensitivities of `bgc fit`.
//!
//! They are symbolic derivatives of the explicit rates `f` and outputs `h` (in the shared engine
//! [`crate::symbolic`]), evaluated at the point. The derivative with respect to a
//! parameter is total through the derived parameters ([`ParamChain`]). Where the rates are not explicit the
//! implicit function theorem supplies the rest, so no derivative is taken by differences:
//! - nonlinear algebraic loops, `0 = r(z, x, u, p, t)` for the tears `z` ([`super::tear`]):
//!   `∂r/∂z · dz/dv = −∂r/∂v` for `v` a state or a parameter, and `df/dv = ∂f/∂v + ∂f/∂z · dz/dv` (the same for
//!   `h` and for the inertia matrices);
//! - the mass-matrix rows of I-fields, `M ẋ_B = F` ([`super::MassBlock`]): `M · dẋ_B/dv = dF/dv − (dM/dv) ẋ_B`.
//!
//! Affine algebraic loops need nothing of their own: the equations stage solves them symbolically, so their
//! solution is part of `f` and `h`. [`Equations::sensitivity`] does the symbolic work once (the fit evaluates it at
//! every step); [`Equations::param_jacobian_at`] is the one-off form.

use super::Equations;
use super::dense::{self, Mat};
use super::linear::{LinearError, check_len};
use super::numeric::point;
use super::param_chain::ParamChain;
use super::symbols::Sym;
use super::tear::solve_all;
use crate::symbolic::{Compiled, Expr, Symbol};

/// Which Jacobians [`Sensitivity::at`] evaluates: a caller that needs only the outputs' (or only the rates')
/// does not pay for the others.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rows {
    Rates,
    Outputs,
    Both,
}

impl Rows {
    fn rates(self) -> bool {
        matches!(self, Rows::Rates | Rows::Both)
    }

    fn outputs(self) -> bool {
        matches!(self, Rows::Outputs | Rows::Both)
    }
}

/// `∂f/∂x`, `∂f/∂p`, `∂h/∂x`, `∂h/∂p` at a point, row-major (`fx[i][j] = ∂f_i/∂x_j`); the parameter columns are
/// those asked for, in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct PointJacobians {
    pub fx: Vec<Vec<f64>>,
    pub fp: Vec<Vec<f64>>,
    pub hx: Vec<Vec<f64>>,
    pub hp: Vec<Vec<f64>>,
}

/// Partial derivatives `[∂/∂x | ∂/∂p]` of some expressions: one row per expression, the state columns then the
/// chosen parameters' (total through the derived parameters).
type Partials = Vec<Vec<Expr>>;

/// A matrix of expressions, compiled once to be evaluated at every point.
#[derive(Debug)]
struct Matrix {
    exprs: Vec<Vec<Expr>>,
    compiled: Compiled,
    /// Where the value of each of the compiled symbols is in a point's values ([`Sensitivity::symbols`] order);
    /// `None` for a symbol that has none.
    slots: Vec<Option<usize>>,
}

impl Matrix {
    fn new(exprs: Vec<Vec<Expr>>, symbols: &[Symbol]) -> Matrix {
        let flat: Vec<Expr> = exprs.iter().flatten().cloned().collect();
        let compiled = Compiled::new(&flat);
        let slots = compiled
            .symbols()
            .iter()
            .map(|s| symbols.iter().position(|k| k == s))
            .collect();
        Matrix {
            exprs,
            compiled,
            slots,
        }
    }
}

/// The nonlinear algebraic loops' part.
#[derive(Debug)]
struct Loops {
    tears: Vec<Symbol>,
    /// `∂r/∂z` over all tears (block-triangular).
    rz: Matrix,
    rv: Matrix,
    fz: Matrix,
    hz: Matrix,
}

/// One inertia matrix `M`, the generalised forces `F` of its rows, and the derivatives of `M`'s entries
/// (flattened row-major) by the states and parameters and by the tears.
#[derive(Debug)]
struct Mass {
    element: String,
    rows: Vec<usize>,
    m: Matrix,
    forces: Matrix,
    mv: Matrix,
    mz: Matrix,
}

/// The symbolic Jacobians of a model with respect to its states and chosen parameters, ready to evaluate.
#[derive(Debug)]
pub struct Sensitivity<'e> {
    eqs: &'e Equations,
    /// The symbols with a value at a point: the parameters, states and inputs in order, time, then the tears of
    /// the loops in solving order.
    symbols: Vec<Symbol>,
    fv: Matrix,
    hv: Matrix,
    loops: Option<Loops>,
    mass: Vec<Mass>,
}

impl Equations {
    /// The symbolic Jacobians with respect to the states and the parameters `free` (indices into
    /// [`Equations::params`]), for the parameter values that follow from `given` ([`Equations::param_values`]): a
    /// derived parameter given a value is held there, the others follow the parameters they are defined from.
    pub fn sensitivity(
        &self,
        given: &[Option<f64>],
        free: &[usize],
    ) -> Result<Sensitivity<'_>, LinearError> {
        let pinned: Vec<usize> = (0..self.params.len())
            .filter(|&j| self.derived.get(j).is_some_and(Option::is_some))
            .filter(|&j| given.get(j).copied().flatten().is_some())
            .collect();
        let chain = ParamChain::new(self, free, &pinned)?;
        let states: Vec<Symbol> = (0..self.states.len())
            .map(|i| Sym::State(i).symbol())
            .collect();
        let symbols: Vec<Symbol> = (0..self.params.len())
            .map(Sym::Param)
            .map(Sym::symbol)
            .chain(states.iter().cloned())
            .chain((0..self.inputs.len()).map(|i| Sym::Input(i).symbol()))
            .chain(std::iter::once(Sym::Time.symbol()))
            .chain(
                self.tear_blocks
                    .iter()
                    .flat_map(|b| b.tears.iter().map(|&z| z.symbol())),
            )
            .collect();
        let matrix = |m: Vec<Vec<Expr>>| Matrix::new(m, &symbols);
        let partials = |exprs: &[Expr]| -> Partials {
            let x = Expr::jacobian(exprs, &states);
            x.into_iter()
                .zip(chain.jacobian(exprs))
                .map(|(mut row, p)| {
                    row.extend(p);
                    row
                })
                .collect()
        };
        let (f, h) = self.explicit_rows()?;
        let loops = self.loop_partials(&f, &h, &partials, &matrix)?;
        let tears = loops.as_ref().map_or(&[][..], |l| &l.tears[..]);
        let mut mass = Vec::with_capacity(self.mass.len());
        for b in &self.mass {
            let entries: Vec<Expr> = b
                .matrix
                .iter()
                .flatten()
                .map(|e| self.convert(e, || format!("M_{}", b.element)))
                .collect::<Result<_, _>>()?;
            let m: Vec<Vec<Expr>> = entries
                .chunks(b.states.len().max(1))
                .map(<[Expr]>::to_vec)
                .collect();
            let forces: Vec<Vec<Expr>> = b
                .states
                .iter()
                .map(|&r| vec![f.get(r).cloned().unwrap_or_else(Expr::zero)])
                .collect();
            mass.push(Mass {
                element: b.element.clone(),
                rows: b.states.clone(),
                m: matrix(m),
                forces: matrix(forces),
                mv: matrix(partials(&entries)),
                mz: matrix(Expr::jacobian(&entries, tears)),
            });
        }
        Ok(Sensitivity {
            eqs: self,
            fv: matrix(partials(&f)),
            hv: matrix(partials(&h)),
            symbols,
            loops,
            mass,
        })
    }

    /// The Jacobians at state `x`, input `u`, time `t`, with the parameter values that follow from `given`
    /// ([`Equations::param_values`]), differentiated with respect to the parameters `free` (indices into
    /// [`Equations::params`]).
    pub fn param_jacobian_at(
        &self,
        given: &[Option<f64>],
        x: &[f64],
        u: &[f64],
        t: f64,
        free: &[usize],
    ) -> Result<PointJacobians, LinearError> {
        self.sensitivity(given, free)?
            .at(&self.param_values(given), (x, u, t), Rows::Both)
    }

    /// [`Equations::param_jacobian_at`] without the outputs (`hx`, `hp` are left empty).
    pub fn rate_param_jacobian_at(
        &self,
        given: &[Option<f64>],
        x: &[f64],
        u: &[f64],
        t: f64,
        free: &[usize],
    ) -> Result<PointJacobians, LinearError> {
        self.sensitivity(given, free)?
            .at(&self.param_values(given), (x, u, t), Rows::Rates)
    }

    fn convert(&self, e: &Expr, _what: impl Fn() -> String) -> Result<Expr, LinearError> {
        Ok(e.clone())
    }

    /// The rates and outputs on the shared engine, converted once ([`super::ModelRows`]): an earlier output read
    /// by a later one is one shared node, so a chain of outputs through outputs stays as small as it is written.
    fn explicit_rows(&self) -> Result<(Vec<Expr>, Vec<Expr>), LinearError> {
        let rows = super::ModelRows::new(self);
        let f = rows
            .f
            .into_iter()
            .enumerate()
            .map(|(i, e)| {
                e.ok_or_else(|| LinearError::Incomplete {
                    what: format!("the rate of `{}`", self.sym_name(Sym::State(i))),
                })
            })
            .collect::<Result<_, _>>()?;
        let h = self
            .outputs
            .iter()
            .zip(rows.h)
            .map(|(o, e)| {
                e.ok_or_else(|| LinearError::Incomplete {
                    what: format!("output `{}`", o.name),
                })
            })
            .collect::<Result<_, _>>()?;
        Ok((f, h))
    }

    fn loop_partials(
        &self,
        f: &[Expr],
        h: &[Expr],
        partials: &dyn Fn(&[Expr]) -> Partials,
        matrix: &dyn Fn(Vec<Vec<Expr>>) -> Matrix,
    ) -> Result<Option<Loops>, LinearError> {
        if self.tear_blocks.is_empty() {
            return Ok(None);
        }
        let mut tears = Vec::new();
        let mut residuals = Vec::new();
        for b in &self.tear_blocks {
            tears.extend(b.tears.iter().map(|&z| z.symbol()));
            for (r, name) in b.residuals.iter().zip(&b.names) {
                residuals
                    .push(self.convert(r, || super::tear::loop_named(std::slice::from_ref(name)))?);
            }
        }
        Ok(Some(Loops {
            rz: matrix(Expr::jacobian(&residuals, &tears)),
            rv: matrix(partials(&residuals)),
            fz: matrix(Expr::jacobian(f, &tears)),
            hz: matrix(Expr::jacobian(h, &tears)),
            tears,
        }))
    }
}

/// The values of the symbols at a point.
struct Point<'a> {
    eqs: &'a Equations,
    /// In [`Sensitivity::symbols`] order.
    values: Vec<f64>,
}

impl Point<'_> {
    /// `m` evaluated; `what(i, j)` names an entry in errors.
    fn matrix(
        &self,
        m: &Matrix,
        what: &dyn Fn(usize, usize) -> String,
    ) -> Result<Mat, LinearError> {
        let mut symbol_values = Vec::with_capacity(m.slots.len());
        for (s, slot) in m.compiled.symbols().iter().zip(&m.slots) {
            match slot.and_then(|k| self.values.get(k)) {
                Some(&v) => symbol_values.push(v),
                None => return Err(self.unbound(m, s, what)),
            }
        }
        let mut values = m.compiled.eval(&symbol_values).into_iter();
        m.exprs
            .iter()
            .enumerate()
            .map(|(i, row)| {
                row.iter()
                    .enumerate()
                    .map(|(j, _)| match values.next() {
                        Some(v) if v.is_finite() => Ok(v),
                        _ => Err(LinearError::NonFinite { what: what(i, j) }),
                    })
                    .collect()
            })
            .collect()
    }

    /// The error for the symbol `s` without a value, naming the first entry of `m` that reads it.
    fn unbound(
        &self,
        m: &Matrix,
        s: &Symbol,
        what: &dyn Fn(usize, usize) -> String,
    ) -> LinearError {
        let (i, j) = m
            .exprs
            .iter()
            .enumerate()
            .find_map(|(i, row)| row.iter().position(|e| e.depends_on(s)).map(|j| (i, j)))
            .unwrap_or((0, 0));
        LinearError::Unbound {
            what: what(i, j),
            symbol: self.eqs.symbol_name(s),
        }
    }

    /// The name of column `j` of a `[∂/∂x | ∂/∂p]` matrix.
    fn column(&self, j: usize) -> String {
        match self.eqs.states.get(j) {
            Some(s) => s.name.clone(),
            None => format!("parameter column {}", j - self.eqs.states.len()),
        }
    }
}

impl Sensitivity<'_> {
    /// The Jacobians at the parameter values `params` (all of them, in [`Equations::params`] order, as
    /// [`Equations::param_values`] gives them), state `x`, input `u` and time `t`; the rows not in `rows` are
    /// left empty.
    pub fn at(
        &self,
        params: &[f64],
        (x, u, t): (&[f64], &[f64], f64),
        rows: Rows,
    ) -> Result<PointJacobians, LinearError> {
        let eqs = self.eqs;
        let values = self.values_at(params, (x, u, t))?;
        let at = Point { eqs, values };
        let rate = |i: usize| format!("the rate of `{}`", eqs.sym_name(Sym::State(i)));
        let output = |k: usize| format!("output `{}`", eqs.sym_name(Sym::Output(k)));
        let mut fv = if rows.rates() {
            at.matrix(&self.fv, &|i, j| {
                format!("∂({})/∂{}", rate(i), at.column(j))
            })?
        } else {
            Vec::new()
        };
        let mut hv = if rows.outputs() {
            at.matrix(&self.hv, &|k, j| {
                format!("∂({})/∂{}", output(k), at.column(j))
            })?
        } else {
            Vec::new()
        };
        let dz = match &self.loops {
            Some(l) => Some(self.through_loops(&at, l, &mut fv, &mut hv, rows)?),
            None => None,
        };
        if rows.rates() {
            for b in &self.mass {
                self.solve_mass_rows(&at, b, dz.as_ref(), &mut fv)?;
            }
        }
        let n = x.len();
        let split = |m: Mat| -> (Mat, Mat) {
            m.into_iter()
                .map(|mut row| {
                    let p = row.split_off(n.min(row.len()));
                    (row, p)
                })
                .unzip()
        };
        let (fx, fp) = split(fv);
        let (hx, hp) = split(hv);
        Ok(PointJacobians { fx, fp, hx, hp })
    }

    /// The value of every symbol the expressions read at a point: parameters, states, inputs, time and, with
    /// nonlinear loops, the tears (solved by Newton's method, as `rates_at` solves them).
    fn values_at(
        &self,
        params: &[f64],
        (x, u, t): (&[f64], &[f64], f64),
    ) -> Result<Vec<f64>, LinearError> {
        let eqs = self.eqs;
        check_len("parameter", eqs.params.len(), params.len())?;
        check_len("state", eqs.states.len(), x.len())?;
        check_len("input", eqs.inputs.len(), u.len())?;
        let mut values = Vec::with_capacity(self.symbols.len());
        values.extend_from_slice(params);
        values.extend_from_slice(x);
        values.extend_from_slice(u);
        values.push(t);
        if self.loops.is_some() {
            let tears = solve_all(eqs, &|s| point(s, params, x, u, t)).map_err(|e| {
                LinearError::LoopNotSolved {
                    tears: e.tear_list(),
                    reason: e.failure.kind.describe(),
                    residual: e.failure.residual,
                }
            })?;
            // In solving order, as `symbols` lists them.
            values.extend(tears.into_iter().map(|(_, v)| v));
        }
        Ok(values)
    }

    /// Adds the loops' contribution `∂g/∂z · dz/dv` to the rates' and outputs' columns; returns `dz/dv`.
    fn through_loops(
        &self,
        at: &Point,
        l: &Loops,
        fv: &mut Mat,
        hv: &mut Mat,
        rows: Rows,
    ) -> Result<Mat, LinearError> {
        let eqs = self.eqs;
        let names: Vec<String> = l.tears.iter().map(|z| eqs.symbol_name(z)).collect();
        let tears = super::tear::tear_names(&names);
        let label = super::tear::loop_for(&tears);
        let what = |_: usize, _: usize| label.clone();
        let rz = at.matrix(&l.rz, &what)?;
        let mut rv = at.matrix(&l.rv, &what)?;
        rv.iter_mut().flatten().for_each(|v| *v = -*v);
        // dz/dv = −(∂r/∂z)⁻¹ ∂r/∂v
        let dz = dense::solve(&rz, &rv).ok_or(LinearError::SingularLoop { tears })?;
        if rows.rates() {
            let rate =
                |i: usize, _: usize| format!("∂(the rate of `{}`)/∂z", eqs.sym_name(Sym::State(i)));
            add_product(fv, &at.matrix(&l.fz, &rate)?, &dz);
        }
        if rows.outputs() {
            let output =
                |k: usize, _: usize| format!("∂(output `{}`)/∂z", eqs.sym_name(Sym::Output(k)));
            add_product(hv, &at.matrix(&l.hz, &output)?, &dz);
        }
        Ok(dz)
    }

    /// Replaces the rows of the generalised forces' derivatives `dF/dv` of a mass block by those of the rates:
    /// `M · dẋ_B/dv = dF/dv − (dM/dv) ẋ_B`.
    fn solve_mass_rows(
        &self,
        at: &Point,
        b: &Mass,
        dz: Option<&Mat>,
        fv: &mut Mat,
    ) -> Result<(), LinearError> {
        let eqs = self.eqs;
        let element = &b.element;
        let nb = b.rows.len();
        let what = |k: usize, _: usize| {
            format!("M_{element}[{},{}]", k / nb.max(1) + 1, k % nb.max(1) + 1)
        };
        let m = at.matrix(&b.m, &|i, j| format!("M_{element}[{},{}]", i + 1, j + 1))?;
        let singular = || LinearError::SingularMass {
            element: element.clone(),
        };
        let forces = at.matrix(&b.forces, &|i, _| {
            let r = b.rows.get(i).copied().unwrap_or_default();
            format!("the rate of `{}`", eqs.sym_name(Sym::State(r)))
        })?;
        let rates: Vec<f64> = dense::solve(&m, &forces)
            .ok_or_else(singular)?
            .into_iter()
            .map(|r| r.first().copied().unwrap_or(0.0))
            .collect();
        let mut dm = at.matrix(&b.mv, &what)?;
        if let Some(dz) = dz {
            add_product(&mut dm, &at.matrix(&b.mz, &what)?, dz);
        }
        let mut rhs: Mat = b
            .rows
            .iter()
            .map(|&r| fv.get(r).cloned().unwrap_or_default())
            .collect();
        for (i, row) in rhs.iter_mut().enumerate() {
            for (j, rate) in rates.iter().enumerate() {
                if let Some(d) = dm.get(i * nb + j) {
                    row.iter_mut()
                        .zip(d)
                        .for_each(|(slot, d)| *slot -= d * rate);
                }
            }
        }
        let solved = dense::solve(&m, &rhs).ok_or_else(singular)?;
        for (&r, row) in b.rows.iter().zip(solved) {
            if let Some(slot) = fv.get_mut(r) {
                *slot = row;
            }
        }
        Ok(())
    }
}

/// `acc += a · b`.
fn add_product(acc: &mut Mat, a: &Mat, b: &Mat) {
    let product = dense::mul(a, b);
    for (row, add) in acc.iter_mut().zip(product) {
        row.iter_mut().zip(add).for_each(|(v, a)| *v += a);
    }
}
