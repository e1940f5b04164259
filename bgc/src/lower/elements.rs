//! Constitutive relations of the elements, their unit checks against the element's kind and domain (BG0303), and
//! the physical checks of their values with the parameters at their defaults (BG0401).
//!
//! Expected units (docs/language.md, Elements): a source's value is an effort or a flow of its domain; a `C`
//! parameter is displacement/effort, an `I` momentum/flow, an `R` effort/flow; a TF ratio is flow_in/flow_out
//! (dimensionless within one domain) and a GY modulus effort_in/flow_out. Laws in braces must give their left side's
//! unit. Non-physical values: a compliance or inertia must be positive, a resistance not negative, a TF/GY modulus
//! not zero; a zero resistance is physical (no friction).

use super::builder::Builder;
use super::consteval::{eval, params_of};
use super::exprs::{Allow, Cx, Q, port_var, var_letter};
use super::unit_hints::Place;
use crate::diagnostic::{Diagnostic, number};
use crate::ir::{self, CoefficientFault, Domain, Law, PortVar, Relation};
use crate::span::Span;
use crate::syntax::ast::{self, ElementBody, ElementKind as K};
use crate::units::{Dim, domain_units, storage_parameter_unit};
use petgraph::graph::NodeIndex;
use std::collections::HashMap;

