//! `bgc lsp`: a Language Server Protocol server for `.bg` files.
//!
//! The server speaks JSON-RPC over standard input and output ([`run_stdio`]) or over any
//! [`lsp_server::Connection`] ([`serve`], which the tests drive in memory). It keeps the open documents
//! ([`document`]) in sync incrementally, analyses each one with the compiler's front end on the text in memory
//! ([`analysis`]; imports see the unsaved text of open documents through [`files::OverlayLoader`]), and publishes
//! every stage's diagnostics ([`diagnostics`]). On top of the analysis: hover ([`hover`]), go to definition,
//! references, rename and the outline ([`navigation`], over the names of [`index`]), formatting and quick fixes
//! ([`edits`]) and completion ([`completion`]).
//!
//! Like the CLI and the build-script API, the server touches the outside world (the connection, files on disk,
//! a copy of the standard library for go-to-definition); the analysis is a pure function of the texts.

pub mod analysis;
pub mod background;
pub mod completion;
pub mod diagnostics;
pub mod document;
pub mod edits;
pub mod files;
pub mod hover;
pub mod index;
pub mod lifecycle;
pub mod line_diff;
pub mod lines;
pub mod navigation;
pub mod server;
pub mod transport;

pub use lifecycle::Ended;
use lsp_server::Connection;
use lsp_types::{
    CodeActionKind, CodeActionOptions, CodeActionProviderCapability, CompletionOptions,
    HoverProviderCapability, OneOf, PositionEncodingKind, RenameOptions, ServerCapabilities,
    ServerInfo, TextDocumentSyncCapability, TextDocumentSyncKind, TextDocumentSyncOptions,
    TextDocumentSyncSaveOptions,
};
use std::path::PathBuf;

/// What the server offers.
pub fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        position_encoding: Some(PositionEncodingKind::UTF16),
        text_document_sync: Some(TextDocumentSyncCapability::Options(
            TextDocumentSyncOptions {
                open_close: Some(true),
                change: Some(TextDocumentSyncKind::INCREMENTAL),
                will_save: None,
                will_save_wait_until: None,
                save: Some(TextDocumentSyncSaveOptions::Supported(true)),
            },
        )),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        rename_provider: Some(OneOf::Right(RenameOptions {
            prepare_provider: Some(true),
            work_done_progress_options: Default::default(),
        })),
        document_symbol_provider: Some(OneOf::Left(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        document_range_formatting_provider: Some(OneOf::Left(true)),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec![".".into(), "[".into(), "(".into()]),
            ..CompletionOptions::default()
        }),
        code_action_provider: Some(CodeActionProviderCapability::Options(CodeActionOptions {
            code_action_kinds: Some(vec![CodeActionKind::QUICKFIX]),
            ..CodeActionOptions::default()
        })),
        ..ServerCapabilities::default()
    }
}

/// How the server runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// The directories imports are also looked up in (`bgc -I DIR lsp`), as for the other commands.
    pub include: Vec<PathBuf>,
    /// A document whose models have more elements and junctions than this gets the equation stage's findings in a
    /// second publication, derived on a thread of its own, so that the rest of its diagnostics come at once.
    pub background_above: usize,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            include: Vec::new(),
            background_above: 1000,
        }
    }
}

/// Initialises the connection and serves it until the client says `exit` (or goes away).
pub fn serve(connection: &Connection, options: Options) -> Ended {
    let init = serde_json::json!({
        "capabilities": capabilities(),
        "serverInfo": ServerInfo {
            name: "bgc".to_string(),
            version: Some(env!("CARGO_PKG_VERSION").to_string()),
        },
    });
    let id = match lifecycle::await_initialize(connection) {
        Ok((id, _params)) => id,
        Err(ended) => return ended,
    };
    // The `initialized` notification that follows is one the server loop drops, like any it does not use.
    let _ = connection
        .sender
        .send(lsp_server::Response::new_ok(id, init).into());
    server::Server::new(options, connection).run(connection)
}

/// Serves on standard input and output: how the session ended, or why the connection failed.
pub fn run_stdio(options: Options) -> Result<Ended, String> {
    let (connection, transport) =
        transport::stdio().map_err(|e| format!("the connection's threads could not start: {e}"))?;
    let served = serve(&connection, options);
    drop(connection);
    transport.finish(served)
}
