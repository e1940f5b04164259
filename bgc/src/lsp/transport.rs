//! The standard input and output transport: JSON-RPC messages framed by a `Content-Length` header.
//!
//! It does what lsp-server's `Connection::stdio` does, with two differences an editor session needs:
//! - a body that is not a JSON-RPC message is skipped, not the end of the session: a request whose `id` can be read
//!   is answered with `InvalidRequest`, anything else is reported to the client (`window/logMessage`) and on
//!   standard error; only a broken frame (a header without `Content-Length`, input that ends inside a message),
//!   after which no later message can be found, ends the session;
//! - a body is read as it arrives, never allocated up front from the length its header declares, so a corrupt
//!   `Content-Length` cannot exhaust the memory.

use super::lifecycle::Ended;
use lsp_server::{Connection, ErrorCode, Message, Notification, RequestId, Response};
use std::io::{self, BufRead, Read, Write};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::{self, JoinHandle};

/// The longest header line read; a real one (`Content-Length: …`, `Content-Type: …`) is a few dozen bytes.
const MAX_HEADER_LINE: u64 = 4096;

/// The threads of a connection on standard input and output, and why the reader stopped if the input broke.
pub struct Transport {
    reader: JoinHandle<()>,
    writer: JoinHandle<io::Result<()>>,
    broken: Arc<Mutex<Option<String>>>,
}

/// A connection on standard input and output, and its threads; an error when a thread cannot be started.
pub fn stdio() -> io::Result<(Connection, Transport)> {
    let (to_writer, from_server) = crossbeam_channel::bounded::<Message>(0);
    let (to_server, incoming) = crossbeam_channel::bounded::<Message>(0);
    // The reader's own answers (to skipped bodies) reach the writer on a channel of their own, so that the writer
    // ends with the server's side and does not wait for a reader still blocked on the client's input.
    let (replies, from_reader) = crossbeam_channel::unbounded::<Message>();
    let writer = thread::Builder::new()
        .name("bgc-lsp-writer".into())
        .spawn(move || {
            let stdout = io::stdout();
            write_messages(&from_server, from_reader, &mut stdout.lock())
        })?;
    let broken = Arc::new(Mutex::new(None));
    let cause = Arc::clone(&broken);
    let reader = thread::Builder::new()
        .name("bgc-lsp-reader".into())
        .spawn(move || {
            let stdin = io::stdin();
            let read = read_messages(&mut stdin.lock(), &to_server, &replies, &mut io::stderr());
            // Recorded before the server's channel closes, so that the server, which stops when it does, finds it.
            if let Err(why) = read {
                *cause.lock().unwrap_or_else(PoisonError::into_inner) = Some(why);
            }
            drop(to_server);
        })?;
    let connection = Connection {
        sender: to_writer,
        receiver: incoming,
    };
    let transport = Transport {
        reader,
        writer,
        broken,
    };
    Ok((connection, transport))
}

impl Transport {
    /// The outcome of a session that ended as `ended`, once everything the server sent is written. A broken input
    /// is the cause to name (the server only saw its channel close). The session ends when the client says `exit`
    /// or closes the input, so the reader has stopped or is about to.
    pub fn finish(self, ended: Ended) -> Result<Ended, String> {
        let written = self.writer.join();
        let read = self.reader.join();
        if let Some(why) = self
            .broken
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
        {
            return Err(format!("the connection failed: {why}"));
        }
        match (read, written) {
            (Ok(()), Ok(Ok(()))) => Ok(ended),
            (Ok(()), Ok(Err(e))) => Err(format!("writing to standard output failed: {e}")),
            _ => Err("a thread of the connection panicked".to_string()),
        }
    }
}

/// Writes the server's messages, and the reader's answers while the reader runs, until the server's side closes.
fn write_messages(
    server: &crossbeam_channel::Receiver<Message>,
    reader: crossbeam_channel::Receiver<Message>,
    out: &mut impl Write,
) -> io::Result<()> {
    enum Next {
        Write(Message),
        ReaderDone,
        ServerDone,
    }
    let mut reader = reader;
    loop {
        let next = crossbeam_channel::select! {
            recv(server) -> m => m.map_or(Next::ServerDone, Next::Write),
            recv(reader) -> m => m.map_or(Next::ReaderDone, Next::Write),
        };
        match next {
            Next::Write(m) => m.write(out)?,
            // A closed channel is always ready: select on one that never is from now on.
            Next::ReaderDone => reader = crossbeam_channel::never(),
            Next::ServerDone => return Ok(()),
        }
    }
}

