//! The session's beginning and end as the protocol defines them: `initialize` before anything else, `shutdown`
//! then `exit`.
//!
//! A request before `initialize` is answered `ServerNotInitialized`, a notification then is dropped; a request after
//! `shutdown` is answered `InvalidRequest`, a notification then is dropped; `exit` ends the session, with status 0
//! after `shutdown` and 1 without it, as the specification asks. An editor that sends a request in the window
//! between its `shutdown` and `exit` (or a `didOpen` before its `initialized`) gets an answer, not a server that
//! stops.

use lsp_server::{Connection, ErrorCode, Message, Request, RequestId, Response};
use serde_json::Value;

/// How a session ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// `exit` after `shutdown`.
    Shutdown,
    /// `exit` without `shutdown` (before `initialize`, or during the session): the protocol's exit status 1.
    ExitWithoutShutdown,
    /// The client closed the connection.
    Closed,
}

/// Waits for `initialize`: its id and parameters, or how the session ended before it.
pub fn await_initialize(connection: &Connection) -> Result<(RequestId, Value), Ended> {
    loop {
        let Ok(message) = connection.receiver.recv() else {
            return Err(Ended::Closed);
        };
        match message {
            Message::Request(r) if r.method == "initialize" => return Ok((r.id, r.params)),
            Message::Request(r) => refuse(
                connection,
                &r,
                ErrorCode::ServerNotInitialized,
                "the server is not initialised: send `initialize` first",
            ),
            Message::Notification(n) if n.method == "exit" => {
                return Err(Ended::ExitWithoutShutdown);
            }
            Message::Notification(_) | Message::Response(_) => {}
        }
    }
}

/// What the server loop does with a request in the session's lifecycle, before it answers it.
pub enum Step {
    /// An ordinary request: answer it.
    Answer(Request),
    /// Answered here (`shutdown`, or a request the lifecycle refuses).
    Done,
}

/// `shutdown` (answered, and recorded in `shut`), a second `initialize`, or a request after `shutdown`.
pub fn request(connection: &Connection, request: Request, shut: &mut bool) -> Step {
    if *shut {
        refuse(
            connection,
            &request,
            ErrorCode::InvalidRequest,
            "the server is shutting down: only `exit` is accepted",
        );
        return Step::Done;
    }
    match request.method.as_str() {
        "shutdown" => {
            *shut = true;
            let _ = connection
                .sender
                .send(Response::new_ok(request.id, ()).into());
            Step::Done
        }
        "initialize" => {
            refuse(
                connection,
                &request,
                ErrorCode::InvalidRequest,
                "the server is already initialised",
            );
            Step::Done
        }
        _ => Step::Answer(request),
    }
}

/// How `exit` ends the session.
pub fn exit(shut: bool) -> Ended {
    match shut {
        true => Ended::Shutdown,
        false => Ended::ExitWithoutShutdown,
    }
}

fn refuse(connection: &Connection, request: &Request, code: ErrorCode, why: &str) {
    let message = format!("{why} (got `{}`)", request.method);
    let response = Response::new_err(request.id.clone(), code as i32, message);
    // A client that went away ends the loop at the next receive.
    let _ = connection.sender.send(response.into());
}

#[cfg(test)]
mod tests {
    use super::*;
    use lsp_server::Notification;
    use serde_json::json;
    use std::time::Duration;

    /// A server on a thread over an in-memory connection, and the client's end.
    fn session() -> (Connection, std::thread::JoinHandle<Ended>) {
        let (server, client) = Connection::memory();
        let handle = std::thread::spawn(move || super::super::serve(&server, Default::default()));
        (client, handle)
    }

    fn request(client: &Connection, id: i32, method: &str) -> Response {
        let request = Request::new(RequestId::from(id), method.to_string(), json!({}));
        client
            .sender
            .send(request.into())
            .expect("the server listens");
        loop {
            match client.receiver.recv_timeout(Duration::from_secs(60)) {
                Ok(Message::Response(r)) => return r,
                Ok(_) => continue,
                Err(e) => panic!("no answer to `{method}`: {e}"),
            }
        }
    }

    fn notify(client: &Connection, method: &str, params: Value) {
        let n = Notification::new(method.to_string(), params);
        client.sender.send(n.into()).expect("the server listens");
    }

    fn error_code(r: &Response) -> Option<i32> {
        r.error.as_ref().map(|e| e.code)
    }

    #[test]
    fn requests_before_initialize_and_after_shutdown_are_answered_and_exit_ends_the_session() {
        let (client, server) = session();
        let early = request(&client, 1, "textDocument/hover");
        assert_eq!(
            error_code(&early),
            Some(ErrorCode::ServerNotInitialized as i32)
        );
        let message = early.error.map(|e| e.message).unwrap_or_default();
        assert_eq!(
            message,
            "the server is not initialised: send `initialize` first (got `textDocument/hover`)"
        );
        notify(&client, "textDocument/didOpen", json!({}));
        assert!(request(&client, 2, "initialize").result.is_some());
        notify(&client, "initialized", json!({}));
        let again = request(&client, 3, "initialize");
        assert_eq!(error_code(&again), Some(ErrorCode::InvalidRequest as i32));
        assert_eq!(request(&client, 4, "shutdown").result, Some(Value::Null));
        // An editor may still send a request or a notification before its `exit`.
        let late = request(&client, 5, "textDocument/hover");
        assert_eq!(error_code(&late), Some(ErrorCode::InvalidRequest as i32));
        let uri = "file:///nowhere/a.bg";
        let open = json!({"textDocument": {"uri": uri, "languageId": "bg", "version": 1, "text": "model m {}"}});
        notify(&client, "textDocument/didOpen", open);
        assert_eq!(
            error_code(&request(&client, 6, "shutdown")),
            Some(ErrorCode::InvalidRequest as i32)
        );
        notify(&client, "exit", Value::Null);
        assert_eq!(server.join().ok(), Some(Ended::Shutdown));
    }

    #[test]
    fn exit_without_shutdown_is_said_so_before_and_after_initialize() {
        let (client, server) = session();
        notify(&client, "exit", Value::Null);
        assert_eq!(server.join().ok(), Some(Ended::ExitWithoutShutdown));
        let (client, server) = session();
        assert!(request(&client, 1, "initialize").result.is_some());
        notify(&client, "exit", Value::Null);
        assert_eq!(server.join().ok(), Some(Ended::ExitWithoutShutdown));
        let (client, server) = session();
        drop(client);
        assert_eq!(server.join().ok(), Some(Ended::Closed));
    }
}
