//! The examples of docs/language.md are in the canonical layout of `bgc fmt`, and parse.
//!
//! A block that is a whole file is formatted as it stands; a block of statements (an element, a law, a bond) is
//! formatted inside a model and compared without the model's lines and indent.

use bgc::span::FileId;

fn examples() -> Vec<(usize, String)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/language.md");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        match (&mut current, line) {
            (None, "```bg") => current = Some((i + 2, String::new())),
            (Some(_), "```") => out.extend(current.take()),
            (Some((_, block)), l) => {
                block.push_str(l);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    assert!(current.is_none(), "an unclosed ```bg block");
    out
}

fn formatted(text: &str) -> Option<String> {
    let (ast, diags) = bgc::syntax::parse(FileId(0), text);
    (!bgc::diagnostic::has_errors(&diags) && !ast.items.is_empty())
        .then(|| bgc::syntax::format(&ast))
}

#[test]
fn language_examples_are_in_the_canonical_layout() {
    let blocks = examples();
    assert!(blocks.len() >= 12, "only {} examples found", blocks.len());
    let mut wrong = Vec::new();
    for (line, block) in &blocks {
        if let Some(f) = formatted(block) {
            if f != *block {
                wrong.push(format!(
                    "docs/language.md:{line}: a file\n--- as written\n{block}--- canonical\n{f}"
                ));
            }
            continue;
        }
        let indented: String = block
            .lines()
            .map(|l| {
                if l.is_empty() {
                    "\n".to_string()
                } else {
                    format!("    {l}\n")
                }
            })
            .collect();
        let wrapped = format!("model doc_example {{\n{indented}}}\n");
        let Some(f) = formatted(&wrapped) else {
            wrong.push(format!(
                "docs/language.md:{line}: does not parse, alone or inside a model\n{block}"
            ));
            continue;
        };
        if f != wrapped {
            let inner: String = f
                .lines()
                .skip(1)
                .take(f.lines().count().saturating_sub(2))
                .map(|l| format!("{}\n", l.strip_prefix("    ").unwrap_or(l)))
                .collect();
            wrong.push(format!(
                "docs/language.md:{line}: statements\n--- as written\n{block}--- canonical\n{inner}"
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
