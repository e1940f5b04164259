//! The build-script API: compile `.bg` files into Rust modules from a crate's `build.rs`, in the style of
//! `prost-build`.
//!
//! ```toml
//! [dependencies]
//! bgc-runtime = { path = "../runtime" }
//! libm = "0.2"
//! nalgebra = "0.34"
//!
//! [build-dependencies]
//! bgc = { path = "../bgc", default-features = false }
//! ```
//!
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), bgc::build::Error> {
//!     bgc::build::compile(&["back_support.bg"])?;
//!     Ok(())
//! }
//! ```
//!
//! ```text
//! // src/lib.rs: the module of `back_support.bg` is `$OUT_DIR/back_support.rs`.
//! pub mod back_support {
//!     include!(concat!(env!("OUT_DIR"), "/back_support.rs"));
//! }
//! ```
//!
//! The generated functions call `libm` for the elementary functions (`sin`, `exp`, ...), so that they need only
//! `core`. For a `#![no_std]` crate, leave out the runtime's trait implementations with [`Config::runtime`]:
//!
//! ```toml
//! [dependencies]
//! libm = "0.2"
//! nalgebra = { version = "0.34", default-features = false }
//! ```
//!
//! ```no_run
//! // build.rs of a `#![no_std]` crate
//! fn main() -> Result<(), bgc::build::Error> {
//!     bgc::build::Config::new().runtime(false).compile(&["back_support.bg"])?;
//!     Ok(())
//! }
//! ```
//!
//! Each `.bg` file gives one `<file stem>.rs` in the output directory (`OUT_DIR` unless [`Config::out_dir`] says
//! otherwise; see [`crate::codegen::rust`] for its contents). A file is written only when its content changed, so
//! an unchanged model does not make Cargo rebuild the crate. The first line records the bgc version, the source
//! and an FNV-1a hash of every input text. `cargo:rerun-if-changed` is printed for every `.bg` file and every file
//! it imports (also imports that could not be read, so that creating them reruns the build). On an error the
//! rendered diagnostics (`FILE:LINE:COL` and the source excerpt) go to standard error, which Cargo shows when the
//! build script fails, and [`Config::compile`] returns [`Error::Diagnostics`]; warnings are passed to Cargo as
//! `cargo:warning=` lines.

use crate::codegen;
use crate::diagnostic::{Diagnostic, Severity, render};
use crate::lower::{STD_NAME, SourceLoader};
use crate::span::SourceMap;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Why a compilation failed.
///
/// `Display` is the full message; for [`Error::Diagnostics`] that includes the rendered diagnostics. `Debug` is
/// the same except for [`Error::Diagnostics`], where it is the one-line summary `FILE: bgc found errors (shown
/// above)`: [`Config::compile`] has already printed the diagnostics to standard error, and a build script's
/// `fn main() -> Result<(), bgc::build::Error>` (or `Result<(), Box<dyn std::error::Error>>`) reports its error
/// with `Debug`, so each diagnostic appears once, readable, and not again as an escaped dump of the fields.
#[derive(thiserror::Error)]
pub enum Error {
    #[error(
        "no output directory: OUT_DIR is not set (not run by Cargo?) and Config::out_dir was not given"
    )]
    NoOutDir,
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Errors in a `.bg` file: `rendered` holds them as text (`FILE:LINE:COL` and the source excerpt).
    #[error("{file}: bgc found errors:\n{rendered}")]
    Diagnostics { file: PathBuf, rendered: String },
    #[error("{first} and {second} would both generate {output}")]
    DuplicateOutput {
        first: PathBuf,
        second: PathBuf,
        output: PathBuf,
    },
}

impl std::fmt::Debug for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Diagnostics { file, .. } => {
                write!(f, "{}: bgc found errors (shown above)", file.display())
            }
            other => std::fmt::Display::fmt(other, f),
        }
    }
}

/// What one `.bg` file gave.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Generated {
    pub source: PathBuf,
    pub output: PathBuf,
    /// False when the file on disk already had this content and was left alone.
    pub written: bool,
    /// Every file the compilation read or tried to read (the source and its imports).
    pub inputs: Vec<PathBuf>,
    /// The rendered warnings.
    pub warnings: String,
}

/// The build configuration.
#[derive(Clone, Debug)]
pub struct Config {
    out_dir: Option<PathBuf>,
    cargo_output: bool,
    options: codegen::rust::Options,
}

impl Default for Config {
    fn default() -> Self {
        Config::new()
    }
}

impl Config {
    /// Output to `OUT_DIR`, with Cargo instructions printed.
    pub fn new() -> Config {
        Config {
            out_dir: None,
            cargo_output: true,
            options: codegen::rust::Options::default(),
        }
    }

    /// Whether the generated modules implement `bgc_runtime`'s `ContinuousModel` and `Parametric` for `Model` and
    /// use its `ParamError` (default: true, and the crate depends on `bgc-runtime`). Without them a module needs
    /// only `core`, `nalgebra` (without its `std` feature) and `libm`, and builds in a `#![no_std]` crate.
    pub fn runtime(&mut self, on: bool) -> &mut Config {
        self.options.runtime = on;
        self
    }

    /// Writes the generated files to `dir` (created if missing) instead of `OUT_DIR`.
    pub fn out_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Config {
        self.out_dir = Some(dir.into());
        self
    }

