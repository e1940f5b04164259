//! FMI export: a model as a Functional Mock-up Unit (FMI 2.0 or 3.0, Model Exchange and Co-Simulation in one
//! FMU) that FMPy, Simulink, OpenModelica and other importers load. See docs/fmu.md.
//!
//! [`Config::build`] compiles a `.bg` file, writes a Rust crate of the chosen model (the generated module of
//! [`crate::codegen::rust`] and the C interface of `template/`), builds it with Cargo as a `cdylib` and zips the
//! library with `modelDescription.xml` ([`description`]) into the FMU. Like [`crate::build`], it is an API that
//! touches files; [`package_sources`] and [`description::model_description`] are the plain parts.
//!
//! ```no_run
//! // build.rs or an xtask
//! bgc::fmu::Config::new().model("back_support").build("models/back_support.bg", "back_support.fmu")?;
//! # Ok::<(), bgc::fmu::Error>(())
//! ```

pub mod description;
mod package;
pub mod structure;
pub mod variables;
pub mod zip;

pub use package::{Sources, package_sources};

use crate::build::FsLoader;
use crate::codegen::{self, CompiledFile};
use crate::diagnostic::render;
use crate::span::SourceMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The FMI version of an FMU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Version {
    #[default]
    Fmi2,
    Fmi3,
}

/// Why an FMU was not made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Errors in the `.bg` file, rendered (`FILE:LINE:COL` and the source excerpt).
    #[error("{file}: bgc found errors:\n{rendered}")]
    Diagnostics { file: PathBuf, rendered: String },
    /// No model, or an ambiguous choice: `{file} declares several models (...)`, `{file} has no model ...`.
    #[error("{file} {message}")]
    Model { file: PathBuf, message: String },
    #[error("cannot run cargo ({cargo}): {source}")]
    Cargo {
        cargo: String,
        #[source]
        source: std::io::Error,
    },
    #[error("cargo could not build the FMU's library (crate in {dir}):\n{stderr}")]
    Build { dir: PathBuf, stderr: String },
    #[error("{0}")]
    Zip(#[from] zip::ZipError),
    /// The FMU would be written over a source file of the model.
    #[error("{fmu} is the model's source file {source_file}: choose another name for the FMU")]
    OverwritesSource { fmu: PathBuf, source_file: PathBuf },
}

/// How to make an FMU.
#[derive(Clone, Debug, Default)]
pub struct Config {
    model: Option<String>,
    version: Version,
    target_dir: Option<PathBuf>,
    include: Vec<PathBuf>,
}

/// What [`Config::build`] made.
#[derive(Clone, Debug)]
pub struct Built {
    pub fmu: PathBuf,
    /// The model identifier (the library's name in the FMU).
    pub identifier: String,
    pub guid: String,
    /// The rendered warnings of the compilation.
    pub warnings: String,
}

impl Config {
    pub fn new() -> Config {
        Config::default()
    }

    /// The model to export when the file declares several (default: the only one).
    pub fn model(&mut self, name: impl Into<String>) -> &mut Config {
        self.model = Some(name.into());
        self
    }

    pub fn version(&mut self, version: Version) -> &mut Config {
        self.version = version;
        self
    }

    /// Cargo's target directory for the library (default: `bgc-fmu` in the system's temporary directory). FMUs
    /// built in one directory share the compiled dependencies.
    pub fn target_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Config {
        self.target_dir = Some(dir.into());
        self
    }

    /// A directory where imports are looked up (as for [`crate::build::Config::include_dir`]).
    pub fn include_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Config {
        self.include.push(dir.into());
        self
    }

