//! A small builder of IR models for tests, independent of the parser and lowering. It also writes a source text
//! (one line per declaration) so that every node and bond has a real span to check diagnostics against.
//!
//! Small graphs are written compactly: [`Builder::from_spec`] takes the nodes as `"kind name"` pairs and the
//! bonds as chains of names, and creates both in the order written (the order decides node and bond indices and
//! the order in which causality is assigned, so a test's graph is exactly what it reads).

use super::{Causality, analyse};
use crate::diagnostic::Diagnostic;
use crate::ir::{Bond, Domain, Expr, Hint, Law, Model, Node, PortVar, Relation, SpanTable};
use crate::span::{FileId, SourceMap, Span};
use crate::syntax::ast::ElementKind;
use petgraph::graph::{DiGraph, EdgeIndex, NodeIndex};

pub struct Builder {
    model: Model,
    text: String,
}

impl Builder {
    pub fn new(name: &str) -> Builder {
        Builder {
            model: Model {
                name: name.to_string(),
                doc: Vec::new(),
                graph: DiGraph::new(),
                params: Vec::new(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                vars: Vec::new(),
                coords: None,
                spans: SpanTable::default(),
            },
            text: format!("model {name} {{\n"),
        }
    }

    /// A model `name` with the nodes `nodes` (see [`Builder::nodes`]) and then the bonds along `chains` (see
    /// [`Builder::chains`]).
    pub fn from_spec(name: &str, nodes: &str, chains: &str) -> Builder {
        let mut b = Builder::new(name);
        for (kind, node) in node_specs(nodes) {
            b.node(kind, node);
        }
        b.chains(chains);
        b
    }

    fn line(&mut self, s: &str) -> Span {
        let start = self.text.len() + 4;
        self.text.push_str("    ");
        self.text.push_str(s);
        let span = Span::new(FileId(0), start, self.text.len());
        self.text.push('\n');
        span
    }

    /// A node with a default relation for its kind.
    pub fn node(&mut self, kind: ElementKind, name: &str) -> NodeIndex {
        let relation = match kind {
            ElementKind::Se | ElementKind::Sf | ElementKind::MSe | ElementKind::MSf => {
                Relation::Source(Expr::Const(1.0))
            }
            ElementKind::C | ElementKind::I | ElementKind::R => Relation::Linear(Expr::Const(1.0)),
            ElementKind::TF | ElementKind::GY | ElementKind::MTF | ElementKind::MGY => {
                Relation::Modulus(Expr::Const(2.0))
            }
            _ => Relation::Junction,
        };
        let ports = match kind {
            ElementKind::Zero | ElementKind::One => 0,
            k if k.is_two_port() => 2,
            _ => 1,
        };
        self.add(kind, name, relation, ports)
    }

    /// Nodes with default relations from comma-separated `"kind name"` pairs, kinds as the language writes them
    /// (`"Se u, 1 j, I m"`); their indices in the order written.
    pub fn nodes<const N: usize>(&mut self, spec: &str) -> [NodeIndex; N] {
        let nodes: Vec<NodeIndex> = node_specs(spec)
            .map(|(kind, name)| self.node(kind, name))
            .collect();
        nodes
            .try_into()
            .unwrap_or_else(|v: Vec<_>| panic!("{} nodes in {spec:?}, {N} expected", v.len()))
    }

    /// The node called `name`.
    pub fn id(&self, name: &str) -> NodeIndex {
        self.model
            .node_by_name(name)
            .unwrap_or_else(|| panic!("no node {name}"))
    }

    /// A node with a given relation and port count.
    pub fn add(
        &mut self,
        kind: ElementKind,
        name: &str,
        relation: Relation,
        ports: u32,
    ) -> NodeIndex {
        let span = self.line(&format!("{} {name};", kind.keyword()));
        let n = self.model.graph.add_node(Node {
            name: name.to_string(),
            kind,
            relation,
            ports,
            doc: Vec::new(),
        });
        let name_start = span.start as usize + kind.keyword().len() + 1;
        self.model.spans.nodes.push(span);
        self.model
            .spans
            .node_names
            .push(Span::new(FileId(0), name_start, name_start + name.len()));
        self.model.spans.node_relations.push(None);
        self.model.spans.node_instances.push(None);
        n
    }

    /// A resistor with a nonlinear law in the form `lhs = ...`.
    pub fn r_law(&mut self, name: &str, lhs: PortVar) -> NodeIndex {
        let law = Law {
            lhs,
            port: 0,
            rhs: Expr::Const(1.0),
        };
        self.add(ElementKind::R, name, Relation::Laws(vec![law]), 1)
    }

    /// A bond; the ports of TF/GY follow the convention (output port 1 at the `from` end, input port 0 at `to`).
    pub fn bond(&mut self, a: NodeIndex, b: NodeIndex) -> EdgeIndex {
        self.bond_full(a, None, b, None, None)
    }

    /// A bond with a hint: `stroke_at_to` puts the stroke at `b`.
    pub fn bond_hint(
        &mut self,
        a: NodeIndex,
        b: NodeIndex,
        stroke_at_to: bool,
        fixed: bool,
    ) -> EdgeIndex {
        self.bond_full(
            a,
            None,
            b,
            None,
            Some(Hint {
                stroke_at_to,
                fixed,
            }),
        )
    }

    /// A bond to or from given ports (0-based) of fields.
    pub fn bond_full(
        &mut self,
        a: NodeIndex,
        a_port: Option<u32>,
        b: NodeIndex,
        b_port: Option<u32>,
        hint: Option<Hint>,
    ) -> EdgeIndex {
        let from_port = a_port.unwrap_or(u32::from(self.model.graph[a].kind.is_two_port()));
        let to_port = b_port.unwrap_or(0);
        let an = self.model.graph[a].name.clone();
        let bn = self.model.graph[b].name.clone();
        let stroke = match hint {
            Some(h) => format!(
                " stroke{} {}",
                if h.fixed { "!" } else { "" },
                if h.stroke_at_to { &bn } else { &an }
            ),
            None => String::new(),
        };
        let span = self.line(&format!("bond {an} -> {bn}{stroke};"));
        self.model.spans.bonds.push(span);
        self.model.graph.add_edge(
            a,
            b,
            Bond {
                name: None,
                from_port,
                to_port,
                domain: Domain::Rotational,
                hint,
            },
        )
    }

    /// Bonds along a chain.
    pub fn chain(&mut self, nodes: &[NodeIndex]) {
        for w in nodes.windows(2) {
            self.bond(w[0], w[1]);
        }
    }

    /// Bonds along chains of node names, the chains separated by `;`: `"u j m; j c"` bonds `u -> j`, `j -> m`,
    /// `j -> c`, in this order.
    pub fn chains(&mut self, spec: &str) {
        for chain in spec.split(';').filter(|c| !c.trim().is_empty()) {
            let nodes: Vec<NodeIndex> = chain.split_whitespace().map(|n| self.id(n)).collect();
            self.chain(&nodes);
        }
    }

    /// The finished model with its causality and findings.
    pub fn analyse(self) -> (Model, Causality, Vec<Diagnostic>) {
        let (m, _) = self.finish();
        let (c, d) = analyse(&m);
        (m, c, d)
    }

    pub fn finish(mut self) -> (Model, SourceMap) {
        self.text.push_str("}\n");
        self.model.spans.model = Span::new(FileId(0), 0, self.text.len());
        let mut sources = SourceMap::new();
        sources.add(format!("{}.bg", self.model.name), self.text);
        (self.model, sources)
    }
}

/// The `(kind, name)` pairs of a node list `"Se u, 1 j, I m"`.
fn node_specs(spec: &str) -> impl Iterator<Item = (ElementKind, &str)> {
    spec.split(',').map(|item| {
        let (kind, name) = item
            .trim()
            .split_once(' ')
            .unwrap_or_else(|| panic!("{item:?} is not `kind name`"));
        let kind =
            ElementKind::from_keyword(kind).unwrap_or_else(|| panic!("no element kind {kind}"));
        (kind, name.trim())
    })
}
