//! The build-script API: compile `.bg` files into Rust modules from a crate's `build.rs`, in the style of
//! `prost-build`.
//!
//! ```toml
//! [dependencies]
//! bgc-runtime = { path = "../runtime" }
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
//! `core`. They reach `nalgebra` and `libm` through the runtime's re-exports (`bgc_runtime::nalgebra`), so the
//! crate needs no dependency on either, and a `nalgebra` of its own may be another version. For a `#![no_std]`
//! crate, leave out the runtime's trait implementations with [`Config::runtime`]; the module then uses the crate's
//! own `nalgebra` and `libm`:
//!
//! ```toml
//! [dependencies]
//! libm = "0.2"
//! nalgebra = { version = "0.35", default-features = false }
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
use crate::lower::{Resolved, SourceLoader};
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
    warnings: bool,
    options: codegen::rust::Options,
    include: Vec<PathBuf>,
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
            warnings: true,
            options: codegen::rust::Options::default(),
            include: Vec::new(),
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

    /// Adds a directory where imports are looked up when they are not found beside the importing file. Imports
    /// resolve only to `.bg` files inside the directory of the file compiled and the include directories.
    pub fn include_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Config {
        self.include.push(dir.into());
        self
    }

    /// Whether to print `cargo:` instructions and diagnostics (default: true; tests turn it off).
    pub fn cargo_output(&mut self, on: bool) -> &mut Config {
        self.cargo_output = on;
        self
    }

    /// Whether to print the models' warnings as `cargo:warning` lines (default: true). Turn it off for fixtures
    /// whose findings are intended and checked elsewhere (a compiler's test corpus), so that a build stays quiet;
    /// in a model of one's own, acknowledge an intended finding at its place with `allow` instead (see
    /// docs/language.md). Errors are printed and returned whatever this says.
    pub fn warnings(&mut self, on: bool) -> &mut Config {
        self.warnings = on;
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
        let mut loader = FsLoader::new(&self.include).map_err(|source| Error::Io {
            path: self.include.first().cloned().unwrap_or_default(),
            source,
        })?;
        let rerun = |loader: &FsLoader| {
            if self.cargo_output {
                println!("cargo:rerun-if-changed={}", source.display());
                for p in loader.requested().filter(|p| *p != source) {
                    println!("cargo:rerun-if-changed={}", p.display());
                }
            }
        };
        let bytes = match read_source_file(source) {
            Ok(b) => b,
            Err(e) => {
                rerun(&loader);
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
        rerun(&loader);
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
        if self.cargo_output && self.warnings {
            for d in compiled
                .warnings
                .iter()
                .filter(|d| d.severity == Severity::Warning)
            {
                println!("cargo:warning={}", one_line(&sources, d));
            }
        }
        let base = std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from);
        let name = header_name(source, base.as_deref());
        let code = codegen::rust::generate_with(&compiled, &name, self.options);
        let written = write_if_changed(output, &code)?;
        Ok(Generated {
            source: source.to_path_buf(),
            output: output.to_path_buf(),
            written,
            inputs: std::iter::once(source.to_path_buf())
                .chain(
                    loader
                        .requested()
                        .filter(|p| *p != source)
                        .map(Path::to_path_buf),
                )
                .collect(),
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

/// The name of a source in the `@generated` header: relative to `base` (the crate's directory) when it lies inside
/// it, with `.` and `..` resolved and `/` between components, so that two checkouts of a crate, on any platform,
/// generate the same bytes.
pub fn header_name(source: &Path, base: Option<&Path>) -> String {
    let relative = base
        .and_then(|b| {
            let b = std::fs::canonicalize(b).ok()?;
            let s = std::fs::canonicalize(source).ok()?;
            s.strip_prefix(&b).ok().map(Path::to_path_buf)
        })
        .unwrap_or_else(|| crate::lower::normalize(source));
    let parts: Vec<String> = relative
        .components()
        .map(|c| match c {
            // Joined with `/`, the root's empty part gives the leading `/`.
            std::path::Component::RootDir => String::new(),
            other => other.as_os_str().to_string_lossy().into_owned(),
        })
        .collect();
    parts.join("/")
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
    crate::files::write_whole(path, text.as_bytes()).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(true)
}

/// The largest source file read (64 MiB): a model is text written by people or generated (a chain of 100,000
/// elements takes 24 MB); anything larger is a mistake or an attack, and is refused before it fills the memory.
pub const MAX_SOURCE_BYTES: u64 = 64 << 20;

/// The first of `inputs` that `output` names too (the same existing file, links resolved): writing the output
/// there would destroy an input (`bgc fmu model.bg -o model.bg`).
pub fn overwritten_input<'a>(
    output: &Path,
    inputs: impl IntoIterator<Item = &'a Path>,
) -> Option<&'a Path> {
    let target = std::fs::canonicalize(output).ok()?;
    inputs
        .into_iter()
        .find(|p| std::fs::canonicalize(p).is_ok_and(|q| q == target))
}

/// Reads a source file: a `.bg` file (by the name it resolves to, so a link named `x.bg` to another file is
/// refused too) that is a regular file (not a FIFO, a device or a directory, which could block or never end) of at
/// most [`MAX_SOURCE_BYTES`]. Refusing other files keeps their contents out of diagnostics, which quote the source.
pub fn read_source_file(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let refuse = |why: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, why);
    // Asked before opening, because opening a FIFO blocks until something writes to it.
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        return Err(refuse(format!("not a regular file ({})", describe(kind))));
    }
    let resolved = std::fs::canonicalize(path)?;
    if resolved.extension().is_none_or(|e| e != "bg") {
        return Err(refuse(if path.extension().is_some_and(|e| e == "bg") {
            format!(
                "it leads to {}, which is not a `.bg` file (only `.bg` files are read as models)",
                resolved.display()
            )
        } else {
            "not a `.bg` file (only `.bg` files are read as models)".to_string()
        }));
    }
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    if len > MAX_SOURCE_BYTES {
        return Err(refuse(too_large(len)));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // The file may grow between the check and the read: read one byte more than allowed to notice.
    file.take(MAX_SOURCE_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_SOURCE_BYTES {
        return Err(refuse(too_large(bytes.len() as u64)));
    }
    Ok(bytes)
}

fn too_large(len: u64) -> String {
    format!(
        "the file is larger than the {} MiB a source file may have ({len} bytes or more)",
        MAX_SOURCE_BYTES >> 20
    )
}

fn describe(kind: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

/// Reads sources from the file system for the CLI and [`Config`], and remembers every path asked for.
///
/// A file is identified by its canonical path, so that one file reached by different relative paths or through
/// a symbolic link is one file (a diamond of imports loads it once; a file that imports itself under another name
/// is a cycle). An import is looked up relative to the importing file, then in each include directory, and must
/// resolve to a `.bg` file inside the root file's directory or an include directory: a model cannot make bgc read,
/// or show in a diagnostic, anything else.
#[derive(Clone, Debug, Default)]
pub struct FsLoader {
    /// The include directories as given (for names in diagnostics) and canonical.
    include: Vec<(PathBuf, PathBuf)>,
    /// The canonical directories imports may resolve into.
    allowed: Vec<PathBuf>,
    requested: BTreeSet<PathBuf>,
}

impl FsLoader {
    /// A loader with these include directories (each must exist).
    pub fn new(include: &[PathBuf]) -> std::io::Result<FsLoader> {
        let mut loader = FsLoader::default();
        for dir in include {
            let canonical = std::fs::canonicalize(dir).map_err(|e| {
                std::io::Error::new(
                    e.kind(),
                    format!("include directory {}: {e}", dir.display()),
                )
            })?;
            if !canonical.is_dir() {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("include directory {}: not a directory", dir.display()),
                ));
            }
            loader.allowed.push(canonical.clone());
            loader.include.push((dir.clone(), canonical));
        }
        Ok(loader)
    }

    /// Lets imports resolve into `dir` (which must exist), as into the importing file's directory: for a root that
    /// is not a file (a model read from standard input), whose imports are looked up in the current directory.
    pub fn allow_directory(&mut self, dir: &Path) -> std::io::Result<()> {
        self.allowed.push(std::fs::canonicalize(dir)?);
        Ok(())
    }

    /// Every path read or asked for (the root file and its imports, also those that could not be read).
    pub fn requested(&self) -> impl Iterator<Item = &Path> {
        self.requested.iter().map(PathBuf::as_path)
    }

    fn candidate(&self, path: &Path) -> std::io::Result<PathBuf> {
        let canonical = std::fs::canonicalize(path)?;
        if canonical.extension().is_none_or(|e| e != "bg") {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the file it leads to is not a `.bg` file",
            ));
        }
        if !self.allowed.iter().any(|dir| canonical.starts_with(dir)) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::PermissionDenied,
                "the file is outside the importing file's directory and the include directories",
            ));
        }
        Ok(canonical)
    }
}

