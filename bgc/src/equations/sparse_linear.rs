//! Sparse Jacobians and state spaces on the shared expression engine, for models of any size.
//!
//! [`ModelRows`] converts the rates and outputs to [`Expr`] once: an output that reads earlier outputs gets their
//! expressions substituted as shared nodes of the DAG (a chain of outputs `yᵢ = g(yᵢ₋₁)` stays as small as its
//! source), never inlined as trees. [`sparse_jacobians`] differentiates each row only by the states and inputs it
//! reads ([`Expr::sparse_jacobian`], memoised per node), and keeps per row the list of its non-zero columns
//! ([`SparseMatrix`]): the cost follows the non-zeros, not `rows × columns`. [`sparse_linear_state_space`] checks
//! linearity on those entries.
//!
//! Both give the errors of their dense counterparts in [`super::linear`] (in the same order and with the same
//! texts). [`linearise_sparse`] linearises a model with mass-matrix rows at a point, each block solved with its own
//! `M` there, and a model with nonlinear algebraic loops by the implicit function theorem
//! ([`super::implicit_linear`]), sparse as well.

use super::Equations;
use super::linear::{self, LinearError, StateSelection};
use super::symbols::{Sym, SymExt};
use crate::ir::Func;
use crate::symbolic::{Expr, Symbol, SymbolKind};
use std::collections::{BTreeSet, HashMap};

/// A matrix of expressions stored by rows, each row its non-zero entries `(column, value)` in column order.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    pub rows: usize,
    pub cols: usize,
    pub entries: Vec<Vec<(usize, Expr)>>,
}

impl SparseMatrix {
    /// The Jacobian `∂ exprsᵢ / ∂ varsⱼ`, differentiated only where a variable occurs.
    pub fn jacobian(exprs: &[Expr], vars: &[Symbol]) -> SparseMatrix {
        let mut entries = vec![Vec::new(); exprs.len()];
        for (i, j, e) in Expr::sparse_jacobian(exprs, vars) {
            if let Some(row) = entries.get_mut(i) {
                row.push((j, e));
            }
        }
        SparseMatrix {
            rows: exprs.len(),
            cols: vars.len(),
            entries,
        }
    }

    /// The non-zero entries of a dense matrix with `cols` columns.
    pub fn from_dense(m: &[Vec<Expr>], cols: usize) -> SparseMatrix {
        SparseMatrix {
            rows: m.len(),
            cols,
            entries: m
                .iter()
                .map(|row| {
                    row.iter()
                        .enumerate()
                        .filter(|(_, e)| !e.is_zero())
                        .map(|(c, e)| (c, e.clone()))
                        .collect()
                })
                .collect(),
        }
    }

    /// The entries `(row, column, value)` in row-major order.
    pub fn iter(&self) -> impl Iterator<Item = (usize, usize, &Expr)> {
        self.entries
            .iter()
            .enumerate()
            .flat_map(|(r, row)| row.iter().map(move |(c, e)| (r, *c, e)))
    }

    /// The number of stored (non-zero) entries.
    pub fn nnz(&self) -> usize {
        self.entries.iter().map(Vec::len).sum()
    }

    /// The entry at `(r, c)`, `None` for a zero.
    pub fn get(&self, r: usize, c: usize) -> Option<&Expr> {
        let row = self.entries.get(r)?;
        row.binary_search_by_key(&c, |(col, _)| *col)
            .ok()
            .and_then(|k| row.get(k))
            .map(|(_, e)| e)
    }

    /// The dense matrix, zeros written out: for small models only.
    pub fn to_dense(&self) -> Vec<Vec<Expr>> {
        let mut dense = vec![vec![Expr::zero(); self.cols]; self.rows];
        for (r, c, e) in self.iter() {
            if let Some(slot) = dense.get_mut(r).and_then(|row| row.get_mut(c)) {
                *slot = e.clone();
            }
        }
        dense
    }
}

/// The Jacobians `∂f/∂x, ∂f/∂u, ∂h/∂x, ∂h/∂u` of a state selection, sparse.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseJacobians {
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub dfdx: SparseMatrix,
    pub dfdu: SparseMatrix,
    pub dhdx: SparseMatrix,
    pub dhdu: SparseMatrix,
}

