//! The CLI's side of the outside world: reading source files (through `bgc::build`'s checks) and writing the
//! results.

use bgc::build::FsLoader;
use bgc::diagnostic::Diagnostic;
use bgc::span::{FileId, SourceMap};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The loader of this run, with the include directories of `-I`.
static LOADER: OnceLock<FsLoader> = OnceLock::new();

/// Sets the include directories for the run; an include directory that does not exist is an error.
pub fn set_include_dirs(dirs: &[PathBuf]) -> std::io::Result<()> {
    let loader = FsLoader::new(dirs)?;
    let _ = LOADER.set(loader);
    Ok(())
}

/// A fresh loader for one compilation (the allowed directories depend on its root file).
pub fn loader() -> FsLoader {
    LOADER.get().cloned().unwrap_or_default()
}

/// The name of a model read from standard input (`-`), as diagnostics show it.
pub const STDIN_NAME: &str = "<stdin>";

/// Whether `path` is `-`: the model comes from standard input, as formatters and checkers take `-`.
pub fn is_stdin(path: &Path) -> bool {
    path == Path::new("-")
}

/// A model's root file read into the source map with the loader for its imports.
pub struct Root {
    pub id: FileId,
    /// The file is not valid UTF-8 (it was added with the bad bytes replaced).
    pub decode_error: Option<Diagnostic>,
    pub loader: FsLoader,
}

/// Reads the root file `path` ([`read_source`]) and makes the loader for its imports ([`loader_for`]).
pub fn read_root(sources: &mut SourceMap, path: &Path) -> std::io::Result<Root> {
    let (id, decode_error) = read_source(sources, path)?;
    Ok(Root {
        id,
        decode_error,
        loader: loader_for(path)?,
    })
}

/// The loader for the file `path`: [`loader`], and for standard input the current directory, which is where its
/// imports are looked up (as beside a file).
fn loader_for(path: &Path) -> std::io::Result<FsLoader> {
    let mut loader = loader();
    if is_stdin(path) {
        loader.allow_directory(&std::env::current_dir()?)?;
    }
    Ok(loader)
}

/// Reads standard input as a source file: at most `MAX_SOURCE_BYTES`, like a file.
fn read_stdin() -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let limit = bgc::build::MAX_SOURCE_BYTES;
    let mut bytes = Vec::new();
    std::io::stdin()
        .lock()
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "standard input is larger than the {} MiB a source file may have",
                limit >> 20
            ),
        ));
    }
    Ok(bytes)
}

/// Reads a file (standard input for `-`) into the source map. Invalid UTF-8 is not an I/O error: the file is added with the bad bytes
/// replaced, so that the diagnostic returned can show where they are.
pub fn read_source(
    sources: &mut SourceMap,
    path: &Path,
) -> std::io::Result<(FileId, Option<Diagnostic>)> {
    let (bytes, name) = if is_stdin(path) {
        (read_stdin()?, STDIN_NAME.to_string())
    } else {
        (
            bgc::build::read_source_file(path)?,
            path.display().to_string(),
        )
    };
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

/// Refuses to write `output` over an input of the command: a source file of the model, or another file it reads
/// (`bgc draw m.bg -o m.bg`, `bgc fit ... --data rig.csv --plot rig.csv`). Prints the error; the caller ends with
/// [`crate::cli::Status::UsageOrIo`].
pub fn refuse_overwrite(output: &Path, sources: &SourceMap, others: &[&Path]) -> Result<(), ()> {
    let names: Vec<PathBuf> = sources
        .files()
        .map(|(_, f)| PathBuf::from(&f.name))
        .collect();
    let inputs = names
        .iter()
        .map(PathBuf::as_path)
        .chain(others.iter().copied());
    match bgc::build::overwritten_input(output, inputs) {
        Some(input) => {
            let same = match input == output {
                true => String::new(),
                false => format!(" (the same file as {})", input.display()),
            };
            stderrln(&format!(
                "error: {}{same} is an input of this command: choose another file for the output",
                output.display(),
            ));
            Err(())
        }
        None => Ok(()),
    }
}

/// The largest measured record `bgc fit --data` and `bgc simulate --data` read.
pub const MAX_RECORD_BYTES: u64 = 256 << 20;

/// Refuses a command line that names standard input (`-`) more than once: the first read would take it all and
/// the others would see an empty file. Prints the error; the caller ends with the status returned.
pub fn stdin_once<'a>(paths: impl IntoIterator<Item = &'a Path>) -> Result<(), crate::cli::Status> {
    match paths.into_iter().filter(|p| is_stdin(p)).count() {
        0 | 1 => Ok(()),
        n => {
            stderrln(&format!(
                "error: standard input (`-`) is named {n} times, but it can be read only once: save all but one \
                 of them to files"
            ));
            Err(crate::cli::Status::UsageOrIo)
        }
    }
}

/// Reads a measured record: a regular file, a pipe (`--data <(...)`) or standard input (`-`), up to
/// [`MAX_RECORD_BYTES`]. A device (`/dev/zero` never ends), a directory or a socket is refused without being read.
pub fn read_record(path: &Path) -> std::io::Result<String> {
    use std::io::Read;
    let refuse = |why: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, why);
    let mut bytes = Vec::new();
    if is_stdin(path) {
        std::io::stdin()
            .lock()
            .take(MAX_RECORD_BYTES + 1)
            .read_to_end(&mut bytes)?;
        return record_text(bytes);
    }
    let kind = std::fs::metadata(path)?.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() || kind.is_block_device() || kind.is_socket() {
            return Err(refuse("not a regular file (a device or a socket)".into()));
        }
    }
    if kind.is_dir() {
        return Err(refuse("not a regular file (a directory)".into()));
    }
    std::fs::File::open(path)?
        .take(MAX_RECORD_BYTES + 1)
        .read_to_end(&mut bytes)?;
    record_text(bytes)
}

/// The text of a record read as `bytes`, refused when it is too large or not text (see [`super::record_text`]).
fn record_text(bytes: Vec<u8>) -> std::io::Result<String> {
    let refuse = |why: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, why);
    if bytes.len() as u64 > MAX_RECORD_BYTES {
        return Err(refuse(format!(
            "the record is larger than the {} MiB it may have",
            MAX_RECORD_BYTES >> 20
        )));
    }
    super::record_text::record_text(bytes)
}

/// Writes to standard output. A closed pipe (`bgc ... | head`) is not an error: the output is simply no longer
/// wanted, and the command ends quietly (status 0, as `head` expects). Any other failure (a full disk, `>
/// /dev/full`) ends the command with status 2 and the OS error, because the result was not delivered.
pub fn stdout(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        drop(out);
        output_failed(&e);
    }
}

/// Leaves `value` to the end of the process instead of dropping it: a command's derived model lives until the
/// command ends, and freeing its millions of expression nodes one by one took 0.43 s of the 5.9 s of
/// `bgc equations` (0.9 s of `bgc rust`) on a 100,000-mass chain, where the exit returns the memory at once. For
/// plain data only: nothing whose drop writes or releases anything but memory.
pub fn keep_until_exit<T>(value: T) {
    std::mem::forget(value);
}

/// Ends the process after a failed write to standard output: quietly (0) for a closed pipe, else with status 2.
pub fn output_failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    stderrln(&format!("error: cannot write the output: {e}"));
    std::process::exit(2);
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

/// [`stderr`] with a line end, for a message: what it quotes of the user's input (a file name, a record's column,
/// an option's value) is shown without its control characters, which would drive the terminal.
pub fn stderrln(text: &str) {
    stderr(&format!("{}\n", bgc::diagnostic::unprintable::shown(text)));
}
