//! The server loop: notifications change the documents, requests read the analyses.
//!
//! Analysis is lazy and coalesced: a change marks its document (and every open document that imports it) stale;
//! the stale documents are analysed, and their diagnostics published, when no message is waiting or before a
//! request is answered, so that a burst of keystrokes costs one analysis and every answer sees the latest text.
//! A panic while answering a request is caught and answered as an internal error; the server keeps its state and
//! goes on.

use super::Options;
use super::analysis::{Analysis, analyse_front, derive_equations};
use super::background::{Job, Worker};
use super::document::Documents;
use super::files::{OverlayLoader, document_key, uri_to_path};
use super::lifecycle::{self, Ended, Step};
use super::{completion, diagnostics, edits, hover, navigation};
use crate::build::FsLoader;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, DidSaveTextDocument,
    Notification as _, PublishDiagnostics,
};
use lsp_types::request::{
    CodeActionRequest, Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest,
    PrepareRenameRequest, RangeFormatting, References, Rename, Request as _,
};
use lsp_types::{
    DocumentSymbolResponse, GotoDefinitionResponse, Hover, HoverContents, MarkupContent,
    MarkupKind, PrepareRenameResponse, PublishDiagnosticsParams, TextDocumentPositionParams, Uri,
};
use serde_json::Value;
use std::collections::{BTreeSet, HashMap};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

/// The state of a session.
pub struct Server {
    documents: Documents,
    /// The latest analysis of each open document, by URI, with the version it analysed.
    analyses: HashMap<String, (i32, Analysis)>,
    /// Open documents whose analysis is older than their text (or than a file they import).
    stale: BTreeSet<String>,
    /// Documents closed since the last refresh, whose diagnostics are to be cleared.
    closed: Vec<Uri>,
    include: Vec<PathBuf>,
    /// Documents with more elements and junctions than this get their equations from the worker.
    background_above: usize,
    worker: Worker,
}

type Answer = Result<Value, (ErrorCode, String)>;

impl Server {
    pub fn new(options: Options, connection: &Connection) -> Server {
        let sender = connection.sender.clone();
        let publish = Arc::new(move |uri: &str, version: i32, analysis: &Analysis| {
            if let Ok(uri) = Uri::from_str(uri) {
                let found = diagnostics::document_diagnostics(analysis);
                let params = PublishDiagnosticsParams::new(uri, found, Some(version));
                let n = Notification::new(PublishDiagnostics::METHOD.to_string(), params);
                let _ = sender.send(n.into());
            }
        });
        Server {
            documents: Documents::default(),
            analyses: HashMap::new(),
            stale: BTreeSet::new(),
            closed: Vec::new(),
            include: options.include,
            background_above: options.background_above,
            worker: Worker::start(publish),
        }
    }

    /// Serves an initialised connection until `exit` (or until the client goes away).
    pub fn run(&mut self, connection: &Connection) -> Ended {
        let mut shut = false;
        loop {
            let message = if self.stale.is_empty() {
                match connection.receiver.recv() {
                    Ok(m) => m,
                    Err(_) => return Ended::Closed,
                }
            } else {
                match connection.receiver.try_recv() {
                    Ok(m) => m,
                    Err(e) if e.is_empty() => {
                        self.refresh(connection);
                        continue;
                    }
                    Err(_) => return Ended::Closed,
                }
            };
            match message {
                Message::Request(request) => {
                    let Step::Answer(request) = lifecycle::request(connection, request, &mut shut)
                    else {
                        continue;
                    };
                    self.refresh(connection);
                    self.collect_done();
                    let response = self.respond(request);
                    send(connection, response.into());
                }
                Message::Notification(n) if n.method == "exit" => return lifecycle::exit(shut),
                // After `shutdown` the documents no longer change.
                Message::Notification(_) if shut => {}
                Message::Notification(n) => self.notify(n),
                Message::Response(_) => {}
            }
        }
    }

