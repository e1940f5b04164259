//! From an assignment to the public result and its diagnostics (codes in the module docs of [`super`]).

use super::engine::{Conflict, Engine, Reason, Role};
use super::scap::{Assignment, storage_ports};
use super::{
    ArbitraryChoice, Causality, End, HintOutcome, StorageCausality, StorageForm, StorageKind,
};
use crate::diagnostic::Diagnostic;
use crate::ir::Model;
use crate::span::Span;
use crate::syntax::ast::ElementKind;
use petgraph::graph::{EdgeIndex, NodeIndex};
use std::collections::{BTreeSet, HashMap};

/// Longest causal path shown in full; longer ones keep their two ends.
const PATH_SHOWN: usize = 12;

struct Ctx<'a> {
    model: &'a Model,
    engine: &'a Engine,
    /// Per bond: the first bond of its causal path.
    first: Vec<u32>,
    /// Per bond: the number of propagation steps from the first bond of its path.
    depth: Vec<u32>,
    /// Preferences that were overruled, by bond, with the conflict that overruled them.
    fallbacks: HashMap<u32, Conflict>,
}

impl<'a> Ctx<'a> {
    /// Origins and depths of all causal paths, in one pass over the assignment order.
    fn new(model: &'a Model, engine: &'a Engine, fallbacks: &[(u32, Conflict)]) -> Ctx<'a> {
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
    fn path(&self, bond: u32) -> (Vec<(usize, u32, u32)>, usize) {
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
    fn path_nodes(&self, bond: u32) -> Vec<u32> {
        self.path(bond).0.iter().map(|&(_, n, _)| n).collect()
    }

    fn node(&self, n: u32) -> NodeIndex {
        NodeIndex::new(n as usize)
    }

    fn name(&self, n: u32) -> &str {
        self.model
            .graph
            .node_weight(self.node(n))
            .map_or("?", |w| w.name.as_str())
    }

    fn kind(&self, n: u32) -> Option<ElementKind> {
        self.model.graph.node_weight(self.node(n)).map(|w| w.kind)
    }

    fn node_span(&self, n: u32) -> Span {
        self.model
            .spans
            .nodes
            .get(n as usize)
            .copied()
            .unwrap_or(self.model.spans.model)
    }

    fn bond_span(&self, b: u32) -> Span {
        self.model
            .spans
            .bonds
            .get(b as usize)
            .copied()
            .unwrap_or(self.model.spans.model)
    }

    fn bond_name(&self, b: u32) -> String {
        self.model.bond_name(EdgeIndex::new(b as usize))
    }

    /// `inertia `J_m``, `1-junction `j``, ...
    fn describe(&self, n: u32) -> String {
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
    fn path_labels(&self, mut d: Diagnostic, bond: u32) -> Diagnostic {
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
    fn origin(&self, bond: u32) -> (u32, Reason) {
        let f = self.first[bond as usize];
        (self.engine.origin_node(f), self.engine.reason[f as usize])
    }
}

/// Turns the assignment into the result and the diagnostics.
pub fn conclude(
    model: &Model,
    a: Assignment,
    loops: Vec<Vec<NodeIndex>>,
) -> (Causality, Vec<Diagnostic>) {
    let cx = Ctx::new(model, &a.engine, &a.fallbacks);
    let mut diags = Vec::new();
    let mut hints_in_conflict = BTreeSet::new();

    let mut seen = BTreeSet::new();
    let source_conflicts = a
        .forced_sources
        .iter()
        .map(|&(node, bond)| Conflict { node, bond });
    for c in source_conflicts.chain(a.conflicts.iter().copied()) {
        if seen.insert(c.node) {
            diags.push(conflict(&cx, c, &mut hints_in_conflict));
        }
    }

    let hints: Vec<HintOutcome> = a
        .hints
        .iter()
        .map(|h| HintOutcome {
            bond: EdgeIndex::new(h.bond as usize),
            fixed: h.fixed,
            honoured: a.engine.effort_from[h.bond as usize] == Some(h.wants_effort_from),
        })
        .collect();
    for h in &hints {
        let b = h.bond.index() as u32;
        if h.fixed && !h.honoured {
            diags.push(violated_hint(&cx, b));
        } else if !hints_in_conflict.contains(&b) {
            diags.push(hint_note(&cx, b, h));
        }
    }

    let mut storage = Vec::new();
    for (n, port, b, integral_sets) in storage_ports(model, &a.engine) {
        let kind = if integral_sets {
            StorageKind::C
        } else {
            StorageKind::I
        };
        let form = if a.engine.node_sets(n, b) == Some(integral_sets) {
            StorageForm::Integral
        } else {
            StorageForm::Derivative
        };
        if form == StorageForm::Derivative {
            diags.push(derivative(&cx, n, b, kind));
        }
        storage.push(StorageCausality {
            node: NodeIndex::new(n as usize),
            kind,
            port,
            bond: EdgeIndex::new(b as usize),
            causality: form,
        });
    }

    for l in &loops {
        diags.push(algebraic_loop(&cx, l));
    }

    let arbitrary: Vec<ArbitraryChoice> = a
        .arbitrary
        .iter()
        .map(|&(n, b)| ArbitraryChoice {
            node: NodeIndex::new(n as usize),
            bond: EdgeIndex::new(b as usize),
        })
        .collect();
    for &(n, b) in &a.arbitrary {
        diags.push(arbitrary_note(&cx, n, b));
    }

    let mut inverted_laws = Vec::new();
    for &(n, port, b, prefers_sets) in &a.laws {
        if a.engine.node_sets(n, b) != Some(prefers_sets) {
            inverted_laws.push((NodeIndex::new(n as usize), port));
            diags.push(inverted_law(&cx, n, b, prefers_sets));
        }
    }

    diags.sort_by_key(|x| x.code);
    let consistent = !crate::diagnostic::has_errors(&diags);
    let effort_set_by = a
        .engine
        .effort_from
        .iter()
        .map(|f| {
            if *f == Some(false) {
                End::To
            } else {
                End::From
            }
        })
        .collect();
    (
        Causality {
            effort_set_by,
            storage,
            loops,
            arbitrary,
            hints,
            inverted_laws,
            consistent,
        },
        diags,
    )
}

/// BG0501, BG0502, BG0503 or BG0541 for a violated constraint.
fn conflict(cx: &Ctx, c: Conflict, hints_in_conflict: &mut BTreeSet<u32>) -> Diagnostic {
    let e = cx.engine;
    let role = e.roles.get(c.node as usize).copied().unwrap_or(Role::Free);
    if matches!(role, Role::EffortSource | Role::FlowSource) {
        return forced_source(cx, c, role, hints_in_conflict);
    }
    // The bonds whose causality meets at the node.
    let bonds: Vec<u32> = match role {
        Role::Zero | Role::One => {
            let strong_sets = role == Role::One;
            let strong: Vec<u32> = e
                .incident(c.node)
                .iter()
                .copied()
                .filter(|&b| e.node_sets(c.node, b) == Some(strong_sets))
                .collect();
            if strong.len() > 1 {
                strong
            } else {
                e.incident(c.node).to_vec()
            }
        }
        _ => e.incident(c.node).to_vec(),
    };
    let origins: Vec<(u32, Reason)> = bonds.iter().map(|&b| cx.origin(b)).collect();
    let mut sources: Vec<u32> = Vec::new();
    for &(n, r) in &origins {
        if matches!(r, Reason::Source(_)) && !sources.contains(&n) {
            sources.push(n);
        }
    }
    let hint_bonds: Vec<u32> = bonds
        .iter()
        .map(|&b| cx.first[b as usize])
        .filter(|&first| e.reason[first as usize] == Reason::FixedHint)
        .collect();
    let what = match role {
        Role::Zero => "effort",
        Role::One => "flow",
        _ => "causality",
    };
    let mut d = if let Some(&hb) = hint_bonds.first() {
        hints_in_conflict.extend(hint_bonds.iter().copied());
        Diagnostic::error(
            "BG0541",
            format!(
                "the fixed causality hint on bond `{}` cannot be met: it over-determines {}",
                cx.bond_name(hb),
                cx.describe(c.node)
            ),
        )
        .with_primary(cx.bond_span(hb), "fixed hint")
        .with_secondary(cx.node_span(c.node), "over-determined here")
        .with_help("remove the hint or change it to a preference (`stroke` instead of `stroke!`)")
    } else if sources.len() >= 2 {
        Diagnostic::error(
            "BG0501",
            format!(
                "{} and {} both impose the {what} of {}",
                cx.describe(sources[0]),
                cx.describe(sources[1]),
                cx.describe(c.node)
            ),
        )
        .with_primary(cx.node_span(c.node), format!("{what} imposed twice"))
        .with_help(
            "remove one of the sources, or put a storage or resistive element between them so that each \
             imposes its variable on its own element",
        )
    } else {
        let detail = match role {
            Role::Zero | Role::One
                if bonds.len() > 1 && e.incident(c.node).len() != bonds.len() =>
            {
                format!("more than one bond imposes its {what}")
            }
            Role::Zero | Role::One => format!("no bond imposes its {what}"),
            Role::Transformer => {
                let imposed = e
                    .incident(c.node)
                    .iter()
                    .filter(|&&b| e.node_sets(c.node, b) == Some(false))
                    .count();
                if imposed >= 2 {
                    "both of its ports have their effort imposed".to_string()
                } else {
                    "both of its ports have their flow imposed".to_string()
                }
            }
            _ => "one of its ports has its effort imposed and the other its flow".to_string(),
        };
        Diagnostic::error(
            "BG0502",
            format!("{} is over-determined: {detail}", cx.describe(c.node)),
        )
        .with_primary(cx.node_span(c.node), "over-determined")
        .with_help(
            "the elements around it impose incompatible variables: remove one of them, or add a storage \
             element (a compliance on a 0-junction, an inertia on a 1-junction) to absorb the difference",
        )
    };
    for &b in bonds.iter().take(3) {
        d = cx.path_labels(d, b);
    }
    d
}

/// A source whose bond the rest of the graph assigns against it.
fn forced_source(cx: &Ctx, c: Conflict, role: Role, hints: &mut BTreeSet<u32>) -> Diagnostic {
    let e = cx.engine;
    let (origin, reason) = cx.origin(c.bond);
    let mine = if role == Role::EffortSource {
        "effort"
    } else {
        "flow"
    };
    let (from, to) = e.ends[c.bond as usize];
    let neighbour = if from == c.node { to } else { from };
    let shared = matches!(
        (role, e.roles.get(neighbour as usize)),
        (Role::EffortSource, Some(Role::Zero)) | (Role::FlowSource, Some(Role::One))
    );
    let d = if matches!(reason, Reason::Source(_)) && shared {
        Diagnostic::error(
            "BG0501",
            format!(
                "{} and {} both impose the {mine} of {}",
                cx.describe(origin),
                cx.describe(c.node),
                cx.describe(neighbour)
            ),
        )
        .with_primary(cx.node_span(neighbour), format!("{mine} imposed twice"))
        .with_secondary(cx.node_span(c.node), format!("also imposes the {mine}"))
        .with_help(
            "remove one of the sources, or put a storage or resistive element between them so that each \
             imposes its variable on its own element",
        )
    } else {
        if reason == Reason::FixedHint {
            hints.insert(cx.first[c.bond as usize]);
        }
        Diagnostic::error(
            "BG0503",
            format!(
                "{} is forced into the wrong causality: {} imposes the {mine} on its bond",
                cx.describe(c.node),
                cx.describe(origin)
            ),
        )
        .with_primary(cx.node_span(c.node), format!("must set the {mine}"))
        .with_help(format!(
            "a source sets its {mine} whatever the rest of the graph does: remove the element that also \
             imposes it, or add a storage or resistive element between them"
        ))
    };
    cx.path_labels(d, c.bond)
}

/// BG0541 for a fixed hint the final causality does not meet.
fn violated_hint(cx: &Ctx, b: u32) -> Diagnostic {
    let (origin, _) = cx.origin(b);
    let d = Diagnostic::error(
        "BG0541",
        format!(
            "the fixed causality hint on bond `{}` cannot be met: {} decides the other way",
            cx.bond_name(b),
            cx.describe(origin)
        ),
    )
    .with_primary(cx.bond_span(b), "fixed hint violated")
    .with_help("remove the hint, change it to a preference (`stroke`), or move the stroke to the other end");
    cx.path_labels(d, b)
}

/// BG0540 for a hint that was honoured or overruled.
fn hint_note(cx: &Ctx, b: u32, h: &HintOutcome) -> Diagnostic {
    let kind = if h.fixed { "fixed" } else { "preferred" };
    if h.honoured {
        return Diagnostic::note_diag(
            "BG0540",
            format!(
                "the {kind} causality hint on bond `{}` is honoured",
                cx.bond_name(b)
            ),
        )
        .with_primary(cx.bond_span(b), "honoured")
        .with_help("nothing to do");
    }
    let mut d = Diagnostic::note_diag(
        "BG0540",
        format!(
            "the preferred causality hint on bond `{}` is overruled",
            cx.bond_name(b)
        ),
    )
    .with_primary(cx.bond_span(b), "overruled");
    if let Some(c) = cx.fallbacks.get(&b) {
        d = d.with_note(format!(
            "the hinted causality would over-determine {}",
            cx.describe(c.node)
        ));
    } else {
        let (origin, _) = cx.origin(b);
        d = d.with_note(format!("{} decides the other way", cx.describe(origin)));
        d = cx.path_labels(d, b);
    }
    d.with_help("make it fixed (`stroke!`) to turn it into a requirement, or remove it")
}

/// BG0510 for a storage port in derivative causality.
fn derivative(cx: &Ctx, n: u32, b: u32, kind: StorageKind) -> Diagnostic {
    let (what, var) = match kind {
        StorageKind::I => ("inertia", "flow"),
        StorageKind::C => ("compliance", "effort"),
    };
    let name = cx.name(n);
    let (origin, reason) = cx.origin(b);
    let through: Vec<String> = cx
        .path_nodes(b)
        .into_iter()
        .skip(1)
        .filter(|&m| m != n && m != origin)
        .map(|m| cx.describe(m))
        .collect();
    let shortened = cx.path(b).1 > cx.path(b).0.len();
    let across = match (through.is_empty(), shortened) {
        (true, _) => String::new(),
        (false, false) => format!(" across {}", through.join(", ")),
        (false, true) => format!(" across ..., {}", through.join(", ")),
    };
    let fallback = cx.fallbacks.get(&b).copied();
    let (imposer, help) = match (fallback, reason, cx.kind(origin)) {
        (Some(c), _, _) => (
            format!(
                "integral causality would over-determine {}",
                cx.describe(c.node)
            ),
            "add a storage or resistive element so that the junction structure can take it in integral \
             causality"
                .to_string(),
        ),
        (None, Reason::FixedHint | Reason::PreferredHint, _) => {
            let first = cx.first[b as usize];
            (
                format!(
                    "its {var} is imposed by the causality hint on bond `{}`{across}",
                    cx.bond_name(first)
                ),
                format!(
                    "this is what the hint asks for; remove or move the hint to let `{name}` take integral \
                     causality"
                ),
            )
        }
        (None, Reason::Storage(_), _) => (
            format!("its {var} is imposed by {}{across}", cx.describe(origin)),
            match kind {
                StorageKind::I => format!(
                    "`{name}` and `{}` are rigidly coupled: merge them into one inertia (referred through \
                     any transformer ratio squared), or add a compliance (a shaft or belt stiffness) between them",
                    cx.name(origin)
                ),
                StorageKind::C => format!(
                    "`{name}` and `{}` share one effort: merge them into one compliance, or add a resistance \
                     or an inertia between them",
                    cx.name(origin)
                ),
            },
        ),
        (None, Reason::Source(_), _) => (
            format!("its {var} is imposed by {}{across}", cx.describe(origin)),
            format!(
                "the source prescribes `{name}`'s {var}, so `{name}` adds no state and the source must be \
                 differentiable; if that is not intended, add a {} between `{}` and `{name}`, or drive it \
                 with {} instead",
                if kind == StorageKind::I {
                    "compliance"
                } else {
                    "resistance or an inertia"
                },
                cx.name(origin),
                if kind == StorageKind::I {
                    "an effort source"
                } else {
                    "a flow source"
                },
            ),
        ),
        _ => (
            format!("its {var} is imposed by {}{across}", cx.describe(origin)),
            "add a storage element between them, or move the causality hint that imposes it".to_string(),
        ),
    };
    let d = Diagnostic::warning(
        "BG0510",
        format!("{what} `{name}` is in derivative causality: {imposer}"),
    )
    .with_primary(cx.node_span(n), "derivative causality")
    .with_note(format!(
        "the model stays usable: `{name}` contributes no independent state"
    ))
    .with_help(help);
    cx.path_labels(d, b)
}

/// BG0520 for an algebraic loop.
fn algebraic_loop(cx: &Ctx, l: &[NodeIndex]) -> Diagnostic {
    let names: Vec<String> = l
        .iter()
        .map(|n| format!("`{}`", cx.name(n.index() as u32)))
        .collect();
    let first = l.first().map_or(0, |n| n.index() as u32);
    let mut d = Diagnostic::warning(
        "BG0520",
        format!(
            "zero-order causal path (algebraic loop) through {}",
            names.join(" -> ")
        ),
    )
    .with_primary(cx.node_span(first), "(1) the loop starts here");
    for (i, n) in l.iter().enumerate().skip(1) {
        d = d.with_secondary(
            cx.node_span(n.index() as u32),
            format!("({}) `{}`", i + 1, cx.name(n.index() as u32)),
        );
    }
    d.with_note("the equations of these elements depend on each other without an integration between them")
        .with_help(
            "the equations stage must solve this loop as an implicit algebraic equation; to remove it, add a \
             small storage element on the loop (a parasitic compliance or inertia), or choose other resistor \
             causalities with `stroke` hints",
        )
}

/// BG0530 for an arbitrary choice.
fn arbitrary_note(cx: &Ctx, n: u32, b: u32) -> Diagnostic {
    let e = cx.engine;
    let setter = if e.effort_from[b as usize] == Some(false) {
        e.ends[b as usize].1
    } else {
        e.ends[b as usize].0
    };
    let is_r = matches!(cx.kind(n), Some(ElementKind::R | ElementKind::RF));
    let (span, label, choice) = if is_r {
        let form = if setter == n {
            "resistance causality: it sets the effort"
        } else {
            "conductance causality: it sets the flow"
        };
        (
            cx.node_span(n),
            "causality chosen arbitrarily",
            format!("`{}` takes {form}", cx.name(n)),
        )
    } else {
        (
            cx.bond_span(b),
            "causality chosen arbitrarily",
            format!("`{}` sets the effort", cx.name(setter)),
        )
    };
    let subject = if is_r {
        format!("the causality of {}", cx.describe(n))
    } else {
        format!("the causality of bond `{}`", cx.bond_name(b))
    };
    Diagnostic::note_diag(
        "BG0530",
        format!("{subject} is an arbitrary choice: nothing in the graph decides it"),
    )
    .with_primary(span, label)
    .with_note(format!("chosen: {choice}"))
    .with_help("add a causality hint (`stroke NODE`) on the bond to make the choice yourself")
}

/// BG0531 for a resistor law that its causality makes the other way round.
fn inverted_law(cx: &Ctx, n: u32, b: u32, prefers_sets: bool) -> Diagnostic {
    let (form, given) = if prefers_sets {
        ("e = g(f)", "its effort")
    } else {
        ("f = g(e)", "its flow")
    };
    let (origin, _) = cx.origin(b);
    let d = Diagnostic::note_diag(
        "BG0531",
        format!(
            "the law of resistor `{}` is written `{form}` but the graph imposes {given}: the law must be inverted",
            cx.name(n)
        ),
    )
    .with_primary(cx.node_span(n), "law used the other way round")
    .with_note(format!("{} decides its causality", cx.describe(origin)))
    .with_help("write the law in the other form if it has a closed-form inverse");
    cx.path_labels(d, b)
}
