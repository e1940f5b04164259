//! `bgc lsp` as editors run it: a child process speaking JSON-RPC with `Content-Length` framing on its standard
//! input and output.

use crate::lsp_support::{back_support_path, back_support_unacknowledged, uri};
use std::io::Write;
use std::process::{Command, Stdio};

fn frame(message: &serde_json::Value) -> Vec<u8> {
    let body = message.to_string();
    format!("Content-Length: {}\r\n\r\n{body}", body.len()).into_bytes()
}

/// Runs `bgc ARGS` with the framed `session` on its standard input and returns what it wrote and its status. A
/// server may stop reading at a protocol violation: a closed pipe is part of the outcome, which the caller checks.
fn serve(args: &[&str], session: &[serde_json::Value]) -> std::process::Output {
    let input: Vec<u8> = session.iter().flat_map(frame).collect();
    serve_bytes(args, &input)
}

/// Runs `bgc ARGS` with `input` (framing included) on its standard input.
fn serve_bytes(args: &[&str], input: &[u8]) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("bgc lsp starts");
    let mut stdin = child.stdin.take().expect("stdin");
    let _ = stdin.write_all(input);
    drop(stdin);
    child.wait_with_output().expect("bgc lsp ends")
}

/// Splits the framed output into messages.
fn messages(mut out: &[u8]) -> Vec<serde_json::Value> {
    let mut found = Vec::new();
    while let Some(end) = out.windows(4).position(|w| w == b"\r\n\r\n") {
        let header = String::from_utf8_lossy(&out[..end]).to_string();
        let length: usize = header
            .trim()
            .strip_prefix("Content-Length: ")
            .and_then(|n| n.parse().ok())
            .expect("a Content-Length header");
        let body = &out[end + 4..end + 4 + length];
        found.push(serde_json::from_slice(body).expect("a JSON body"));
        out = &out[end + 4 + length..];
    }
    found
}

#[test]
fn a_session_over_stdio_ends_with_status_zero() {
    let doc = uri(&back_support_path());
    let session = [
        serde_json::json!({"jsonrpc": "2.0", "id": 1, "method": "initialize",
            "params": {"processId": null, "rootUri": null, "capabilities": {}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "initialized", "params": {}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument":
            {"uri": doc, "languageId": "bg", "version": 1, "text": back_support_unacknowledged()}}}),
        serde_json::json!({"jsonrpc": "2.0", "id": 2, "method": "textDocument/hover", "params":
            {"textDocument": {"uri": doc}, "position": {"line": 21, "character": 11}}}),
        serde_json::json!({"jsonrpc": "2.0", "id": 3, "method": "shutdown", "params": null}),
        serde_json::json!({"jsonrpc": "2.0", "method": "exit", "params": null}),
    ];
    let out = serve(&["lsp", "--stdio"], &session);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let received = messages(&out.stdout);
    let by_id = |id: i64| {
        received
            .iter()
            .find(|m| m["id"] == id)
            .unwrap_or_else(|| panic!("response {id} in {received:#?}"))
    };
    assert_eq!(by_id(1)["result"]["serverInfo"]["name"], "bgc");
    let hover = by_id(2)["result"]["contents"]["value"]
        .as_str()
        .unwrap_or("");
    assert!(
        hover.contains("parameter `k_g` of model `back_support`: gearbox stiffness (C1 = 1/k_g)"),
        "{hover}"
    );
    assert!(
        hover.contains("`k_g` = 26400 N m (SI; declared in [N m/rad])"),
        "{hover}"
    );
    assert_eq!(by_id(3)["result"], serde_json::Value::Null);
    let published: Vec<&serde_json::Value> = received
        .iter()
        .filter(|m| m["method"] == "textDocument/publishDiagnostics")
        .collect();
    assert_eq!(published.len(), 1);
    let codes: Vec<&str> = published[0]["params"]["diagnostics"]
        .as_array()
        .map(|a| a.iter().filter_map(|d| d["code"].as_str()).collect())
        .unwrap_or_default();
    assert_eq!(codes, ["BG0510", "BG0510"]);
}

