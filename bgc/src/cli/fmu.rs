//! `bgc fmu`: a model as a Functional Mock-up Unit (see `bgc::fmu`).

use super::Status;
use super::io::stderrln;
use bgc::fmu::{Config, Error, Version};
use std::path::{Path, PathBuf};

pub fn fmu(
    file: &Path,
    model: Option<&str>,
    fmi: u8,
    output: &Path,
    target_dir: Option<PathBuf>,
    include: &[PathBuf],
) -> Status {
    let mut config = Config::new();
    config.version(if fmi == 3 {
        Version::Fmi3
    } else {
        Version::Fmi2
    });
    if let Some(m) = model {
        config.model(m);
    }
    if let Some(dir) = target_dir {
        config.target_dir(dir);
    }
    for dir in include {
        config.include_dir(dir.clone());
    }
    match config.build(file, output) {
        Ok(built) => {
            if !built.warnings.trim().is_empty() {
                super::io::stderr(&built.warnings);
            }
            stderrln(&format!(
                "wrote {} (FMI {}.0, model identifier `{}`, GUID {})",
                output.display(),
                fmi,
                built.identifier,
                built.guid
            ));
            Status::Ok
        }
        Err(Error::Diagnostics { rendered, .. }) => {
            super::io::stderr(&rendered);
            Status::InputErrors
        }
        Err(e) => {
            stderrln(&format!("error: {e}"));
            Status::UsageOrIo
        }
    }
}
