//! The linearisation of a model with nonlinear algebraic loops, by the implicit function theorem, sparse.
//!
//! With the residuals `r(z(x, u), x, u) = 0` of the tear variables `z`, `dz/dx = −(∂r/∂z)⁻¹ ∂r/∂x` and
//! `dz/du = −(∂r/∂z)⁻¹ ∂r/∂u`, so `A = ∂f/∂x + ∂f/∂z dz/dx`, `B = ∂f/∂u + ∂f/∂z dz/du`, and the same for `C` and
//! `D`. Each row is differentiated only by the symbols it reads, and `dz` is formed only in the columns the
//! residuals read: the cost follows the entries, not the square of the model. The rows of mass-matrix blocks
//! (I-fields, configuration-dependent dependent storage) hold generalised forces and are turned into rates at the
//! point, as on the path without loops.

use super::Equations;
use super::dense::{self, Mat};
use super::linear::{LinearError, NumericStateSpace};
use super::numeric;
use super::sparse_linear::{NumericSparse, SparseNumericStateSpace};
use super::symbols::{self, Sym, SymExt};
use crate::symbolic::Expr;
use std::collections::{BTreeMap, HashMap};

/// One row's partial derivatives at the point: by states and inputs (column `i` for state `i`, `n + k` for input
/// `k`), and by tear variables (their index in the solved tears), each in increasing order.
struct Partials {
    direct: Vec<(usize, f64)>,
    tears: Vec<(usize, f64)>,
}

/// The point and the solved tears, and how to name a column.
struct Point<'a> {
    eqs: &'a Equations,
    n: usize,
    value: &'a dyn Fn(Sym) -> Option<f64>,
    tear_index: HashMap<Sym, usize>,
}

impl Point<'_> {
    /// The partial derivatives of `e` by the states, inputs and tears it reads, at the point.
    fn partials(&self, e: &Expr, what: &str) -> Result<Partials, LinearError> {
        let mut p = Partials {
            direct: Vec::new(),
            tears: Vec::new(),
        };
        let slots: Vec<(Sym, (bool, usize))> = e
            .syms()
            .into_iter()
            .filter_map(|s| match s {
                Sym::State(i) if i < self.n => Some((s, (false, i))),
                Sym::Input(k) => Some((s, (false, self.n + k))),
                Sym::Tear(_) => self.tear_index.get(&s).map(|&l| (s, (true, l))),
                _ => None,
            })
            .collect();
        let wrt: Vec<Sym> = slots.iter().map(|&(s, _)| s).collect();
        let slopes = symbols::gradient(e, &wrt).map_err(|symbols::NotDifferentiable(func)| {
            LinearError::NotDifferentiable {
                what: what.to_string(),
                func: func.name(),
            }
        })?;
        for ((_, slot), d) in slots.into_iter().zip(slopes) {
            let x = numeric::value_of(self.eqs, &d, &|| what.to_string(), self.value)?;
            match slot {
                (false, c) => p.direct.push((c, x)),
                (true, l) => p.tears.push((l, x)),
            }
        }
        p.direct.sort_by_key(|&(c, _)| c);
        p.tears.sort_by_key(|&(l, _)| l);
        Ok(p)
    }
}

/// `dz/d(x, u)` in the columns the residuals read: the columns, and for each tear its row over them.
struct TearSlopes {
    columns: Vec<usize>,
    rows: Mat,
}

/// Solves `∂r/∂z · dz = −∂r/∂(x, u)` for the residuals of all blocks.
fn tear_slopes(
    point: &Point<'_>,
    residuals: &[Expr],
    names: &str,
) -> Result<TearSlopes, LinearError> {
    let what = super::tear::loop_for(names);
    let m = point.tear_index.len();
    let partials: Vec<Partials> = residuals
        .iter()
        .map(|r| point.partials(r, &what))
        .collect::<Result<_, _>>()?;
    let mut columns: Vec<usize> = partials
        .iter()
        .flat_map(|p| p.direct.iter().map(|&(c, _)| c))
        .collect();
    columns.sort_unstable();
    columns.dedup();
    let place: HashMap<usize, usize> = columns.iter().enumerate().map(|(k, &c)| (c, k)).collect();
    let mut rz = vec![vec![0.0; m]; partials.len()];
    let mut rxu = vec![vec![0.0; columns.len()]; partials.len()];
    for (i, p) in partials.iter().enumerate() {
        for &(l, x) in &p.tears {
            rz[i][l] = x;
        }
        for &(c, x) in &p.direct {
            rxu[i][place[&c]] = -x;
        }
    }
    let rows = dense::solve(&rz, &rxu).ok_or_else(|| LinearError::SingularLoop {
        tears: names.to_string(),
    })?;
    Ok(TearSlopes { columns, rows })
}