impl Builder<'_> {
    pub fn build_relations(&mut self) {
        for i in 0..self.nodes.len() {
            let n = NodeIndex::new(i);
            let relation = self.relation(n).unwrap_or(Relation::Junction);
            self.model.graph[n].relation = relation;
        }
    }

    fn relation(&mut self, n: NodeIndex) -> Option<Relation> {
        let info = self.node_info(n)?;
        let decl = info.decl;
        let scope = info.scope;
        let kind = decl.kind;
        if kind.is_junction() && matches!(decl.body, ElementBody::None) {
            // Most of a large model; nothing to check, and no need for a copy of the name.
            return Some(Relation::Junction);
        }
        let name = self.model.graph[n].name.clone();
        match (&decl.body, kind) {
            (ElementBody::None, k) if k.is_junction() => Some(Relation::Junction),
            (ElementBody::None, _) => {
                self.body_error(
                    decl,
                    &name,
                    "needs a value or laws",
                    match kind {
                        K::CF | K::RF | K::IF => format!(
                            "write its laws in braces: `{} {}(n) {{ ... }}`",
                            kind.keyword(),
                            decl.name.name
                        ),
                        _ => format!("write `{} {} = EXPR;`", kind.keyword(), decl.name.name),
                    },
                );
                None
            }
            (_, k) if k.is_junction() => {
                self.body_error(
                    decl,
                    &name,
                    "takes no value",
                    format!("write `{} {};`", kind.keyword(), decl.name.name),
                );
                None
            }
            (ElementBody::Value(v), K::Se | K::Sf | K::MSe | K::MSf) => {
                let allow = if matches!(kind, K::Se | K::Sf) {
                    Allow::Signals
                } else {
                    Allow::States {
                        outputs_before: Some(self.model.outputs.len()),
                    }
                };
                let cx = Cx {
                    scope,
                    allow,
                    host: None,
                    what: "the value of a source",
                };
                let (expr, q) = self.expr(v, cx)?;
                if let Some(d) = self.port_domain(n, 0) {
                    let u = domain_units(d);
                    let (want, text, what) = if matches!(kind, K::Se | K::MSe) {
                        (u.effort, u.effort_text, "an effort")
                    } else {
                        (u.flow, u.flow_text, "a flow")
                    };
                    self.one_port_unit(kind, &name, (&expr, q, v.span), (want, text, what), d);
                }
                Some(Relation::Source(expr))
            }
            (ElementBody::Value(v), K::C | K::I | K::R) => {
                let cx = Cx {
                    scope,
                    allow: Allow::Parameters,
                    host: None,
                    what: "the parameter of a linear element",
                };
                let (expr, q) = self.expr(v, cx)?;
                if let Some(d) = self.port_domain(n, 0)
                    && let Some((want, text)) = storage_parameter_unit(kind, d)
                {
                    let what = match kind {
                        K::C => "a compliance",
                        K::I => "an inertia",
                        _ => "a resistance",
                    };
                    self.one_port_unit(kind, &name, (&expr, q, v.span), (want, text, what), d);
                }
                self.check_value(kind, &name, &expr, v.span);
                Some(Relation::Linear(expr))
            }
            (ElementBody::Value(v), K::TF | K::GY | K::MTF | K::MGY) => {
                let allow = if matches!(kind, K::TF | K::GY) {
                    Allow::Parameters
                } else {
                    Allow::States {
                        outputs_before: Some(self.model.outputs.len()),
                    }
                };
                let cx = Cx {
                    scope,
                    allow,
                    host: None,
                    what: "the modulus of a transformer or gyrator",
                };
                let (expr, q) = self.expr(v, cx)?;
                if let (Some(din), Some(dout)) = (self.port_domain(n, 0), self.port_domain(n, 1)) {
                    let (ui, uo) = (domain_units(din), domain_units(dout));
                    let (num, what) = if matches!(kind, K::TF | K::MTF) {
                        (ui.flow, "a transformer ratio: input flow over output flow")
                    } else {
                        (
                            ui.effort,
                            "a gyrator modulus: input effort over output flow",
                        )
                    };
                    if let Some(want) = num.checked_div(uo.flow) {
                        let text = || format!("{want} ({what}, {} to {})", din.name(), dout.name());
                        if self.expect_unit(q, want, v.span, text, &name) {
                            self.explain_units(&expr);
                            self.suggest_domain(Place::TwoPort(kind), &name, q.dim(), (din, dout));
                        }
                    }
                }
                if matches!(kind, K::TF | K::GY) {
                    self.check_value(kind, &name, &expr, v.span);
                }
                Some(Relation::Modulus(expr))
            }
            (ElementBody::Laws(laws), K::C | K::I | K::R) => {
                self.one_port_laws(n, scope, kind, &name, laws)
            }
            (ElementBody::Laws(laws), K::CF | K::RF | K::IF) => {
                self.field_laws(n, scope, kind, &name, decl, laws)
            }
            (ElementBody::Laws(_), _) => {
                self.body_error(
                    decl,
                    &name,
                    "cannot be given laws",
                    format!("write `{} {} = EXPR;`", kind.keyword(), decl.name.name),
                );
                None
            }
            (ElementBody::Value(_), _) => {
                self.body_error(
                    decl,
                    &name,
                    "is given by laws, not a value",
                    format!("write `{} {}(n) {{ ... }}`", kind.keyword(), decl.name.name),
                );
                None
            }
        }
    }

    fn body_error(&mut self, decl: &ast::ElementDecl, name: &str, what: &str, help: String) {
        let span = match &decl.body {
            ElementBody::Value(v) => v.span,
            ElementBody::Laws(l) => l.first().map(|x| x.span).unwrap_or(decl.span),
            ElementBody::None => decl.name.span,
        };
        self.diags.push(
            Diagnostic::error(
                "BG0313",
                format!("`{name}`, {}, {what}", decl.kind.with_article()),
            )
            .with_primary(span, what.to_string())
            .with_help(help),
        );
    }

    /// Checks the unit `q` of a one-port element's value (`value`: the expression, its unit, its span) against
    /// `expected` (the unit, its text, what the value is) in domain `d`, and explains a mismatch.
    fn one_port_unit(
        &mut self,
        kind: K,
        name: &str,
        value: (&ir::Expr, Q, Span),
        expected: (Dim, &str, &str),
        d: Domain,
    ) {
        let (expr, q, span) = value;
        let (want, text, what) = expected;
        if self.expect_unit(
            q,
            want,
            span,
            || format!("{text} ({what} in the {} domain)", d.name()),
            name,
        ) {
            self.explain_units(expr);
            self.suggest_domain(Place::OnePort(kind), name, q.dim(), (d, d));
        }
    }

    /// BG0303 when a value's dimension is not the one its place needs; `expected` spells the expectation out and
    /// is called only then (values that fit, nearly all, format nothing).
    pub fn expect_unit(
        &mut self,
        q: Q,
        want: Dim,
        span: Span,
        expected: impl FnOnce() -> String,
        name: &str,
    ) -> bool {
        if q.fits(want) {
            return false;
        }
        let expected = expected();
        self.diags.push(
            Diagnostic::error(
                "BG0303",
                format!(
                    "unit mismatch in `{name}`: expected {expected}, found {}",
                    q.dim()
                ),
            )
            .with_primary(span, format!("this is in {}", q.dim()))
            .with_help(format!("the value must be in {expected}")),
        );
        true
    }

    /// Adds to the last diagnostic a secondary label at the declared unit of each parameter `expr` uses.
    fn explain_units(&mut self, expr: &ir::Expr) {
        let mut used = Vec::new();
        params_of(expr, &mut used);
        let labels: Vec<(Span, String)> = used
            .into_iter()
            .filter_map(|id| {
                let p = self.model.params.get(id)?;
                let info = self.params.get(id)?;
                Some((
                    info.unit_span,
                    format!("`{}` is declared in {}", p.name, p.unit_text),
                ))
            })
            .collect();
        if let Some(d) = self.diags.last_mut() {
            for (span, msg) in labels {
                d.labels.push(crate::diagnostic::Label {
                    span,
                    message: msg,
                    primary: false,
                    replacement: None,
                });
            }
        }
    }

    /// BG0401: the value with the parameters at their defaults must be physical.
    fn check_value(&mut self, kind: K, name: &str, expr: &ir::Expr, span: Span) {
        let mut used = Vec::new();
        params_of(expr, &mut used);
        if self.values_reported(&used) {
            return;
        }
        let Some(v) = eval(expr, &self.model.params) else {
            return;
        };
        let Some(fault) = ir::coefficient_fault(kind, v) else {
            return;
        };
        let shown = number(v);
        let what = match kind {
            K::I => "an inertia",
            K::C => "a compliance",
            K::R => "a resistance",
            K::TF => "a transformer ratio",
            _ => "a gyrator modulus",
        };
        let problem = match (fault, kind) {
            (CoefficientFault::NotFinite, K::C) => {
                "an infinite compliance (a zero stiffness)".to_string()
            }
            (CoefficientFault::NotFinite, K::I | K::R) => {
                format!("{what} of {shown} (it must be finite)")
            }
            (CoefficientFault::NotFinite | CoefficientFault::Zero, _) => {
                format!("{what} of {shown} (it must be finite and non-zero)")
            }
            (CoefficientFault::NotPositive, K::C) => {
                format!("{what} of {shown} (a compliance and its stiffness must be positive)")
            }
            (CoefficientFault::NotPositive, _) => {
                format!("{what} of {shown} (an inertia must be positive)")
            }
            (CoefficientFault::Negative, _) => {
                format!("{what} of {shown} (a resistance cannot be negative)")
            }
            (CoefficientFault::ReciprocalNotFinite, _) => format!(
                "{what} of {shown}, whose reciprocal is not finite (the equations divide by it)"
            ),
        };
        let mut d = Diagnostic::error("BG0401", format!("`{name}` has {problem}")).with_primary(
            span,
            format!("this is {shown} with the default parameter values"),
        );
        for id in used {
            if let (Some(p), Some(info)) = (self.model.params.get(id), self.params.get(id)) {
                d = d.with_secondary(
                    info.value_span,
                    format!("`{}` is {}", p.name, number(p.default)),
                );
            }
        }
        self.diags
            .push(d.with_help("fix the parameter's default value"));
    }

    fn one_port_laws(
        &mut self,
        n: NodeIndex,
        scope: usize,
        kind: K,
        name: &str,
        laws: &[ast::Law],
    ) -> Option<Relation> {
        let allowed: [PortVar; 2] = match kind {
            K::R => [PortVar::Effort, PortVar::Flow],
            K::C => [PortVar::Effort, PortVar::Displacement],
            _ => [PortVar::Flow, PortVar::Momentum],
        };
        let mut out = Vec::new();
        for (i, law) in laws.iter().enumerate() {
            if i > 0 {
                self.diags.push(
                    Diagnostic::error("BG0202", format!("`{name}` has more than one law"))
                        .with_primary(law.span, "a second law")
                        .with_secondary(laws[0].span, "first law")
                        .with_help(
                            "a 1-port has one constitutive law, in one of its two causal forms",
                        ),
                );
                continue;
            }
            let var =
                port_var(&law.lhs.name).filter(|v| allowed.contains(v) && law.indices.is_empty());
            let Some(var) = var else {
                let forms = allowed.map(var_letter);
                self.diags.push(
                    Diagnostic::error(
                        "BG0207",
                        format!(
                            "a law of {} gives `{}` or `{}`",
                            kind.with_article(),
                            forms[0],
                            forms[1]
                        ),
                    )
                    .with_primary(law.lhs.span, "not a variable this element can define")
                    .with_help(format!(
                        "write `{} = ...` or `{} = ...`",
                        forms[0], forms[1]
                    )),
                );
                continue;
            };
            let cx = Cx {
                scope,
                allow: Allow::States {
                    outputs_before: None,
                },
                host: Some(n),
                what: "a constitutive law",
            };
            let Some((rhs, q)) = self.expr(&law.rhs, cx) else {
                continue;
            };
            if let Some(d) = self.port_domain(n, 0) {
                let (want, text) = var_unit(d, var);
                self.expect_unit(
                    q,
                    want,
                    law.rhs.span,
                    || {
                        format!(
                            "{text} (the unit of `{}` in the {} domain)",
                            var_letter(var),
                            d.name()
                        )
                    },
                    name,
                );
            }
            out.push(Law {
                lhs: var,
                port: 0,
                rhs,
            });
        }
        Some(Relation::Laws(out))
    }

    fn field_laws(
        &mut self,
        n: NodeIndex,
        scope: usize,
        kind: K,
        name: &str,
        decl: &ast::ElementDecl,
        laws: &[ast::Law],
    ) -> Option<Relation> {
        let ports = self.model.graph[n].ports;
        let size = ports as usize;
        if size > super::flatten::MAX_FIELD_PORTS {
            // Reported at the declaration.
            return None;
        }
        let cx = Cx {
            scope,
            allow: Allow::States {
                outputs_before: None,
            },
            host: Some(n),
            what: "a constitutive law",
        };
        // The laws given, by slot: only those written are stored, so that the cost follows the file's length.
        let mut seen: HashMap<usize, Span> = HashMap::new();
        let mut out = Vec::new();
        let mut mass: Vec<ir::Expr> = if kind == K::IF {
            vec![ir::Expr::Const(0.0); size * size]
        } else {
            Vec::new()
        };
        for law in laws {
            let indices: Vec<u32> = law.indices.iter().map(|(i, _)| *i).collect();
            let lhs_ok = match kind {
                K::IF => law.lhs.name == "mass" && indices.len() == 2,
                K::CF => matches!(law.lhs.name.as_str(), "e" | "q") && indices.len() == 1,
                _ => matches!(law.lhs.name.as_str(), "e" | "f") && indices.len() == 1,
            };
            if !lhs_ok {
                let form = match kind {
                    K::IF => "`mass[i,j] = ...` (upper triangle, i <= j)",
                    K::CF => "`e[i] = ...` or `q[i] = ...`",
                    _ => "`e[i] = ...` or `f[i] = ...`",
                };
                self.diags.push(
                    Diagnostic::error(
                        "BG0207",
                        format!("a law of {} is written {form}", kind.with_article()),
                    )
                    .with_primary(law.lhs.span, "not a variable this field can define")
                    .with_help(format!("write the laws of `{}` as {form}", decl.name.name)),
                );
                continue;
            }
            if let Some(&(i, span)) = law.indices.iter().find(|(i, _)| *i < 1 || *i > ports) {
                self.diags.push(
                    Diagnostic::error("BG0205", format!("index {i} is out of range for `{name}`"))
                        .with_primary(span, format!("the field has ports 1 to {ports}"))
                        .with_secondary(decl.name.span, format!("declared with {ports} ports"))
                        .with_help("use indices between 1 and the port count"),
                );
                continue;
            }
            let slot = match indices[..] {
                [i, j] if kind == K::IF => {
                    if i > j {
                        self.diags.push(
                            Diagnostic::error(
                                "BG0205",
                                format!("`mass[{i},{j}]` is below the diagonal"),
                            )
                            .with_primary(law.lhs.span, "the lower triangle follows from symmetry")
                            .with_help(format!("write `mass[{j},{i}]` instead")),
                        );
                        continue;
                    }
                    ((i - 1) as usize) * size + (j - 1) as usize
                }
                [i] => (i - 1) as usize,
                _ => continue,
            };
            if let Some(first) = seen.get(&slot) {
                self.diags.push(
                    Diagnostic::error(
                        "BG0202",
                        format!("`{name}` defines the same port variable twice"),
                    )
                    .with_primary(law.span, "defined again here")
                    .with_secondary(*first, "first defined here")
                    .with_help("give each port (each matrix entry) one law"),
                );
                continue;
            }
            seen.insert(slot, law.span);
            let Some((rhs, q)) = self.expr(&law.rhs, cx) else {
                continue;
            };
            if kind == K::IF {
                let (i, j) = (indices[0] - 1, indices[1] - 1);
                if let (Some(di), Some(dj)) = (self.port_domain(n, i), self.port_domain(n, j))
                    && let Some(want) = domain_units(di).momentum.checked_div(domain_units(dj).flow)
                {
                    self.expect_unit(
                        q,
                        want,
                        law.rhs.span,
                        || {
                            format!(
                                "{want} (momentum of port {} over flow of port {})",
                                i + 1,
                                j + 1
                            )
                        },
                        name,
                    );
                }
                let (i, j) = (i as usize, j as usize);
                if let Some(slot) = mass.get_mut(i * size + j) {
                    *slot = rhs.clone();
                }
                if let Some(slot) = mass.get_mut(j * size + i) {
                    *slot = rhs;
                }
            } else {
                let var = port_var(&law.lhs.name).unwrap_or(PortVar::Effort);
                let port = indices[0] - 1;
                if let Some(d) = self.port_domain(n, port) {
                    let (want, text) = var_unit(d, var);
                    self.expect_unit(
                        q,
                        want,
                        law.rhs.span,
                        || {
                            format!(
                                "{text} (the unit of `{}[{}]` in the {} domain)",
                                var_letter(var),
                                port + 1,
                                d.name()
                            )
                        },
                        name,
                    );
                }
                out.push(Law {
                    lhs: var,
                    port,
                    rhs,
                });
            }
        }
        if kind == K::IF {
            return Some(Relation::MassMatrix {
                n: ports,
                entries: mass,
            });
        }
        for i in 0..size {
            if !seen.contains_key(&i) {
                self.diags.push(
                    Diagnostic::error(
                        "BG0313",
                        format!("port {} of field `{name}` has no law", i + 1),
                    )
                    .with_primary(decl.name.span, format!("no law for port {}", i + 1))
                    .with_help("give every port of a field one law"),
                );
            }
        }
        Some(Relation::Laws(out))
    }
}

/// The unit of a port variable in a domain, with its conventional text.
fn var_unit(d: Domain, v: PortVar) -> (Dim, &'static str) {
    let u = domain_units(d);
    match v {
        PortVar::Effort => (u.effort, u.effort_text),
        PortVar::Flow => (u.flow, u.flow_text),
        PortVar::Momentum => (u.momentum, u.momentum_text),
        PortVar::Displacement => (u.displacement, u.displacement_text),
    }
}