/// Hands every message of `input` to the server until the input ends or the client says `exit`. A skipped body is
/// answered through `replies` and noted on `log`.
pub fn read_messages(
    input: &mut impl BufRead,
    server: &crossbeam_channel::Sender<Message>,
    replies: &crossbeam_channel::Sender<Message>,
    log: &mut impl Write,
) -> Result<(), String> {
    while let Some(body) = read_frame(input)? {
        let message = match to_message(&body) {
            Ok(message) => message,
            Err((id, why)) => {
                let text = format!("bgc lsp: skipped a message that is not JSON-RPC: {why}");
                // The standard error is the server's log; a failed write there must not end the session.
                let _ = writeln!(log, "{text}");
                let _ = replies.send(refusal(id, text));
                continue;
            }
        };
        let exit = matches!(&message, Message::Notification(n) if n.method == "exit");
        if server.send(message).is_err() || exit {
            // The server stopped (it says why), or the client said goodbye.
            break;
        }
    }
    Ok(())
}

/// The message of a body, or why it is none (with the request's `id` when one can be read).
///
/// lsp-server's own parsing takes any object with an `id` for a response (`{"id":4,"method":7}` included), so the
/// kind is decided here by the keys, as JSON-RPC defines it: `method` and `id` make a request, `method` alone a
/// notification, `id` without `method` a response.
fn to_message(body: &[u8]) -> Result<Message, (Option<RequestId>, String)> {
    let value: serde_json::Value =
        serde_json::from_slice(body).map_err(|e| (None, e.to_string()))?;
    let Some(object) = value.as_object() else {
        return Err((None, "a message is a JSON object".to_string()));
    };
    let id = object.get("id").and_then(|id| match id {
        serde_json::Value::Number(n) => i32::try_from(n.as_i64()?).ok().map(RequestId::from),
        serde_json::Value::String(s) => Some(RequestId::from(s.clone())),
        _ => None,
    });
    let parsed = match (object.contains_key("method"), object.contains_key("id")) {
        (true, true) => serde_json::from_value(value).map(Message::Request),
        (true, false) => serde_json::from_value(value).map(Message::Notification),
        (false, true) => serde_json::from_value(value).map(Message::Response),
        (false, false) => return Err((None, "a message has a `method` or an `id`".to_string())),
    };
    parsed.map_err(|e| (id, e.to_string()))
}

/// The answer to a body that is not a message: an `InvalidRequest` error for a request whose `id` is readable,
/// otherwise a log message to the client.
fn refusal(id: Option<RequestId>, text: String) -> Message {
    match id {
        Some(id) => Response::new_err(id, ErrorCode::InvalidRequest as i32, text).into(),
        None => Notification::new(
            "window/logMessage".to_string(),
            serde_json::json!({ "type": 1, "message": text }),
        )
        .into(),
    }
}

/// The body of the next frame; `None` when the input ends between frames.
fn read_frame(input: &mut impl BufRead) -> Result<Option<Vec<u8>>, String> {
    let mut length = None;
    let mut started = false;
    let mut line = Vec::new();
    loop {
        line.clear();
        let read = input
            .by_ref()
            .take(MAX_HEADER_LINE)
            .read_until(b'\n', &mut line)
            .map_err(|e| format!("reading standard input failed: {e}"))?;
        if read == 0 {
            return match started {
                false => Ok(None),
                true => Err("the input ended inside a message header".to_string()),
            };
        }
        started = true;
        let Some(text) = line.strip_suffix(b"\r\n") else {
            return Err(format!(
                "malformed header line {:?}: a header line is at most {MAX_HEADER_LINE} bytes and ends with CR LF",
                String::from_utf8_lossy(&line)
            ));
        };
        if text.is_empty() {
            break;
        }
        if let Some(n) = content_length(text)? {
            length = Some(n);
        }
    }
    let length = length.ok_or("a message header without `Content-Length`")?;
    let mut body = Vec::new();
    input
        .by_ref()
        .take(length)
        .read_to_end(&mut body)
        .map_err(|e| format!("reading standard input failed: {e}"))?;
    if body.len() as u64 != length {
        return Err(format!(
            "the input ended after {} of the {length} bytes that the message's `Content-Length` announced",
            body.len()
        ));
    }
    Ok(Some(body))
}