/// The explicit rates and outputs as expressions of the shared engine (`None` where one was not derived, or where
/// an output reads one that was not).
#[derive(Clone, Debug)]
pub struct ModelRows {
    pub f: Vec<Option<Expr>>,
    pub h: Vec<Option<Expr>>,
}

impl ModelRows {
    /// Converts the rates and outputs once. An output that reads an earlier output ([`Sym::Output`]) gets that
    /// output's expression substituted: one shared node however often it is read.
    pub fn new(eqs: &Equations) -> ModelRows {
        let f = eqs.f.to_vec();
        let mut h: Vec<Option<Expr>> = Vec::with_capacity(eqs.outputs.len());
        for o in &eqs.outputs {
            let reads_missing = |e: &Expr| {
                e.any_sym(&|s| matches!(s, Sym::Output(j) if h.get(j).is_none_or(Option::is_none)))
            };
            let value = o.explicit.as_ref().filter(|e| !reads_missing(e)).map(|e| {
                e.substitute_with(&|s: &Symbol| match Sym::of(s) {
                    Some(Sym::Output(j)) => h.get(j).cloned().flatten(),
                    _ => None,
                })
            });
            h.push(value);
        }
        ModelRows { f, h }
    }
}

/// The states of a model's state space: the energy states, unless a selected rate or an output reads an
/// integrated flow; then all states (as `bgc statespace` and the generated `state_space` choose).
pub fn state_selection(eqs: &Equations, rows: &ModelRows) -> StateSelection {
    match selected(eqs, rows, StateSelection::Energy) {
        Err(LinearError::NeedsIntegratedState { .. }) => StateSelection::All,
        _ => StateSelection::Energy,
    }
}

/// The state and input symbols of the selection, as the rows name them.
fn variables(eqs: &Equations, n: usize) -> (Vec<Symbol>, Vec<Symbol>) {
    let xs = (0..n).map(|i| Sym::State(i).symbol()).collect();
    let us = (0..eqs.inputs.len())
        .map(|i| Sym::Input(i).symbol())
        .collect();
    (xs, us)
}

fn what_rate(eqs: &Equations, i: usize) -> String {
    format!("the rate of `{}`", eqs.sym_name(Sym::State(i)))
}

fn what_output(eqs: &Equations, k: usize) -> String {
    format!(
        "output `{}`",
        eqs.outputs.get(k).map(|o| o.name.as_str()).unwrap_or("?")
    )
}

/// The selected rates and all outputs, checked as [`super::linear`] checks them: every one derived, none reading a
/// left-out state.
fn selected(
    eqs: &Equations,
    rows: &ModelRows,
    selection: StateSelection,
) -> Result<(Vec<Expr>, Vec<Expr>), LinearError> {
    let n = eqs.state_count(selection);
    let mut f = Vec::with_capacity(n);
    for i in 0..n {
        let e = rows.f.get(i).cloned().flatten();
        f.push(e.ok_or_else(|| LinearError::Incomplete {
            what: format!(
                "the rate of `{}`",
                eqs.states.get(i).map(|s| s.name.as_str()).unwrap_or("")
            ),
        })?);
    }
    let mut h = Vec::with_capacity(eqs.outputs.len());
    for (k, o) in eqs.outputs.iter().enumerate() {
        h.push(
            rows.h
                .get(k)
                .cloned()
                .flatten()
                .ok_or_else(|| LinearError::Incomplete {
                    what: format!("output `{}`", o.name),
                })?,
        );
    }
    if n < eqs.states.len() {
        let left_out: HashMap<Symbol, usize> = (n..eqs.states.len())
            .map(|j| (Sym::State(j).symbol(), j))
            .collect();
        let first_left_out = |e: &Expr| {
            e.free_symbols()
                .iter()
                .filter_map(|s| left_out.get(s).copied())
                .min()
        };
        let whats = (0..f.len())
            .map(|i| what_rate(eqs, i))
            .chain((0..h.len()).map(|k| what_output(eqs, k)));
        for (e, what) in f.iter().chain(&h).zip(whats) {
            if let Some(j) = first_left_out(e) {
                return Err(LinearError::NeedsIntegratedState {
                    what,
                    state: eqs.sym_name(Sym::State(j)),
                });
            }
        }
    }
    Ok((f, h))
}