    /// Whether to print `cargo:` instructions and diagnostics (default: true; tests turn it off).
    pub fn cargo_output(&mut self, on: bool) -> &mut Config {
        self.cargo_output = on;
        self
    }

    /// Compiles every file (paths relative to the working directory, which Cargo sets to the package root) and
    /// writes `<stem>.rs` for each. Stops at the first file with errors.
    pub fn compile(&self, files: &[impl AsRef<Path>]) -> Result<Vec<Generated>, Error> {
        let out_dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => std::env::var_os("OUT_DIR")
                .map(PathBuf::from)
                .ok_or(Error::NoOutDir)?,
        };
        std::fs::create_dir_all(&out_dir).map_err(|source| Error::Io {
            path: out_dir.clone(),
            source,
        })?;
        let mut outputs: Vec<(PathBuf, PathBuf)> = Vec::new();
        let mut report = Vec::with_capacity(files.len());
        for file in files {
            let source = file.as_ref().to_path_buf();
            let stem = source
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "model".into());
            let output = out_dir.join(format!("{stem}.rs"));
            if let Some((first, _)) = outputs.iter().find(|(_, o)| *o == output) {
                return Err(Error::DuplicateOutput {
                    first: first.clone(),
                    second: source,
                    output,
                });
            }
            outputs.push((source.clone(), output.clone()));
            report.push(self.compile_one(&source, &output)?);
        }
        Ok(report)
    }

    fn compile_one(&self, source: &Path, output: &Path) -> Result<Generated, Error> {
        let mut loader = RecordingFsLoader::default();
        let rerun = |inputs: &BTreeSet<PathBuf>| {
            if self.cargo_output {
                for p in inputs {
                    println!("cargo:rerun-if-changed={}", p.display());
                }
            }
        };
        loader.requested.insert(source.to_path_buf());
        let bytes = match std::fs::read(source) {
            Ok(b) => b,
            Err(e) => {
                rerun(&loader.requested);
                return Err(Error::Io {
                    path: source.to_path_buf(),
                    source: e,
                });
            }
        };
        let mut sources = SourceMap::new();
        let name = source.display().to_string();
        let next = crate::span::FileId(0);
        let decoded = crate::syntax::decode(next, &bytes).map(str::to_string);
        let result = match decoded {
            Ok(text) => {
                let root = sources.add(name, text);
                codegen::compile(&mut sources, root, &mut loader)
            }
            Err(diag) => {
                sources.add(name, String::from_utf8_lossy(&bytes).into_owned());
                Err(vec![diag])
            }
        };
        rerun(&loader.requested);
        let compiled = match result {
            Ok(c) => c,
            Err(diags) => {
                let rendered = render::to_text(&sources, &diags, false);
                if self.cargo_output {
                    eprintln!("{rendered}");
                }
                return Err(Error::Diagnostics {
                    file: source.to_path_buf(),
                    rendered,
                });
            }
        };
        let warnings = render::to_text(&sources, &compiled.warnings, false);
        if self.cargo_output {
            for d in compiled
                .warnings
                .iter()
                .filter(|d| d.severity == Severity::Warning)
            {
                println!("cargo:warning={}", one_line(&sources, d));
            }
        }
        let code =
            codegen::rust::generate_with(&compiled, &source.display().to_string(), self.options);
        let written = write_if_changed(output, &code)?;
        Ok(Generated {
            source: source.to_path_buf(),
            output: output.to_path_buf(),
            written,
            inputs: loader.requested.into_iter().collect(),
            warnings,
        })
    }
}

/// `FILE:LINE:COL: warning[CODE]: message` (the full text is in [`Generated::warnings`]).
fn one_line(sources: &SourceMap, d: &Diagnostic) -> String {
    let place = d
        .primary_span()
        .and_then(|s| {
            let f = sources.get(s.file)?;
            let (line, col) = f.line_col(s.start as usize);
            Some(format!("{}:{line}:{col}: ", f.name))
        })
        .unwrap_or_default();
    format!(
        "{place}warning[{}]: {}",
        d.code.0,
        d.message.replace('\n', " ")
    )
}

/// Compiles `files` into `OUT_DIR` with the default configuration.
pub fn compile(files: &[impl AsRef<Path>]) -> Result<Vec<Generated>, Error> {
    Config::new().compile(files)
}

/// Writes `text` to `path` unless the file already holds exactly that; returns whether it wrote.
fn write_if_changed(path: &Path, text: &str) -> Result<bool, Error> {
    if std::fs::read(path).is_ok_and(|old| old == text.as_bytes()) {
        return Ok(false);
    }
    std::fs::write(path, text).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(true)
}

/// Reads imports from the file system and remembers every path asked for.
#[derive(Default)]
struct RecordingFsLoader {
    requested: BTreeSet<PathBuf>,
}

impl SourceLoader for RecordingFsLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<String> {
        if path != Path::new(STD_NAME) {
            self.requested.insert(path.to_path_buf());
        }
        let bytes = std::fs::read(path)?;
        String::from_utf8(bytes).map_err(|e| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "not valid UTF-8 (first bad byte at offset {})",
                    e.utf8_error().valid_up_to()
                ),
            )
        })
    }
}
