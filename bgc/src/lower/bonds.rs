//! Bonds and their ends: chains and fan-outs become one bond per arrow; an end is an element or junction, `leg[i]`
//! (port i of a field), or `inst.port` (`a.b.port` through nested instances), which resolves to the node the port
//! names inside the instance. A bond whose end does not resolve is left out (reported as BG0203 or BG0205).

use super::builder::{BondInfo, Builder};
use super::scope::{End, Entity};
use crate::diagnostic::Diagnostic;
use crate::diagnostic::suggest::closest;
use crate::ir::{self, Domain};
use crate::syntax::ast::{BondStmt, Ident, NodeRef};

impl<'a> Builder<'a> {
    pub(super) fn bond_stmt(&mut self, sid: usize, b: &'a BondStmt) {
        if b.malformed {
            // Which bonds a fan-out inside the chain meant is unknown (BG0110 says so): none is made, and the
            // counts of its nodes follow from that error.
            for node in b.chain.iter().flatten() {
                if let Some(end) = self.resolve_end(sid, node) {
                    self.suspect_nodes.insert(end.node);
                }
            }
            return;
        }
        // The label and the hint apply only when the statement made exactly one bond: count, keep the first.
        let mut created = 0usize;
        let mut first = None;
        for pair in b.chain.windows(2) {
            let [tails, heads] = pair else { continue };
            for tail in tails {
                for head in heads {
                    let (from, to) = (self.resolve_end(sid, tail), self.resolve_end(sid, head));
                    let (Some(from), Some(to)) = (from, to) else {
                        // The other end lost a bond: do not also report its bond count.
                        self.suspect_nodes.extend(from.or(to).map(|e| e.node));
                        continue;
                    };
                    if from.node == to.node {
                        self.diags.push(
                            Diagnostic::error("BG0203", "a bond cannot join a node to itself")
                                .with_primary(
                                    tail.span.to(head.span),
                                    "both ends are the same node",
                                )
                                .with_help("a bond joins two different elements or junctions"),
                        );
                        continue;
                    }
                    let e = self.model.graph.add_edge(
                        from.node,
                        to.node,
                        ir::Bond {
                            name: b.label.as_ref().map(|l| self.qualified(sid, &l.name)),
                            from_port: 0,
                            to_port: 0,
                            domain: Domain::Rotational,
                            hint: None,
                        },
                    );
                    self.model.spans.bonds.push(tail.span.to(head.span));
                    self.bonds.push(BondInfo {
                        from,
                        to,
                        domain: None,
                    });
                    created += 1;
                    first = first.or(Some((e, from, to)));
                }
            }
        }
        if created == 1
            && let Some((e, from, to)) = first
        {
            if let Some(label) = &b.label {
                let _ = self.declare(sid, label, Entity::Bond(e));
            }
            if let Some(h) = &b.hint
                && let Some(at) = self.resolve_end(sid, &h.at)
            {
                let stroke_at_to = at == to;
                if at != from && at != to {
                    self.diags.push(
                        Diagnostic::error(
                            "BG0203",
                            "the causal stroke must be at one of the bond's ends",
                        )
                        .with_primary(h.at.span, "not an end of this bond")
                        .with_help("name one of the two nodes the bond joins after `stroke`"),
                    );
                } else {
                    self.model.graph[e].hint = Some(ir::Hint {
                        stroke_at_to,
                        fixed: h.fixed,
                    });
                }
            }
        }
    }

