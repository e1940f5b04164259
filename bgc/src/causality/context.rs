//! The context in which findings are written: names, places and causal paths of a finished assignment.

use super::engine::{Conflict, Engine, Reason};
use crate::diagnostic::Diagnostic;
use crate::ir::Model;
use crate::span::Span;
use crate::syntax::ast::ElementKind;
use petgraph::graph::{EdgeIndex, NodeIndex};
use std::collections::HashMap;

/// Longest causal path shown in full; longer ones keep their two ends.
pub const PATH_SHOWN: usize = 12;

pub struct Ctx<'a> {
    pub model: &'a Model,
    pub engine: &'a Engine,
    /// Per bond: the first bond of its causal path.
    pub first: Vec<u32>,
    /// Per bond: the number of propagation steps from the first bond of its path.
    pub depth: Vec<u32>,
    /// Preferences that were overruled, by bond, with the conflict that overruled them.
    pub fallbacks: HashMap<u32, Conflict>,
}

impl<'a> Ctx<'a> {
    /// Origins and depths of all causal paths, in one pass over the assignment order.
    pub fn new(model: &'a Model, engine: &'a Engine, fallbacks: &[(u32, Conflict)]) -> Ctx<'a> {
        let m = engine.ends.len();
        let mut first: Vec<u32> = (0..m as u32).collect();
        let mut depth = vec![0u32; m];
        for &b in engine.order() {
            if let Reason::Propagated { via, .. } = engine.reason[b as usize] {
                first[b as usize] = first[via as usize];
                depth[b as usize] = depth[via as usize] + 1;
            }
        }
        Ctx {
            model,
            engine,
            first,
            depth,
            fallbacks: fallbacks.iter().copied().collect(),
        }
    }

    /// The causal path to a bond as `(position, deciding node, bond)`: the origin and at most [`PATH_SHOWN`] steps
    /// before the bond, with the total number of steps.
    pub fn path(&self, bond: u32) -> (Vec<(usize, u32, u32)>, usize) {
        let total = self.depth[bond as usize] as usize + 1;
        let tail = self.engine.path_to(bond, PATH_SHOWN);
        let mut out = Vec::with_capacity(tail.len() + 1);
        if tail.len() < total {
            let f = self.first[bond as usize];
            out.push((0, self.engine.origin_node(f), f));
        }
        let start = total - tail.len();
        out.extend(
            tail.iter()
                .enumerate()
                .map(|(i, &(n, b))| (start + i, n, b)),
        );
        (out, total)
    }

    /// The nodes along the path to a bond (as far as [`Ctx::path`] goes).
    pub fn path_nodes(&self, bond: u32) -> Vec<u32> {
        self.path(bond).0.iter().map(|&(_, n, _)| n).collect()
    }

    pub fn node(&self, n: u32) -> NodeIndex {
        NodeIndex::new(n as usize)
    }

    pub fn name(&self, n: u32) -> &str {
        self.model
            .graph
            .node_weight(self.node(n))
            .map_or("?", |w| w.name.as_str())
    }

    pub fn kind(&self, n: u32) -> Option<ElementKind> {
        self.model.graph.node_weight(self.node(n)).map(|w| w.kind)
    }

    pub fn node_span(&self, n: u32) -> Span {
        self.model
            .spans
            .nodes
            .get(n as usize)
            .copied()
            .unwrap_or(self.model.spans.model)
    }

    pub fn bond_span(&self, b: u32) -> Span {
        self.model
            .spans
            .bonds
            .get(b as usize)
            .copied()
            .unwrap_or(self.model.spans.model)
    }

    pub fn bond_name(&self, b: u32) -> String {
        self.model.bond_name(EdgeIndex::new(b as usize))
    }

    /// `inertia `J_m``, `1-junction `j``, ...
    pub fn describe(&self, n: u32) -> String {
        let what = match self.kind(n) {
            Some(ElementKind::Se) => "effort source",
            Some(ElementKind::MSe) => "modulated effort source",
            Some(ElementKind::Sf) => "flow source",
            Some(ElementKind::MSf) => "modulated flow source",
            Some(ElementKind::C) => "compliance",
            Some(ElementKind::I) => "inertia",
            Some(ElementKind::R) => "resistor",
            Some(ElementKind::TF) => "transformer",
            Some(ElementKind::MTF) => "modulated transformer",
            Some(ElementKind::GY) => "gyrator",
            Some(ElementKind::MGY) => "modulated gyrator",
            Some(ElementKind::Zero) => "0-junction",
            Some(ElementKind::One) => "1-junction",
            Some(ElementKind::CF) => "C-field",
            Some(ElementKind::RF) => "R-field",
            Some(ElementKind::IF) => "I-field",
            None => "element",
        };
        format!("{what} `{}`", self.name(n))
    }

    /// Secondary labels along the causal path to a bond, element by element.
    pub fn path_labels(&self, mut d: Diagnostic, bond: u32) -> Diagnostic {
        let (steps, total) = self.path(bond);
        if total > steps.len() {
            d = d.with_note(format!(
                "the causal path has {total} steps; {} in its middle are not shown",
                total - steps.len()
            ));
        }
        for (i, n, b) in steps {
            let var = if self.engine.node_sets(n, b) == Some(true) {
                "effort"
            } else {
                "flow"
            };
            let span = self.node_span(n);
            let message = format!(
                "({}) `{}` sets the {var} on bond `{}`",
                i + 1,
                self.name(n),
                self.bond_name(b)
            );
            // Paths that share their beginning are shown once.
            if !d
                .labels
                .iter()
                .any(|l| l.span == span && l.message == message)
            {
                d = d.with_secondary(span, message);
            }
        }
        d
    }

    /// The origin of the causal path of a bond, with its reason.
    pub fn origin(&self, bond: u32) -> (u32, Reason) {
        let f = self.first[bond as usize];
        (self.engine.origin_node(f), self.engine.reason[f as usize])
    }
}
