//! The numeric functions of a generated module: `rhs`, `outputs`, the Jacobians, the state spaces and the energy
//! and power functions. Each body binds the states and inputs it uses and the elementary functions of states,
//! inputs, parameters and time it calls (`let cos_theta = libm::cos(theta);`, computed once: the same call gives the
//! same bits), then computes its statements, each under the equation it computes.

use super::super::emit::{Block, MAX_LETS, StateSpace};
use super::super::layout::Body;
use super::super::mass::MassColumns;
use super::super::names::{Namer, comment};
use super::calls::{call_depth, call_name, early_calls, with_bound_calls};
use super::parts::{Out, Statement};
use super::terms::term_field;
use super::{Arg, Function, Uses, Writer, output_names};
use crate::equations::{EnergyKind, SparseMatrix, StateSelection};
use crate::symbolic::{Expr, RustCode, Symbol, SymbolKind};
use std::collections::{BTreeMap, BTreeSet};

/// The lines and facts of a function body being written.
pub(in crate::codegen) struct Draft {
    pub(super) namer: Namer,
    pub(in crate::codegen) lines: Vec<String>,
    pub(super) locals: Vec<String>,
    pub(in crate::codegen) uses: Uses,
    /// The number of the next temporary.
    next_temp: usize,
    /// Calls bound at the top of the body: the call's text and the name bound to it.
    calls: BTreeMap<String, String>,
    /// Whether the body reads its parameter-only subexpressions from `c: &ParamTerms` ([`super::terms`]).
    cache: bool,
    /// Whether it reads any.
    pub(super) reads_terms: bool,
}

impl Draft {
    /// Records a local name the body binds.
    pub(in crate::codegen) fn push_local(&mut self, name: String) {
        self.locals.push(name);
    }
}

/// Where a body finds the values of the algebraic loops' tears that its expressions read.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(in crate::codegen) enum TearValues {
    /// The body reads no tear.
    None,
    /// The body solves the loops: `let z = loop_values(p, t, x, u);`.
    Solved,
    /// The tears are the body's argument `z`.
    Given,
}

impl<'a> Writer<'a> {
    /// A body that binds the states and inputs `exprs` use, and what it uses.
    pub(in crate::codegen) fn draft(&self, exprs: &[&Expr]) -> Draft {
        self.draft_with(exprs, false, TearValues::None)
    }

    /// A body as [`Self::draft`] whose statements read parameter-only subexpressions from `c: &ParamTerms`.
    pub(super) fn draft_cached(&self, exprs: &[&Expr]) -> Draft {
        self.draft_with(exprs, self.terms_enabled, TearValues::None)
    }

    /// A body as [`Self::draft`] (with the parameter terms when `cache`) that also binds the tears `exprs` read,
    /// from `tears`, before the calls that are computed once: a call on a tear (`exp((u - R*loop_i)/V_t)` in a
    /// residual, its slope and its parameter derivatives) is then computed once too.
    pub(in crate::codegen) fn draft_through_loops(
        &self,
        exprs: &[&Expr],
        cache: bool,
        tears: TearValues,
    ) -> Draft {
        self.draft_with(exprs, cache && self.terms_enabled, tears)
    }

    /// `e` as the body of `d` computes it: with its parameter terms when `d` reads them from `c`.
    fn as_computed(&self, d: &Draft, e: &Expr) -> Expr {
        if d.cache {
            self.terms.borrow_mut().rewrite(e)
        } else {
            e.clone()
        }
    }

