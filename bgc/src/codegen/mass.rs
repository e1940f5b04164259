//! The mass-matrix blocks of I-fields in generated code.
//!
//! For the flow states `f_B` of an I-field the equations give the generalised forces `F` and the inertia matrix
//! `M(q)` (`M ḟ_B = F`). The generated `rhs_into` writes `F` into those rows like any other rate, then solves
//! `M ḟ_B = F` in place by Gaussian elimination with partial pivoting ([`SOLVE_FN`], emitted into the module so
//! that it needs no more than `core`, `nalgebra` and `libm`; a singular matrix leaves NaN in those rows rather than
//! a panic). The Jacobians follow from
//! differentiating `M ḟ_B = F`:
//!
//! ```text
//! ∂ḟ_B/∂x_k = M⁻¹ (∂F/∂x_k − (∂M/∂x_k) ḟ_B)        ∂ḟ_B/∂u = M⁻¹ ∂F/∂u
//! ```
//!
//! so `jac_x_into` and `jac_u_into` write the rows of `∂F` first and then correct and solve them. Everything is
//! on fixed-size `nalgebra` values: no allocation.

use super::adapter::to_symbolic;
use super::names::comment;
use super::rust::{Draft, Writer};
use crate::equations::{Equations, ParamChain};
use crate::symbolic::{Expr, Symbol};

/// One I-field's block for the generator.
#[derive(Clone, Debug)]
pub(crate) struct MassPlan {
    /// The field's name, as written in the model.
    pub element: String,
    /// The identifier part of the generated function's name (`mass_<ident>`).
    pub ident: String,
    /// Indices of its flow states, in port order.
    pub rows: Vec<usize>,
    /// `M(q)`.
    pub matrix: Vec<Vec<Expr>>,
    /// Per state `k` that `M` depends on: `(k, ∂M/∂x_k)`.
    pub derivatives: Vec<(usize, Vec<Vec<Expr>>)>,
    /// Per free parameter `c` (`PARAM_NAMES` order) that `M` depends on: `(c, dM/dp_c)`, total through the
    /// derived parameters.
    pub param_derivatives: Vec<(usize, Vec<Vec<Expr>>)>,
}

/// The blocks of every I-field of the equations.
pub(crate) fn plan(
    eqs: &Equations,
    states: &[Symbol],
    chain: &ParamChain,
) -> Result<Vec<MassPlan>, String> {
    let mut out = Vec::with_capacity(eqs.mass.len());
    // `a.leg` and `a_leg` give one sanitized name; each field gets its own function.
    let mut idents = super::names::Namer::default();
    for b in &eqs.mass {
        let matrix: Vec<Vec<Expr>> = b
            .matrix
            .iter()
            .map(|row| row.iter().map(|e| to_symbolic(eqs, e)).collect())
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        // Only the states some entry reads can have a derivative that is not zero: a model of many blocks
        // differentiates each by its own few states, not by all of them.
        let read: std::collections::BTreeSet<Symbol> = matrix
            .iter()
            .flatten()
            .flat_map(Expr::free_symbols)
            .collect();
        let mut derivatives = Vec::new();
        for (k, s) in states.iter().enumerate().filter(|(_, s)| read.contains(s)) {
            let d: Vec<Vec<Expr>> = matrix
                .iter()
                .map(|row| row.iter().map(|m| m.diff(s)).collect())
                .collect();
            if d.iter().flatten().any(|e| !e.is_zero()) {
                derivatives.push((k, d));
            }
        }
        let n = matrix.len();
        let flat: Vec<Expr> = matrix.iter().flatten().cloned().collect();
        let by_param = chain.jacobian(&flat);
        let param_derivatives = (0..chain.columns.len())
            .filter(|&c| by_param.iter().any(|row| !row[c].is_zero()))
            .map(|c| {
                let d: Vec<Vec<Expr>> = by_param
                    .chunks(n.max(1))
                    .map(|rows| rows.iter().map(|row| row[c].clone()).collect())
                    .collect();
                (c, d)
            })
            .collect();
        let ident = idents.ident(&b.element);
        out.push(MassPlan {
            param_derivatives,
            element: b.element.clone(),
            ident,
            rows: b.states.clone(),
            matrix,
            derivatives,
        });
    }
    Ok(out)
}