    fn respond(&mut self, request: Request) -> Response {
        let id = request.id.clone();
        guarded(id, || self.answer(request))
    }

    fn answer(&self, request: Request) -> Answer {
        let params = request.params;
        match request.method.as_str() {
            HoverRequest::METHOD => {
                let p: lsp_types::HoverParams = parse(params)?;
                let hover = self.hover(&p.text_document_position_params);
                to_value(hover)
            }
            GotoDefinition::METHOD => {
                let p: lsp_types::GotoDefinitionParams = parse(params)?;
                let found = self
                    .at(&p.text_document_position_params)
                    .and_then(|(a, offset)| navigation::definition(a, a.root, offset));
                to_value(found.map(GotoDefinitionResponse::Scalar))
            }
            References::METHOD => {
                let p: lsp_types::ReferenceParams = parse(params)?;
                let key = self.key_at(&p.text_document_position);
                let all = self.all_analyses();
                let found =
                    key.map(|k| navigation::references(&all, &k, p.context.include_declaration));
                to_value(found)
            }
            PrepareRenameRequest::METHOD => {
                let p: TextDocumentPositionParams = parse(params)?;
                let found = self.at(&p).and_then(|(a, offset)| {
                    let (_, span) = navigation::symbol_at(a, a.root, offset)?;
                    Some(PrepareRenameResponse::Range(
                        diagnostics::Lines::new(a).range(span),
                    ))
                });
                to_value(found)
            }
            Rename::METHOD => {
                let p: lsp_types::RenameParams = parse(params)?;
                let key = self.key_at(&p.text_document_position).ok_or((
                    ErrorCode::InvalidParams,
                    "no name to rename here".to_string(),
                ))?;
                let all = self.all_analyses();
                let edit = navigation::rename(&all, &key, &p.new_name)
                    .map_err(|e| (ErrorCode::InvalidParams, e))?;
                to_value(edit)
            }
            DocumentSymbolRequest::METHOD => {
                let p: lsp_types::DocumentSymbolParams = parse(params)?;
                let found = self
                    .analysis(&p.text_document.uri)
                    .map(|a| DocumentSymbolResponse::Nested(navigation::document_symbols(a)));
                to_value(found)
            }
            Formatting::METHOD => {
                let p: lsp_types::DocumentFormattingParams = parse(params)?;
                let found = self
                    .documents
                    .get(&p.text_document.uri)
                    .and_then(|d| edits::format(&d.text));
                to_value(found)
            }
            RangeFormatting::METHOD => {
                let p: lsp_types::DocumentRangeFormattingParams = parse(params)?;
                let found = self
                    .documents
                    .get(&p.text_document.uri)
                    .and_then(|d| edits::format_range(&d.text, p.range));
                to_value(found)
            }
            Completion::METHOD => {
                let p: lsp_types::CompletionParams = parse(params)?;
                let found = self
                    .at(&p.text_document_position)
                    .map(|(a, offset)| completion::respond(a, offset));
                to_value(found)
            }
            CodeActionRequest::METHOD => {
                let p: lsp_types::CodeActionParams = parse(params)?;
                let uri = &p.text_document.uri;
                let found = self
                    .analysis(uri)
                    .map(|a| edits::code_actions(a, uri, p.range));
                to_value(found)
            }
            other => Err((
                ErrorCode::MethodNotFound,
                format!("unknown request `{other}`"),
            )),
        }
    }

    /// The analysis of a document and the byte offset of a position in it.
    fn at(&self, p: &TextDocumentPositionParams) -> Option<(&Analysis, usize)> {
        let uri = &p.text_document.uri;
        let document = self.documents.get(uri)?;
        let (_, analysis) = self.analyses.get(uri.as_str())?;
        Some((analysis, document.lines.offset(&document.text, p.position)))
    }

