//! Drawing bond graphs as SVG (self-contained, laid out here in pure Rust) and as Graphviz DOT text.
//!
//! The layout (`layout`) puts junctions, transformers and gyrators in layers along the power direction and
//! hangs each 1-port next to its junction. Bonds carry the half-arrow of positive power at their `to` end and,
//! when a [`Causality`] is given, the causal stroke at the end that receives the effort. Element labels are in the
//! usual `KIND:parameter` style (`I:J_m`, `C:1/k_g`) with the element's name underneath. Storage in derivative
//! causality and elements on algebraic loops are highlighted, with a legend.

mod dot;
mod label;
mod layers;
mod layout;
mod svg;

#[cfg(test)]
mod tests;

pub use label::expr_text;

use crate::causality::{Causality, StorageForm};
use crate::ir::Model;

/// How a node is emphasised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Highlight {
    None,
    Derivative,
    Loop,
}

/// Highlights per node and per bond.
struct Marks {
    nodes: Vec<Highlight>,
    /// Bonds between two consecutive elements of a loop.
    loop_bonds: Vec<bool>,
}

fn marks(model: &Model, causality: Option<&Causality>) -> Marks {
    let mut m = Marks {
        nodes: vec![Highlight::None; model.graph.node_count()],
        loop_bonds: vec![false; model.graph.edge_count()],
    };
    let Some(c) = causality else { return m };
    for l in &c.loops {
        for &n in l {
            if let Some(h) = m.nodes.get_mut(n.index()) {
                *h = Highlight::Loop;
            }
        }
        for (k, &a) in l.iter().enumerate() {
            let b = l[(k + 1) % l.len()];
            for e in model
                .graph
                .edges_connecting(a, b)
                .chain(model.graph.edges_connecting(b, a))
            {
                if let Some(f) = m
                    .loop_bonds
                    .get_mut(petgraph::visit::EdgeRef::id(&e).index())
                {
                    *f = true;
                }
            }
        }
    }
    for s in &c.storage {
        if s.causality == StorageForm::Derivative
            && let Some(h) = m.nodes.get_mut(s.node.index())
        {
            *h = Highlight::Derivative;
        }
    }
    m
}

/// The bond graph as a standalone SVG document. With a causality, causal strokes are drawn and storage in
/// derivative causality and algebraic-loop members are highlighted.
pub fn svg(model: &Model, causality: Option<&Causality>) -> String {
    let lay = layout::layout(model);
    svg::render(model, &lay, causality, &marks(model, causality))
}

/// The bond graph as Graphviz DOT text. Node positions from bgc's own layout are included (`pos`, in points), so
/// `neato -n2 -Tsvg` reproduces this layout and `dot -Tsvg` computes its own.
pub fn dot(model: &Model, causality: Option<&Causality>) -> String {
    let lay = layout::layout(model);
    dot::render(model, &lay, causality, &marks(model, causality))
}