/// The linear solve of the mass-matrix rows: Gaussian elimination with partial pivoting on fixed-size values (no
/// allocation, no `std`, no panic: indices stay below the fixed sizes); a singular matrix gives NaN.
pub(crate) const SOLVE_FN: &str = "
/// Solves `m z = b` by Gaussian elimination with partial pivoting; all NaN when `m` is singular.
fn bgc_solve<const N: usize, const C: usize>(
    mut m: SMatrix<f64, N, N>,
    mut b: SMatrix<f64, N, C>,
) -> SMatrix<f64, N, C> {
    for col in 0..N {
        let mut pivot = col;
        for r in col + 1..N {
            if libm::fabs(m[(r, col)]) > libm::fabs(m[(pivot, col)]) {
                pivot = r;
            }
        }
        let largest = libm::fabs(m[(pivot, col)]);
        if largest == 0.0 || largest.is_nan() {
            b.fill(f64::NAN);
            return b;
        }
        if pivot != col {
            for c in 0..N {
                let held = m[(col, c)];
                m[(col, c)] = m[(pivot, c)];
                m[(pivot, c)] = held;
            }
            for c in 0..C {
                let held = b[(col, c)];
                b[(col, c)] = b[(pivot, c)];
                b[(pivot, c)] = held;
            }
        }
        for r in col + 1..N {
            let f = m[(r, col)] / m[(col, col)];
            for c in col..N {
                m[(r, c)] -= f * m[(col, c)];
            }
            for c in 0..C {
                b[(r, c)] -= f * b[(col, c)];
            }
        }
    }
    for r in (0..N).rev() {
        for c in 0..C {
            let mut acc = b[(r, c)];
            for k in r + 1..N {
                acc -= m[(r, k)] * b[(k, c)];
            }
            b[(r, c)] = acc / m[(r, r)];
        }
    }
    b
}
";

/// The mass blocks' solve in the dense Jacobians: each block's rows are solved in a frame of their own, so that the
/// Jacobian of many blocks holds one block's rows on the stack at a time (150 pairs of coupled coils held all
/// their rows at once and overflowed a 2 MiB thread). Emitted after [`SOLVE_FN`] when the model has mass blocks.
pub(crate) const SOLVE_ROWS_FN: &str = "
/// Solves `m z = b` for the rows `rows` of `jac` (`b` is those rows, and `z` is written back
/// into them) in a frame of its own, so that one block's rows are on the stack at a time.
#[inline(never)]
fn bgc_solve_rows<const R: usize, const C: usize, const N: usize>(
    jac: &mut SMatrix<f64, R, C>,
    rows: [usize; N],
    m: SMatrix<f64, N, N>,
) {
    let mut b = SMatrix::<f64, N, C>::zeros();
    for (k, &r) in rows.iter().enumerate() {
        for c in 0..C {
            b[(k, c)] = jac[(r, c)];
        }
    }
    let solved = bgc_solve(m, b);
    for (k, &r) in rows.iter().enumerate() {
        for c in 0..C {
            jac[(r, c)] = solved[(k, c)];
        }
    }
}
";

/// `(column, ∂M/∂v_column)` for the columns `M` depends on.
pub(crate) type Derivatives = [(usize, Vec<Vec<Expr>>)];

/// The columns of a Jacobian whose mass-matrix rows are solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MassColumns {
    States,
    Inputs,
    Params,
}

impl MassColumns {
    /// A block's `(column, ∂M/∂v_column)` by these columns (`M` does not depend on the inputs).
    fn slopes(self, b: &MassPlan) -> &Derivatives {
        match self {
            MassColumns::States => &b.derivatives,
            MassColumns::Inputs => &[],
            MassColumns::Params => &b.param_derivatives,
        }
    }

    /// The term of `M`'s slope in the rows' equation, as the comments write it.
    fn slope_term(self) -> &'static str {
        match self {
            MassColumns::States => " − (∂M/∂x_k) ḟ",
            MassColumns::Inputs => "",
            MassColumns::Params => " − (∂M/∂p_k) ḟ",
        }
    }
}

