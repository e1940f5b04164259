//! Where the tests write their files: Cargo's temporary directory of this target (`target/tmp`), so that a run
//! leaves nothing in the system's temporary directory and each run overwrites the files of the last one.

use std::path::PathBuf;

/// The path of `name` in the tests' scratch directory, which exists after this call.
pub fn path(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bgc-tests");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir.join(name)
}
