//! Diagnostics located inside a component of another file (the standard library, an imported file): each also
//! points at the instance in the model's own file that brought the component in, so that a finding at
//! `bgc/std/std.bg:67:5` says which `gearbox` of the user's model it is about.

use crate::diagnostic::{Diagnostic, Label};
use crate::ir::Model;
use crate::span::Span;

fn contains(outer: Span, inner: Span) -> bool {
    outer.file == inner.file && outer.start <= inner.start && inner.end <= outer.end
}

/// Adds to each diagnostic whose primary label lies in a node declared by a component instance in another file a
/// secondary label at that instance (`in instance `gb`, declared here`), unless a label already marks it.
pub fn add_instance_context(model: &Model, diags: &mut [Diagnostic]) {
    let spans = &model.spans;
    for d in diags.iter_mut() {
        let Some(primary) = d.labels.iter().find(|l| l.primary).map(|l| l.span) else {
            continue;
        };
        let node = spans
            .nodes
            .iter()
            .enumerate()
            .find(|(_, s)| contains(**s, primary))
            .map(|(i, _)| i);
        let Some(i) = node else { continue };
        let Some(Some(instance)) = spans.node_instances.get(i).copied() else {
            continue;
        };
        if instance.file == primary.file || d.labels.iter().any(|l| contains(instance, l.span)) {
            continue;
        }
        let name = model
            .graph
            .node_weights()
            .nth(i)
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
