//! `bgc statespace --sparse`: each matrix as its size and the coordinate triplets `[row, column, value]` of its
//! nonzero entries (0-based, row-major order), for models whose dense rows would be mostly zeros.

use serde_json::{Value, json};

/// The triplet form of a numeric state space evaluated sparse (what [`triplets`] makes of its dense form), marked
/// so that [`json`] and [`text`] take it as it is.
pub fn numeric_triplets(ss: &bgc::equations::SparseNumericStateSpace) -> Value {
    let matrix = |m: &bgc::equations::NumericSparse| {
        let entries: Vec<Value> = m
            .entries
            .iter()
            .map(|&(r, c, v)| json!([r, c, v]))
            .collect();
        // As the dense form counts them: a matrix without rows has no columns either.
        let cols = if m.rows == 0 { 0 } else { m.cols };
        json!({ "rows": m.rows, "cols": cols, "entries": entries })
    };
    json!({
        "states": ss.states, "inputs": ss.inputs, "outputs": ss.outputs,
        "A": matrix(&ss.a), "B": matrix(&ss.b), "C": matrix(&ss.c), "D": matrix(&ss.d),
        SPARSE_MARK: true,
    })
}

/// The key that marks a value already in triplet form.
const SPARSE_MARK: &str = "sparse";

/// The names and matrices of a state-space value, each matrix as `{"rows", "cols", "entries"}`.
fn triplets(v: &Value) -> Value {
    if v.get(SPARSE_MARK).is_some_and(|m| m == &Value::Bool(true)) {
        return v.clone();
    }
    let mut out = serde_json::Map::new();
    for k in ["states", "inputs", "outputs"] {
        out.insert(k.into(), v.get(k).cloned().unwrap_or(Value::Null));
    }
    for m in ["A", "B", "C", "D"] {
        out.insert(m.into(), matrix(v.get(m)));
    }
    Value::Object(out)
}

/// One dense matrix (rows of numbers, or of expressions as strings) as its size and nonzero entries.
fn matrix(m: Option<&Value>) -> Value {
    let rows: Vec<&Vec<Value>> = m
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_array)
        .collect();
    let cols = rows.first().map_or(0, |r| r.len());
    let mut entries = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            if !is_zero(x) {
                entries.push(json!([i, j, x]));
            }
        }
    }
    json!({ "rows": rows.len(), "cols": cols, "entries": entries })
}

/// A structural or numeric zero: `0` (or `-0`) as a number, `"0"` as an expression.
fn is_zero(x: &Value) -> bool {
    match x {
        Value::Number(n) => n.as_f64() == Some(0.0),
        Value::String(s) => s.trim() == "0",
        _ => false,
    }
}

/// The JSON form: the names, then each matrix's size and one triplet per line.
pub fn json(v: &Value) -> String {
    let t = triplets(v);
    let compact = |x: &Value| serde_json::to_string(x).unwrap_or_else(|_| "null".into());
    let mut out = String::from("{\n");
    for k in ["states", "inputs", "outputs"] {
        out.push_str(&format!("  \"{k}\": {},\n", compact(&t[k])));
    }
    let matrices = ["A", "B", "C", "D"];
    for (n, m) in matrices.iter().enumerate() {
        let entries: Vec<String> = t[*m]["entries"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|e| format!("      {}", compact(e)))
            .collect();
        let body = if entries.is_empty() {
            "[]".to_string()
        } else {
            format!("[\n{}\n    ]", entries.join(",\n"))
        };
        let sep = if n + 1 == matrices.len() { "" } else { "," };
        out.push_str(&format!(
            "  \"{m}\": {{\n    \"rows\": {},\n    \"cols\": {},\n    \"entries\": {body}\n  }}{sep}\n",
            t[*m]["rows"], t[*m]["cols"]
        ));
    }
    out.push_str("}\n");
    out
}

/// The text form: the names, then each matrix's size and one `row column value` line per nonzero entry.
pub fn text(v: &Value) -> String {
    let t = triplets(v);
    let mut out = super::model::names_text(&t);
    for m in ["A", "B", "C", "D"] {
        let entries = t[m]["entries"].as_array().cloned().unwrap_or_default();
        out.push_str(&format!(
            "\n{m}: {} x {}, {} nonzero\n",
            t[m]["rows"],
            t[m]["cols"],
            entries.len()
        ));
        for e in entries {
            let value = match &e[2] {
                Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            out.push_str(&format!("  {} {} {value}\n", e[0], e[1]));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nonzeros_become_triplets_in_row_major_order() {
        let dense = json!({
            "states": ["q", "p"], "inputs": ["F"], "outputs": ["x"],
            "A": [[0.0, -0.5], [800.0, -2.0]], "B": [[0.0], [1.0]], "C": [[1.0, 0.0]], "D": [[-0.0]],
        });
        let t = triplets(&dense);
        assert_eq!(
            t["A"],
            json!({"rows": 2, "cols": 2, "entries": [[0, 1, -0.5], [1, 0, 800.0], [1, 1, -2.0]]})
        );
        assert_eq!(
            t["B"],
            json!({"rows": 2, "cols": 1, "entries": [[1, 0, 1.0]]})
        );
        assert_eq!(t["D"], json!({"rows": 1, "cols": 1, "entries": []}));
        let text = text(&dense);
        assert!(
            text.contains("\nA: 2 x 2, 3 nonzero\n  0 1 -0.5\n  1 0 800.0\n  1 1 -2.0\n"),
            "{text}"
        );
        let parsed: Value = serde_json::from_str(&json(&dense)).expect("valid JSON");
        assert_eq!(parsed["A"], t["A"]);
        assert_eq!(parsed["states"], json!(["q", "p"]));
    }

    #[test]
    fn symbolic_zeros_are_left_out() {
        let dense = json!({"states": ["q"], "inputs": [], "outputs": [], "A": [["0", "-k/m"]], "B": [], "C": [], "D": []});
        let t = triplets(&dense);
        assert_eq!(t["A"]["entries"], json!([[0, 1, "-k/m"]]));
        assert_eq!(t["B"], json!({"rows": 0, "cols": 0, "entries": []}));
    }
}
