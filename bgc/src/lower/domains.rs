//! Domain inference.
//!
//! All bonds of a junction or of a 1-port carry one domain, so bonds are grouped with a union-find over junctions;
//! a TF, GY or field keeps its bonds in separate groups (they may join two domains). A group takes the domain
//! written on any of its elements (`I rotor : rotational`); two different written domains are a mismatch (BG0302).
//! A group with no written domain takes the default (`domain NAME;`) of the scopes its junctions and 1-ports come
//! from, or failing those the default of the scopes of its TFs, GYs and fields; two different defaults are also a
//! mismatch, and no domain at all is BG0311.

use super::builder::Builder;
use crate::diagnostic::Diagnostic;
use crate::ir::Domain;
use crate::span::Span;
use petgraph::graph::{EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;

/// A domain that applies to a group, with where it comes from.
#[derive(Clone, Copy)]
struct Constraint {
    domain: Domain,
    /// The written domain or the `domain` statement.
    span: Span,
    node: NodeIndex,
    /// The constrained bond of that node in this group.
    bond: EdgeIndex,
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

impl Builder<'_> {
    pub fn infer_domains(&mut self) {
        let nb = self.model.graph.edge_count();
        let mut parent: Vec<usize> = (0..nb).collect();
        // One buffer for every node's bonds, rather than a fresh vector per node.
        let mut edges: Vec<usize> = Vec::new();
        for n in self.model.graph.node_indices() {
            if !self.model.graph[n].kind.is_junction() {
                continue;
            }
            edges.clear();
            edges.extend(self.model.graph.edges(n).map(|e| e.id().index()));
            edges.extend(
                self.model
                    .graph
                    .edges_directed(n, petgraph::Direction::Incoming)
                    .map(|e| e.id().index()),
            );
            if let Some((&first, rest)) = edges.split_first() {
                for &e in rest {
                    let (a, b) = (find(&mut parent, first), find(&mut parent, e));
                    parent[a] = b;
                }
            }
        }
        let mut explicit: Vec<Vec<Constraint>> = vec![Vec::new(); nb];
        let mut defaults: Vec<Vec<Constraint>> = vec![Vec::new(); nb];
        let mut weak: Vec<Vec<Constraint>> = vec![Vec::new(); nb];
        let mut node_edges: Vec<EdgeIndex> = Vec::new();
        for n in self.model.graph.node_indices() {
            let Some(info) = self.node_info(n) else {
                continue;
            };
            let kind = info.decl.kind;
            let written = info.explicit_domain;
            let default = self.scopes.get(info.scope).and_then(|s| s.default_domain);
            // A TF, GY or field may join domains: its scope's default only decides when nothing else does.
            let weak_default = kind.is_two_port() || kind.is_field();
            node_edges.clear();
            node_edges.extend(bonds_at(&self.model.graph, n));
            for &e in &node_edges {
                let g = find(&mut parent, e.index());
                if let Some((domain, span)) = written {
                    explicit[g].push(Constraint {
                        domain,
                        span,
                        node: n,
                        bond: e,
                    });
                }
                if let Some((domain, span)) = default {
                    let list = if weak_default {
                        &mut weak[g]
                    } else {
                        &mut defaults[g]
                    };
                    list.push(Constraint {
                        domain,
                        span,
                        node: n,
                        bond: e,
                    });
                }
            }
        }
        let mut group_domain: Vec<Option<Domain>> = vec![None; nb];
        let mut reported = vec![false; nb];
        for e in 0..nb {
            let g = find(&mut parent, e);
            if reported[g] || group_domain[g].is_some() {
                continue;
            }
            reported[g] = true;
            let chosen = match (explicit[g].first(), defaults[g].first().or(weak[g].first())) {
                (Some(&first), _) => self.agree(&explicit[g], first, "declared"),
                (None, Some(&first)) if !defaults[g].is_empty() => {
                    self.agree(&defaults[g], first, "default")
                }
                (None, Some(&first)) => self.agree(&weak[g], first, "default"),
                (None, None) if self.domain_reported => None,
                (None, None) => {
                    let span = self.bond_span(EdgeIndex::new(e));
                    self.diags.push(
                        Diagnostic::error("BG0311", "cannot infer the domain of these bonds")
                            .with_primary(span, "no element bonded here names a domain")
                            .with_help("add `domain rotational;` (or another domain) to the model, or `: DOMAIN` to one of the elements"),
                    );
                    None
                }
            };
            group_domain[g] = chosen;
        }
        for e in 0..nb {
            let g = find(&mut parent, e);
            let d = group_domain[g];
            if let Some(info) = self.bonds.get_mut(e) {
                info.domain = d;
            }
            if let (Some(d), Some(w)) = (d, self.model.graph.edge_weight_mut(EdgeIndex::new(e))) {
                w.domain = d;
            }
        }
        for n in self.model.graph.node_indices() {
            let d = bonds_at(&self.model.graph, n)
                .find_map(|e| self.bonds.get(e.index()).and_then(|b| b.domain));
            if let Some(info) = self.nodes.get_mut(n.index()) {
                info.domain = d;
            }
        }
    }

    /// The domain of a group whose constraints must agree; reports BG0302 at the first disagreement.
    fn agree(&mut self, list: &[Constraint], first: Constraint, how: &str) -> Option<Domain> {
        let Some(&other) = list.iter().find(|c| c.domain != first.domain) else {
            return Some(first.domain);
        };
        let a = self.model.graph[first.node].name.clone();
        let b = self.model.graph[other.node].name.clone();
        self.diags.push(
            Diagnostic::error(
                "BG0302",
                format!(
                    "domain mismatch: `{b}` is {} but it is bonded to `{a}`, which is {}",
                    other.domain.name(),
                    first.domain.name()
                ),
            )
            .with_primary(
                self.bond_span(other.bond),
                "the two ends of this bond are of different domains",
            )
            .with_secondary(first.span, format!("{how} {} here", first.domain.name()))
            .with_secondary(other.span, format!("{how} {} here", other.domain.name()))
            .with_help(
                "a bond joins two ports of one domain; use a TF or GY to pass between domains",
            ),
        );
        Some(first.domain)
    }
}

/// The bonds at node `n`: those leaving it, then those arriving.
fn bonds_at(
    graph: &petgraph::graph::DiGraph<crate::ir::Node, crate::ir::Bond>,
    n: NodeIndex,
) -> impl Iterator<Item = EdgeIndex> + '_ {
    graph
        .edges_directed(n, petgraph::Direction::Outgoing)
        .chain(graph.edges_directed(n, petgraph::Direction::Incoming))
        .map(|e| e.id())
}