    fn draft_with(&self, exprs: &[&Expr], cache: bool, tears: TearValues) -> Draft {
        let rewritten: Vec<Expr> = if cache {
            let mut terms = self.terms.borrow_mut();
            exprs.iter().map(|e| terms.rewrite(e)).collect()
        } else {
            exprs.iter().map(|e| (*e).clone()).collect()
        };
        let exprs: Vec<&Expr> = rewritten.iter().collect();
        let mut used: BTreeSet<Symbol> = BTreeSet::new();
        for e in &exprs {
            used.extend(e.free_symbols());
        }
        let mut d = Draft {
            namer: self.namer.clone(),
            lines: Vec::new(),
            locals: Vec::new(),
            uses: Uses {
                p: used
                    .iter()
                    .any(|s| s.kind() == SymbolKind::Param && term_field(s).is_none()),
                t: used.iter().any(|s| s.kind() == SymbolKind::Time),
                x: false,
                u: false,
            },
            next_temp: 1,
            calls: BTreeMap::new(),
            cache,
            reads_terms: used.iter().any(|s| term_field(s).is_some()),
        };
        // The states, then the inputs, in order (looked up: a large model has many, a part reads few).
        let mut read: Vec<((u8, usize), &Symbol)> = used
            .iter()
            .filter_map(|s| self.positions.get(s).map(|&at| (at, s)))
            .collect();
        read.sort_by_key(|&(at, _)| at);
        for ((vector, i), s) in read {
            let name = self.name(s);
            let vector = if vector == 0 {
                d.uses.x = true;
                "x"
            } else {
                d.uses.u = true;
                "u"
            };
            d.lines.push(format!("    let {name} = {vector}[{i}];"));
            d.locals.push(name);
        }
        // The names available from the start: states and inputs bound above, parameters, time, the tears bound
        // next (not the intermediates and earlier outputs, computed in the body).
        let mut early: BTreeSet<String> = used
            .iter()
            .filter(|s| !matches!(s.kind(), SymbolKind::Intermediate | SymbolKind::Output))
            .map(|s| self.name(s))
            .collect();
        early.extend(self.bind_tears(&mut d, &used, tears));
        let mut calls = BTreeMap::new();
        for e in &exprs {
            early_calls(&self.code(e), &early, &mut calls);
        }
        let mut calls: Vec<(String, RustCode)> = calls.into_iter().collect();
        calls.sort_by_key(|(_, call)| call_depth(call));
        for (text, call) in calls {
            let name = d.namer.ident(&call_name(&call));
            let bound = match call {
                RustCode::Call(callee, args) => RustCode::Call(
                    callee,
                    args.into_iter()
                        .map(|a| with_bound_calls(a, &d.calls))
                        .collect(),
                ),
                other => other,
            };
            self.statement_code(&mut d, Vec::new(), &bound, &format!("let {name} = "), ";");
            d.locals.push(name.clone());
            d.calls.insert(text, name);
        }
        d
    }

    /// Appends the statement `head code tail` of `d` under the comment `{label}{e}` (`d/dt x = ...`).
    pub(in crate::codegen) fn statement(
        &self,
        d: &mut Draft,
        label: &str,
        e: &Expr,
        head: &str,
        tail: &str,
    ) {
        let computed = self.as_computed(d, e);
        if d.cache {
            for s in computed.free_symbols() {
                if term_field(&s).is_some() {
                    d.reads_terms = true;
                } else if s.kind() == SymbolKind::Param {
                    d.uses.p = true;
                }
            }
        }
        let code = with_bound_calls(self.code(&computed), &d.calls);
        self.statement_code(d, self.equation(4, label, e), &code, head, tail);
    }

    fn statement_code(
        &self,
        d: &mut Draft,
        comment_lines: Vec<String>,
        code: &RustCode,
        head: &str,
        tail: &str,
    ) {
        let mut body = Body::new(&mut d.namer, 4, self.width).first_temp(d.next_temp);
        body.lines(comment_lines);
        body.statement(head, code, tail);
        d.next_temp = body.next_temp();
        d.lines.extend(body.finish().lines().map(str::to_string));
    }

    pub(super) fn body_text(lines: &[String]) -> String {
        lines.iter().map(|l| format!("{l}\n")).collect()
    }

    /// The model arguments `p, t, x, u` as `d` uses them.
    pub(super) fn model_args(uses: Uses) -> Vec<Arg> {
        vec![
            Arg::new("p", "&Params", uses.p),
            Arg::new("t", "f64", uses.t),
            Arg::new("x", "&State", uses.x),
            Arg::new("u", "&Inputs", uses.u),
        ]
    }

    /// `name` writing the block `b` into `target` (`dx` or `y`): the `let`s of the intermediates, then each entry.
    fn block_fn(
        &mut self,
        name: &str,
        doc: &str,
        b: &Block,
        target: (&'static str, &'static str),
        lhs: &[String],
    ) {
        let with_mass = target.0 == "dx" && !self.plan.mass.is_empty();
        if b.lets.is_empty() && !with_mass && self.splits(b.results.len()) {
            let statements: Vec<Statement> = b
                .results
                .iter()
                .enumerate()
                .map(|(i, r)| Statement {
                    label: format!("{} = ", lhs.get(i).map_or("", String::as_str)),
                    expr: r,
                    head: format!("{}[{i}] = ", target.0),
                    tail: ";",
                })
                .collect();
            let out = Out {
                name: target.0,
                ty: target.1,
                passed: target.0,
            };
            let stem = name.strip_suffix("_into").unwrap_or(name);
            let d = self.parts(stem, &statements, out, self.terms_enabled, Vec::new());
            self.model_function(name, doc, d, Arg::new(target.0, target.1, true));
            return;
        }
        let mut all: Vec<&Expr> = b.lets.iter().map(|l| &l.1).collect();
        all.extend(b.results.iter());
        let mut d = self.draft_through_loops(&all, true, TearValues::Solved);
        for (s, v) in &b.lets {
            let local = self.name(s);
            self.statement(
                &mut d,
                &format!("{} = ", s.name()),
                v,
                &format!("let {local} = "),
                ";",
            );
            d.locals.push(local);
        }
        for (i, r) in b.results.iter().enumerate() {
            let lhs = lhs.get(i).cloned().unwrap_or_default();
            self.statement(
                &mut d,
                &format!("{lhs} = "),
                r,
                &format!("{}[{i}] = ", target.0),
                ";",
            );
        }
        if target.0 == "dx" {
            self.mass_solve_in_rhs(&mut d);
        }
        let out = Arg::new(target.0, target.1, !b.results.is_empty());
        self.model_function(name, doc, d, out);
    }