/// `Min` and `Max` have no derivative in the dense path; the same rows are refused here, in its order.
fn check_differentiable(
    rows: &[Expr],
    vars: &[Symbol],
    what: &dyn Fn(usize) -> String,
) -> Result<(), LinearError> {
    let vars: BTreeSet<&Symbol> = vars.iter().collect();
    for (i, r) in rows.iter().enumerate() {
        if let Some((func, read)) = r.symbols_under_calls(&[Func::Min, Func::Max])
            && read.iter().any(|s| vars.contains(s))
        {
            return Err(LinearError::NotDifferentiable {
                what: what(i),
                func: func.name(),
            });
        }
    }
    Ok(())
}

/// The sparse Jacobians of the selected state vector: the counterpart of [`linear::jacobians`], with its errors.
pub fn sparse_jacobians(
    eqs: &Equations,
    rows: &ModelRows,
    selection: StateSelection,
) -> Result<SparseJacobians, LinearError> {
    if !eqs.tear_blocks.is_empty() {
        return linear::jacobians(eqs, selection).and_then(|j| from_dense(eqs, &j));
    }
    let (f, h) = selected(eqs, rows, selection)?;
    let (xs, us) = variables(eqs, f.len());
    let wf = |i: usize| what_rate(eqs, i);
    let wh = |k: usize| what_output(eqs, k);
    check_differentiable(&f, &xs, &wf)?;
    check_differentiable(&f, &us, &wf)?;
    check_differentiable(&h, &xs, &wh)?;
    check_differentiable(&h, &us, &wh)?;
    Ok(SparseJacobians {
        states: (0..f.len()).map(|i| eqs.sym_name(Sym::State(i))).collect(),
        inputs: eqs.inputs.clone(),
        outputs: eqs.outputs.iter().map(|o| o.name.clone()).collect(),
        dfdx: SparseMatrix::jacobian(&f, &xs),
        dfdu: SparseMatrix::jacobian(&f, &us),
        dhdx: SparseMatrix::jacobian(&h, &xs),
        dhdu: SparseMatrix::jacobian(&h, &us),
    })
}

/// Dense Jacobians of the equations stage, converted.
fn from_dense(_eqs: &Equations, j: &linear::Jacobians) -> Result<SparseJacobians, LinearError> {
    let convert =
        |m: &[Vec<Expr>], cols: usize, _name: &str| -> Result<SparseMatrix, LinearError> {
            let dense = m
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|e| Ok::<Expr, LinearError>(e.clone()))
                        .collect::<Result<Vec<_>, _>>()
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok(SparseMatrix::from_dense(&dense, cols))
        };
    let (n, m) = (j.states.len(), j.inputs.len());
    Ok(SparseJacobians {
        states: j.states.clone(),
        inputs: j.inputs.clone(),
        outputs: j.outputs.clone(),
        dfdx: convert(&j.dfdx, n, "A")?,
        dfdu: convert(&j.dfdu, m, "B")?,
        dhdx: convert(&j.dhdx, n, "C")?,
        dhdu: convert(&j.dhdu, m, "D")?,
    })
}

/// Whether the dense path is cheap for this model: then it names a nonlinear entry exactly as it always has.
fn small(rows: &[Expr], columns: usize) -> bool {
    let size: usize = rows
        .iter()
        .map(Expr::node_count)
        .fold(0, usize::saturating_add);
    size <= 50_000 && rows.len().saturating_mul(columns) <= 1_000_000
}

