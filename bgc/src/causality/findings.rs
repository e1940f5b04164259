//! From an assignment to the public result and its diagnostics (codes in the module docs of [`super`]).

use super::conflicts::{conflict, violated_hint};
use super::context::Ctx;
use super::engine::{Conflict, Reason};
use super::scap::{Assignment, storage_ports};
use super::{
    ArbitraryChoice, Causality, End, HintOutcome, StorageCausality, StorageForm, StorageKind,
};
use crate::diagnostic::Diagnostic;
use crate::ir::Model;
use crate::syntax::ast::ElementKind;
use petgraph::graph::{EdgeIndex, NodeIndex};
use std::collections::BTreeSet;

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