    /// The model function `name` with the body of `d` and the output argument `out` (`dx`, `y`, `jac`): itself
    /// when the body reads no parameter term, else `{base}_with(p, c, t, x, u, out)` that reads them from `c` and
    /// `name` that computes them and calls it.
    pub(super) fn model_function(&mut self, name: &str, doc: &str, d: Draft, out: Arg) {
        let mut args = Self::model_args(d.uses);
        if !d.reads_terms {
            args.push(out);
            self.function(Function {
                doc: doc.to_string(),
                name: name.to_string(),
                args,
                ret: String::new(),
                body: Self::body_text(&d.lines),
                locals: d.locals,
                inline: true,
            });
            return;
        }
        let with = with_terms_name(name);
        args.insert(1, Arg::new("c", "&ParamTerms", true));
        let (out_name, out_ty) = (out.name, out.ty);
        args.push(out);
        self.function(Function {
            doc: format!(
                "{doc} `c` holds the parameter terms, `ParamTerms::at(p)` (`Model` computes them once per \
                 parameter set)."
            ),
            name: with.clone(),
            args,
            ret: String::new(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: true,
        });
        let mut wrapper = Self::model_args(Uses {
            p: true,
            t: true,
            x: true,
            u: true,
        });
        wrapper.push(Arg::new(out_name, out_ty, true));
        self.function(Function {
            doc: format!("{doc} Computes the parameter terms first: `{with}` takes them."),
            name: name.to_string(),
            args: wrapper,
            ret: String::new(),
            body: format!("    {with}(p, &ParamTerms::at(p), t, x, u, {out_name});\n"),
            locals: Vec::new(),
            inline: false,
        });
        self.with_terms.push(name.to_string());
    }

    /// Emits a function with the body of `d`; `args` are `(name, type, used)`.
    pub(in crate::codegen) fn emit_function(
        &mut self,
        doc: &str,
        name: &str,
        args: Vec<(&'static str, &'static str, bool)>,
        ret: &str,
        d: Draft,
    ) {
        self.function(Function {
            doc: doc.to_string(),
            name: name.to_string(),
            args: args
                .into_iter()
                .map(|(n, t, used)| Arg::new(n, t, used))
                .collect(),
            ret: ret.to_string(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        });
    }

    /// Comment lines `    // text` inside a function body.
    pub(in crate::codegen) fn comment_lines(&self, text: &str) -> Vec<String> {
        super::super::format::comment(4, "//", text, super::super::format::Wrap::Prose, self.width)
    }

    pub(super) fn functions(&mut self) {
        self.terms_enabled = self.param_terms_fit();
        self.loop_fns();
        self.mass_fns();
        self.rhs();
        self.outputs();
        self.jacobians();
        self.param_jacobians();
        self.state_spaces();
        self.energy();
    }

    fn rhs(&mut self) {
        let mass_rows: Vec<usize> = self
            .plan
            .mass
            .iter()
            .flat_map(|b| b.rows.iter().copied())
            .collect();
        let lhs: Vec<String> = self
            .plan
            .states
            .iter()
            .enumerate()
            .map(|(i, s)| {
                if mass_rows.contains(&i) {
                    format!("the force of d/dt {}", s.name())
                } else {
                    format!("d/dt {}", s.name())
                }
            })
            .collect();
        let b = self.plan.rhs.clone();
        self.block_fn(
            "rhs_into",
            "Writes the state derivative `ẋ = f(t, x, u)` into `dx`.",
            &b,
            ("dx", "&mut State"),
            &lhs,
        );
        self.out.push_str(
            "
/// The state derivative `ẋ = f(t, x, u)`.
pub fn rhs(p: &Params, t: f64, x: &State, u: &Inputs) -> State {
    let mut dx = State::zeros();
    rhs_into(p, t, x, u, &mut dx);
    dx
}
",
        );
    }

    fn outputs(&mut self) {
        let lhs = output_names(&self.m.equations);
        let b = self.plan.outputs.clone();
        self.block_fn(
            "outputs_into",
            "Writes the outputs `y = h(t, x, u)` into `y`.",
            &b,
            ("y", "&mut Outputs"),
            &lhs,
        );
        self.out.push_str(
            "
/// The outputs `y = h(t, x, u)`.
pub fn outputs(p: &Params, t: f64, x: &State, u: &Inputs) -> Outputs {
    let mut y = Outputs::zeros();
    outputs_into(p, t, x, u, &mut y);
    y
}
",
        );
    }

    /// A function that fills a matrix: zeros, then every non-zero entry under a comment naming it.
    fn matrix_fn(
        &mut self,
        (name, doc, ty): (&str, &str, &'static str),
        m: &SparseMatrix,
        rows: &[String],
        cols: &[String],
        row_prefix: &str,
    ) {
        let mut nonzero: Vec<&Expr> = m.iter().map(|(_, _, e)| e).collect();
        if name == "jac_x_into" {
            // The mass-matrix correction uses ∂M/∂x as well.
            let plan = self.plan;
            nonzero.extend(
                plan.mass
                    .iter()
                    .flat_map(|b| b.derivatives.iter().flat_map(|(_, d)| d.iter().flatten())),
            );
        }
        let plan = self.plan;
        let (g_z, r_v) = match (name, &plan.loops) {
            ("jac_x_into", Some(l)) => (&l.dfdz[..], &l.drdx[..]),
            ("jac_u_into", Some(l)) => (&l.dfdz[..], &l.drdu[..]),
            ("output_jac_x_into", Some(l)) => (&l.dhdz[..], &l.drdx[..]),
            ("output_jac_u_into", Some(l)) => (&l.dhdz[..], &l.drdu[..]),
            _ => (&[][..], &[][..]),
        };
        let correction = self.loop_correction_exprs(g_z, r_v);
        nonzero.extend(correction.iter());
        let shared = self.shared_lets(name);
        let corrected = !correction.is_empty()
            || !shared.is_empty()
            || (matches!(name, "jac_x_into" | "jac_u_into") && !plan.mass.is_empty());
        let d = if !corrected && self.splits(m.iter().filter(|e| !e.2.is_zero()).count()) {
            let statements = self.entry_statements(m.iter(), (rows, cols, row_prefix));
            self.jacobian_parts(name, ty, &statements, self.terms_enabled)
        } else {
            nonzero.extend(shared.iter().map(|(_, v)| v));
            let mut d = self.draft_through_loops(&nonzero, true, TearValues::Solved);
            self.shared_statements(&mut d, shared);
            self.matrix_entries(&mut d, m.iter(), (rows, cols, row_prefix));
            self.loop_correction(&mut d, g_z, r_v);
            match name {
                "jac_x_into" => self.mass_solve_in_jacobian(&mut d, MassColumns::States),
                // Without inputs `∂f/∂u` has no columns to solve for (and an empty loop fails `clippy`).
                "jac_u_into" if !self.plan.inputs.is_empty() => {
                    self.mass_solve_in_jacobian(&mut d, MassColumns::Inputs)
                }
                _ => {}
            }
            d
        };
        if !(d.uses.t || d.uses.x || d.uses.u) {
            self.constant_jacobian(name, ty);
        }
        let sparse = name == "jac_x_into" && self.wants_sparse_jac_x();
        self.model_function(name, doc, d, Arg::new("jac", ty, true));
        if sparse {
            self.sparse_jac_x(m, rows, cols, row_prefix);
        }
    }

    /// The shared subexpressions the entries of the Jacobian function `name` are written over.
    pub(super) fn shared_lets(&self, name: &str) -> &'a [(Symbol, Expr)] {
        let plan = self.plan;
        plan.shared.get(name).map_or(&[], Vec::as_slice)
    }

    /// One `let` per shared subexpression, in order (each after those it reads).
    pub(super) fn shared_statements(&self, d: &mut Draft, lets: &[(Symbol, Expr)]) {
        for (s, v) in lets {
            let local = self.name(s);
            self.statement(
                d,
                &format!("{} = ", s.name()),
                v,
                &format!("let {local} = "),
                ";",
            );
            d.locals.push(local);
        }
    }

    /// One assignment `jac[(r, c)] = value;` per entry that is not identically zero, in the order given, under a
    /// comment naming it ([`entry_label`]).
    pub(super) fn entry_statements<'e>(
        &self,
        entries: impl Iterator<Item = (usize, usize, &'e Expr)>,
        names: (&[String], &[String], &str),
    ) -> Vec<Statement<'e>> {
        entries
            .filter(|(_, _, e)| !e.is_zero())
            .map(|(r, c, e)| Statement {
                label: entry_label(names, r, c),
                expr: e,
                head: format!("jac[({r}, {c})] = "),
                tail: ";",
            })
            .collect()
    }

    /// `jac.fill(0.0)` and the entry statements in one body, as [`Self::entry_statements`] gives them.
    pub(super) fn matrix_entries<'e>(
        &self,
        d: &mut Draft,
        entries: impl Iterator<Item = (usize, usize, &'e Expr)>,
        names: (&[String], &[String], &str),
    ) {
        d.lines.push("    jac.fill(0.0);".into());
        for s in self.entry_statements(entries, names) {
            self.statement(d, &s.label, s.expr, &s.head, s.tail);
        }
    }

    /// The body of the Jacobian function `name` (`jac_x_into`, writing a `ty`) as `jac.fill(0.0)` and calls of
    /// parts of bounded size that write the `statements`.
    pub(super) fn jacobian_parts(
        &mut self,
        name: &str,
        ty: &'static str,
        statements: &[Statement],
        cached: bool,
    ) -> Draft {
        let out = Out {
            name: "jac",
            ty,
            passed: "jac",
        };
        let stem = name.strip_suffix("_into").unwrap_or(name);
        let prologue = vec!["    jac.fill(0.0);".to_string()];
        self.parts(stem, statements, out, cached, prologue)
    }

    fn jacobians(&mut self) {
        let xs: Vec<String> = self
            .plan
            .states
            .iter()
            .map(|s| s.name().to_string())
            .collect();
        let us: Vec<String> = self
            .plan
            .inputs
            .iter()
            .map(|s| s.name().to_string())
            .collect();
        let ys: Vec<String> = output_names(&self.m.equations);
        let plan = self.plan;
        self.matrix_fn(
            ("jac_x_into", "Writes `∂f/∂x` into `jac`.", "&mut JacX"),
            &plan.dfdx,
            &xs,
            &xs,
            "d/dt ",
        );
        self.matrix_fn(
            ("jac_u_into", "Writes `∂f/∂u` into `jac`.", "&mut JacU"),
            &plan.dfdu,
            &xs,
            &us,
            "d/dt ",
        );
        self.matrix_fn(
            (
                "output_jac_x_into",
                "Writes `∂h/∂x` into `jac`.",
                "&mut OutJacX",
            ),
            &plan.dhdx,
            &ys,
            &xs,
            "",
        );
        self.matrix_fn(
            (
                "output_jac_u_into",
                "Writes `∂h/∂u` into `jac`.",
                "&mut OutJacU",
            ),
            &plan.dhdu,
            &ys,
            &us,
            "",
        );
    }

    fn state_space_fn(&mut self, (name, ty): (&str, &str), size: &str, ss: &StateSpace, doc: &str) {
        let n = ss.states.len();
        if !super::model::square_fits(n) {
            self.state_space_entries(name, ss, doc);
            return;
        }
        self.state_space_type(ty, size, doc);
        let matrices = [
            ("a", &ss.a, size, size),
            ("b", &ss.b, size, "N_INPUTS"),
            ("c", &ss.c, "N_OUTPUTS", size),
            ("d", &ss.d, "N_OUTPUTS", "N_INPUTS"),
        ];
        let shared = self.shared_lets(name);
        let all: Vec<&Expr> = matrices
            .iter()
            .flat_map(|m| m.1.iter().map(|(_, _, e)| e))
            .chain(shared.iter().map(|(_, v)| v))
            .collect();
        // Entries are free of states, inputs and time: the draft binds nothing.
        let mut d = self.draft(&all);
        self.shared_statements(&mut d, shared);
        for (var, m, rows, cols) in matrices {
            let mutable = if m.iter().any(|(_, _, e)| !e.is_zero()) {
                "mut "
            } else {
                ""
            };
            d.lines.push(format!(
                "    let {mutable}{var} = SMatrix::<f64, {rows}, {cols}>::zeros();"
            ));
        }
        let ys: Vec<String> = output_names(&self.m.equations);
        let us: Vec<String> = self.m.equations.inputs.clone();
        for (var, m, rows, cols) in [
            ("a", &ss.a, &ss.states, &ss.states),
            ("b", &ss.b, &ss.states, &us),
            ("c", &ss.c, &ys, &ss.states),
            ("d", &ss.d, &ys, &us),
        ] {
            for (r, col, e) in m.iter().filter(|(_, _, e)| !e.is_zero()) {
                let lhs = format!(
                    "{}[{}, {}] = ",
                    var.to_uppercase(),
                    rows.get(r).map_or("", String::as_str),
                    cols.get(col).map_or("", String::as_str)
                );
                self.statement(&mut d, &lhs, e, &format!("{var}[({r}, {col})] = "), ";");
            }
        }
        d.lines.push("    (a, b, c, d)".into());
        self.function(Function {
            doc: format!("The linear state space {doc}, at the parameters `p`."),
            name: name.to_string(),
            args: vec![Arg::new("p", "&Params", d.uses.p)],
            ret: format!(" -> {ty}"),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        });
    }

    /// `{name}_entries(p, entry)`, the state space of a model whose `A` would take more than
    /// [`super::model::MAX_CONSTANT_JACOBIAN_BYTES`]: each entry that is not identically zero passed to `entry`,
    /// so that no `N²` matrix is declared (a thread's stack holds few).
    fn state_space_entries(&mut self, name: &str, ss: &StateSpace, doc: &str) {
        let ys: Vec<String> = output_names(&self.m.equations);
        let us: Vec<String> = self.m.equations.inputs.clone();
        let mut statements = Vec::new();
        for (var, m, rows, cols) in [
            ('A', &ss.a, &ss.states, &ss.states),
            ('B', &ss.b, &ss.states, &us),
            ('C', &ss.c, &ys, &ss.states),
            ('D', &ss.d, &ys, &us),
        ] {
            for (r, col, e) in m.iter().filter(|(_, _, e)| !e.is_zero()) {
                statements.push(Statement {
                    label: format!(
                        "{var}[{}, {}] = ",
                        rows.get(r).map_or("", String::as_str),
                        cols.get(col).map_or("", String::as_str)
                    ),
                    expr: e,
                    head: format!("entry('{var}', {r}, {col}, "),
                    tail: ");",
                });
            }
        }
        let function = format!("{name}_entries");
        let ty = "&mut dyn FnMut(char, usize, usize, f64)";
        // Entries written over shared `let`s stay in one function, as the Jacobians' entries do.
        let shared = self.shared_lets(name);
        let d = if shared.is_empty() && self.splits(statements.len()) {
            let out = Out {
                name: "entry",
                ty,
                passed: "entry",
            };
            self.parts(&function, &statements, out, false, Vec::new())
        } else {
            let exprs: Vec<&Expr> = statements
                .iter()
                .map(|s| s.expr)
                .chain(shared.iter().map(|(_, v)| v))
                .collect();
            let mut d = self.draft(&exprs);
            self.shared_statements(&mut d, shared);
            for s in &statements {
                self.statement(&mut d, &s.label, s.expr, &s.head, s.tail);
            }
            d
        };
        self.function(Function {
            doc: format!(
                "The linear state space `ẋ = A x + B u`, `y = C x + D u` {doc}, at the parameters `p`, as the \
                 entries that are not identically zero: `entry(matrix, row, column, value)` for each, `matrix` \
                 being `'A'`, `'B'`, `'C'` or `'D'` (in that order). A model this large gets no dense \
                 `{name}`: its `A` would not fit a thread's stack."
            ),
            name: function,
            args: vec![
                Arg::new("p", "&Params", d.uses.p),
                Arg::new("entry", ty, !statements.is_empty()),
            ],
            ret: String::new(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        });
    }

    pub(super) fn state_spaces(&mut self) {
        let (ty, size, states) = match self.plan.linear_selection {
            StateSelection::Energy => (
                "EnergyStateSpace",
                "N_ENERGY_STATES",
                "in the energy states (the first `N_ENERGY_STATES` states)",
            ),
            StateSelection::All => (
                "FullStateSpace",
                "N_STATES",
                "in all states `STATE_NAMES` (the energy states, then the integrated flows, which the outputs or \
                 rates read)",
            ),
        };
        match &self.plan.linear_ss {
            Ok(ss) => self.state_space_fn(("state_space", ty), size, &ss.clone(), states),
            Err(_) if state_space_through_loops(self.plan) => {
                self.state_space_at_origin(ty, size, states);
            }
            Err(why) => {
                self.out.push('\n');
                self.note(0, &format!("No `state_space`: {}.", comment(why)));
            }
        }
        match &self.plan.declared_ss {
            Some(Ok(ss)) => {
                let names: Vec<String> = ss.states.clone();
                self.out.push('\n');
                self.doc(
                    0,
                    "The number of declared coordinates (`coords` of the model).",
                );
                self.out
                    .push_str(&format!("pub const N_COORDS: usize = {};\n", names.len()));
                self.name_array("COORD_NAMES", "N_COORDS", "declared coordinates", &names);
                self.state_space_fn(
                    ("state_space_declared", "DeclaredStateSpace"),
                    "N_COORDS",
                    &ss.clone(),
                    "in the declared coordinates `COORD_NAMES`",
                );
            }
            Some(Err(why)) => {
                self.out.push('\n');
                self.note(0, &format!("No `state_space_declared`: {}.", comment(why)));
            }
            None => {}
        }
    }

    /// The type `{ty}` of `(A, B, C, D)` in `size` states.
    fn state_space_type(&mut self, ty: &str, size: &str, doc: &str) {
        self.out.push('\n');
        self.doc(
            0,
            &format!("`A, B, C, D` of `ẋ = A x + B u`, `y = C x + D u` {doc}."),
        );
        self.out.push_str(&format!(
            "pub type {ty} = (\n    SMatrix<f64, {size}, {size}>,\n    SMatrix<f64, {size}, N_INPUTS>,\n    \
             SMatrix<f64, N_OUTPUTS, {size}>,\n    SMatrix<f64, N_OUTPUTS, N_INPUTS>,\n);\n"
        ));
    }

    /// `state_space` of a linear model whose algebraic loops are solved numerically: it has no symbolic `A, B, C,
    /// D`, but its Jacobians, which take the loops' implicit derivatives, are constant and are `A, B, C, D`. They
    /// are taken at the origin, where the loops' residuals are linear in the tears (so the same at any point).
    fn state_space_at_origin(&mut self, ty: &str, size: &str, doc: &str) {
        self.state_space_type(ty, size, doc);
        self.out.push('\n');
        self.doc(
            0,
            &format!(
                "The linear state space {doc}, at the parameters `p`. The model's algebraic loops are solved \
                 numerically, so these are its Jacobians `jac_x_into`, `jac_u_into`, `output_jac_x_into` and \
                 `output_jac_u_into` at the origin, which are exact for this linear model; all NaN when the \
                 loops are singular at `p`."
            ),
        );
        // The energy states are the first ones: their block of the full Jacobians, copied entry by entry (the
        // generated code uses nothing of `nalgebra` beyond `zeros` and indexing).
        let states = self.plan.states.len();
        let selected = match self.plan.linear_selection {
            StateSelection::Energy => self.m.equations.energy_states,
            StateSelection::All => states,
        };
        let blocks = if selected == states {
            "    (jx, ju, hx, hu)\n".to_string()
        } else {
            let inputs = !self.plan.inputs.is_empty();
            let outputs = !output_names(&self.m.equations).is_empty();
            energy_block(size, selected > 0, inputs, outputs)
        };
        self.out.push_str(&format!(
            "pub fn state_space(p: &Params) -> {ty} {{
    let (x, u) = (State::zeros(), Inputs::zeros());
    let mut jx = JacX::zeros();
    jac_x_into(p, 0.0, &x, &u, &mut jx);
    let mut ju = JacU::zeros();
    jac_u_into(p, 0.0, &x, &u, &mut ju);
    let mut hx = OutJacX::zeros();
    output_jac_x_into(p, 0.0, &x, &u, &mut hx);
    let mut hu = OutJacU::zeros();
    output_jac_u_into(p, 0.0, &x, &u, &mut hu);
{blocks}}}
"
        ));
    }