/// The value of a `Content-Length` header line, `None` for another header.
fn content_length(line: &[u8]) -> Result<Option<u64>, String> {
    let text = String::from_utf8_lossy(line);
    let Some((name, value)) = text.split_once(':') else {
        return Err(format!(
            "malformed header line {text:?}: a header is `Name: value`"
        ));
    };
    if !name.trim().eq_ignore_ascii_case("Content-Length") {
        return Ok(None);
    }
    value.trim().parse().map(Some).map_err(|_| {
        format!("malformed header line {text:?}: the length is not a whole number of bytes")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(body: &str) -> String {
        format!("Content-Length: {}\r\n\r\n{body}", body.len())
    }

    /// What the server and the client receive, the log, and the reader's result.
    fn read(input: &str) -> (Vec<Message>, Vec<Message>, String, Result<(), String>) {
        let (to_server, server) = crossbeam_channel::unbounded();
        let (to_client, client) = crossbeam_channel::unbounded();
        let mut log = Vec::new();
        let result = read_messages(&mut input.as_bytes(), &to_server, &to_client, &mut log);
        let log = String::from_utf8_lossy(&log).to_string();
        (
            server.try_iter().collect(),
            client.try_iter().collect(),
            log,
            result,
        )
    }

    #[test]
    fn a_body_that_is_not_a_message_is_skipped_and_answered() {
        let input = [
            frame("{not json"),
            frame(r#"{"jsonrpc":"2.0","id":4,"method":7}"#),
            frame(r#"{"jsonrpc":"2.0","id":5,"method":"shutdown"}"#),
        ]
        .concat();
        let (server, client, log, result) = read(&input);
        assert_eq!(result, Ok(()));
        assert!(
            matches!(&server[..], [Message::Request(r)] if r.method == "shutdown"),
            "{server:?}"
        );
        match &client[..] {
            [Message::Notification(n), Message::Response(r)] => {
                assert_eq!(n.method, "window/logMessage");
                assert_eq!(n.params["type"], 1);
                assert!(
                    n.params["message"]
                        .as_str()
                        .unwrap_or("")
                        .contains("key must be a string")
                );
                assert_eq!(r.id, RequestId::from(4));
                assert_eq!(
                    r.error.as_ref().map(|e| e.code),
                    Some(ErrorCode::InvalidRequest as i32)
                );
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(log.lines().count(), 2, "{log}");
    }

    #[test]
    fn a_declared_length_beyond_the_input_is_an_error_not_an_allocation() {
        let (server, _, _, result) = read("Content-Length: 100000000000\r\n\r\n{}");
        assert!(server.is_empty());
        assert_eq!(
            result,
            Err("the input ended after 2 of the 100000000000 bytes that the message's `Content-Length` announced".to_string())
        );
    }

    #[test]
    fn broken_headers_end_the_session_with_the_cause() {
        let cases = [
            (
                "Content-Type: x\r\n\r\n{}",
                "a message header without `Content-Length`",
            ),
            (
                "Content-Length: -3\r\n\r\n",
                "the length is not a whole number of bytes",
            ),
            ("Content-Length 3\r\n\r\n{}", "a header is `Name: value`"),
            ("Content-Length: 2\n\n{}", "ends with CR LF"),
            (
                "Content-Length: 2\r\n",
                "the input ended inside a message header",
            ),
        ];
        for (input, cause) in cases {
            let (_, _, _, result) = read(input);
            let error = result.err().unwrap_or_default();
            assert!(error.contains(cause), "{input:?}: {error}");
        }
    }

    #[test]
    fn headers_are_read_as_clients_write_them() {
        let body = r#"{"jsonrpc":"2.0","method":"exit"}"#;
        let input = format!(
            "content-length:{}\r\nContent-Type: application/vscode-jsonrpc; charset=utf-8\r\n\r\n{body}{}",
            body.len(),
            frame(r#"{"jsonrpc":"2.0","method":"after exit"}"#)
        );
        let (server, _, _, result) = read(&input);
        assert_eq!(result, Ok(()));
        // `exit` is the last message handed over.
        assert!(
            matches!(&server[..], [Message::Notification(n)] if n.method == "exit"),
            "{server:?}"
        );
    }
}
