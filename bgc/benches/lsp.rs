//! The language server's answer to a keystroke: from a `didChange` to the `publishDiagnostics` of that version
//! (parse, lower, causality and equations of the document, and the conversion of the findings), over an
//! in-memory connection. Two documents: models/back_support.bg, and a generated chain of 10,001 elements and
//! junctions (`Se -> 1 -> {I, R} -> 0 -> C -> 1 -> ...`, 2,000 stages).
//!
//! Each iteration changes a parameter's default (`1` <-> `2`), so every analysis is a full one. The time is that of
//! the first publication for the new version: for back_support all its diagnostics; for the chain, which is above
//! the server's size for deriving equations on the loop (`Options::background_above`), those of parse, lowering
//! and causality, while the equations follow from the worker thread.
//!
//! `lsp_references` times find-all-references of a parameter with 100,000 uses. `lsp_positions` times the positions
//! of the 20,000 declarations of a model written on one line. `fmt_check` times the unified diff of `bgc fmt --check` (shared with range formatting) on a file of 800,000
//! lines, 100,000 of them changed.

use criterion::{Criterion, criterion_group, criterion_main};
use lsp_server::{Connection, Message, Notification, Request, RequestId};
use lsp_types::notification::{
    DidChangeTextDocument, DidOpenTextDocument, Exit, Initialized, Notification as _,
    PublishDiagnostics,
};
use lsp_types::{Position, Range, TextDocumentContentChangeEvent, Uri};
use std::time::Duration;

const STAGES: usize = 2000;

fn chain() -> String {
    let mut out = String::from(
        "model chain {\n    domain translational;\n    param m = 1 [kg] \"mass of each stage\";\n    \
         param d = 1 [N s/m] \"damping of each stage\";\n    param k = 100 [N/m] \"stiffness of each stage\";\n    \
         input force [N] \"drive\";\n    Se src = force;\n",
    );
    let mut prev = "src".to_string();
    for i in 0..STAGES {
        out.push_str(&format!(
            "    1 v{i};\n    I m{i} = m;\n    R d{i} = d;\n    0 f{i};\n    C k{i} = 1 / k;\n    \
             bond {prev} -> v{i} -> m{i}, d{i}, f{i};\n    bond f{i} -> k{i};\n"
        ));
        prev = format!("f{i}");
    }
    out.push_str("}\n");
    out
}

struct Session {
    client: Connection,
    server: Option<std::thread::JoinHandle<bgc::lsp::Ended>>,
    uri: Uri,
    version: i32,
}

impl Session {
    fn start(name: &str, text: &str) -> Session {
        let (server_side, client) = Connection::memory();
        let server =
            std::thread::spawn(move || bgc::lsp::serve(&server_side, bgc::lsp::Options::default()));
        let init = Request::new(
            RequestId::from(1),
            "initialize".into(),
            serde_json::json!({ "processId": null, "rootUri": null, "capabilities": {} }),
        );
        client.sender.send(init.into()).expect("server running");
        client.receiver.recv().expect("initialize answered");
        let n = Notification::new(Initialized::METHOD.into(), serde_json::json!({}));
        client.sender.send(n.into()).expect("server running");
        let path = std::env::temp_dir().join("bgc-lsp-bench").join(name);
        let uri = bgc::lsp::files::path_to_uri(&path).expect("a file URI");
        let open = Notification::new(
            DidOpenTextDocument::METHOD.into(),
            serde_json::json!({ "textDocument": { "uri": uri, "languageId": "bg", "version": 1, "text": text } }),
        );
        client.sender.send(open.into()).expect("server running");
        let mut s = Session {
            client,
            server: Some(server),
            uri,
            version: 1,
        };
        s.wait(1);
        s
    }

    /// Waits for the diagnostics of a version; returns how many there are.
    fn wait(&mut self, version: i32) -> usize {
        self.wait_for(version, 1)
    }

    /// Waits for the `publications`-th publication of a version (a large document's front-end findings come
    /// first, the complete list with the equation stage's second); returns how many diagnostics it holds.
    fn wait_for(&mut self, version: i32, publications: usize) -> usize {
        let mut seen = 0;
        loop {
            let Ok(Message::Notification(n)) = self.client.receiver.recv() else {
                panic!("the server answers with notifications only here");
            };
            if n.method != PublishDiagnostics::METHOD {
                continue;
            }
            let p: lsp_types::PublishDiagnosticsParams =
                serde_json::from_value(n.params).expect("publishDiagnostics");
            if p.version == Some(version) {
                seen += 1;
                if seen == publications {
                    return p.diagnostics.len();
                }
            }
        }
    }

    /// Replaces one character at `at` and waits for the new diagnostics' `publications`-th publication.
    fn change(&mut self, at: Position, text: &str, publications: usize) -> usize {
        self.version += 1;
        let change = TextDocumentContentChangeEvent {
            range: Some(Range::new(at, Position::new(at.line, at.character + 1))),
            range_length: None,
            text: text.to_string(),
        };
        let n = Notification::new(
            DidChangeTextDocument::METHOD.into(),
            serde_json::json!({
                "textDocument": { "uri": self.uri, "version": self.version },
                "contentChanges": [change],
            }),
        );
        self.client.sender.send(n.into()).expect("server running");
        self.wait_for(self.version, publications)
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        let shutdown = Request::new(
            RequestId::from(2),
            "shutdown".into(),
            serde_json::Value::Null,
        );
        let _ = self.client.sender.send(shutdown.into());
        let _ = self.client.receiver.recv();
        let _ = self
            .client
            .sender
            .send(Notification::new(Exit::METHOD.into(), ()).into());
        if let Some(h) = self.server.take() {
            let _ = h.join();
        }
    }
}

