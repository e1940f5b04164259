//! Structure checks: every node has the bonds its kind requires, TF/GY and field ports are numbered, and power
//! directions make sense.
//!
//! - a node without any bond is unconnected (BG0306);
//! - a 1-port (Se, Sf, MSe, MSf, C, I, R) has exactly one bond (BG0301);
//! - a TF, GY, MTF or MGY has exactly one bond in (its port 0) and one out (its port 1) (BG0304);
//! - a junction has at least two bonds (BG0305);
//! - each port of a field has exactly one bond (BG0307);
//! - a source whose bond points into it, or a C, I or R whose bond points out of it, is a warning (BG0308): a C, I
//!   or R behaves the same either way (its own `e` and `f` are taken with power into it), but the bond's variables
//!   change sign, and a source drawn this way absorbs the power it sets; either is almost always a reversed arrow.

use super::builder::Builder;
use super::flatten::kind_name;
use crate::diagnostic::Diagnostic;
use crate::syntax::ast::ElementKind;
use petgraph::Direction;
use petgraph::graph::{EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;

/// The bonds of one node, reused from node to node.
#[derive(Default)]
struct NodeBonds {
    incoming: Vec<EdgeIndex>,
    outgoing: Vec<EdgeIndex>,
    /// Both, in bond order.
    all: Vec<EdgeIndex>,
}

impl Builder<'_> {
    pub fn check_structure(&mut self) {
        // An instance none of whose ports is bonded is reported once, not through each of its nodes.
        let mut loose: Vec<String> = Vec::new();
        for scope in &self.scopes {
            if let Some(span) = scope.own_instance
                && !scope.connected
                && !scope.broken
                && !loose.iter().any(|p| scope.prefix.starts_with(p.as_str()))
            {
                let name = scope.prefix.trim_end_matches('.').to_string();
                self.diags.push(
                    Diagnostic::error("BG0306", format!("instance `{name}` is not connected"))
                        .with_primary(span, "no bond goes to any of its ports")
                        .with_help(format!(
                            "bond one of its ports (`bond j -> {name}.PORT;`) or remove it"
                        )),
                );
                loose.push(scope.prefix.clone());
            }
        }
        // One set of bond lists for all nodes, rather than three fresh vectors per node.
        let mut bonds = NodeBonds::default();
        for i in 0..self.model.graph.node_count() {
            let n = NodeIndex::new(i);
            // Ports are still numbered, but the counts of these nodes follow from errors already reported.
            let quiet = loose
                .iter()
                .any(|p| self.model.graph[n].name.starts_with(p.as_str()))
                || self.suspect_nodes.contains(&n);
            let reported = self.diags.len();
            self.check_node(n, &mut bonds);
            if quiet {
                self.diags.truncate(reported);
            }
        }
    }

    fn check_node(&mut self, n: NodeIndex, bonds: &mut NodeBonds) {
        let NodeBonds {
            incoming,
            outgoing,
            all,
        } = bonds;
        let graph = &self.model.graph;
        incoming.clear();
        incoming.extend(graph.edges_directed(n, Direction::Incoming).map(|e| e.id()));
        outgoing.clear();
        outgoing.extend(graph.edges_directed(n, Direction::Outgoing).map(|e| e.id()));
        all.clear();
        all.extend(incoming.iter().chain(outgoing.iter()).copied());
        all.sort_unstable();
        let (incoming, outgoing, all) = (&*incoming, &*outgoing, &*all);
        let kind = self.model.graph[n].kind;
        let decl_span = self.node_name_span(n);
        // The node's name is copied (out of the graph that the checks change) only for a message.
        if all.is_empty() {
            let name = self.model.graph[n].name.clone();
            self.diags.push(
                Diagnostic::error("BG0306", format!("`{name}` is not connected"))
                    .with_primary(decl_span, format!("this {} has no bond", kind_name(kind)))
                    .with_help(format!(
                        "bond it (`bond {junction} -> {name};`, from a junction) or remove it",
                        junction = if name == "j" { "j1" } else { "j" }
                    )),
            );
            return;
        }
        match kind {
            k if k.is_junction() => {
                if all.len() < 2 {
                    let name = self.model.graph[n].name.clone();
                    self.diags.push(
                            Diagnostic::error("BG0305", format!("junction `{name}` has only one bond"))
                                .with_primary(decl_span, "a junction joins at least two bonds")
                                .with_secondary(self.bond_span(all[0]), "its only bond")
                                .with_help("bond the element directly, without the junction, or add the missing bond"),
                        );
                }
            }
            k if k.is_two_port() => {
                if incoming.len() != 1 || outgoing.len() != 1 {
                    let name = self.model.graph[n].name.clone();
                    let mut d = Diagnostic::error(
                        "BG0304",
                        format!(
                            "`{name}` needs one bond in and one bond out, found {} in and {} out",
                            incoming.len(),
                            outgoing.len()
                        ),
                    )
                    .with_primary(
                        decl_span,
                        format!("{} has an input and an output port", k.with_article()),
                    );
                    for e in all {
                        d = d.with_secondary(self.bond_span(*e), "a bond of it");
                    }
                    self.diags.push(d.with_help(
                            "the bond pointing into it is its input (port 0), the bond pointing out of it its output (port 1)",
                        ));
                }
                for e in incoming {
                    self.model.graph[*e].to_port = 0;
                }
                for e in outgoing {
                    self.model.graph[*e].from_port = 1;
                }
            }
            k if k.is_field() => {
                let name = self.model.graph[n].name.clone();
                self.field_ports(n, &name, incoming, outgoing, decl_span);
            }
            _ => {
                if all.len() > 1 {
                    let name = self.model.graph[n].name.clone();
                    let mut d = Diagnostic::error(
                        "BG0301",
                        format!("`{name}` is a 1-port but has {} bonds", all.len()),
                    )
                    .with_primary(self.bond_span(all[1]), "a second bond");
                    d = d.with_secondary(self.bond_span(all[0]), "first bond");
                    d = d
                        .with_secondary(decl_span, format!("{} has one port", kind.with_article()));
                    self.diags.push(d.with_help(format!(
                        "bond `{name}` to a junction and bond the other elements to that junction"
                    )));
                }
                self.power_direction(n, kind, incoming, outgoing);
            }
        }
    }

    fn field_ports(
        &mut self,
        n: NodeIndex,
        name: &str,
        incoming: &[EdgeIndex],
        outgoing: &[EdgeIndex],
        decl_span: crate::span::Span,
    ) {
        let ports = self.model.graph[n].ports;
        let mut on_port: Vec<Vec<EdgeIndex>> = vec![Vec::new(); ports as usize];
        for (e, is_in) in incoming
            .iter()
            .map(|e| (*e, true))
            .chain(outgoing.iter().map(|e| (*e, false)))
        {
            let Some(info) = self.bonds.get(e.index()) else {
                continue;
            };
            let end = if is_in { info.to } else { info.from };
            let Some(port) = end.port else { continue };
            if let Some(list) = on_port.get_mut(port as usize) {
                list.push(e);
            }
            let bond = &mut self.model.graph[e];
            if is_in {
                bond.to_port = port;
            } else {
                bond.from_port = port;
            }
        }
        for (i, list) in on_port.iter().enumerate() {
            match list[..] {
                [e] => {
                    self.field_bonds.insert((n, i as u32), e);
                }
                [] => self.diags.push(
                    Diagnostic::error(
                        "BG0307",
                        format!("port {} of field `{name}` has no bond", i + 1),
                    )
                    .with_primary(decl_span, format!("`{name}[{}]` is not bonded", i + 1))
                    .with_help(format!("bond it: `bond j -> {name}[{}];`", i + 1)),
                ),
                [first, second, ..] => self.diags.push(
                    Diagnostic::error(
                        "BG0307",
                        format!("port {} of field `{name}` has {} bonds", i + 1, list.len()),
                    )
                    .with_primary(self.bond_span(second), "a second bond on this port")
                    .with_secondary(self.bond_span(first), "first bond")
                    .with_help(
                        "each port of a field takes one bond; join several through a junction",
                    ),
                ),
            }
        }
    }

    /// BG0308: a source whose bond points into it, or a C, I or R whose bond points out of it. The message says
    /// which way the bond is drawn and which way is usual, and the help writes the bond turned round.
    fn power_direction(
        &mut self,
        n: NodeIndex,
        kind: ElementKind,
        incoming: &[EdgeIndex],
        outgoing: &[EdgeIndex],
    ) {
        use ElementKind as K;
        let source = matches!(kind, K::Se | K::Sf | K::MSe | K::MSf);
        let bad = match kind {
            _ if source => incoming.first(),
            K::C | K::I | K::R => outgoing.first(),
            _ => None,
        };
        let Some(&e) = bad else { return };
        let Some((from, to)) = self.model.graph.edge_endpoints(e) else {
            return;
        };
        let name = self.model.graph[n].name.clone();
        let from = self.model.graph[from].name.clone();
        let to = self.model.graph[to].name.clone();
        let kw = kind.with_article();
        let (message, label, note) = if source {
            (
                format!("the bond of source `{name}` points into it"),
                format!("this bond points from `{from}` into `{name}`"),
                "a source's bond usually points away from it, along the power it delivers; drawn into it, the source \
                 is connected the other way round at its junction (a battery with its terminals swapped): its own \
                 `e`, `f` and `supplied` (the power it delivers) are the same either way, but the bond's flow is \
                 minus the source's",
            )
        } else {
            (
                format!("the bond of `{name}` ({kw}) points out of it"),
                format!("this bond points from `{name}` out to `{to}`"),
                "a C, I or R usually has its bond pointing into it, so that the power it stores or dissipates counts \
                 positive along the bond; the element's own `e`, `f` and energy are the same either way, but the \
                 bond's flow is minus the element's",
            )
        };
        let turned = if source {
            format!("bond {name} -> {from};")
        } else {
            format!("bond {to} -> {name};")
        };
        self.diags.push(
            Diagnostic::warning("BG0308", message)
                .with_primary(self.bond_span(e), label)
                .with_note(note)
                .with_help(format!(
                    "write `{turned}` unless the reversed sign is intended"
                )),
        );
    }
}