/// `A, B, C, D` of a linear model, sparse: the counterpart of [`linear::linear_state_space`], with its errors.
pub fn sparse_linear_state_space(
    eqs: &Equations,
    rows: &ModelRows,
    selection: StateSelection,
) -> Result<SparseJacobians, LinearError> {
    if !eqs.tear_blocks.is_empty() || !eqs.mass.is_empty() {
        return linear::linear_state_space(eqs, selection).and_then(|j| from_dense(eqs, &j));
    }
    let j = sparse_jacobians(eqs, rows, selection)?;
    let (f, h) = selected(eqs, rows, selection)?;
    let variable = |s: &Symbol| {
        matches!(
            s.kind(),
            SymbolKind::State | SymbolKind::Input | SymbolKind::Time
        )
    };
    for (m, name, what) in [
        (&j.dfdx, "A", "f"),
        (&j.dfdu, "B", "f"),
        (&j.dhdx, "C", "h"),
        (&j.dhdu, "D", "h"),
    ] {
        for (r, c, e) in m.iter() {
            let Some(symbol) = e.free_symbols().into_iter().find(|s| variable(s)) else {
                continue;
            };
            let all: Vec<Expr> = f.iter().chain(&h).cloned().collect();
            if small(&all, j.states.len() + j.inputs.len()) {
                linear::linear_state_space(eqs, selection)?;
            }
            let entry = format!("{name}[{r}][{c}]");
            return Err(linear::not_linear(eqs, what, entry, &symbol));
        }
    }
    // Linear, not affine: f(0, 0, t) = 0 and h(0, 0, t) = 0 for every t.
    let at_zero = |e: &Expr| {
        e.substitute_with(&|s: &Symbol| {
            matches!(s.kind(), SymbolKind::State | SymbolKind::Input).then(Expr::zero)
        })
    };
    let whats = (0..f.len())
        .map(|i| what_rate(eqs, i))
        .chain((0..h.len()).map(|k| what_output(eqs, k)));
    for (e, what) in f.iter().chain(&h).zip(whats) {
        let rest = at_zero(e);
        if rest.depends_on(&Symbol::time()) {
            return Err(LinearError::TimeDependent {
                what,
                elements: linear::time_elements_text(eqs),
            });
        }
        if !rest.is_zero() {
            return Err(LinearError::Affine { what });
        }
    }
    Ok(j)
}

/// Whether the dense path of `equations::linear` is cheap for this model: small trees (outputs inlined) and few
/// entries. `bgc statespace` keeps that path (and its numbers, bit for bit) for such models and evaluates the sparse
/// entries for the others.
pub fn dense_is_cheap(eqs: &Equations, rows: &ModelRows) -> bool {
    let all: Vec<Expr> = rows.f.iter().chain(&rows.h).flatten().cloned().collect();
    small(&all, eqs.states.len() + eqs.inputs.len())
}

/// A matrix of numbers by its non-zero entries `(row, column, value)` in row-major order.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericSparse {
    pub rows: usize,
    pub cols: usize,
    pub entries: Vec<(usize, usize, f64)>,
}

impl NumericSparse {
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut dense = vec![vec![0.0; self.cols]; self.rows];
        for &(r, c, v) in &self.entries {
            if let Some(slot) = dense.get_mut(r).and_then(|row| row.get_mut(c)) {
                *slot = v;
            }
        }
        dense
    }
}

/// A numeric state space by non-zero entries.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseNumericStateSpace {
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub a: NumericSparse,
    pub b: NumericSparse,
    pub c: NumericSparse,
    pub d: NumericSparse,
}

impl SparseNumericStateSpace {
    /// The non-zero entries of a dense state space.
    pub fn from_dense(ss: &linear::NumericStateSpace) -> SparseNumericStateSpace {
        let sparse = |m: &[Vec<f64>], cols: usize| NumericSparse {
            rows: m.len(),
            cols,
            entries: m
                .iter()
                .enumerate()
                .flat_map(|(r, row)| {
                    row.iter()
                        .enumerate()
                        .filter(|(_, v)| **v != 0.0)
                        .map(move |(c, v)| (r, c, *v))
                })
                .collect(),
        };
        let (n, m) = (ss.states.len(), ss.inputs.len());
        SparseNumericStateSpace {
            states: ss.states.clone(),
            inputs: ss.inputs.clone(),
            outputs: ss.outputs.clone(),
            a: sparse(&ss.a, n),
            b: sparse(&ss.b, m),
            c: sparse(&ss.c, n),
            d: sparse(&ss.d, m),
        }
    }

