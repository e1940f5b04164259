//! Models that bgc accepts must give code that rustc and rustdoc accept: parameter names that are also the names
//! of the generated `Params` methods, and descriptions with text that means something to rustdoc (code fences,
//! indented code blocks). Bidirectional overrides, which rustc refuses in comments, are refused in strings by
//! the lexer (BG0104), as rustc refuses them in its literals.

use crate::codegen_support;

use bgc::codegen::rust::Options;
use codegen_support::rustc::{compile_no_std, document_no_std, stand_ins};
use codegen_support::{generate_text, scratch};

/// Derived parameters named as the methods of `Params` (before: E0592 "duplicate definitions"), descriptions with
/// ```` ``` ````, `~~~` and a leading indent (before: a code fence or block that `cargo test --doc` compiled as
/// Rust).
const HOSTILE: &str = "model m {
    domain translational;
    param m0 = 2 [kg] \"a mass\";
    param get = 2 * m0 [kg] \"```\";
    param set = get + m0 [kg] \"~~~~\";
    param validate = set * 1 [kg] \"    fn main() { assert!(false) }\";
    param default = validate [kg] \"``not a fence`` but ```this is```\";
    param clone = default [kg] \"isolated\";
    param fmt = clone [kg];
    param eq = fmt [kg];
    input F [N] \"```rust\";
    Se push = F;
    I mass = eq;
    1 v;
    bond push -> v -> mass;
}
";

fn doc_texts(code: &str) -> Vec<&str> {
    code.lines()
        .filter_map(|l| l.trim_start().strip_prefix("///"))
        .map(str::trim)
        .collect()
}

#[test]
fn hostile_names_and_descriptions_give_code_rustc_and_rustdoc_accept() {
    for runtime in [false, true] {
        let code = generate_text("hostile.bg", HOSTILE, Options { runtime });
        for doc in doc_texts(&code) {
            assert!(
                !(doc.starts_with("```") || doc.starts_with("~~~")),
                "a code fence: {doc}"
            );
        }
        // Four spaces after `///` (an indented code block) never come from a description.
        assert!(!code.contains("///     fn main()"), "{code}");
        assert!(code.contains("/// \\`\\`\\`\n"), "{code}");
        assert!(
            code.contains("``not a fence`` but \\`\\`\\`this is\\`\\`\\`"),
            "{code}"
        );
        // The methods keep their names; the derived parameters get a `_` suffix, as keywords do.
        for method in ["get", "set", "validate"] {
            assert_eq!(
                code.matches(&format!("pub fn {method}(")).count(),
                1,
                "{method}"
            );
        }
        for derived in [
            "get_",
            "set_",
            "validate_",
            "default_",
            "clone_",
            "fmt_",
            "eq_",
        ] {
            assert!(
                code.contains(&format!("pub fn {derived}(&self) -> f64")),
                "{derived}\n{code}"
            );
        }
    }
    let dir = scratch("hostile-names");
    stand_ins(&dir);
    let code = generate_text("hostile.bg", HOSTILE, Options { runtime: false });
    let compiled = compile_no_std(&dir, "hostile", &code);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(compiled.is_ok(), "{}", compiled.err().unwrap_or_default());
}

/// Documentation of the model file as engineers write it: units in brackets, symbols in angle brackets, a code
/// fence. rustdoc read `[kg]` as an unresolved intra-doc link and `<m>` as an unclosed HTML tag (errors under
/// `RUSTDOCFLAGS=-D warnings`), and compiled and ran the fenced example as a doctest of the user's crate.
const MARKDOWN_DOCS: &str =
    "/// A rig <b>after</b> [1], [the paper](https://example.org/p) and <https://example.org>.
///
/// `[kg]` and `<T>` as code stay as they are.
///
/// An unclosed ` backtick, then [kg] again.
///
/// ```
/// fn main() { panic!(\"a doctest\") }
/// ```
///
/// ```bg
/// param m = 1 [kg];
/// ```
model m {
    domain translational;
    /// The mass <m> [kg], after [Smith 2020]
    param m0 = 2 [kg] \"mass <m> [kg] of [`Params`]\";
    input F [N];
    Se push = F;
    I mass = m0;
    bond push -> mass;
}
";

#[test]
fn markdown_of_the_model_file_is_literal_for_rustdoc_and_no_doctest() {
    let code = generate_text("docs.bg", MARKDOWN_DOCS, Options { runtime: false });
    for expected in [
        "/// A rig \\<b>after\\</b> \\[1\\], [the paper](https://example.org/p) and <https://example.org>.",
        "/// `[kg]` and `<T>` as code stay as they are.\n",
        "/// An unclosed ` backtick, then \\[kg\\] again.\n",
        "/// ```text\n/// fn main()",
        "/// ```bg\n/// param m = 1 [kg];\n/// ```",
        "/// The mass \\<m> \\[kg\\], after \\[Smith 2020\\]",
        "mass \\<m> \\[kg\\] of \\[`Params`\\]",
    ] {
        assert!(code.contains(expected), "{expected}\n{code}");
    }
    let dir = scratch("markdown-docs");
    stand_ins(&dir);
    let documented = document_no_std(&dir, "docs", &code);
    let _ = std::fs::remove_dir_all(&dir);
    let (doc, tests) = documented.unwrap_or_else(|e| panic!("{e}"));
    assert!(!doc.contains("warning"), "{doc}");
    assert!(tests.contains("running 0 tests"), "{tests}");
}

/// The `@generated` header names the source relative to the crate, with `/`, so two checkouts in different
/// directories generate the same bytes.
#[test]
fn the_generated_header_is_the_same_from_two_checkouts() {
    let root = scratch("checkouts");
    let text = "model osc { domain translational; param k = 800 [N/m]; input F [N]; Se push = F; C spring = 1/k; 1 v; bond push -> v -> spring; }\n";
    let mut outputs = Vec::new();
    for checkout in ["one", "two/deeper"] {
        let crate_dir = root.join(checkout);
        let model = crate_dir.join("models/osc.bg");
        std::fs::create_dir_all(model.parent().unwrap_or(&crate_dir))
            .unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&model, text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            bgc::build::header_name(&model, Some(&crate_dir)),
            "models/osc.bg"
        );
        let generated = bgc::build::Config::new()
            .out_dir(crate_dir.join("out"))
            .cargo_output(false)
            .compile(&[&model]);
        let generated = generated.unwrap_or_else(|e| panic!("{e}"));
        outputs.push(std::fs::read_to_string(&generated[0].output).unwrap_or_default());
    }
    let _ = std::fs::remove_dir_all(&root);
    // Under Cargo the crate is `CARGO_MANIFEST_DIR`, which is not these directories: the name falls back to the
    // path as given, absolute here. Relative to a base it is the same in both.
    let first_line = |s: &str| s.lines().next().unwrap_or_default().to_string();
    assert!(
        first_line(&outputs[0]).starts_with("// @generated by bgc "),
        "{}",
        outputs[0]
    );
    let bodies: Vec<String> = outputs
        .iter()
        .map(|o| o.lines().skip(1).collect::<Vec<_>>().join("\n"))
        .collect();
    assert_eq!(bodies[0], bodies[1]);
    assert_eq!(
        bgc::build::header_name(std::path::Path::new("./models/../models/./osc.bg"), None),
        "models/osc.bg"
    );
}