impl Writer<'_> {
    /// `pub fn mass_<field>(p, x) -> SMatrix`: the inertia matrix of each I-field.
    pub(super) fn mass_fns(&mut self) {
        for b in self.plan.mass.clone() {
            let n = b.rows.len();
            let entries: Vec<&Expr> = b.matrix.iter().flatten().filter(|e| !e.is_zero()).collect();
            let mut d = self.draft(&entries);
            d.lines.push(format!(
                "    let mut m = SMatrix::<f64, {n}, {n}>::zeros();"
            ));
            for (i, row) in b.matrix.iter().enumerate() {
                for (j, e) in row.iter().enumerate() {
                    if !e.is_zero() {
                        let label = format!("M[{}, {}] = ", i + 1, j + 1);
                        self.statement(&mut d, &label, e, &format!("m[({i}, {j})] = "), ";");
                    }
                }
            }
            d.lines.push("    m".into());
            let uses = d.uses;
            self.emit_function(
                &format!(
                    "`M(q)` of the I-field `{}`: the inertia matrix of the rows of its flow states.",
                    comment(&b.element)
                ),
                &format!("mass_{}", b.ident),
                vec![("p", "&Params", uses.p), ("x", "&State", uses.x)],
                &format!(" -> SMatrix<f64, {n}, {n}>"),
                d,
            );
        }
    }

    /// The lines of `rhs_into` that turn the forces in the mass rows of `dx` into rates.
    pub(super) fn mass_solve_in_rhs(&self, d: &mut Draft) {
        for b in &self.plan.mass {
            let n = b.rows.len();
            d.lines.extend(self.comment_lines(&format!(
                "M_{}(q) d/dt [{}] = the forces above.",
                b.element,
                self.state_list(&b.rows)
            )));
            d.lines.push(format!(
                "    let mut force = SMatrix::<f64, {n}, 1>::zeros();"
            ));
            for (k, r) in b.rows.iter().enumerate() {
                d.lines.push(format!("    force[{k}] = dx[{r}];"));
            }
            d.lines.push(format!(
                "    let rate = bgc_solve(mass_{}(p, x), force);",
                b.ident
            ));
            for (k, r) in b.rows.iter().enumerate() {
                d.lines.push(format!("    dx[{r}] = rate[{k}];"));
            }
            d.uses.p = true;
            d.uses.x = true;
        }
    }

    /// The lines of a Jacobian function (`jac_x_into`, `jac_u_into`, `jac_p_into`: the columns `columns`) that
    /// turn the rows of `∂F` in `jac` into those of the rates: `M ∂ḟ = ∂F − (∂M/∂v) ḟ` (`M` does not depend on the
    /// inputs).
    pub(super) fn mass_solve_in_jacobian(&self, d: &mut Draft, columns: MassColumns) {
        // The rates `ḟ` that the slope corrections read, once for all blocks.
        if self.plan.mass.iter().any(|b| !columns.slopes(b).is_empty()) {
            d.lines.push("    let mut dx = State::zeros();".into());
            d.lines.push("    rhs_into(p, t, x, u, &mut dx);".into());
            d.uses.t = true;
            d.uses.u = true;
        }
        for b in &self.plan.mass {
            let derivatives = columns.slopes(b);
            d.lines.extend(self.comment_lines(&format!(
                "The rows of d/dt [{}]: M (∂ḟ) = ∂F{}, solved with M.",
                self.state_list(&b.rows),
                columns.slope_term(),
            )));
            for (k, dm) in derivatives {
                let by = self.column_name(columns, *k);
                let cell = |i: usize| {
                    format!("jac[({}, {k})]", b.rows.get(i).copied().unwrap_or_default())
                };
                self.slope_correction(d, (&b.rows, &cell), dm, &by);
            }
            let rows: Vec<String> = b.rows.iter().map(usize::to_string).collect();
            d.lines.push(format!(
                "    bgc_solve_rows(jac, [{}], mass_{}(p, x));",
                rows.join(", "),
                b.ident
            ));
            d.uses.p = true;
            d.uses.x = true;
        }
    }

    /// The lines `{cell(i)} -= ∂M[i, j]/∂by · dx[j-th row]` of the correction of a block with the rows `rows`, for
    /// the derivative `dm` of its `M` by the variable `by`; `cell(i)` is where row `i` of the block holds the column
    /// of `by`.
    pub(super) fn slope_correction(
        &self,
        d: &mut Draft,
        (rows, cell): (&[usize], &dyn Fn(usize) -> String),
        dm: &[Vec<Expr>],
        by: &str,
    ) {
        for (i, row) in dm.iter().enumerate() {
            for (j, e) in row.iter().enumerate().filter(|(_, e)| !e.is_zero()) {
                let label = format!("∂M[{}, {}]/∂{by} = ", i + 1, j + 1);
                self.statement(d, &label, e, "let dm = ", ";");
                let rate = rows.get(j).copied().unwrap_or_default();
                d.lines.push(format!("    {} -= dm * dx[{rate}];", cell(i)));
            }
        }
    }

    /// The name of column `k` of a Jacobian by `columns`.
    fn column_name(&self, columns: MassColumns, k: usize) -> String {
        let symbol = match columns {
            MassColumns::States => self.plan.states.get(k),
            MassColumns::Inputs => self.plan.inputs.get(k),
            MassColumns::Params => return self.free_param_name(k),
        };
        symbol.map(|s| s.name().to_string()).unwrap_or_default()
    }

    fn state_list(&self, rows: &[usize]) -> String {
        rows.iter()
            .filter_map(|&r| self.plan.states.get(r).map(|s| s.name().to_string()))
            .collect::<Vec<_>>()
            .join(", ")
    }
}
