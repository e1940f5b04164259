//! The findings a model acknowledges with `allow CODE NODE;` (see `lower::allow`) are left out of the causality
//! stage's diagnostics; an `allow` that matches no finding is itself a warning (`BG0542`).
//!
//! A finding matches when its code is the allowed one, its primary label is at the node's declaration and its
//! message names the node (qualified, as `g.inertia`): two instances of one component share the declaration, so
//! the name tells them apart.

use crate::diagnostic::{Diagnostic, Severity};
use crate::ir::{Allowance, Model};
use petgraph::graph::NodeIndex;

/// `diags` without the acknowledged warnings, plus a warning for each `allow` that matched nothing.
pub(super) fn apply(model: &Model, diags: Vec<Diagnostic>) -> Vec<Diagnostic> {
    let allowed = &model.spans.allowed;
    if allowed.is_empty() {
        return diags;
    }
    let mut used = vec![false; allowed.len()];
    let mut out = Vec::with_capacity(diags.len());
    for d in diags {
        match allowed.iter().position(|a| matches(model, a, &d)) {
            Some(k) => used[k] = true,
            None => out.push(d),
        }
    }
    for (a, _) in allowed.iter().zip(&used).filter(|(_, used)| !**used) {
        let name = node_name(model, a);
        out.push(
            Diagnostic::warning(
                "BG0542",
                format!(
                    "`allow {} {name}` matches no finding: `{name}` has no {} warning",
                    a.code, a.code
                ),
            )
            .with_primary(a.span, "nothing to allow")
            .with_help("remove the `allow`, or name the element the finding is located at"),
        );
    }
    out
}

fn node_name<'m>(model: &'m Model, a: &Allowance) -> &'m str {
    model
        .graph
        .node_weight(NodeIndex::new(a.node))
        .map_or("?", |n| n.name.as_str())
}

fn matches(model: &Model, a: &Allowance, d: &Diagnostic) -> bool {
    d.severity == Severity::Warning
        && d.code.0 == a.code
        && d.primary_span().is_some()
        && d.primary_span() == model.spans.nodes.get(a.node).copied()
        && d.message.contains(&format!("`{}`", node_name(model, a)))
}
