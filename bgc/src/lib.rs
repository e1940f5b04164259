//! bgc: a bond-graph modelling language and compiler.
//!
//! The pipeline is a sequence of stages with plain data between them (see docs/ARCHITECTURE.md):
//! [`syntax`] parses text into an AST, [`lower`] resolves names, components, domains and units into the bond-graph
//! IR of [`ir`], and later stages analyse causality and derive equations. No stage prints or touches files; the CLI
//! (`src/main.rs`) and the build-script API do.

pub mod build;
pub mod causality;
pub mod codegen;
mod concurrent;
pub mod diagnostic;
pub mod draw;
pub mod equations;
pub mod files;
pub mod fmu;
pub mod ir;
pub mod lower;
#[cfg(feature = "lsp")]
pub mod lsp;
pub mod simulate;
pub mod span;
pub mod symbolic;
pub mod syntax;
pub mod units;
