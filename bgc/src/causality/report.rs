//! The causality of a model as JSON (for tools) and as a readable text table.

use super::{Causality, End, StorageForm, StorageKind};
use crate::ir::Model;
use petgraph::graph::{EdgeIndex, NodeIndex};
use serde_json::{Value, json};

fn node_name(model: &Model, n: NodeIndex) -> String {
    model
        .graph
        .node_weight(n)
        .map_or_else(|| format!("node#{}", n.index()), |w| w.name.clone())
}

/// The name of a storage port: the element's name, with `[i]` (1-based, as in source) for fields.
fn port_name(model: &Model, n: NodeIndex, port: u32) -> String {
    let is_field = model
        .graph
        .node_weight(n)
        .is_some_and(|w| w.kind.is_field());
    if is_field {
        format!("{}[{}]", node_name(model, n), port + 1)
    } else {
        node_name(model, n)
    }
}

fn ends(model: &Model, e: EdgeIndex) -> (String, String) {
    match model.graph.edge_endpoints(e) {
        Some((a, b)) => (node_name(model, a), node_name(model, b)),
        None => (String::new(), String::new()),
    }
}

fn kind_name(k: StorageKind) -> &'static str {
    match k {
        StorageKind::C => "C",
        StorageKind::I => "I",
    }
}

fn form_name(f: StorageForm) -> &'static str {
    match f {
        StorageForm::Integral => "integral",
        StorageForm::Derivative => "derivative",
    }
}

/// The causality as JSON, with qualified names:
/// `{"model", "bonds": [{"from", "to", "name"?, "effort_set_by": "from"|"to", "effort_setter"}],
/// "storage": [{"element", "kind": "C"|"I", "port", "causality": "integral"|"derivative"}], "independent_states",
/// "loops": [[NAME, ...]], "arbitrary": [{"element", "bond"}], "hints": [{"bond", "fixed", "honoured"}],
/// "inverted_laws": [NAME, ...], "consistent", "diagnostics": diag_json}`.
/// `diag_json` is the rendered diagnostics (`diagnostic::render::to_json_value`), passed through unchanged.
pub fn to_json(model: &Model, c: &Causality, diag_json: Value) -> Value {
    let bonds: Vec<Value> = model
        .graph
        .edge_indices()
        .map(|e| {
            let (from, to) = ends(model, e);
            let by = c.effort_set_by.get(e.index()).copied().unwrap_or(End::From);
            let setter = if by == End::From { &from } else { &to };
            let mut v = json!({
                "from": from,
                "to": to,
                "effort_set_by": by.name(),
                "effort_setter": setter,
            });
            if let (Some(obj), Some(name)) = (v.as_object_mut(), &model.graph[e].name) {
                obj.insert("name".into(), json!(name));
            }
            v
        })
        .collect();
    let storage: Vec<Value> = c
        .storage
        .iter()
        .map(|s| {
            json!({
                "element": port_name(model, s.node, s.port),
                "kind": kind_name(s.kind),
                "port": s.port + 1,
                "causality": form_name(s.causality),
            })
        })
        .collect();
    let loops: Vec<Vec<String>> = c
        .loops
        .iter()
        .map(|l| l.iter().map(|&n| node_name(model, n)).collect())
        .collect();
    let arbitrary: Vec<Value> = c
        .arbitrary
        .iter()
        .map(|a| json!({"element": node_name(model, a.node), "bond": model.bond_name(a.bond)}))
        .collect();
    let hints: Vec<Value> = c
        .hints
        .iter()
        .map(|h| json!({"bond": model.bond_name(h.bond), "fixed": h.fixed, "honoured": h.honoured}))
        .collect();
    let inverted: Vec<String> = c
        .inverted_laws
        .iter()
        .map(|&(n, p)| port_name(model, n, p))
        .collect();
    json!({
        "model": model.name,
        "bonds": bonds,
        "storage": storage,
        "independent_states": c.independent_states(),
        "loops": loops,
        "arbitrary": arbitrary,
        "hints": hints,
        "inverted_laws": inverted,
        "consistent": c.consistent,
        "diagnostics": diag_json,
    })
}

fn table(out: &mut String, header: &[&str], rows: &[Vec<String>]) {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (w, cell) in widths.iter_mut().zip(r) {
            *w = (*w).max(cell.chars().count());
        }
    }
    // Each line is written straight into `out` (cells left-aligned and padded to their column's width in
    // characters, trailing blanks dropped): a formatted string per cell and per line is a large share of the time
    // on models with a hundred thousand bonds.
    let line = |out: &mut String, cells: &mut dyn Iterator<Item = &str>| {
        let start = out.len();
        out.push(' ');
        for (cell, w) in cells.zip(&widths) {
            out.push(' ');
            out.push_str(cell);
            let pad = w.saturating_sub(cell.chars().count());
            out.extend(std::iter::repeat_n(' ', pad));
        }
        let kept = out[start..].trim_end().len();
        out.truncate(start + kept);
        out.push('\n');
    };
    line(out, &mut header.iter().copied());
    let rule: Vec<String> = widths.iter().map(|w| "-".repeat(*w)).collect();
    line(out, &mut rule.iter().map(String::as_str));
    for r in rows {
        line(out, &mut r.iter().map(String::as_str));
    }
}

/// The causality as readable text: a table of bonds (who sets the effort, where the stroke is), a table of storage
/// ports, the number of independent states and the algebraic loops. Diagnostics are rendered separately.
pub fn to_text(model: &Model, c: &Causality) -> String {
    let mut out = format!("causality of model `{}`\n\nbonds\n", model.name);
    let rows: Vec<Vec<String>> = model
        .graph
        .edge_indices()
        .map(|e| {
            let (from, to) = ends(model, e);
            let by = c.effort_set_by.get(e.index()).copied().unwrap_or(End::From);
            let (setter, stroke) = if by == End::From {
                (from.clone(), to.clone())
            } else {
                (to.clone(), from.clone())
            };
            vec![model.bond_name(e), from, to, setter, stroke]
        })
        .collect();
    table(
        &mut out,
        &["bond", "from", "to", "effort set by", "stroke at"],
        &rows,
    );
    out.push_str("\nstorage\n");
    let rows: Vec<Vec<String>> = c
        .storage
        .iter()
        .map(|s| {
            vec![
                port_name(model, s.node, s.port),
                kind_name(s.kind).to_string(),
                form_name(s.causality).to_string(),
            ]
        })
        .collect();
    table(&mut out, &["element", "kind", "causality"], &rows);
    out.push_str(&format!(
        "\nindependent states: {} of {} storage ports\n",
        c.independent_states(),
        c.storage.len()
    ));
    if c.loops.is_empty() {
        out.push_str("algebraic loops: none\n");
    } else {
        out.push_str("algebraic loops:\n");
        for l in &c.loops {
            let names: Vec<String> = l.iter().map(|&n| node_name(model, n)).collect();
            out.push_str(&format!("  {}\n", names.join(" -> ")));
        }
    }
    if !c.arbitrary.is_empty() {
        let names: Vec<String> = c
            .arbitrary
            .iter()
            .map(|a| format!("{} ({})", node_name(model, a.node), model.bond_name(a.bond)))
            .collect();
        out.push_str(&format!("arbitrary choices: {}\n", names.join(", ")));
    }
    if !c.consistent {
        out.push_str("the causality is inconsistent: see the errors\n");
    }
    out
}
