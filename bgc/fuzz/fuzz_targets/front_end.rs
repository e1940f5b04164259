//! Any bytes through decode → parse → lower → causality → equations: nothing may panic, hang or overflow the stack, and every
//! error must be located inside the text.
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
    if bgc::diagnostic::has_errors(&diags) {
        return;
    }
    for m in &models {
        let (causality, causal_diags) = bgc::causality::analyse(m);
        if !bgc::diagnostic::has_errors(&causal_diags) {
            let _ = bgc::equations::derive(m, &causality);
        }
    }
});
