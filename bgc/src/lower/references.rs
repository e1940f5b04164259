//! References to the power and energy variables in expressions: `e(x)`, `f(x)`, `p(x)`, `q(x)` of elements,
//! junctions, named bonds, elements inside instances and field ports, and the bare `e`, `f`, `p`, `q` (or `e[i]` ...)
//! of an element's own laws. Each has the unit of its domain's variable (free when the domain could not be inferred,
//! which is reported elsewhere).

use super::builder::Builder;
use super::exprs::{Allow, Cx, Q, var_letter};
use super::scope::Entity;
use crate::diagnostic::Diagnostic;
use crate::ir::{self, PortVar, Target};
use crate::syntax::ast::{self, ElementKind, ExprKind, NodeRef};
use crate::units::domain_units;
use petgraph::graph::NodeIndex;

impl Builder<'_> {
    /// `e`, `f`, `p`, `q` (or `e[i]` ...) inside the laws of `host`.
    pub(super) fn law_var(
        &mut self,
        host: NodeIndex,
        var: PortVar,
        index: Option<u32>,
        e: &ast::Expr,
    ) -> Option<(ir::Expr, Q)> {
        let (kind, ports) = {
            let n = &self.model.graph[host];
            (n.kind, n.ports)
        };
        let letter = var_letter(var);
        if kind.is_field() {
            let Some(i) = index else {
                self.diags.push(
                    Diagnostic::error(
                        "BG0207",
                        format!("`{letter}` of a field needs a port index"),
                    )
                    .with_primary(e.span, "which port?")
                    .with_help(format!("write `{letter}[i]` with i from 1 to {ports}")),
                );
                return None;
            };
            if i < 1 || i > ports {
                self.diags.push(
                    Diagnostic::error("BG0205", format!("port {i} is out of range"))
                        .with_primary(e.span, format!("the field has ports 1 to {ports}"))
                        .with_secondary(
                            self.node_name_span(host),
                            format!("declared with {ports} ports"),
                        )
                        .with_help("use an index between 1 and the port count"),
                );
                return None;
            }
            if var == PortVar::Momentum {
                self.diags.push(
                    Diagnostic::error("BG0207", "`p[i]` is not defined in a field's laws")
                        .with_primary(e.span, "no momentum variable here")
                        .with_help(
                            "field laws use `e[i]`, `f[i]` and `q[i]` (the integral of `f[i]`)",
                        ),
                );
                return None;
            }
            let q = self.var_dim(host, i - 1, var);
            return Some((
                ir::Expr::FieldPort {
                    node: host,
                    var,
                    port: i - 1,
                },
                q,
            ));
        }
        if index.is_some() {
            self.diags.push(
                Diagnostic::error(
                    "BG0207",
                    format!("`{letter}` of {} has no index", kind.with_article()),
                )
                .with_primary(e.span, "only fields have indexed port variables")
                .with_help(format!("write `{letter}`")),
            );
            return None;
        }
        let ok = match var {
            PortVar::Effort | PortVar::Flow => true,
            PortVar::Momentum => kind == ElementKind::I,
            PortVar::Displacement => kind == ElementKind::C,
        };
        if !ok {
            self.no_such_var(var, host, e.span);
            return None;
        }
        let q = self.var_dim(host, 0, var);
        let target = Target::Node(host);
        Some((var_expr(var, target, host), q))
    }

    pub(super) fn no_such_var(&mut self, var: PortVar, node: NodeIndex, span: crate::span::Span) {
        let letter = var_letter(var);
        let (kind, name) = {
            let n = &self.model.graph[node];
            (n.kind, n.name.clone())
        };
        let (what, help) = match var {
            PortVar::Momentum => (
                "momentum",
                "only an inertia `I` has a momentum `p`; use `f(x)` or `e(x)`",
            ),
            PortVar::Displacement => (
                "displacement",
                "only a compliance `C` has a displacement `q`; use `f(x)` or `e(x)`",
            ),
            PortVar::Effort => (
                "single effort",
                "a 1-junction has one common flow and a TF or GY two efforts: name a bond instead",
            ),
            PortVar::Flow => (
                "single flow",
                "a 0-junction has one common effort and a TF or GY two flows: name a bond instead",
            ),
        };
        self.diags.push(
            Diagnostic::error(
                "BG0207",
                format!(
                    "`{letter}({name})` is not defined: `{name}` is {} and has no {what}",
                    super::flatten::kind_with_article(kind)
                ),
            )
            .with_primary(span, format!("no `{letter}` here"))
            .with_help(help),
        );
    }

    /// The dimension of a port variable; free when the domain is unknown (already reported).
    fn var_dim(&self, node: NodeIndex, port: u32, var: PortVar) -> Q {
        match self.port_domain(node, port) {
            Some(d) => {
                let u = domain_units(d);
                Q::Dim(match var {
                    PortVar::Effort => u.effort,
                    PortVar::Flow => u.flow,
                    PortVar::Momentum => u.momentum,
                    PortVar::Displacement => u.displacement,
                })
            }
            None => Q::Free,
        }
    }

    /// `e(x)`, `f(x)`, `p(x)`, `q(x)`.
    pub(super) fn reference(
        &mut self,
        var: PortVar,
        arg: &ast::Expr,
        e: &ast::Expr,
        cx: Cx,
    ) -> Option<(ir::Expr, Q)> {
        let letter = var_letter(var);
        if !matches!(cx.allow, Allow::States { .. }) {
            self.not_allowed(e, &format!("`{letter}(..)`, a variable of the state"), cx);
            return None;
        }
        let r = match &arg.kind {
            ExprKind::Node(r) => r.clone(),
            ExprKind::Name(n) => NodeRef {
                path: ast::ShortList::one(ast::Ident {
                    name: n.clone(),
                    span: arg.span,
                }),
                port: None,
                span: arg.span,
            },
            ExprKind::Indexed(n, i) => NodeRef {
                path: ast::ShortList::one(ast::Ident {
                    name: n.clone(),
                    span: arg.span,
                }),
                port: Some((*i, arg.span)),
                span: arg.span,
            },
            _ => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0207",
                        format!("`{letter}(..)` takes the name of an element, junction or bond"),
                    )
                    .with_primary(arg.span, "not a name")
                    .with_help(format!(
                        "write `{letter}(x)` where `x` is declared in this model"
                    )),
                );
                return None;
            }
        };
        if var == PortVar::Displacement
            && let Some((i, _)) = r.port
            && let Some(n) = self.field_node(&r, cx.scope)
        {
            // `q(leg[i])`: the integral of the flow on field port i.
            let q = self.var_dim(n, i - 1, var);
            return Some((
                ir::Expr::FieldPort {
                    node: n,
                    var,
                    port: i - 1,
                },
                q,
            ));
        }
        let (target, node) = self.reference_target(&r, cx.scope)?;
        match (target, node) {
            (Target::Bond(edge), _) => {
                if matches!(var, PortVar::Momentum | PortVar::Displacement) {
                    self.diags.push(
                        Diagnostic::error("BG0207", format!("`{letter}` of a bond is not defined"))
                            .with_primary(arg.span, "a bond has an effort and a flow only")
                            .with_help(format!(
                                "`{letter}(x)` takes an element: {}",
                                if var == PortVar::Momentum {
                                    "an inertia I"
                                } else {
                                    "a compliance C"
                                }
                            )),
                    );
                    return None;
                }
                let q = match self.bonds.get(edge.index()).and_then(|b| b.domain) {
                    Some(d) => {
                        let u = domain_units(d);
                        Q::Dim(if var == PortVar::Effort {
                            u.effort
                        } else {
                            u.flow
                        })
                    }
                    None => Q::Free,
                };
                let x = if var == PortVar::Effort {
                    ir::Expr::Effort(target)
                } else {
                    ir::Expr::Flow(target)
                };
                Some((x, q))
            }
            (Target::Node(n), _) => {
                let kind = self.model.graph[n].kind;
                let ok = match var {
                    PortVar::Effort => {
                        !matches!(kind, ElementKind::One) && !kind.is_two_port() && !kind.is_field()
                    }
                    PortVar::Flow => {
                        !matches!(kind, ElementKind::Zero)
                            && !kind.is_two_port()
                            && !kind.is_field()
                    }
                    PortVar::Momentum => kind == ElementKind::I,
                    PortVar::Displacement => kind == ElementKind::C,
                };
                if !ok {
                    self.no_such_var(var, n, arg.span);
                    return None;
                }
                let q = self.var_dim(n, 0, var);
                Some((var_expr(var, target, n), q))
            }
        }
    }

    /// The field a `leg[i]` argument names, when `i` is one of its ports (otherwise `reference_target` reports).
    fn field_node(&self, r: &NodeRef, scope: usize) -> Option<NodeIndex> {
        let [name] = &r.path[..] else { return None };
        let (i, _) = r.port?;
        match self.scopes.get(scope)?.get(&name.name)? {
            Entity::Node(n) => {
                let node = &self.model.graph[n];
                (node.kind.is_field() && i >= 1 && i <= node.ports).then_some(n)
            }
            _ => None,
        }
    }

    /// The node or bond an `e`/`f`/`p`/`q` argument names: `x`, `inst.x` (an element inside an instance),
    /// `inst.port`, `field[i]` (the bond on that port), or a named bond.
    pub(super) fn reference_target(&mut self, r: &NodeRef, scope: usize) -> Option<(Target, ())> {
        let (last, walk) = r.path.split_last()?;
        let mut cur = scope;
        for step in walk {
            match self.scopes.get(cur).and_then(|s| s.get(&step.name)) {
                Some(Entity::Instance(child)) => cur = child,
                None if self.scopes[cur].unparsed(&step.name) => return None,
                _ => {
                    self.diags.push(
                        Diagnostic::error(
                            "BG0201",
                            format!("no component instance `{}`", step.name),
                        )
                        .with_primary(step.span, "not an instance")
                        .with_help("`a.b` names element `b` of instance `a`"),
                    );
                    return None;
                }
            }
        }
        if self.scopes.get(cur).is_some_and(|s| s.broken) {
            return None;
        }
        let found = self.scopes.get(cur).and_then(|s| s.get(&last.name));
        match found {
            Some(Entity::Node(n)) => {
                if let Some((i, span)) = r.port {
                    let ports = self.model.graph[n].ports;
                    let bond = if self.model.graph[n].kind.is_field() && i >= 1 && i <= ports {
                        self.field_bonds.get(&(n, i - 1)).copied()
                    } else {
                        None
                    };
                    return match bond {
                        Some(b) => Some((Target::Bond(b), ())),
                        None => {
                            self.diags.push(
                                Diagnostic::error(
                                    "BG0205",
                                    format!("`{}[{i}]` is not a bonded field port", last.name),
                                )
                                .with_primary(span, "no such port")
                                .with_help("fields have ports 1 to n, each with one bond"),
                            );
                            None
                        }
                    };
                }
                Some((Target::Node(n), ()))
            }
            Some(Entity::Bond(b)) => Some((Target::Bond(b), ())),
            None if !walk.is_empty() && self.scopes[cur].ports.contains_key(&last.name) => {
                let end = self.scopes[cur].ports[&last.name].0;
                Some((Target::Node(end.node), ()))
            }
            None if self.scopes[cur].unparsed(&last.name) => None,
            other => {
                let msg = match other {
                    Some(x) => format!(
                        "`{}` is {}, not an element, junction or bond",
                        last.name,
                        x.describe()
                    ),
                    None => format!("unknown element `{}`", last.name),
                };
                let help = self.scopes[cur]
                    .suggest(&last.name, |x| {
                        matches!(x, Entity::Node(_) | Entity::Bond(_))
                    })
                    .map(|c| format!("did you mean `{c}`?"))
                    .unwrap_or_else(|| "name an element, a junction or a named bond".to_string());
                self.diags.push(
                    Diagnostic::error("BG0201", msg)
                        .with_primary(r.span, "no such node")
                        .with_help(help),
                );
                None
            }
        }
    }
}

fn var_expr(var: PortVar, target: Target, node: NodeIndex) -> ir::Expr {
    match var {
        PortVar::Effort => ir::Expr::Effort(target),
        PortVar::Flow => ir::Expr::Flow(target),
        PortVar::Momentum => ir::Expr::Momentum(node),
        PortVar::Displacement => ir::Expr::Displacement(node),
    }
}