    pub fn to_dense(&self) -> linear::NumericStateSpace {
        linear::NumericStateSpace {
            states: self.states.clone(),
            inputs: self.inputs.clone(),
            outputs: self.outputs.clone(),
            a: self.a.to_dense(),
            b: self.b.to_dense(),
            c: self.c.to_dense(),
            d: self.d.to_dense(),
        }
    }
}

/// The linearisation of any model at `(x0, u0, t0)`, sparse: the Jacobians of
/// [`sparse_jacobians`] evaluated there, and the rows of mass-matrix blocks (I-fields, the velocity states of
/// configuration-dependent dependent storage) turned into those of the rates. The numbers are those of
/// [`linear::linearise`]; a model whose rates or outputs read the tears of algebraic loops is linearised by the
/// implicit function theorem, sparse as well.
pub fn linearise_sparse(
    eqs: &Equations,
    rows: &ModelRows,
    selection: StateSelection,
    (params, x0, u0, t0): (&[f64], &[f64], &[f64], f64),
) -> Result<SparseNumericStateSpace, LinearError> {
    if !eqs.tear_blocks.is_empty() {
        let (f, h) = linear::selected(eqs, selection)?;
        if linear::implicit_in(eqs, &f, &h).is_some() {
            return super::implicit_linear::linearise_sparse(eqs, (&f, &h), (params, x0, u0, t0));
        }
    }
    let j = sparse_jacobians(eqs, rows, selection)?;
    let mut ss = evaluate_sparse(eqs, &j, params, x0, u0, t0)?;
    let value = |s: Sym| super::numeric::point(s, params, x0, u0, t0);
    super::numeric::correct_mass_rows_sparse(eqs, &value, &mut ss)?;
    Ok(ss)
}

/// Evaluates sparse Jacobians at parameter values, operating point `x0`, `u0` and time `t0` (the counterpart of
/// [`linear::evaluate_at`], with its errors). Entries that evaluate to zero are left out.
pub fn evaluate_sparse(
    eqs: &Equations,
    j: &SparseJacobians,
    params: &[f64],
    x0: &[f64],
    u0: &[f64],
    t0: f64,
) -> Result<SparseNumericStateSpace, LinearError> {
    linear::check_len("parameter", eqs.params.len(), params.len())?;
    linear::check_len("state", j.states.len(), x0.len())?;
    linear::check_len("input", eqs.inputs.len(), u0.len())?;
    let mut values: HashMap<Symbol, f64> = HashMap::new();
    for (k, v) in params.iter().enumerate() {
        values.insert(Sym::Param(k).symbol(), *v);
    }
    for (i, v) in x0.iter().enumerate() {
        values.insert(Sym::State(i).symbol(), *v);
    }
    for (i, v) in u0.iter().enumerate() {
        values.insert(Sym::Input(i).symbol(), *v);
    }
    values.insert(Symbol::time(), t0);
    let evaluate = |m: &SparseMatrix, name: &str| -> Result<NumericSparse, LinearError> {
        let mut entries = Vec::with_capacity(m.nnz());
        for (r, c, e) in m.iter() {
            let what = || format!("{name}[{r}][{c}]");
            let v = e
                .eval(|s| values.get(s).copied())
                .map_err(|err| match err {
                    crate::symbolic::SymbolicError::UnboundSymbol { name, .. } => {
                        LinearError::Unbound {
                            what: what(),
                            symbol: name,
                        }
                    }
                    _ => LinearError::NonFinite { what: what() },
                })?;
            if !v.is_finite() {
                return Err(LinearError::NonFinite { what: what() });
            }
            if v != 0.0 {
                entries.push((r, c, v));
            }
        }
        Ok(NumericSparse {
            rows: m.rows,
            cols: m.cols,
            entries,
        })
    };
    Ok(SparseNumericStateSpace {
        states: j.states.clone(),
        inputs: j.inputs.clone(),
        outputs: j.outputs.clone(),
        a: evaluate(&j.dfdx, "A")?,
        b: evaluate(&j.dfdu, "B")?,
        c: evaluate(&j.dhdx, "C")?,
        d: evaluate(&j.dhdu, "D")?,
    })
}