    /// Resolves a bond end or a port target: `j1`, `leg[2]`, `inst.port`, `a.b.port`.
    pub fn resolve_end(&mut self, sid: usize, r: &NodeRef) -> Option<End> {
        let (last, walk) = r.path.split_last()?;
        let mut cur = sid;
        for step in walk {
            match self.scopes.get(cur).and_then(|s| s.get(&step.name)) {
                Some(Entity::Instance(child)) => cur = child,
                None if self.scopes[cur].unparsed(&step.name) => return None,
                other => {
                    let msg = match other {
                        Some(e) => format!(
                            "`{}` is {}, not a component instance",
                            step.name,
                            e.describe()
                        ),
                        None => format!("no component instance `{}`", step.name),
                    };
                    let help = self.scopes[cur]
                        .suggest(&step.name, |e| matches!(e, Entity::Instance(_)))
                        .map(|c| format!("did you mean `{c}`?"))
                        .unwrap_or_else(|| "`a.b` names port `b` of instance `a`".to_string());
                    self.diags.push(
                        Diagnostic::error("BG0203", msg)
                            .with_primary(step.span, "not an instance")
                            .with_help(help),
                    );
                    return None;
                }
            }
        }
        if self.scopes.get(cur).is_some_and(|s| s.broken) {
            return None;
        }
        if !walk.is_empty() {
            return self.instance_port(cur, walk, last, r);
        }
        let found = self.scopes.get(sid).and_then(|s| s.get(&last.name));
        match found {
            Some(Entity::Node(node)) => self.node_end(node, last, r),
            Some(Entity::Instance(child)) => {
                let ports = self.scopes[child].port_order.join(", ");
                self.diags.push(
                    Diagnostic::error(
                        "BG0203",
                        format!(
                            "`{}` is a component instance; a bond goes to one of its ports",
                            last.name
                        ),
                    )
                    .with_primary(r.span, "an instance, not a node")
                    .with_help(format!(
                        "write `{}.PORT`; its ports are: {ports}",
                        last.name
                    )),
                );
                None
            }
            Some(other) => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0203",
                        format!(
                            "`{}` is {}, not an element or junction",
                            last.name,
                            other.describe()
                        ),
                    )
                    .with_primary(r.span, "cannot be bonded")
                    .with_help("bonds join elements, junctions and ports of instances and fields"),
                );
                None
            }
            None if self.scopes[sid].unparsed(&last.name) => None,
            None => {
                let suggestion = self.scopes[sid].suggest(&last.name, |e| {
                    matches!(e, Entity::Node(_) | Entity::Instance(_))
                });
                // The element the misspelling meant lost this bond: its bond count follows from this error.
                if let Some(Entity::Node(meant)) =
                    suggestion.as_ref().and_then(|c| self.scopes[sid].get(c))
                {
                    self.suspect_nodes.insert(meant);
                }
                let help = suggestion
                    .map(|c| format!("did you mean `{c}`?"))
                    .unwrap_or_else(|| {
                        format!("declare it, e.g. `1 {};` for a 1-junction", last.name)
                    });
                self.diags.push(
                    Diagnostic::error(
                        "BG0203",
                        format!("bond to `{}`, which does not exist", last.name),
                    )
                    .with_primary(r.span, "no element or junction of this name")
                    .with_help(help),
                );
                None
            }
        }
    }

    fn node_end(
        &mut self,
        node: petgraph::graph::NodeIndex,
        name: &Ident,
        r: &NodeRef,
    ) -> Option<End> {
        let (kind, ports) = {
            let n = &self.model.graph[node];
            (n.kind, n.ports)
        };
        match (kind.is_field(), r.port) {
            (true, Some((i, span))) => {
                if i >= 1 && i <= ports {
                    Some(End {
                        node,
                        port: Some(i - 1),
                    })
                } else {
                    self.diags.push(
                        Diagnostic::error(
                            "BG0205",
                            format!("field `{}` has no port {i}", name.name),
                        )
                        .with_primary(span, format!("out of range 1..={ports}"))
                        .with_secondary(
                            self.node_name_span(node),
                            format!("declared with {ports} ports"),
                        )
                        .with_help(format!(
                            "the ports of `{}` are `{0}[1]` to `{0}[{ports}]`",
                            name.name
                        )),
                    );
                    None
                }
            }
            (true, None) => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0205",
                        format!(
                            "`{}` is a multiport field; a bond goes to one of its ports",
                            name.name
                        ),
                    )
                    .with_primary(r.span, "which port?")
                    .with_help(format!("write `{}[i]` with i from 1 to {ports}", name.name)),
                );
                None
            }
            (false, Some((_, span))) => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0205",
                        format!(
                            "`{}` is {}, not a multiport field",
                            name.name,
                            kind.with_article()
                        ),
                    )
                    .with_primary(span, "only fields have numbered ports")
                    .with_help(format!("write `{}` without an index", name.name)),
                );
                None
            }
            (false, None) => Some(End { node, port: None }),
        }
    }

    fn instance_port(
        &mut self,
        child: usize,
        walk: &[Ident],
        port: &Ident,
        r: &NodeRef,
    ) -> Option<End> {
        let scope = self.scopes.get_mut(child)?;
        if let Some((end, _)) = scope.ports.get(&port.name) {
            let end = *end;
            scope.connected = true;
            if let Some((_, span)) = r.port {
                self.diags.push(
                    Diagnostic::error("BG0205", "a component port has no index")
                        .with_primary(span, "unexpected index")
                        .with_help("write the port without `[i]`"),
                );
                return None;
            }
            return Some(end);
        }
        // The bond was meant for one of this instance's ports: "not connected", of the instance or of the node of
        // a port, would only repeat this error.
        scope.connected = true;
        let port_nodes: Vec<_> = scope.ports.values().map(|(end, _)| end.node).collect();
        self.suspect_nodes.extend(port_nodes);
        let scope = self.scopes.get(child)?;
        let inst = walk.last().map(|i| i.name.as_str()).unwrap_or("");
        let (comp, comp_span) = scope.component.clone().unwrap_or_default();
        let names: Vec<&str> = scope.port_order.iter().map(String::as_str).collect();
        let help = match closest(&port.name, names.iter().copied()) {
            Some(c) => format!("did you mean `{inst}.{c}`?"),
            None if names.is_empty() => format!("component `{comp}` declares no ports"),
            None => format!("the ports of `{comp}` are: {}", names.join(", ")),
        };
        self.diags.push(
            Diagnostic::error(
                "BG0205",
                format!(
                    "instance `{inst}` (component `{comp}`) has no port `{}`",
                    port.name
                ),
            )
            .with_primary(port.span, "no such port")
            .with_secondary(comp_span, "component declared here")
            .with_help(help),
        );
        None
    }
}
