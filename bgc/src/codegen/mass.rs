//! The mass-matrix blocks of I-fields in generated code.
//!
//! For the flow states `f_B` of an I-field the equations give the generalised forces `F` and the inertia matrix
//! `M(q)` (`M ḟ_B = F`). The generated `rhs_into` writes `F` into those rows like any other rate, then solves
//! `M ḟ_B = F` in place with a Cholesky factorisation (an inertia matrix is symmetric positive definite; one that
//! is not, at some configuration, leaves NaN in those rows rather than a panic). The Jacobians follow from
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
use super::rust::Writer;
use crate::equations::Equations;
use crate::symbolic::{Expr, Symbol, to_text};
use std::fmt::Write;

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
}

/// The blocks of every I-field of the equations.
pub(crate) fn plan(eqs: &Equations, states: &[Symbol]) -> Result<Vec<MassPlan>, String> {
    let mut out = Vec::with_capacity(eqs.mass.len());
    for b in &eqs.mass {
        let matrix: Vec<Vec<Expr>> = b
            .matrix
            .iter()
            .map(|row| row.iter().map(|e| to_symbolic(eqs, e)).collect())
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        let mut derivatives = Vec::new();
        for (k, s) in states.iter().enumerate() {
            let d: Vec<Vec<Expr>> = matrix
                .iter()
                .map(|row| row.iter().map(|m| m.diff(s)).collect())
                .collect();
            if d.iter().flatten().any(|e| !e.is_zero()) {
                derivatives.push((k, d));
            }
        }
        let ident: String = b
            .element
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        out.push(MassPlan {
            element: b.element.clone(),
            ident,
            rows: b.states.clone(),
            matrix,
            derivatives,
        });
    }
    Ok(out)
}

impl Writer<'_> {
    /// `fn mass_<field>(p, x) -> SMatrix`: the inertia matrix of each I-field.
    pub(super) fn mass_fns(&mut self) {
        for b in self.plan.mass.clone() {
            let n = b.rows.len();
            let _ = writeln!(
                self.out,
                "\n/// `M(q)` of the I-field `{}`: the inertia matrix of the rows of its flow states.\n{}\nfn mass_{}(p: &Params, x: &State) -> SMatrix<f64, {n}, {n}> {{",
                comment(&b.element),
                super::rust::FN_ALLOW,
                b.ident
            );
            let entries: Vec<&Expr> = b.matrix.iter().flatten().collect();
            self.bindings(&entries);
            let _ = writeln!(
                self.out,
                "    let mut m = SMatrix::<f64, {n}, {n}>::zeros();"
            );
            for (i, row) in b.matrix.iter().enumerate() {
                for (j, e) in row.iter().enumerate() {
                    if e.is_zero() {
                        continue;
                    }
                    let _ = writeln!(
                        self.out,
                        "    // M[{}, {}] = {}\n    m[({i}, {j})] = {};",
                        i + 1,
                        j + 1,
                        comment(&to_text(e)),
                        self.rust(e)
                    );
                }
            }
            self.line("    m\n}");
        }
    }

    /// The lines of `rhs_into` that turn the forces in the mass rows of `dx` into rates.
    pub(super) fn mass_solve_in_rhs(&mut self) {
        for b in self.plan.mass.clone() {
            let n = b.rows.len();
            let rows: Vec<String> = b.rows.iter().map(|r| format!("dx[{r}]")).collect();
            let _ = writeln!(
                self.out,
                "    // M_{0}(q) d/dt [{1}] = the forces above, solved by Cholesky (M is symmetric positive definite;\n    // where it is not, the rates are NaN).\n    let force = SVector::<f64, {n}>::new({2});\n    let rate = match mass_{3}(p, x).cholesky() {{\n        Some(m) => m.solve(&force),\n        None => SVector::<f64, {n}>::repeat(f64::NAN),\n    }};",
                comment(&b.element),
                self.state_list(&b.rows),
                rows.join(", "),
                b.ident
            );
            for (k, r) in b.rows.iter().enumerate() {
                let _ = writeln!(self.out, "    dx[{r}] = rate[{k}];");
            }
        }
    }

    /// The lines of `jac_x_into` (`with_dm`) or `jac_u_into` that turn the rows of `∂F` in `jac` into those of the
    /// rates.
    pub(super) fn mass_solve_in_jacobian(&mut self, with_dm: bool, cols: &str) {
        for b in self.plan.mass.clone() {
            let n = b.rows.len();
            let _ = writeln!(
                self.out,
                "    // The rows of d/dt [{}]: M (∂ḟ) = ∂F{}, solved with M.\n    let mut rows = SMatrix::<f64, {n}, {cols}>::zeros();",
                self.state_list(&b.rows),
                if with_dm {
                    " − (∂M/∂x_k) ḟ"
                } else {
                    ""
                },
            );
            for (k, r) in b.rows.iter().enumerate() {
                let _ = writeln!(self.out, "    rows.set_row({k}, &jac.row({r}));");
            }
            if with_dm && !b.derivatives.is_empty() {
                self.line("    let mut dx = State::zeros();\n    rhs_into(p, t, x, u, &mut dx);");
                let rates: Vec<String> = b.rows.iter().map(|r| format!("dx[{r}]")).collect();
                let _ = writeln!(
                    self.out,
                    "    let rate = SVector::<f64, {n}>::new({});",
                    rates.join(", ")
                );
                for (k, d) in &b.derivatives {
                    let state = self.plan.states.get(*k).map(|s| s.name().to_string());
                    let _ = writeln!(
                        self.out,
                        "    // ∂M/∂{}\n    let mut dm = SMatrix::<f64, {n}, {n}>::zeros();",
                        state.unwrap_or_default()
                    );
                    for (i, row) in d.iter().enumerate() {
                        for (j, e) in row.iter().enumerate() {
                            if e.is_zero() {
                                continue;
                            }
                            let _ = writeln!(self.out, "    dm[({i}, {j})] = {};", self.rust(e));
                        }
                    }
                    self.line("    let correction = dm * rate;");
                    for i in 0..n {
                        let _ = writeln!(self.out, "    rows[({i}, {k})] -= correction[{i}];");
                    }
                }
            }
            let _ = writeln!(
                self.out,
                "    let solved = match mass_{}(p, x).cholesky() {{\n        Some(m) => m.solve(&rows),\n        None => SMatrix::<f64, {n}, {cols}>::repeat(f64::NAN),\n    }};",
                b.ident
            );
            for (k, r) in b.rows.iter().enumerate() {
                let _ = writeln!(self.out, "    jac.set_row({r}, &solved.row({k}));");
            }
        }
    }

    fn state_list(&self, rows: &[usize]) -> String {
        rows.iter()
            .filter_map(|&r| self.plan.states.get(r).map(|s| s.name().to_string()))
            .collect::<Vec<_>>()
            .join(", ")
    }
}
