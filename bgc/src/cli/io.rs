//! Reading source files for the CLI: the filesystem side of `lower::SourceLoader`.

use bgc::diagnostic::Diagnostic;
use bgc::lower::SourceLoader;
use bgc::span::{FileId, SourceMap};
use std::path::Path;

/// Loads imports from the filesystem.
pub struct FsLoader;

impl SourceLoader for FsLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<String> {
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

/// Reads a file into the source map. Invalid UTF-8 is not an I/O error: the file is added with the bad bytes
/// replaced, so that the diagnostic returned can show where they are.
pub fn read_source(
    sources: &mut SourceMap,
    path: &Path,
) -> std::io::Result<(FileId, Option<Diagnostic>)> {
    let bytes = std::fs::read(path)?;
    let name = path.display().to_string();
    // The id the file will get, so that the decode diagnostic points into it.
    let next = FileId(sources.files().count() as u32);
    match bgc::syntax::decode(next, &bytes) {
        Ok(text) => Ok((sources.add(name, text), None)),
        Err(diag) => {
            let id = sources.add(name, String::from_utf8_lossy(&bytes).into_owned());
            Ok((id, Some(diag)))
        }
    }
}

/// Writes to standard output. A closed pipe (`bgc ... | head`) is not an error worth a panic, as `print!` would
/// make it: the output is simply no longer wanted.
pub fn stdout(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// Writes to standard error, ignoring a closed pipe.
pub fn stderr(text: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// [`stdout`] with a line end.
pub fn stdoutln(text: &str) {
    stdout(&format!("{text}\n"));
}

/// [`stderr`] with a line end.
pub fn stderrln(text: &str) {
    stderr(&format!("{text}\n"));
}