    /// `stored_energy`, `dissipated_power` and `supplied_power`: one `let` per element, then their sum.
    fn energy(&mut self) {
        for (kind, terms) in self.plan.energy.clone() {
            let (name, doc) = match kind {
                EnergyKind::Stored => (
                    "stored_energy",
                    "The energy stored in the inertias and compliances (J).",
                ),
                EnergyKind::Dissipated => (
                    "dissipated_power",
                    "The power dissipated in the resistors (W).",
                ),
                EnergyKind::Supplied => {
                    ("supplied_power", "The power delivered by the sources (W).")
                }
            };
            let terms = match terms {
                Ok(t) => t,
                Err(missing) => {
                    self.out.push('\n');
                    self.note(
                        0,
                        &format!(
                            "No `{name}`: no closed form for `{}`.",
                            comment(&missing.join("`, `"))
                        ),
                    );
                    continue;
                }
            };
            // Terms written over shared `let`s stay in one function, as the Jacobians' entries do.
            let shared = self.shared_lets(name);
            if shared.is_empty() && self.splits(terms.len()) {
                self.energy_in_parts(name, doc, &terms);
                continue;
            }
            let mut exprs: Vec<&Expr> = terms.iter().map(|t| &t.1).collect();
            exprs.extend(shared.iter().map(|(_, v)| v));
            let mut d = self.draft_through_loops(&exprs, false, TearValues::Solved);
            self.shared_statements(&mut d, shared);
            match terms.as_slice() {
                [] => d.lines.push("    0.0".into()),
                [(element, e)] => self.statement(&mut d, &format!("{element}: "), e, "", ""),
                many if many.len() <= MAX_LETS => {
                    let mut parts = Vec::with_capacity(many.len());
                    for (element, e) in many {
                        let local = d.namer.ident(element);
                        let head = format!("let {local} = ");
                        self.statement(&mut d, &format!("{element}: "), e, &head, ";");
                        d.locals.push(local.clone());
                        parts.push(RustCode::Atom(local));
                    }
                    let mut iter = parts.into_iter();
                    let first = iter.next().unwrap_or(RustCode::Atom("0.0".into()));
                    let sum = RustCode::Chain(
                        Box::new(first),
                        iter.map(|p| (crate::symbolic::RustOp::Add, p)).collect(),
                    );
                    self.statement_code(&mut d, Vec::new(), &sum, "", "");
                }
                // One `let` per element would nest too many scopes for rustc (see `MAX_LETS`): a running total
                // instead, added in the same order.
                many => {
                    // Reserved: no state, input or intermediate takes it.
                    let total = "total";
                    for (k, (element, e)) in many.iter().enumerate() {
                        let head = if k == 0 {
                            format!("let mut {total} = ")
                        } else {
                            format!("{total} += ")
                        };
                        self.statement(&mut d, &format!("{element}: "), e, &head, ";");
                    }
                    d.lines.push(format!("    {total}"));
                }
            }
            self.scalar_function(name, doc, d);
        }
    }
}