/// A client that sends a document before `initialized`, then a request after `shutdown`, and ends with `exit`:
/// the server stopped with status 2 at the first ("expected initialized notification") and, had it got past it, at
/// the second ("unexpected message during shutdown"), losing the session. It now takes the early document, answers
/// the late request `InvalidRequest` and ends with status 0; an `exit` without `shutdown` is status 1.
#[test]
fn a_session_goes_on_past_an_early_notification_and_a_late_request() {
    let session = [
        serde_json::json!({"jsonrpc": "2.0", "id": 1, "method": "initialize",
            "params": {"processId": null, "rootUri": null, "capabilities": {}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument":
            {"uri": "file:///tmp/early.bg", "languageId": "bg", "version": 1, "text": "model a { 0 j; }"}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "initialized", "params": {}}),
        serde_json::json!({"jsonrpc": "2.0", "id": 2, "method": "shutdown", "params": null}),
        serde_json::json!({"jsonrpc": "2.0", "id": 3, "method": "textDocument/hover", "params":
            {"textDocument": {"uri": "file:///tmp/early.bg"}, "position": {"line": 0, "character": 10}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "exit", "params": null}),
    ];
    let out = serve(&["lsp"], &session);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let received = messages(&out.stdout);
    let late = received
        .iter()
        .find(|m| m["id"] == 3)
        .expect("an answer to the late request");
    assert_eq!(late["error"]["code"], -32600, "{late}");
    let published = received
        .iter()
        .find(|m| m["method"] == "textDocument/publishDiagnostics")
        .expect("the early document's diagnostics");
    assert_eq!(published["params"]["uri"], "file:///tmp/early.bg");
    let without_shutdown = [
        serde_json::json!({"jsonrpc": "2.0", "id": 1, "method": "initialize",
            "params": {"processId": null, "rootUri": null, "capabilities": {}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "exit", "params": null}),
    ];
    let out = serve(&["lsp"], &without_shutdown);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A body that is not JSON ended the session ("malformed LSP payload", status 2), losing every open document. It
/// is now skipped and reported, a request whose id can be read is answered with `InvalidRequest`, and the session
/// goes on.
#[test]
fn a_malformed_message_is_skipped_and_the_session_goes_on() {
    let doc = uri(&back_support_path());
    let mut input = [
        serde_json::json!({"jsonrpc": "2.0", "id": 1, "method": "initialize",
            "params": {"processId": null, "rootUri": null, "capabilities": {}}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "initialized", "params": {}}),
        serde_json::json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument":
            {"uri": doc, "languageId": "bg", "version": 1, "text": back_support_unacknowledged()}}}),
    ]
    .iter()
    .flat_map(frame)
    .collect::<Vec<u8>>();
    input.extend_from_slice(b"Content-Length: 9\r\n\r\n{not json");
    input.extend(frame(
        &serde_json::json!({"jsonrpc": "2.0", "id": 2, "method": 3}),
    ));
    for m in [
        serde_json::json!({"jsonrpc": "2.0", "id": 3, "method": "textDocument/hover", "params":
            {"textDocument": {"uri": doc}, "position": {"line": 21, "character": 11}}}),
        serde_json::json!({"jsonrpc": "2.0", "id": 4, "method": "shutdown", "params": null}),
        serde_json::json!({"jsonrpc": "2.0", "method": "exit", "params": null}),
    ] {
        input.extend(frame(&m));
    }
    let out = serve_bytes(&["lsp"], &input);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert_eq!(
        err.matches("bgc lsp: skipped a message").count(),
        2,
        "{err}"
    );
    let received = messages(&out.stdout);
    let logged = received
        .iter()
        .find(|m| m["method"] == "window/logMessage")
        .map(|m| m["params"]["message"].to_string())
        .unwrap_or_default();
    assert!(logged.contains("key must be a string"), "{received:#?}");
    let refused = received.iter().find(|m| m["id"] == 2);
    assert_eq!(
        refused.map(|m| m["error"]["code"].clone()),
        Some((-32600).into())
    );
    let hover = received
        .iter()
        .find(|m| m["id"] == 3)
        .map(|m| m["result"]["contents"]["value"].to_string());
    assert!(
        hover.is_some_and(|h| h.contains("gearbox stiffness")),
        "{received:#?}"
    );
}

/// lsp-server allocated the body from its declared length first: a corrupt `Content-Length` of 100 GB had the
/// process killed for memory. The body is now read as it arrives, and the session ends with the cause.
#[test]
fn a_corrupt_content_length_ends_the_session_with_the_cause() {
    let cases: [(&[u8], &str); 3] = [
        (
            b"Content-Length: 100000000000\r\n\r\n{}",
            "the input ended after 2 of the 100000000000 bytes",
        ),
        (
            b"Content-Type: text\r\n\r\n{}",
            "a message header without `Content-Length`",
        ),
        (
            b"Content-Length: twelve\r\n\r\n{}",
            "the length is not a whole number of bytes",
        ),
    ];
    for (input, cause) in cases {
        let out = serve_bytes(&["lsp"], input);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.starts_with("error: bgc lsp: the connection failed: ") && err.contains(cause),
            "{err}"
        );
    }
}
