//! Diagnostics located inside a component of another file (the standard library, an imported file): each also
//! points at the instance in the model's own file that brought the component in, so that a finding at
//! `bgc/std/std.bg:67:5` says which `gearbox` of the user's model it is about.

use crate::diagnostic::{Diagnostic, Label};
use crate::ir::Model;
use crate::span::Span;

fn contains(outer: Span, inner: Span) -> bool {
    outer.file == inner.file && outer.start <= inner.start && inner.end <= outer.end
}

/// The first node (in node order) of `place` whose declaration contains `primary`. `place` holds the nodes declared
/// at one place, sorted by span and then node: one declaration in a component has a node per instance (30,000 of
/// them), so its run of equal spans is stepped over by a binary search, not scanned (a scan per diagnostic was
/// quadratic).
fn first_containing(place: &[(Span, usize)], primary: Span) -> Option<usize> {
    let mut best: Option<usize> = None;
    let mut at = 0;
    while let Some(&(span, node)) = place.get(at) {
        if contains(span, primary) {
            best = Some(best.map_or(node, |b| b.min(node)));
        }
        at += place[at..].partition_point(|&(s, _)| s == span).max(1);
    }
    best
}

/// Adds to each diagnostic whose primary label lies in a node declared by a component instance in another file a
/// secondary label at that instance (`in instance `gb`, declared here`), unless a label already marks it.
pub fn add_instance_context(model: &Model, diags: &mut [Diagnostic]) {
    let spans = &model.spans;
    if !spans.node_instances.iter().any(Option::is_some) {
        return;
    }
    // The declarations by place, each span with the nodes declared there in node order (one per instance of a
    // component): a diagnostic finds its node by binary search, not by a scan of every node (a scan per diagnostic
    // took minutes on a model with an error in each of 300,000 elements).
    let key = |s: Span| (s.file.0, s.start);
    let mut by_place: Vec<(Span, usize)> = spans.nodes.iter().copied().zip(0..).collect();
    by_place.sort_by_key(|&(s, i)| (key(s), s.end, i));
    for d in diags.iter_mut() {
        let Some(primary) = d.labels.iter().find(|l| l.primary).map(|l| l.span) else {
            continue;
        };
        // Declarations do not overlap: the one that can contain `primary` starts last at or before it, and of the
        // nodes declared there the first in node order is the one a scan would find.
        let after = by_place.partition_point(|&(s, _)| key(s) <= key(primary));
        let Some(&(last, _)) = after.checked_sub(1).and_then(|k| by_place.get(k)) else {
            continue;
        };
        let first = by_place.partition_point(|&(s, _)| key(s) < key(last));
        let Some(i) = first_containing(&by_place[first..after], primary) else {
            continue;
        };
        let Some(Some(instance)) = spans.node_instances.get(i).copied() else {
            continue;
        };
        if instance.file == primary.file || d.labels.iter().any(|l| contains(instance, l.span)) {
            continue;
        }
        let name = model
            .graph
            .node_weight(petgraph::graph::NodeIndex::new(i))
            .map(|n| n.name.clone())
            .unwrap_or_default();
        let prefix = name
            .rsplit_once('.')
            .map(|(p, _)| p)
            .unwrap_or(&name)
            .to_string();
        d.labels.push(Label {
            span: instance,
            message: format!("in instance `{prefix}` (the element `{name}`), declared here"),
            primary: false,
            replacement: None,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::first_containing;
    use crate::span::{FileId, Span};

    #[test]
    fn the_first_node_whose_declaration_contains_the_label_is_found_among_many() {
        let span = |start, end| Span::new(FileId(0), start, end);
        // At one place: a short declaration with 10,000 nodes (one per instance), a longer one with two.
        let mut place: Vec<(Span, usize)> =
            (0..10_000).map(|i| (span(10, 20), 2 * i + 7)).collect();
        place.extend([(span(10, 40), 5), (span(10, 40), 30_000)]);
        place.sort_by_key(|&(s, i)| (s.end, i));
        assert_eq!(first_containing(&place, span(12, 14)), Some(5));
        assert_eq!(first_containing(&place, span(25, 30)), Some(5));
        assert_eq!(first_containing(&place, span(45, 50)), None);
        let short: Vec<(Span, usize)> = (0..3).map(|i| (span(10, 20), i + 1)).collect();
        assert_eq!(first_containing(&short, span(15, 16)), Some(1));
        assert_eq!(first_containing(&[], span(15, 16)), None);
    }
}
