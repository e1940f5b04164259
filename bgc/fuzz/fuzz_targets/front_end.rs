//! Any bytes through decode → parse → lower → causality → equations → Rust code: nothing may panic, hang or
//! overflow the stack, every error must be located inside the text, the rendered diagnostics stay bounded (at most
//! `render::MAX_SHOWN`, short excerpt lines), and the generated module has no bidirectional control, no doc line
//! that opens a code block and each `Params` method defined once. (Compiling generated code with rustc is too
//! slow for a fuzz loop: tests/codegen_hostile_names.rs and tests/codegen_no_std.rs compile samples.)
#![no_main]

use bgc::lower::SourceLoader;
use bgc::span::SourceMap;
use libfuzzer_sys::fuzz_target;

/// Imports resolve to nothing: the fuzzer explores one file at a time.
struct NoFiles;

impl SourceLoader for NoFiles {
    fn load(&mut self, _: &std::path::Path) -> std::io::Result<String> {
        Err(std::io::ErrorKind::NotFound.into())
    }
}

fuzz_target!(|data: &[u8]| {
    let mut sources = SourceMap::new();
    let Ok(text) = bgc::syntax::decode(bgc::span::FileId(0), data) else {
        return;
    };
    let id = sources.add("fuzz.bg", text);
    let (models, diags) = bgc::lower::lower(&mut sources, id, &mut NoFiles);
    for d in &diags {
        if let Some(span) = d.primary_span() {
            if span.file == id {
                assert!(span.end as usize <= data.len(), "label out of range: {d:?}");
            }
        }
    }
    let rendered = bgc::diagnostic::render::to_text(&sources, &diags, false);
    assert!(rendered.matches("error[").count() <= bgc::diagnostic::render::MAX_SHOWN);
    for line in rendered.lines().filter(|l| l.contains(" │ ")) {
        assert!(line.chars().count() <= 700, "an excerpt line of {} chars", line.chars().count());
    }
    if bgc::diagnostic::has_errors(&diags) {
        return;
    }
    let mut derived = true;
    for m in &models {
        let (causality, causal_diags) = bgc::causality::analyse(m);
        if bgc::diagnostic::has_errors(&causal_diags) {
            derived = false;
        } else {
            let (_, eq_diags) = bgc::equations::derive(m, &causality);
            derived &= !bgc::diagnostic::has_errors(&eq_diags);
        }
    }
    if !derived {
        return;
    }
    // `bgc rust`: the same compile and generation, checked for what rustc and rustdoc would refuse.
    let mut sources = SourceMap::new();
    let id = sources.add("fuzz.bg", text);
    if let Ok(compiled) = bgc::codegen::compile(&mut sources, id, &mut NoFiles) {
        for runtime in [true, false] {
            let options = bgc::codegen::rust::Options { runtime };
            let code = bgc::codegen::rust::generate_with(&compiled, "fuzz.bg", options);
            check_generated(&code);
        }
    }
});

fn check_generated(code: &str) {
    assert!(
        !code
            .chars()
            .any(|c| matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')),
        "a bidirectional control in generated code"
    );
    for line in code.lines() {
        if let Some(doc) = line.trim_start().strip_prefix("///") {
            let doc = doc.strip_prefix(' ').unwrap_or(doc);
            assert!(!doc.starts_with("```") && !doc.starts_with("~~~"), "a fence: {line}");
        }
    }
    for method in ["get", "set", "validate"] {
        assert!(code.matches(&format!("    pub fn {method}(")).count() <= 1, "`{method}` twice");
    }
}
