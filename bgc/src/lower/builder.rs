//! The state of lowering one model: the IR under construction plus what the checks need beside it.

use super::scope::{End, Scope};
use crate::diagnostic::Diagnostic;
use crate::ir::{self, Domain, OutputId, VarId};
use crate::span::Span;
use crate::syntax::ast::{CoordsDecl, ElementDecl, ModelDecl, OutputDecl, Stmt, VarDecl};
use petgraph::graph::{DiGraph, EdgeIndex, NodeIndex};
use std::collections::HashMap;

/// What lowering knows about a node beyond the IR.
pub(crate) struct NodeInfo<'a> {
    pub scope: usize,
    pub decl: &'a ElementDecl,
    /// The domain written on the element (`I rotor : rotational`).
    pub explicit_domain: Option<(Domain, Span)>,
    /// The domain of its bonds once inferred (for TF/GY and fields, see `bond_domain`).
    pub domain: Option<Domain>,
}

/// What lowering knows about a bond beyond the IR.
pub(crate) struct BondInfo {
    pub from: End,
    pub to: End,
    /// Set by domain inference; None when it failed.
    pub domain: Option<Domain>,
}

/// What lowering knows about a parameter beyond the IR.
pub(crate) struct ParamInfo {
    pub used: bool,
    /// The parameter's name in its declaration.
    pub name_span: Span,
    /// The expression that gave its value (the default, or the instance's override).
    pub value_span: Span,
    /// Its declared unit.
    pub unit_span: Span,
    /// Its value could not be computed (an error says why, and 0 stands in): the checks of values computed from
    /// it are left out, since they would report the stand-in ("an inertia of 0").
    pub value_reported: bool,
}

pub(crate) struct Builder<'a> {
    pub decls: &'a HashMap<String, &'a ModelDecl>,
    pub diags: Vec<Diagnostic>,
    pub model: ir::Model,
    pub scopes: Vec<Scope<'a>>,
    pub nodes: Vec<NodeInfo<'a>>,
    pub bonds: Vec<BondInfo>,
    pub params: Vec<ParamInfo>,
    /// The bond on each port of each field, filled by the structure checks.
    pub field_bonds: HashMap<(NodeIndex, u32), EdgeIndex>,
    pub pending_outputs: Vec<(OutputId, usize, &'a OutputDecl)>,
    pub pending_vars: Vec<(VarId, usize, &'a VarDecl)>,
    pub pending_coords: Option<(usize, &'a CoordsDecl)>,
    /// Declarations whose unit could not be read: their dimension is left free to avoid follow-up errors.
    pub bad_units: Vec<super::scope::Entity>,
    /// Nodes at the resolved end of a bond whose other end could not be resolved (already reported).
    pub suspect_nodes: std::collections::HashSet<NodeIndex>,
    /// Whether the last unit read by `unit` was valid.
    pub last_unit_ok: bool,
    /// An unknown name without a close match was reported: any unused parameter may be the one it meant, so
    /// BG0402 is left out until that error is fixed.
    pub unmatched_name: bool,
    /// An unknown domain or a `domain` statement that did not parse was reported: bonds without a domain follow
    /// from it, so BG0311 is left out.
    pub domain_reported: bool,
    /// The domains a BG0303 hint has already suggested: later hints for the same domain stay short.
    pub suggested_domains: Vec<Domain>,
    /// The components being instantiated, to catch a component that contains itself.
    pub component_stack: Vec<String>,
    /// Every component instantiated while building this model.
    pub instantiated: Vec<String>,
    /// How many instances were expanded (bounded by `flatten::MAX_INSTANCES`).
    pub instance_count: usize,
}

impl<'a> Builder<'a> {
    pub fn new(decls: &'a HashMap<String, &'a ModelDecl>, decl: &'a ModelDecl) -> Self {
        // The model's own elements and bonds (instances add to them): tables of the right size from the start
        // rather than ones that reallocate and copy their way up to hundreds of thousands of entries.
        let (nodes, bonds) = own_size(decl);
        Builder {
            decls,
            diags: Vec::new(),
            model: ir::Model {
                name: decl.name.name.clone(),
                doc: decl.doc.clone(),
                graph: DiGraph::with_capacity(nodes, bonds),
                params: Vec::new(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                vars: Vec::new(),
                coords: None,
                spans: ir::SpanTable {
                    model: decl.span,
                    nodes: Vec::with_capacity(nodes),
                    node_names: Vec::with_capacity(nodes),
                    node_relations: Vec::with_capacity(nodes),
                    node_instances: Vec::with_capacity(nodes),
                    bonds: Vec::with_capacity(bonds),
                    ..Default::default()
                },
            },
            scopes: Vec::new(),
            nodes: Vec::with_capacity(nodes),
            bonds: Vec::with_capacity(bonds),
            params: Vec::new(),
            field_bonds: HashMap::new(),
            pending_outputs: Vec::new(),
            pending_vars: Vec::new(),
            pending_coords: None,
            component_stack: Vec::new(),
            instantiated: Vec::new(),
            instance_count: 0,
            bad_units: Vec::new(),
            last_unit_ok: true,
            unmatched_name: false,
            domain_reported: false,
            suggested_domains: Vec::new(),
            suspect_nodes: std::collections::HashSet::new(),
        }
    }

    pub fn node_info(&self, n: NodeIndex) -> Option<&NodeInfo<'a>> {
        self.nodes.get(n.index())
    }

    /// The domain of the bond on a node's port: the only bond of a 1-port, any bond of a junction, the input (0)
    /// or output (1) bond of a TF/GY, the bond on a field's port.
    pub fn port_domain(&self, n: NodeIndex, port: u32) -> Option<Domain> {
        let info = self.node_info(n)?;
        let kind = info.decl.kind;
        if kind.is_field() {
            let e = self.field_bonds.get(&(n, port))?;
            return self.bonds.get(e.index())?.domain;
        }
        if kind.is_two_port() {
            use petgraph::Direction;
            let dir = if port == 0 {
                Direction::Incoming
            } else {
                Direction::Outgoing
            };
            let e = self.model.graph.edges_directed(n, dir).next()?;
            use petgraph::visit::EdgeRef;
            return self.bonds.get(e.id().index())?.domain;
        }
        info.domain
    }

    /// The span of a node's declaration (its name).
    pub fn node_name_span(&self, n: NodeIndex) -> Span {
        self.model
            .spans
            .node_names
            .get(n.index())
            .copied()
            .unwrap_or_default()
    }

    pub fn bond_span(&self, e: EdgeIndex) -> Span {
        self.model
            .spans
            .bonds
            .get(e.index())
            .copied()
            .unwrap_or_default()
    }
}

/// The number of elements a model declares itself and the number of bonds its bond statements make (a fan-out or
/// chain makes one per pair of neighbouring nodes).
fn own_size(decl: &ModelDecl) -> (usize, usize) {
    let (mut nodes, mut bonds) = (0usize, 0usize);
    for stmt in &decl.body {
        match stmt {
            Stmt::Element(_) => nodes += 1,
            Stmt::Bond(b) => {
                for pair in b.chain.windows(2) {
                    if let [tails, heads] = pair {
                        bonds = bonds.saturating_add(tails.len().saturating_mul(heads.len()));
                    }
                }
            }
            _ => {}
        }
    }
    (nodes, bonds)
}