    /// Compiles `source`, builds the library with Cargo (the `CARGO` environment variable names it, else
    /// `cargo` on the path) and writes the FMU to `fmu`.
    pub fn build(&self, source: impl AsRef<Path>, fmu: impl AsRef<Path>) -> Result<Built, Error> {
        let (source, fmu) = (source.as_ref(), fmu.as_ref());
        let (compiled, warnings, files) = self.compile(source)?;
        if let Some(file) = crate::build::overwritten_input(fmu, files.iter().map(PathBuf::as_path))
        {
            return Err(Error::OverwritesSource {
                fmu: fmu.to_path_buf(),
                source_file: file.to_path_buf(),
            });
        }
        let sources = package_sources(
            &compiled,
            self.model.as_deref(),
            self.version,
            &source.display().to_string(),
        )
        .map_err(|message| Error::Model {
            file: source.to_path_buf(),
            message,
        })?;
        let target = self
            .target_dir
            .clone()
            .unwrap_or_else(|| std::env::temp_dir().join("bgc-fmu"));
        let library = build_library(&sources, &target)?;
        let mut archive = zip::ZipWriter::new();
        archive.add("modelDescription.xml", sources.description.as_bytes())?;
        let platform = match self.version {
            Version::Fmi2 => "linux64",
            Version::Fmi3 => "x86_64-linux",
        };
        let bytes = std::fs::read(&library).map_err(|e| io(&library, e))?;
        archive.add(
            &format!("binaries/{platform}/{}.so", sources.identifier),
            &bytes,
        )?;
        crate::files::write_whole(fmu, &archive.finish()?).map_err(|e| io(fmu, e))?;
        Ok(Built {
            fmu: fmu.to_path_buf(),
            identifier: sources.identifier,
            guid: sources.guid,
            warnings,
        })
    }

    /// The compiled file, its warnings rendered, and the paths of the files it was read from.
    fn compile(&self, source: &Path) -> Result<(CompiledFile, String, Vec<PathBuf>), Error> {
        let bytes = crate::build::read_source_file(source).map_err(|e| io(source, e))?;
        let mut loader = FsLoader::new(&self.include)
            .map_err(|e| io(self.include.first().map_or(source, |p| p), e))?;
        let mut map = SourceMap::new();
        let name = source.display().to_string();
        let text = match crate::syntax::decode(crate::span::FileId(0), &bytes) {
            Ok(t) => t.to_string(),
            Err(d) => {
                map.add(name, String::from_utf8_lossy(&bytes).into_owned());
                return Err(Error::Diagnostics {
                    file: source.to_path_buf(),
                    rendered: render::to_text(&map, &[d], false),
                });
            }
        };
        let root = map.add(name, text);
        match codegen::compile(&mut map, root, &mut loader) {
            Ok(c) => {
                let warnings = render::to_text(&map, &c.warnings, false);
                let files = map.files().map(|(_, f)| PathBuf::from(&f.name)).collect();
                Ok((c, warnings, files))
            }
            Err(diags) => Err(Error::Diagnostics {
                file: source.to_path_buf(),
                rendered: render::to_text(&map, &diags, false),
            }),
        }
    }
}

fn io(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes the crate under `target/crates/<identifier>-<guid>` and builds it; returns the library's path.
fn build_library(sources: &Sources, target: &Path) -> Result<PathBuf, Error> {
    let dir = target.join("crates").join(&sources.crate_name);
    for (name, text) in &sources.files {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
        }
        // Unchanged files keep their time stamps, so that Cargo does not rebuild an unchanged crate.
        if std::fs::read(&path).is_ok_and(|old| old == text.as_bytes()) {
            continue;
        }
        std::fs::write(&path, text).map_err(|e| io(&path, e))?;
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = dir.join("Cargo.toml");
    let output = Command::new(&cargo)
        .args(["build", "--release", "--quiet", "--manifest-path"])
        .arg(&manifest)
        .env("CARGO_TARGET_DIR", target)
        // The flags of an enclosing build (a build script's, a test's) are not the library's.
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_BUILD_RUSTFLAGS")
        .output()
        .map_err(|source| Error::Cargo {
            cargo: cargo.clone(),
            source,
        })?;
    if !output.status.success() {
        return Err(Error::Build {
            dir,
            stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        });
    }
    Ok(target
        .join("release")
        .join(format!("lib{}.so", sources.lib_name)))
}