/// The total derivatives of `rows` by the states and inputs: direct, plus through the tears.
fn total(
    point: &Point<'_>,
    slopes: &TearSlopes,
    rows: &[Expr],
    what: &str,
) -> Result<(NumericSparse, NumericSparse), LinearError> {
    let (n, inputs) = (point.n, point.eqs.inputs.len());
    let mut x = NumericSparse {
        rows: rows.len(),
        cols: n,
        entries: Vec::new(),
    };
    let mut u = NumericSparse {
        rows: rows.len(),
        cols: inputs,
        entries: Vec::new(),
    };
    for (i, e) in rows.iter().enumerate() {
        let p = point.partials(e, what)?;
        // Summed in the tears' order from zero, as a dense product would: the same numbers as the dense form.
        let mut through = vec![0.0; slopes.columns.len()];
        for &(l, fz) in &p.tears {
            for (slot, dz) in through.iter_mut().zip(&slopes.rows[l]) {
                *slot += fz * dz;
            }
        }
        let mut row: BTreeMap<usize, f64> = p.direct.into_iter().collect();
        for (&c, t) in slopes.columns.iter().zip(through) {
            *row.entry(c).or_insert(0.0) += t;
        }
        for (c, v) in row.into_iter().filter(|&(_, v)| v != 0.0) {
            match c.checked_sub(n) {
                None => x.entries.push((i, c, v)),
                Some(k) => u.entries.push((i, k, v)),
            }
        }
    }
    Ok((x, u))
}

/// The linearisation at `(x0, u0, t0)` of the selected rates `f` and outputs `h` (explicit in states, inputs,
/// parameters, `t` and tears) of a model with tear blocks, sparse, with the rows of mass blocks solved.
pub(super) fn linearise_sparse(
    eqs: &Equations,
    (f, h): (&[Expr], &[Expr]),
    (params, x0, u0, t0): (&[f64], &[f64], &[f64], f64),
) -> Result<SparseNumericStateSpace, LinearError> {
    let n = f.len();
    refuse_unselected_states(eqs, n)?;
    let base = |s: Sym| match s {
        Sym::State(i) if i >= n => None,
        other => numeric::point(other, params, x0, u0, t0),
    };
    let tears = super::tear::solve_all(eqs, &base).map_err(|e| LinearError::LoopNotSolved {
        tears: e.tear_list(),
        reason: e.failure.kind.describe(),
        residual: e.failure.residual,
    })?;
    let tear_values: HashMap<Sym, f64> = tears.iter().copied().collect();
    let value = |s: Sym| match s {
        Sym::Tear(_) => tear_values.get(&s).copied(),
        other => base(other),
    };
    let point = Point {
        eqs,
        n,
        value: &value,
        tear_index: tears
            .iter()
            .enumerate()
            .map(|(l, (z, _))| (*z, l))
            .collect(),
    };
    let names = super::tear::tear_names(
        &tears
            .iter()
            .map(|&(z, _)| eqs.sym_name(z))
            .collect::<Vec<_>>(),
    );
    let residuals: Vec<Expr> = eqs
        .tear_blocks
        .iter()
        .flat_map(|b| b.residuals.iter().cloned())
        .collect();
    let slopes = tear_slopes(&point, &residuals, &names)?;
    let (a, b) = total(&point, &slopes, f, "f")?;
    let (c, d) = total(&point, &slopes, h, "h")?;
    let mut ss = SparseNumericStateSpace {
        states: (0..n).map(|i| eqs.sym_name(Sym::State(i))).collect(),
        inputs: eqs.inputs.clone(),
        outputs: eqs.outputs.iter().map(|o| o.name.clone()).collect(),
        a,
        b,
        c,
        d,
    };
    numeric::correct_mass_rows_sparse(eqs, &value, &mut ss)?;
    Ok(ss)
}

/// The same linearisation, dense.
pub(super) fn linearise(
    eqs: &Equations,
    (f, h): (&[Expr], &[Expr]),
    at: (&[f64], &[f64], &[f64], f64),
) -> Result<NumericStateSpace, LinearError> {
    linearise_sparse(eqs, (f, h), at).map(|ss| ss.to_dense())
}

/// A loop that reads a state left out of the selection (an integrated flow) cannot be linearised without it.
fn refuse_unselected_states(eqs: &Equations, n: usize) -> Result<(), LinearError> {
    for block in &eqs.tear_blocks {
        for (r, name) in block.residuals.iter().zip(&block.names) {
            for j in n..eqs.states.len() {
                if r.contains(Sym::State(j)) {
                    return Err(LinearError::NeedsIntegratedState {
                        what: super::tear::loop_named(std::slice::from_ref(name)),
                        state: eqs.sym_name(Sym::State(j)),
                    });
                }
            }
        }
    }
    Ok(())
}
