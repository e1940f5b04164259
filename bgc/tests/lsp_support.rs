//! An in-process client of `bgc lsp` for the tests: the server runs on a thread over
//! `lsp_server::Connection::memory()`, the client sends requests and notifications and blocks on the answers.
//! Nothing sleeps: a receive waits for the server's message, with a long timeout only so that a broken server
//! fails the test instead of hanging it.
// Each test module uses a part of these.
#![allow(dead_code)]

use lsp_server::{Connection, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::Notification as _;
use lsp_types::{Position, PublishDiagnosticsParams, Range, TextDocumentContentChangeEvent, Uri};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::str::FromStr;
use std::thread::JoinHandle;
use std::time::Duration;

/// Only a guard against a server that never answers.
const GUARD: Duration = Duration::from_secs(120);

pub fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

pub fn back_support_path() -> PathBuf {
    std::fs::canonicalize(repo("models/back_support.bg")).expect("models/back_support.bg exists")
}

pub fn back_support_text() -> String {
    std::fs::read_to_string(back_support_path()).expect("models/back_support.bg is readable")
}

/// `models/back_support.bg` without its two `allow BG0510` lines, so that both derivative-causality findings are
/// reported.
pub fn back_support_unacknowledged() -> String {
    let text: String = back_support_text()
        .lines()
        .filter(|l| !l.trim_start().starts_with("allow "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(
        back_support_text().lines().count() - text.lines().count(),
        2
    );
    text
}

pub fn uri(path: &std::path::Path) -> Uri {
    bgc::lsp::files::path_to_uri(path).expect("an absolute UTF-8 path")
}

/// A path in a directory that does not exist: such documents live only in the editor (the server's overlay).
pub fn unsaved(name: &str) -> PathBuf {
    std::env::temp_dir()
        .join("bgc-lsp-tests-unsaved-documents")
        .join(name)
}

pub struct Client {
    connection: Connection,
    server: Option<JoinHandle<bgc::lsp::Ended>>,
    next_id: i32,
    /// Notifications received while waiting for a response.
    notifications: VecDeque<Notification>,
    pub initialize_result: serde_json::Value,
}

impl Client {
    /// Starts a server and completes `initialize` / `initialized`.
    pub fn start() -> Client {
        Client::start_with(bgc::lsp::Options::default())
    }

    pub fn start_with(options: bgc::lsp::Options) -> Client {
        let (server_side, client_side) = Connection::memory();
        let server = std::thread::spawn(move || bgc::lsp::serve(&server_side, options));
        let mut client = Client {
            connection: client_side,
            server: Some(server),
            next_id: 0,
            notifications: VecDeque::new(),
            initialize_result: serde_json::Value::Null,
        };
        let params = serde_json::json!({ "processId": null, "rootUri": null, "capabilities": {} });
        client.initialize_result = client
            .raw_request("initialize", params)
            .result
            .expect("initialize succeeds");
        client.notify::<lsp_types::notification::Initialized>(lsp_types::InitializedParams {});
        client
    }

    fn receive(&self) -> Message {
        self.connection
            .receiver
            .recv_timeout(GUARD)
            .expect("the server answers")
    }

    /// Sends a request by method name and waits for its response.
    pub fn raw_request(&mut self, method: &str, params: serde_json::Value) -> Response {
        self.next_id += 1;
        let id = RequestId::from(self.next_id);
        let request = Request::new(id.clone(), method.to_string(), params);
        self.connection
            .sender
            .send(request.into())
            .expect("the server is running");
        loop {
            match self.receive() {
                Message::Response(r) if r.id == id => return r,
                Message::Notification(n) => self.notifications.push_back(n),
                other => panic!("unexpected message {other:?}"),
            }
        }
    }

    /// A typed request; `Err` holds the error response's code and message.
    pub fn request<R: lsp_types::request::Request>(
        &mut self,
        params: R::Params,
    ) -> Result<R::Result, (i32, String)> {
        let params = serde_json::to_value(params).expect("parameters serialise");
        let response = self.raw_request(R::METHOD, params);
        if let Some(e) = response.error {
            return Err((e.code, e.message));
        }
        let value = response.result.unwrap_or(serde_json::Value::Null);
        Ok(serde_json::from_value(value).expect("the result has the protocol's shape"))
    }

    pub fn notify<N: lsp_types::notification::Notification>(&self, params: N::Params) {
        let n = Notification::new(N::METHOD.to_string(), params);
        self.connection
            .sender
            .send(n.into())
            .expect("the server is running");
    }

    pub fn open(&self, uri: &Uri, text: &str) {
        self.notify::<lsp_types::notification::DidOpenTextDocument>(
            lsp_types::DidOpenTextDocumentParams {
                text_document: lsp_types::TextDocumentItem::new(
                    uri.clone(),
                    "bg".into(),
                    1,
                    text.into(),
                ),
            },
        );
    }

    pub fn change(&self, uri: &Uri, version: i32, changes: Vec<TextDocumentContentChangeEvent>) {
        self.notify::<lsp_types::notification::DidChangeTextDocument>(
            lsp_types::DidChangeTextDocumentParams {
                text_document: lsp_types::VersionedTextDocumentIdentifier::new(
                    uri.clone(),
                    version,
                ),
                content_changes: changes,
            },
        );
    }

    /// Waits for the next publication of the diagnostics of `uri` at `version`; other notifications stay queued
    /// for later calls.
    pub fn diagnostics(&mut self, uri: &Uri, version: i32) -> Vec<lsp_types::Diagnostic> {
        loop {
            let found = self.notifications.iter().position(|n| {
                n.method == lsp_types::notification::PublishDiagnostics::METHOD
                    && serde_json::from_value::<PublishDiagnosticsParams>(n.params.clone())
                        .is_ok_and(|p| &p.uri == uri && p.version == Some(version))
            });
            if let Some(i) = found {
                let n = self
                    .notifications
                    .remove(i)
                    .expect("the notification found");
                let p: PublishDiagnosticsParams =
                    serde_json::from_value(n.params).expect("publishDiagnostics parameters");
                return p.diagnostics;
            }
            match self.receive() {
                Message::Notification(n) => self.notifications.push_back(n),
                other => panic!("unexpected message {other:?}"),
            }
        }
    }

    /// `shutdown` and `exit`; returns how the server says the session ended.
    pub fn shutdown(mut self) -> bgc::lsp::Ended {
        let response = self.raw_request("shutdown", serde_json::Value::Null);
        assert_eq!(response.result, Some(serde_json::Value::Null));
        self.notify::<lsp_types::notification::Exit>(());
        self.server
            .take()
            .expect("the server thread")
            .join()
            .expect("the server thread does not panic")
    }
}

pub fn position_params(uri: &Uri, position: Position) -> lsp_types::TextDocumentPositionParams {
    lsp_types::TextDocumentPositionParams::new(
        lsp_types::TextDocumentIdentifier::new(uri.clone()),
        position,
    )
}

/// The position of the `nth` (0-based) occurrence of `needle` in `text`, plus `shift` characters, counted in
/// UTF-16 units here independently of the server.
pub fn find(text: &str, needle: &str, nth: usize, shift: u32) -> Position {
    let offset = text
        .match_indices(needle)
        .nth(nth)
        .map(|(i, _)| i)
        .expect("the needle occurs");
    let before = &text[..offset];
    let line = before.matches('\n').count() as u32;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column: usize = text[line_start..offset].encode_utf16().count();
    Position::new(line, column as u32 + shift)
}

pub fn range(l0: u32, c0: u32, l1: u32, c1: u32) -> Range {
    Range::new(Position::new(l0, c0), Position::new(l1, c1))
}

pub fn edit(range: Range, text: &str) -> TextDocumentContentChangeEvent {
    TextDocumentContentChangeEvent {
        range: Some(range),
        range_length: None,
        text: text.to_string(),
    }
}

/// Applies text edits (non-overlapping, any order) to a text, positions in UTF-16 units.
pub fn apply(text: &str, edits: &[lsp_types::TextEdit]) -> String {
    let mut sorted: Vec<&lsp_types::TextEdit> = edits.iter().collect();
    sorted.sort_by_key(|e| std::cmp::Reverse((e.range.start.line, e.range.start.character)));
    let mut out = text.to_string();
    for e in sorted {
        let start = offset(&out, e.range.start);
        let end = offset(&out, e.range.end);
        out.replace_range(start..end, &e.new_text);
    }
    out
}

/// The byte offset of a UTF-16 position, computed by walking the characters.
pub fn offset(text: &str, p: Position) -> usize {
    let mut line = 0;
    let mut units = 0;
    for (i, c) in text.char_indices() {
        if line == p.line && (units >= p.character || c == '\n') {
            return i;
        }
        if c == '\n' {
            line += 1;
            units = 0;
        } else if line == p.line {
            units += c.len_utf16() as u32;
        }
    }
    text.len()
}

pub fn code(d: &lsp_types::Diagnostic) -> String {
    match &d.code {
        Some(lsp_types::NumberOrString::String(s)) => s.clone(),
        Some(lsp_types::NumberOrString::Number(n)) => n.to_string(),
        None => String::new(),
    }
}

pub fn parse_uri(s: &str) -> Uri {
    Uri::from_str(s).expect("a URI")
}