impl SourceLoader for FsLoader {
    fn identify_root(&mut self, name: &Path) -> PathBuf {
        self.requested.insert(name.to_path_buf());
        match std::fs::canonicalize(name) {
            Ok(key) => {
                if let Some(dir) = key.parent() {
                    self.allowed.push(dir.to_path_buf());
                }
                key
            }
            Err(_) => crate::lower::normalize(name),
        }
    }

    fn resolve(
        &mut self,
        importer_key: &Path,
        importer_name: &str,
        import: &str,
    ) -> std::io::Result<Resolved> {
        let beside = importer_key.parent().unwrap_or(Path::new("")).join(import);
        let name_dir = Path::new(importer_name).parent().unwrap_or(Path::new(""));
        let shown = crate::lower::normalize(&name_dir.join(import));
        self.requested.insert(shown.clone());
        let mut first_error = match self.candidate(&beside) {
            Ok(key) => return Ok(Resolved::new(key, &shown)),
            Err(e) => e,
        };
        for (given, canonical) in &self.include {
            match self.candidate(&canonical.join(import)) {
                Ok(key) => return Ok(Resolved::new(key, &given.join(import))),
                Err(e) if first_error.kind() == std::io::ErrorKind::NotFound => first_error = e,
                Err(_) => {}
            }
        }
        Err(first_error)
    }

    fn load(&mut self, key: &Path) -> std::io::Result<String> {
        let bytes = read_source_file(key)?;
        // The root file's check (UTF-16 said as such, the first bad byte), in the words of an import error.
        crate::syntax::text_of(&bytes)
            .map(str::to_string)
            .map_err(|cause| std::io::Error::new(std::io::ErrorKind::InvalidData, cause))
    }
}