impl Writer<'_> {
    /// The energy or power function `name` of many terms: parts that add their terms to a running total, in
    /// order.
    fn energy_in_parts(&mut self, name: &str, doc: &str, terms: &[(String, Expr)]) {
        let statements: Vec<Statement> = terms
            .iter()
            .map(|(element, e)| Statement {
                label: format!("{element}: "),
                expr: e,
                head: "*total += ".into(),
                tail: ";",
            })
            .collect();
        let out = Out {
            name: "total",
            ty: "&mut f64",
            passed: "&mut total",
        };
        let prologue = vec!["    let mut total = 0.0;".to_string()];
        let mut d = self.parts(name, &statements, out, false, prologue);
        d.lines.push("    total".into());
        self.scalar_function(name, doc, d);
    }

    /// The model function `name(p, t, x, u) -> f64` whose body `d` ends in its value.
    fn scalar_function(&mut self, name: &str, doc: &str, d: Draft) {
        self.function(Function {
            doc: doc.to_string(),
            name: name.to_string(),
            args: Self::model_args(d.uses),
            ret: " -> f64".into(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        });
    }
}

/// The function that takes the parameter terms for the model function `name`: `rhs_into` → `rhs_with`.
pub(super) fn with_terms_name(name: &str) -> String {
    format!("{}_with", name.strip_suffix("_into").unwrap_or(name))
}

