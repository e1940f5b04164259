//! Name scopes of the lowering stage: one per model and one per component instance.
//!
//! A scope has one namespace for parameters, inputs, outputs, vars, elements, instances and named bonds (so that a
//! bare name or the argument of `e(..)` has one meaning), and a separate one for the ports of a component.

use crate::diagnostic::Diagnostic;
use crate::diagnostic::suggest::closest;
use crate::ir::{Domain, InputId, OutputId, ParamId, VarId};
use crate::span::Span;
use petgraph::graph::{EdgeIndex, NodeIndex};
use std::collections::HashMap;
use std::collections::hash_map::Entry;

/// The name tables of scopes hash with foldhash: several times faster than the standard SipHash on the short names
/// of a model, and seeded per process, so that the names of a file cannot be chosen to collide.
pub(crate) type NameMap<K, V> = HashMap<K, V, foldhash::fast::RandomState>;

/// The "did you mean" searches a scope answers; the text rendering shows 100 diagnostics.
pub(crate) const MAX_SUGGESTIONS: u32 = 200;

/// What a name in a scope stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Entity {
    Param(ParamId),
    Input(InputId),
    Output(OutputId),
    Var(VarId),
    Node(NodeIndex),
    /// A component instance: the index of its scope.
    Instance(usize),
    Bond(EdgeIndex),
}

impl Entity {
    /// "a parameter", "an element", ... for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Entity::Param(_) => "a parameter",
            Entity::Input(_) => "an input",
            Entity::Output(_) => "an output",
            Entity::Var(_) => "an integrated flow (var)",
            Entity::Node(_) => "an element",
            Entity::Instance(_) => "a component instance",
            Entity::Bond(_) => "a bond",
        }
    }
}

/// One end of a bond: a node and, for a multiport field, the 0-based port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct End {
    pub node: NodeIndex,
    pub port: Option<u32>,
}

#[derive(Clone, Debug, Default)]
pub(crate) struct Scope<'a> {
    /// `""` for the model, `"sensor."` for instance `sensor`, `"arm.sensor."` nested.
    pub prefix: String,
    /// Each name's entity, declaration span and rank in declaration order (so that suggestions do not depend on
    /// hashing order). The names are borrowed from the syntax tree, which outlives lowering.
    pub names: NameMap<&'a str, (Entity, Span, u32)>,
    pub ports: NameMap<String, (End, Span)>,
    pub port_order: Vec<String>,
    pub default_domain: Option<(Domain, Span)>,
    /// The component's name and its declaration's name span (None for a model).
    pub component: Option<(String, Span)>,
    /// The outermost instance declaration this scope comes from, for `SpanTable::node_instances`.
    pub instance_span: Option<Span>,
    /// The scope of an instance whose component could not be instantiated (already reported): references into it
    /// are not reported again.
    pub broken: bool,
    /// How many "did you mean" searches this scope has answered.
    pub suggested: std::cell::Cell<u32>,
    /// Names declared by statements that did not parse (already reported): references to them are not reported
    /// again.
    pub unparsed: NameMap<&'a str, ()>,
    /// This scope's own instance declaration (None for the model).
    pub own_instance: Option<Span>,
    /// Whether a bond outside the instance goes to one of its ports.
    pub connected: bool,
}

impl<'a> Scope<'a> {
    /// Declares a name, or returns the duplicate-name diagnostic (BG0202).
    pub fn declare(&mut self, name: &'a str, span: Span, entity: Entity) -> Result<(), Diagnostic> {
        let rank = self.names.len() as u32;
        match self.names.entry(name) {
            Entry::Occupied(first) => Err(duplicate(name, span, first.get().1)),
            Entry::Vacant(slot) => {
                slot.insert((entity, span, rank));
                Ok(())
            }
        }
    }

    pub fn get(&self, name: &str) -> Option<Entity> {
        self.names.get(name).map(|(e, _, _)| *e)
    }

    /// Whether `name` was declared by a statement that did not parse (its error is reported).
    pub fn unparsed(&self, name: &str) -> bool {
        self.unparsed.contains_key(name)
    }

    /// The closest declared name accepted by `filter`, for "did you mean" help. Each search reads every name of
    /// the scope, so a scope answers at most [`MAX_SUGGESTIONS`] of them: a generated model with an unknown name in
    /// each of 300,000 elements took six minutes to report them, and no one reads that many helps.
    pub fn suggest(&self, name: &str, filter: impl Fn(Entity) -> bool) -> Option<String> {
        if self.suggested.get() >= MAX_SUGGESTIONS {
            return None;
        }
        self.suggested.set(self.suggested.get() + 1);
        let mut candidates: Vec<(u32, &str)> = self
            .names
            .iter()
            .filter(|(_, (e, _, _))| filter(*e))
            .map(|(n, (_, _, rank))| (*rank, *n))
            .collect();
        candidates.sort_unstable_by_key(|(rank, _)| *rank);
        closest(name, candidates.into_iter().map(|(_, n)| n))
    }
}

/// The BG0202 diagnostic for a second declaration of `name`.
pub(crate) fn duplicate(name: &str, span: Span, first: Span) -> Diagnostic {
    Diagnostic::error("BG0202", format!("`{name}` is declared twice"))
        .with_primary(span, "declared again here")
        .with_secondary(first, "first declared here")
        .with_help(format!("rename one of the two declarations of `{name}`"))
}
