//! Causality analysis of a bond graph.
//!
//! Every bond gets a causality: which of its two ends sets the effort (the other end then sets the flow; the causal
//! stroke is drawn at the end that receives the effort). The assignment follows the sequential causality assignment
//! procedure with priorities (see `scap`): sources and fixed hints are constraints, preferred hints come next, then
//! storage in integral causality, then the form of nonlinear resistor laws, and last arbitrary choices. Constraints
//! propagate through junctions, transformers and gyrators (`engine`) in time linear in the number of bonds.
//!
//! The result, [`Causality`], is complete even when the model has findings: the equations stage can rely on a
//! causality for every bond and for every storage port. Findings are [`Diagnostic`]s:
//!
//! | code | severity | finding |
//! |---|---|---|
//! | BG0501 | error | two sources impose the same variable on a junction |
//! | BG0502 | error | an over-determined junction, transformer or gyrator |
//! | BG0503 | error | a source forced into the wrong causality |
//! | BG0510 | warning | a storage element in derivative causality |
//! | BG0520 | warning | a zero-order causal path (algebraic loop) |
//! | BG0530 | note | an arbitrary choice of causality |
//! | BG0531 | note | a resistor law in the form its causality does not give (it must be inverted) |
//! | BG0540 | note | a causality hint honoured or overruled |
//! | BG0541 | error | a fixed causality hint that cannot be met |
//!
//! A causally complete model (no conflict, no derivative causality, no loop, no arbitrary choice, no hint) gets no
//! diagnostics at all.

mod allow;
mod conflicts;
mod context;
mod engine;
mod findings;
mod loops;
mod report;
mod scap;

#[cfg(test)]
pub(crate) mod test_model;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_findings;
#[cfg(test)]
mod tests_props;

pub use report::{to_json, to_text};

use crate::diagnostic::Diagnostic;
use crate::ir::Model;
use petgraph::graph::{EdgeIndex, NodeIndex};

/// One end of a bond.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum End {
    /// The node the bond comes from (the tail of the power half-arrow).
    From,
    /// The node the bond points to.
    To,
}

impl End {
    pub fn name(self) -> &'static str {
        match self {
            End::From => "from",
            End::To => "to",
        }
    }
}

/// The two kinds of storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StorageKind {
    /// Compliance (C, and each port of a CF): integral causality means it sets the effort.
    C,
    /// Inertia (I, and each port of an IF): integral causality means it sets the flow.
    I,
}

/// The causality of a storage port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StorageForm {
    /// The port's energy variable is a state: it integrates its input.
    Integral,
    /// The port's input is imposed on its output side: its energy variable is fixed by other states or inputs.
    Derivative,
}

/// One storage port and its causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StorageCausality {
    pub node: NodeIndex,
    pub kind: StorageKind,
    /// 0-based port (0 for C and I).
    pub port: u32,
    /// The bond on this port.
    pub bond: EdgeIndex,
    pub causality: StorageForm,
}

/// The fate of a causality hint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HintOutcome {
    pub bond: EdgeIndex,
    pub fixed: bool,
    pub honoured: bool,
}

/// A choice nothing in the graph decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArbitraryChoice {
    /// The element (a resistor) or, for a bond between junctions, the bond's `from` node.
    pub node: NodeIndex,
    pub bond: EdgeIndex,
}

/// The causality of every bond and storage port of a model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Causality {
    /// Per bond (by `EdgeIndex::index()`): the end that sets the effort.
    pub effort_set_by: Vec<End>,
    /// Every storage port, in node then port order.
    pub storage: Vec<StorageCausality>,
    /// Algebraic loops, each the ordered elements of one cycle, starting at a resistor when it has one.
    pub loops: Vec<Vec<NodeIndex>>,
    pub arbitrary: Vec<ArbitraryChoice>,
    pub hints: Vec<HintOutcome>,
    /// Resistor ports `(node, port)` whose law is written in the other causal form and must be inverted.
    pub inverted_laws: Vec<(NodeIndex, u32)>,
    /// False when a conflict (an error) was found: the causality is then only a best effort.
    pub consistent: bool,
}

impl Causality {
    /// The node that sets the effort on a bond.
    pub fn effort_setter(&self, model: &Model, bond: EdgeIndex) -> Option<NodeIndex> {
        let (from, to) = model.graph.edge_endpoints(bond)?;
        match self.effort_set_by.get(bond.index())? {
            End::From => Some(from),
            End::To => Some(to),
        }
    }

    /// True when `node` sets the effort on `bond` (and so receives the flow).
    pub fn sets_effort(&self, model: &Model, node: NodeIndex, bond: EdgeIndex) -> bool {
        self.effort_setter(model, bond) == Some(node)
    }

    /// The number of storage ports in integral causality: the number of independent states.
    pub fn independent_states(&self) -> usize {
        self.storage
            .iter()
            .filter(|s| s.causality == StorageForm::Integral)
            .count()
    }

    /// Storage ports in derivative causality.
    pub fn derivative(&self) -> impl Iterator<Item = &StorageCausality> {
        self.storage
            .iter()
            .filter(|s| s.causality == StorageForm::Derivative)
    }
}

/// Assigns causality to every bond of `model` and reports what it finds.
pub fn analyse(model: &Model) -> (Causality, Vec<Diagnostic>) {
    let assignment = scap::assign(model);
    let loops = loops::find(model, &assignment.engine);
    let (causality, diags) = findings::conclude(model, assignment, loops);
    (causality, allow::apply(model, diags))
}
