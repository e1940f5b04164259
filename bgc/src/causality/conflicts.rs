//! Conflicts: constraints of the junction structure that cannot all be met (BG0501, BG0502, BG0503, BG0541).

use super::context::Ctx;
use super::engine::{Conflict, Reason, Role};
use crate::diagnostic::Diagnostic;
use std::collections::BTreeSet;

/// BG0501, BG0502, BG0503 or BG0541 for a violated constraint.
pub fn conflict(cx: &Ctx, c: Conflict, hints_in_conflict: &mut BTreeSet<u32>) -> Diagnostic {
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
pub fn violated_hint(cx: &Ctx, b: u32) -> Diagnostic {
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