/// The comment naming the entry `(r, c)` of a Jacobian (`∂(d/dt p_mass)/∂q_spring = `): rows and columns named by
/// `names`, the rows with a prefix.
pub(super) fn entry_label(
    (rows, cols, row_prefix): (&[String], &[String], &str),
    r: usize,
    c: usize,
) -> String {
    format!(
        "∂({row_prefix}{})/∂{} = ",
        rows.get(r).map_or("", String::as_str),
        cols.get(c).map_or("", String::as_str)
    )
}

/// Whether the module's `state_space` comes from its Jacobians at the origin: a linear model whose algebraic loops
/// are solved numerically has no symbolic `A, B, C, D`, and gets one when its `JacX` fits (at most 181 states, as a
/// dense `state_space` does).
pub(in crate::codegen) fn state_space_through_loops(plan: &super::super::emit::Plan) -> bool {
    plan.linear_through_loops && super::model::square_fits(plan.states.len())
}

/// The statements that copy the first `size` states' block of `jx`, `ju` and `hx` into `a`, `b` and `c` and return
/// `(a, b, c, hu)`; no loop over an empty range (a lint), so none without `states`, `inputs` or `outputs`.
fn energy_block(size: &str, states: bool, inputs: bool, outputs: bool) -> String {
    let binding = |written: bool| if written { "let mut" } else { "let" };
    let mut s = format!(
        "    {} a = SMatrix::<f64, {size}, {size}>::zeros();\n    {} b = SMatrix::<f64, {size}, N_INPUTS>::zeros();\n    \
         {} c = SMatrix::<f64, N_OUTPUTS, {size}>::zeros();\n",
        binding(states),
        binding(states && inputs),
        binding(states && outputs),
    );
    if states {
        s += &format!(
            "    for i in 0..{size} {{\n        for j in 0..{size} {{\n            a[(i, j)] = jx[(i, j)];\n        }}\n"
        );
        if inputs {
            s += "        for j in 0..N_INPUTS {\n            b[(i, j)] = ju[(i, j)];\n        }\n";
        }
        s += "    }\n";
        if outputs {
            s += &format!(
                "    for i in 0..N_OUTPUTS {{\n        for j in 0..{size} {{\n            c[(i, j)] = hx[(i, j)];\n        }}\n    }}\n"
            );
        }
    }
    s + "    (a, b, c, hu)\n"
}