    fn key_at(&self, p: &TextDocumentPositionParams) -> Option<navigation::SymbolKey> {
        let (analysis, offset) = self.at(p)?;
        let (id, _) = navigation::symbol_at(analysis, analysis.root, offset)?;
        navigation::key(analysis, id)
    }

    fn all_analyses(&self) -> Vec<&Analysis> {
        self.analyses.values().map(|(_, a)| a).collect()
    }

    fn analysis(&self, uri: &Uri) -> Option<&Analysis> {
        self.analyses.get(uri.as_str()).map(|(_, a)| a)
    }

    /// Takes the worker's analyses with equations that are still of the documents' current versions.
    fn collect_done(&mut self) {
        for (uri, version, analysis) in self.worker.take_done() {
            let current = self.documents.iter().find(|(u, _)| u.as_str() == uri);
            if current.is_some_and(|(_, d)| d.version == version) {
                self.analyses.insert(uri, (version, analysis));
            }
        }
    }

    fn hover(&self, p: &TextDocumentPositionParams) -> Option<Hover> {
        let (analysis, offset) = self.at(p)?;
        let (text, span) = hover::hover(analysis, analysis.root, offset)?;
        Some(Hover {
            contents: HoverContents::Markup(MarkupContent {
                kind: MarkupKind::Markdown,
                value: text,
            }),
            range: Some(diagnostics::Lines::new(analysis).range(span)),
        })
    }

    fn notify(&mut self, n: Notification) {
        match n.method.as_str() {
            DidOpenTextDocument::METHOD => {
                if let Ok(p) =
                    n.extract::<lsp_types::DidOpenTextDocumentParams>(DidOpenTextDocument::METHOD)
                {
                    let doc = p.text_document;
                    self.documents.open(doc.uri.clone(), doc.text, doc.version);
                    self.mark_stale(&doc.uri);
                }
            }
            DidChangeTextDocument::METHOD => {
                if let Ok(p) = n.extract::<lsp_types::DidChangeTextDocumentParams>(
                    DidChangeTextDocument::METHOD,
                ) {
                    let uri = p.text_document.uri;
                    if let Some(doc) = self.documents.get_mut(&uri) {
                        doc.apply(&p.content_changes, p.text_document.version);
                        self.mark_stale(&uri);
                    }
                }
            }
            DidSaveTextDocument::METHOD => {
                if let Ok(p) =
                    n.extract::<lsp_types::DidSaveTextDocumentParams>(DidSaveTextDocument::METHOD)
                {
                    self.mark_stale(&p.text_document.uri);
                }
            }
            DidCloseTextDocument::METHOD => {
                if let Ok(p) =
                    n.extract::<lsp_types::DidCloseTextDocumentParams>(DidCloseTextDocument::METHOD)
                {
                    let uri = p.text_document.uri;
                    // Its importers read the file from disk again.
                    self.mark_stale(&uri);
                    self.documents.close(&uri);
                    self.analyses.remove(uri.as_str());
                    self.stale.remove(uri.as_str());
                    self.closed.push(uri);
                }
            }
            _ => {}
        }
    }

    /// Marks a document and every open document whose analysis read its file as stale.
    fn mark_stale(&mut self, uri: &Uri) {
        self.stale.insert(uri.as_str().to_string());
        let Some(name) = document_name(uri) else {
            return;
        };
        for (other, (_, analysis)) in &self.analyses {
            if diagnostics::imported_names(analysis).any(|n| n == name) {
                self.stale.insert(other.clone());
            }
        }
    }

