//! Numeric evaluation of the equations, including the mass-matrix rows of I-fields.
//!
//! For a model without I-fields the rates are `ẋ = f(x, u, p, t)` evaluated directly. The flow states of an
//! I-field have `f` equal to the generalised forces `F`, and their rates solve `M(q) ẋ_B = F`. Linearising that
//! form: `∂ẋ_B/∂x_k = M⁻¹ (∂F/∂x_k − (∂M/∂x_k) ẋ_B)` and `∂ẋ_B/∂u = M⁻¹ ∂F/∂u` (`M` does not depend on `u`).

use super::dense::{self, Mat};
use super::linear::{LinearError, NumericStateSpace, check_len as check};
use super::sparse_linear::{NumericSparse, SparseNumericStateSpace};
use super::symbols::{self, Sym, SymExt};
use super::{Equations, MassBlock};
use crate::symbolic::{Expr, Node};
use std::collections::BTreeSet;

/// Evaluates `e`, naming `what` in errors.
pub(super) fn value_of(
    eqs: &Equations,
    e: &Expr,
    what: &dyn Fn() -> String,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<f64, LinearError> {
    let v = symbols::eval(e, value).map_err(|err| match err {
        symbols::EvalError::Unbound(s) => LinearError::Unbound {
            what: what(),
            symbol: eqs.sym_name(s),
        },
        symbols::EvalError::Foreign(f) => LinearError::Unbound {
            what: what(),
            symbol: f,
        },
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(LinearError::NonFinite { what: what() })
    }
}

fn mass_at(
    eqs: &Equations,
    block: &MassBlock,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<Mat, LinearError> {
    block
        .matrix
        .iter()
        .enumerate()
        .map(|(i, row)| {
            row.iter()
                .enumerate()
                .map(|(j, m)| {
                    let what = || format!("M_{}[{},{}]", block.element, i + 1, j + 1);
                    value_of(eqs, m, &what, value)
                })
                .collect()
        })
        .collect()
}

/// Solves `M x = rhs` for one block (several right-hand sides as columns).
fn solve_block(block: &MassBlock, m: &Mat, rhs: &Mat) -> Result<Mat, LinearError> {
    dense::solve(m, rhs).ok_or_else(|| LinearError::SingularMass {
        element: block.element.clone(),
    })
}

/// `∂M_ij/∂x_k` of a block at the point.
fn mass_slope(
    eqs: &Equations,
    block: &MassBlock,
    (i, j): (usize, usize),
    k: usize,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<f64, LinearError> {
    let mij = block
        .matrix
        .get(i)
        .and_then(|row| row.get(j))
        .cloned()
        .unwrap_or_else(Expr::zero);
    let d = symbols::diff(&mij, Sym::State(k)).map_err(|symbols::NotDifferentiable(f)| {
        LinearError::NotDifferentiable {
            what: format!("M_{}[{},{}]", block.element, i + 1, j + 1),
            func: f.name(),
        }
    })?;
    let what = || format!("∂M_{}[{},{}]/∂x", block.element, i + 1, j + 1);
    value_of(eqs, &d, &what, value)
}

/// `ẋ_B = M⁻¹ F` of one block at the point, `m` being its `M` there.
fn block_rates(
    eqs: &Equations,
    block: &MassBlock,
    m: &Mat,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<Vec<f64>, LinearError> {
    let mut forces = Vec::with_capacity(block.states.len());
    for &j in &block.states {
        let what = || format!("the rate of `{}`", eqs.sym_name(Sym::State(j)));
        let f = eqs
            .f
            .get(j)
            .cloned()
            .flatten()
            .ok_or_else(|| LinearError::Incomplete { what: what() })?;
        forces.push(vec![value_of(eqs, &f, &what, value)?]);
    }
    Ok(solve_block(block, m, &forces)?
        .into_iter()
        .map(|r| r.first().copied().unwrap_or(0.0))
        .collect())
}

/// [`correct_mass_rows`] on a sparse state space: each block's rows get `M⁻¹ (∂F/∂x − (∂M/∂x) ẋ_B)` and
/// `M⁻¹ ∂F/∂u` in the columns where those rows or the entries of `M` have any, the same numbers as the dense
/// correction gives there (it is zero in the other columns), so that the cost follows the blocks and their
/// entries, not the square of the model.
pub(crate) fn correct_mass_rows_sparse(
    eqs: &Equations,
    value: &dyn Fn(Sym) -> Option<f64>,
    ss: &mut SparseNumericStateSpace,
) -> Result<(), LinearError> {
    let n = ss.a.rows;
    let mut a_rows = by_rows(&ss.a);
    let mut b_rows = by_rows(&ss.b);
    for block in eqs.mass.iter().filter(|b| b.states.iter().all(|&j| j < n)) {
        let m = mass_at(eqs, block, value)?;
        let xb = block_rates(eqs, block, &m, value)?;
        // The states each entry of M reads, and the columns the block's rows fill.
        let reads: Vec<Vec<Vec<usize>>> = block
            .matrix
            .iter()
            .map(|row| row.iter().map(|mij| symbols::states_read(mij, n)).collect())
            .collect();
        let mut xcols: BTreeSet<usize> = reads.iter().flatten().flatten().copied().collect();
        let mut ucols: BTreeSet<usize> = BTreeSet::new();
        for &row in &block.states {
            xcols.extend(a_rows.get(row).into_iter().flatten().map(|(c, _)| *c));
            ucols.extend(b_rows.get(row).into_iter().flatten().map(|(c, _)| *c));
        }
        let xcols: Vec<usize> = xcols.into_iter().collect();
        let ucols: Vec<usize> = ucols.into_iter().collect();
        let place = |cols: &[usize], c: usize| cols.binary_search(&c).ok();
        let mut rhs: Mat = vec![vec![0.0; xcols.len() + ucols.len()]; block.states.len()];
        for (&row, r) in block.states.iter().zip(rhs.iter_mut()) {
            for (c, v) in a_rows.get(row).into_iter().flatten() {
                if let Some(k) = place(&xcols, *c) {
                    r[k] = *v;
                }
            }
            for (c, v) in b_rows.get(row).into_iter().flatten() {
                if let Some(k) = place(&ucols, *c) {
                    r[xcols.len() + k] = *v;
                }
            }
        }
        for (i, (row_reads, rrow)) in reads.iter().zip(rhs.iter_mut()).enumerate() {
            for (j, (entry_reads, xj)) in row_reads.iter().zip(&xb).enumerate() {
                for &k in entry_reads {
                    if let Some(slot) = place(&xcols, k).and_then(|p| rrow.get_mut(p)) {
                        *slot -= mass_slope(eqs, block, (i, j), k, value)? * xj;
                    }
                }
            }
        }
        let sol = solve_block(block, &m, &rhs)?;
        for (&row, srow) in block.states.iter().zip(&sol) {
            if let Some(p) = srow.iter().position(|v| !v.is_finite()) {
                let what = match p.checked_sub(xcols.len()) {
                    None => format!("A[{row}][{}]", xcols[p]),
                    Some(k) => format!("B[{row}][{}]", ucols[k]),
                };
                return Err(LinearError::NonFinite { what });
            }
            let (x, u) = srow.split_at(xcols.len());
            let non_zero = |cols: &[usize], vals: &[f64]| -> Vec<(usize, f64)> {
                cols.iter()
                    .copied()
                    .zip(vals.iter().copied())
                    .filter(|(_, v)| *v != 0.0)
                    .collect()
            };
            if let Some(slot) = a_rows.get_mut(row) {
                *slot = non_zero(&xcols, x);
            }
            if let Some(slot) = b_rows.get_mut(row) {
                *slot = non_zero(&ucols, u);
            }
        }
    }
    ss.a.entries = from_rows(a_rows);
    ss.b.entries = from_rows(b_rows);
    Ok(())
}

/// The entries of a sparse matrix by row, each row in column order.
fn by_rows(m: &NumericSparse) -> Vec<Vec<(usize, f64)>> {
    let mut rows = vec![Vec::new(); m.rows];
    for &(r, c, v) in &m.entries {
        if let Some(row) = rows.get_mut(r) {
            row.push((c, v));
        }
    }
    rows.iter_mut().for_each(|row| row.sort_by_key(|(c, _)| *c));
    rows
}

fn from_rows(rows: Vec<Vec<(usize, f64)>>) -> Vec<(usize, usize, f64)> {
    rows.into_iter()
        .enumerate()
        .flat_map(|(r, row)| row.into_iter().map(move |(c, v)| (r, c, v)))
        .collect()
}

impl Equations {
    /// True when some rates come from the mass-matrix form of an I-field.
    pub fn has_mass(&self) -> bool {
        !self.mass.is_empty()
    }

    /// The parameter values with some given (`given[i] = Some(v)`) and the rest at their defaults, derived
    /// parameters recomputed from the values before them; a given value always wins.
    pub fn param_values(&self, given: &[Option<f64>]) -> Vec<f64> {
        let mut values: Vec<f64> = Vec::with_capacity(self.params.len());
        for (i, (_, default)) in self.params.iter().enumerate() {
            let derived = self.derived.get(i).and_then(Option::as_ref);
            let v = match (given.get(i).copied().flatten(), derived) {
                (Some(v), _) => v,
                (None, Some(e)) => symbols::eval(e, &|s| match s {
                    Sym::Param(j) => values.get(j).copied(),
                    _ => None,
                })
                .unwrap_or(*default),
                (None, None) => *default,
            };
            values.push(v);
        }
        values
    }

    /// The parameters the equations divide by (raised to a negative power in a rate, an intermediate, an output,
    /// an energy term, a loop residual or a mass matrix), in index order: a value without a finite reciprocal (0)
    /// makes them non-finite, although the coefficient checks may allow it (a resistance of 0 in conductance
    /// causality).
    pub fn divisor_params(&self) -> Vec<usize> {
        let mut roots: Vec<Expr> = self.rates.clone();
        roots.extend(self.f.iter().flatten().cloned());
        roots.extend(self.intermediates.iter().map(|i| i.value.clone()));
        roots.extend(self.outputs.iter().map(|o| o.value.clone()));
        roots.extend(self.energy.iter().filter_map(|t| t.value.clone()));
        for block in &self.tear_blocks {
            roots.extend(block.residuals.iter().cloned());
        }
        for block in &self.mass {
            roots.extend(block.matrix.iter().flatten().cloned());
        }
        // The two halves of the roots walked at once: a node both reach is looked at twice, and the union is
        // the same.
        let (first, second) = roots.split_at(roots.len() / 2);
        let (mut found, more) =
            crate::concurrent::join(|| divisors_under(first), || divisors_under(second));
        found.extend(more);
        found.sort_unstable();
        found.dedup();
        found
    }

    /// The rates `ẋ` of all states at parameter values, state, input and time, with the mass-matrix rows solved.
    pub fn rates_at(
        &self,
        params: &[f64],
        x: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<Vec<f64>, LinearError> {
        self.check_point(params, x, u)?;
        let tears = self.tears_at(params, x, u, t)?;
        let value = |s: Sym| point_with_tears(s, params, x, u, t, &tears);
        let mut dx = Vec::with_capacity(x.len());
        for (i, f) in self.f.iter().enumerate() {
            let what = || format!("the rate of `{}`", self.sym_name(Sym::State(i)));
            let e = f
                .as_ref()
                .ok_or_else(|| LinearError::Incomplete { what: what() })?;
            dx.push(value_of(self, e, &what, &value)?);
        }
        solve_mass_rows(self, &value, &mut dx)?;
        Ok(dx)
    }

    fn check_point(&self, params: &[f64], x: &[f64], u: &[f64]) -> Result<(), LinearError> {
        check("parameter", self.params.len(), params.len())?;
        check("state", self.states.len(), x.len())?;
        check("input", self.inputs.len(), u.len())
    }

    /// The outputs `y` at parameter values, state, input and time.
    pub fn outputs_at(
        &self,
        params: &[f64],
        x: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<Vec<f64>, LinearError> {
        self.check_point(params, x, u)?;
        let tears = self.tears_at(params, x, u, t)?;
        // In order: an output defined through earlier outputs reads their values.
        let mut done: Vec<f64> = Vec::with_capacity(self.outputs.len());
        for o in &self.outputs {
            let what = || format!("output `{}`", o.name);
            let e = o
                .explicit
                .as_ref()
                .ok_or_else(|| LinearError::Incomplete { what: what() })?;
            let value = |s: Sym| match s {
                Sym::Output(j) => done.get(j).copied(),
                _ => point_with_tears(s, params, x, u, t, &tears),
            };
            let v = value_of(self, e, &what, &value)?;
            done.push(v);
        }
        Ok(done)
    }
}

impl Equations {
    /// The tear variables of the nonlinear algebraic loops at a point, solved by Newton's method (none without
    /// loops).
    fn tears_at(
        &self,
        params: &[f64],
        x: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<Vec<(Sym, f64)>, LinearError> {
        if self.tear_blocks.is_empty() {
            return Ok(Vec::new());
        }
        super::tear::solve_all(self, &|s| point(s, params, x, u, t)).map_err(|e| {
            LinearError::LoopNotSolved {
                tears: e.tear_list(),
                reason: e.failure.kind.describe(),
                residual: e.failure.residual,
            }
        })
    }
}

/// [`point`], and the tears' values.
fn point_with_tears(
    s: Sym,
    params: &[f64],
    x: &[f64],
    u: &[f64],
    t: f64,
    tears: &[(Sym, f64)],
) -> Option<f64> {
    match s {
        Sym::Tear(_) => tears.iter().find(|(z, _)| *z == s).map(|(_, v)| *v),
        other => point(other, params, x, u, t),
    }
}

/// The value of a symbol at a point: parameters, states, inputs and time.
pub(crate) fn point(s: Sym, params: &[f64], x: &[f64], u: &[f64], t: f64) -> Option<f64> {
    match s {
        Sym::Param(i) => params.get(i).copied(),
        Sym::State(i) => x.get(i).copied(),
        Sym::Input(i) => u.get(i).copied(),
        Sym::Time => Some(t),
        _ => None,
    }
}

/// Replaces the generalised forces in `dx` (the rows of each mass block) by the solved rates.
pub(crate) fn solve_mass_rows(
    eqs: &Equations,
    value: &dyn Fn(Sym) -> Option<f64>,
    dx: &mut [f64],
) -> Result<(), LinearError> {
    for block in &eqs.mass {
        let m = mass_at(eqs, block, value)?;
        let rhs: Mat = block
            .states
            .iter()
            .map(|&j| vec![dx.get(j).copied().unwrap_or(0.0)])
            .collect();
        let sol = solve_block(block, &m, &rhs)?;
        for (&j, row) in block.states.iter().zip(sol) {
            if row.first().is_some_and(|v| !v.is_finite()) {
                return Err(LinearError::NonFinite {
                    what: format!("the rate of `{}`", eqs.sym_name(Sym::State(j))),
                });
            }
            if let (Some(slot), Some(v)) = (dx.get_mut(j), row.first()) {
                *slot = *v;
            }
        }
    }
    Ok(())
}

/// Turns the Jacobians of the generalised forces in the block rows of `ss` (`∂F/∂x` in `a`, `∂F/∂u` in `b`) into
/// those of the rates, at the point where `value` evaluates. The selected states are the first `ss.a.len()`.
pub(crate) fn correct_mass_rows(
    eqs: &Equations,
    value: &dyn Fn(Sym) -> Option<f64>,
    ss: &mut NumericStateSpace,
) -> Result<(), LinearError> {
    let n = ss.a.len();
    for block in &eqs.mass {
        if block.states.iter().any(|&j| j >= n) {
            continue;
        }
        let m = mass_at(eqs, block, value)?;
        // ẋ_B = M⁻¹ F at the point.
        let xb = block_rates(eqs, block, &m, value)?;
        // Columns of ∂F/∂x − (∂M/∂x_k) ẋ_B, then of ∂F/∂u.
        let empty = Vec::new();
        let mut rhs: Mat = block
            .states
            .iter()
            .map(|&row| {
                let a = ss.a.get(row).unwrap_or(&empty);
                let b = ss.b.get(row).unwrap_or(&empty);
                a.iter().chain(b).copied().collect()
            })
            .collect();
        for (i, (mrow, rrow)) in block.matrix.iter().zip(rhs.iter_mut()).enumerate() {
            for (k, slot) in rrow.iter_mut().take(n).enumerate() {
                for (j, (mij, xj)) in mrow.iter().zip(&xb).enumerate() {
                    if !mij.contains(Sym::State(k)) {
                        continue;
                    }
                    *slot -= mass_slope(eqs, block, (i, j), k, value)? * xj;
                }
            }
        }
        let sol = solve_block(block, &m, &rhs)?;
        // A non-singular but badly scaled `M` (or huge forces) can overflow the solve: an entry of A or B that is
        // not finite is an error, as it is for the rows evaluated directly.
        for (&row, srow) in block.states.iter().zip(&sol) {
            if let Some(c) = srow.iter().position(|v| !v.is_finite()) {
                let what = match c.checked_sub(n) {
                    None => format!("A[{row}][{c}]"),
                    Some(k) => format!("B[{row}][{k}]"),
                };
                return Err(LinearError::NonFinite { what });
            }
        }
        for (&row, srow) in block.states.iter().zip(sol) {
            if let Some(a) = ss.a.get_mut(row) {
                a.iter_mut().zip(&srow).for_each(|(x, v)| *x = *v);
            }
            if let Some(b) = ss.b.get_mut(row) {
                b.iter_mut()
                    .zip(srow.iter().skip(n))
                    .for_each(|(x, v)| *x = *v);
            }
        }
    }
    Ok(())
}

/// The parameters raised to a negative power somewhere in `roots` (repeated, unordered).
fn divisors_under(roots: &[Expr]) -> Vec<usize> {
    symbols::post_order(roots)
        .iter()
        .filter_map(|e| match e.node() {
            Node::Pow(base, exponent) if exponent.as_const().is_some_and(|x| x < 0.0) => {
                match base.as_sym() {
                    Some(Sym::Param(i)) => Some(i),
                    _ => None,
                }
            }
            _ => None,
        })
        .collect()
}
