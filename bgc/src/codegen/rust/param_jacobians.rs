//! The parameter Jacobians of a generated module: `JacP`, `OutJacP`, `jac_p_into` and `output_jac_p_into`.
//!
//! They are the full matrices `∂f/∂p` (`N_STATES × N_PARAMS`) and `∂h/∂p` (`N_OUTPUTS × N_PARAMS`), one column
//! per free parameter in `PARAM_NAMES` order, from symbolic derivatives total through the derived parameters (a
//! derived parameter moves with those it is defined from, see [`crate::equations::ParamChain`]). As in `jac_x_into`,
//! a model with nonlinear algebraic loops adds `∂g/∂z dz/dp` with `dz/dp = −(∂r/∂z)⁻¹ ∂r/∂p`, and the mass-matrix
//! rows of an I-field are solved from `M ∂ḟ/∂p = ∂F/∂p − (∂M/∂p) ḟ`. With the runtime, `Model` implements
//! `bgc_runtime::fit::generated::ParamJacobians` (the columns of given indices) from them, for `Generated::exact`.

use super::super::format;
use super::super::mass::MassColumns;
use super::{Arg, TearValues, Writer, output_names};
use crate::symbolic::Expr;

/// A matrix of expressions, row by row.
type Matrix = [Vec<Expr>];

impl Writer<'_> {
    /// The name of free parameter `c` (`PARAM_NAMES[c]`).
    pub(in crate::codegen) fn free_param_name(&self, c: usize) -> String {
        self.free
            .get(c)
            .and_then(|&k| self.m.equations.params.get(k))
            .map(|p| p.0.clone())
            .unwrap_or_default()
    }

    /// `JacP`, `OutJacP`, `jac_p_into` and `output_jac_p_into`.
    pub(super) fn param_jacobians(&mut self) {
        self.out.push_str(
            "
/// `∂f/∂p`: a column per free parameter, in `PARAM_NAMES` order.
pub type JacP = SMatrix<f64, N_STATES, N_PARAMS>;
/// `∂h/∂p`: a column per free parameter, in `PARAM_NAMES` order.
pub type OutJacP = SMatrix<f64, N_OUTPUTS, N_PARAMS>;
",
        );
        let plan = self.plan;
        let params: Vec<String> = (0..self.free.len())
            .map(|c| self.free_param_name(c))
            .collect();
        let states: Vec<String> = plan.states.iter().map(|s| s.name().to_string()).collect();
        let outputs = output_names(&self.m.equations);
        let loops = plan.loops.as_ref();
        self.param_matrix_fn(
            ("jac_p_into", "Writes `∂f/∂p` (a column per free parameter, derived parameters following them) into `jac`.", "&mut JacP"),
            &plan.dfdp,
            (&states, &params, "d/dt "),
            loops.map(|l| (&l.dfdz[..], &l.drdp[..])),
            true,
        );
        self.param_matrix_fn(
            ("output_jac_p_into", "Writes `∂h/∂p` (a column per free parameter, derived parameters following them) into `jac`.", "&mut OutJacP"),
            &plan.dhdp,
            (&outputs, &params, ""),
            loops.map(|l| (&l.dhdz[..], &l.drdp[..])),
            false,
        );
    }

    /// A parameter Jacobian function: zeros, every non-zero entry under a comment naming it, then the loops'
    /// contribution (`g_z`, `r_p`) and, for the rates (`mass`), the mass-matrix rows solved.
    fn param_matrix_fn(
        &mut self,
        (name, doc, ty): (&str, &str, &'static str),
        m: &[Vec<Expr>],
        (rows, cols, row_prefix): (&[String], &[String], &str),
        loops: Option<(&Matrix, &Matrix)>,
        mass: bool,
    ) {
        let (g_z, r_p) = loops.unwrap_or((&[], &[]));
        let mut needed: Vec<&Expr> = m.iter().flatten().filter(|e| !e.is_zero()).collect();
        let plan = self.plan;
        let solve_mass = mass && !self.free.is_empty();
        if solve_mass {
            needed.extend(plan.mass.iter().flat_map(|b| {
                b.param_derivatives
                    .iter()
                    .flat_map(|(_, d)| d.iter().flatten())
            }));
        }
        let correction = self.loop_correction_exprs(g_z, r_p);
        needed.extend(correction.iter());
        let shared = self.shared_lets(name);
        let entries = m
            .iter()
            .enumerate()
            .flat_map(|(r, row)| row.iter().enumerate().map(move |(c, e)| (r, c, e)));
        let with_mass = solve_mass && !plan.mass.is_empty();
        if !with_mass && shared.is_empty() && self.splits(needed.len()) {
            let statements = self.entry_statements(entries, (rows, cols, row_prefix));
            let d = self.jacobian_parts(name, ty, &statements, false);
            self.model_function(name, doc, d, Arg::new("jac", ty, true));
            return;
        }
        needed.extend(shared.iter().map(|(_, v)| v));
        let mut d = self.draft_through_loops(&needed, false, TearValues::Solved);
        self.shared_statements(&mut d, shared);
        self.matrix_entries(&mut d, entries, (rows, cols, row_prefix));
        self.loop_correction(&mut d, g_z, r_p);
        if solve_mass {
            self.mass_solve_in_jacobian(&mut d, MassColumns::Params);
        }
        self.model_function(name, doc, d, Arg::new("jac", ty, true));
    }

    /// The runtime's `ParamJacobians` for `Model`: the requested columns copied from the full matrix,
    /// evaluated once per call (no column exists without free parameters).
    pub(super) fn param_jacobians_impl(&mut self) {
        let empty = self.free.is_empty();
        let arg = |name: &str, ty: &str| {
            let underscore = if empty && name != "indices" { "_" } else { "" };
            format!("{underscore}{name}: {ty}")
        };
        let mut text = String::from(
            "\nimpl bgc_runtime::fit::generated::ParamJacobians<N_STATES, N_INPUTS, N_OUTPUTS> for Model {\n",
        );
        let methods = [
            ("jac_p_columns", "jac_p_into", "JacP", "N_STATES"),
            (
                "output_jac_p_columns",
                "output_jac_p_into",
                "OutJacP",
                "N_OUTPUTS",
            ),
        ];
        for (k, (method, function, ty, rows)) in methods.into_iter().enumerate() {
            if k > 0 {
                text.push('\n');
            }
            let params = [
                "&self".to_string(),
                arg("t", "f64"),
                arg("x", "&State"),
                arg("u", "&Inputs"),
                arg("indices", "&[usize]"),
                arg("columns", "&mut [f64]"),
            ];
            let head = format!("fn {method}");
            text.push_str(&format::signature(
                4, &head, &params, " -> bool", false, self.width,
            ));
            text.push('\n');
            if empty {
                text.push_str("        indices.is_empty()\n");
            } else {
                text.push_str(&format!(
                    "        let valid = |&k: &usize| k < N_PARAMS;
        if columns.len() != {rows} * indices.len() || !indices.iter().all(valid) {{
            return false;
        }}
        let mut jac = {ty}::zeros();
        {function}(&self.params, t, x, u, &mut jac);
        for (c, &k) in indices.iter().enumerate() {{
            let column = &jac.as_slice()[k * {rows}..(k + 1) * {rows}];
            columns[c * {rows}..(c + 1) * {rows}].copy_from_slice(column);
        }}
        true
"
                ));
            }
            text.push_str("    }\n");
        }
        text.push_str("}\n");
        self.out.push_str(&text);
    }
}