    /// Analyses the stale documents and publishes their diagnostics: all of them for a small document; for a large
    /// one those of the front end now and all of them when the worker has derived the equations.
    fn refresh(&mut self, connection: &Connection) {
        for uri in std::mem::take(&mut self.closed) {
            self.worker.forget(uri.as_str());
            publish(connection, uri, Vec::new(), None);
        }
        if self.stale.is_empty() {
            return;
        }
        let overlay: HashMap<PathBuf, String> = self
            .documents
            .iter()
            .filter_map(|(uri, d)| Some((document_key(&uri_to_path(uri)?), d.text.clone())))
            .collect();
        for key in std::mem::take(&mut self.stale) {
            let Some((uri, doc)) = self.documents.iter().find(|(u, _)| u.as_str() == key) else {
                continue;
            };
            let name = document_name(uri).unwrap_or_else(|| key.clone());
            let fs = FsLoader::new(&self.include).unwrap_or_default();
            let mut loader = OverlayLoader {
                fs,
                overlay: &overlay,
            };
            let text = &doc.text;
            let front = catch_unwind(AssertUnwindSafe(|| analyse_front(&name, text, &mut loader)));
            let Ok(mut analysis) = front else {
                eprintln!("bgc lsp: the analysis of {key} failed; its previous results stay");
                continue;
            };
            let size: usize = analysis
                .models
                .iter()
                .map(|m| m.model.graph.node_count())
                .sum();
            let version = doc.version;
            let job = if size > self.background_above {
                Some(Job {
                    version,
                    analysis: analysis.clone(),
                })
            } else {
                if catch_unwind(AssertUnwindSafe(|| derive_equations(&mut analysis))).is_err() {
                    eprintln!("bgc lsp: the equations of {key} failed; the other diagnostics stay");
                }
                None
            };
            let found = diagnostics::document_diagnostics(&analysis);
            let uri = uri.clone();
            self.worker.publish(&key, version, job, || {
                publish(connection, uri, found, Some(version));
            });
            self.analyses.insert(key, (version, analysis));
        }
    }
}

/// The name a document has in the analysis: its path, or the URI of a document that is not a file.
fn document_name(uri: &Uri) -> Option<String> {
    uri_to_path(uri).map(|p| p.display().to_string())
}

fn publish(
    connection: &Connection,
    uri: Uri,
    diagnostics: Vec<lsp_types::Diagnostic>,
    version: Option<i32>,
) {
    let params = PublishDiagnosticsParams {
        uri,
        diagnostics,
        version,
    };
    send(
        connection,
        Notification::new(PublishDiagnostics::METHOD.to_string(), params).into(),
    );
}

fn send(connection: &Connection, message: Message) {
    // A client that went away ends the loop at the next receive.
    let _ = connection.sender.send(message);
}

fn parse<T: serde::de::DeserializeOwned>(params: Value) -> Result<T, (ErrorCode, String)> {
    serde_json::from_value(params).map_err(|e| (ErrorCode::InvalidParams, e.to_string()))
}

fn to_value<T: serde::Serialize>(value: T) -> Answer {
    serde_json::to_value(value).map_err(|e| (ErrorCode::InternalError, e.to_string()))
}

/// Runs a request handler; a panic in it becomes an `InternalError` response.
pub fn guarded(id: RequestId, handler: impl FnOnce() -> Answer) -> Response {
    match catch_unwind(AssertUnwindSafe(handler)) {
        Ok(Ok(value)) => Response::new_ok(id, value),
        Ok(Err((code, message))) => Response::new_err(id, code as i32, message),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".to_string());
            Response::new_err(
                id,
                ErrorCode::InternalError as i32,
                format!("bgc lsp: internal error while answering (the server goes on): {what}"),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panicking_handler_is_answered_as_an_internal_error() {
        let response = guarded(RequestId::from(7), || panic!("boom"));
        let error = response.error.map(|e| (e.code, e.message));
        assert_eq!(
            error,
            Some((
                ErrorCode::InternalError as i32,
                "bgc lsp: internal error while answering (the server goes on): boom".to_string()
            ))
        );
        let ok = guarded(RequestId::from(8), || Ok(Value::Null));
        assert_eq!((ok.result, ok.error.is_none()), (Some(Value::Null), true));
    }
}