/// The position of the first digit after `needle`.
fn digit_after(text: &str, needle: &str) -> Position {
    let at = text.find(needle).expect("needle") + needle.len();
    let line = text[..at].matches('\n').count() as u32;
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    Position::new(line, text[start..at].encode_utf16().count() as u32)
}

fn bench(c: &mut Criterion) {
    let back_support = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/back_support.bg"
    ))
    .expect("models/back_support.bg");
    let chain = chain();
    let mut group = c.benchmark_group("lsp_diagnostics_after_change");
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(10));
    // (name, text, the digit to change, which publication of a version to wait for): the chain's first
    // publication holds the front end's findings, its second the complete list with the equation stage's.
    for (name, text, needle, publications) in [
        ("back_support", back_support.as_str(), "param r_g = 16", 1),
        ("chain_10001_elements", chain.as_str(), "param d = ", 1),
        (
            "chain_10001_elements_complete",
            chain.as_str(),
            "param d = ",
            2,
        ),
    ] {
        let mut session = Session::start(&format!("{name}.bg"), text);
        let at = digit_after(text, needle);
        let mut flip = false;
        // The original digit is restored every second iteration; the findings stay those of a valid model.
        let original = &text[text.find(needle).expect("needle") + needle.len()..][..1];
        let expected = session.change(at, original, publications);
        group.bench_function(name, |b| {
            b.iter(|| {
                flip = !flip;
                let found = session.change(at, if flip { "2" } else { original }, publications);
                assert_eq!(found, expected);
            })
        });
    }
    group.finish();
}

/// `bgc fmt --check`'s diff of a model of 100,000 stages (800,000 lines) written with `1/k`, one line in eight
/// changed by the canonical layout's `1 / k`.
fn bench_format_diff(c: &mut Criterion) {
    let mut text = String::from(
        "model chain {\n    domain translational;\n    param m = 1 [kg];\n    param k = 1 [N/m];\n    Se src = 1;\n    1 v0;\n    bond src -> v0;\n",
    );
    for i in 0..100_000 {
        text.push_str(&format!(
            "    I m{i} = m;\n    bond v{i} -> m{i};\n    0 x{i};\n    C c{i} = 1/k;\n    bond v{i} -> x{i};\n    \
             bond x{i} -> c{i};\n    1 v{};\n    bond x{i} -> v{};\n",
            i + 1,
            i + 1
        ));
    }
    text.push_str("}\n");
    let formatted = bgc::syntax::format_source(bgc::span::FileId(0), &text).expect("a valid model");
    let mut group = c.benchmark_group("fmt_check");
    group.sample_size(10);
    group.bench_function("unified_diff_100k_changed_lines", |b| {
        b.iter(|| {
            bgc::lsp::line_diff::unified(&text, &formatted, "a.bg", "a.bg (canonical layout)")
        })
    });
    group.finish();
}

/// Find all references (and rename, which edits them) of a parameter that 100,000 elements use.
fn bench_references(c: &mut Criterion) {
    let mut text = String::from(
        "model chain {\n    domain translational;\n    param m = 1 [kg];\n    Se src = 1;\n    1 v0;\n    bond src -> v0;\n",
    );
    for i in 0..100_000 {
        text.push_str(&format!("    I m{i} = m;\n    bond v0 -> m{i};\n"));
    }
    text.push_str("}\n");
    let analysis = bgc::lsp::analysis::analyse_front(
        "/tmp/chain.bg",
        &text,
        &mut bgc::lower::MemoryLoader::new(),
    );
    let param = text.find("param m").expect("the parameter") + "param ".len();
    let (id, _) =
        bgc::lsp::navigation::symbol_at(&analysis, analysis.root, param).expect("a symbol");
    let key = bgc::lsp::navigation::key(&analysis, id).expect("a key");
    let mut group = c.benchmark_group("lsp_references");
    group.sample_size(10);
    group.bench_function("parameter_used_by_100k_elements", |b| {
        b.iter(|| {
            let found = bgc::lsp::navigation::references(&[&analysis], &key, true);
            assert_eq!(found.len(), 100_001);
        })
    });
    group.finish();
}

/// Every declaration's position in a generated model written on one line of 20,000 parameters (500 kB): each answer
/// about such a document (its diagnostics, its outline) converts thousands of byte offsets to positions.
fn bench_positions(c: &mut Criterion) {
    let mut text = String::from("model m { domain translational;");
    for i in 0..20_000 {
        text.push_str(&format!(" param p{i} = {i} [1];"));
    }
    text.push_str(" }\n");
    let offsets: Vec<usize> = text.match_indices("param").map(|(i, _)| i).collect();
    let index = bgc::lsp::lines::LineIndex::new(&text);
    let mut group = c.benchmark_group("lsp_positions");
    group.sample_size(10);
    group.bench_function("one_line_of_20k_parameters", |b| {
        b.iter(|| {
            let columns: u64 = offsets
                .iter()
                .map(|&o| u64::from(index.position(&text, o).character))
                .sum();
            assert!(columns > 0);
        })
    });
    group.finish();
}

criterion_group!(
    benches,
    bench,
    bench_format_diff,
    bench_references,
    bench_positions
);
criterion_main!(benches);
