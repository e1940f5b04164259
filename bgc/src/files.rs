//! Writing an output file whole or not at all.
//!
//! A file written in place is truncated first: a full disk, a signal or a crash halfway leaves a broken model, FMU
//! or picture where a good one was (and a build that reads it later fails far from the cause). The new bytes go to
//! a file beside the target, which is renamed over it once complete, so the target holds either its old contents
//! or the new ones.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` whole: through a file beside it that is renamed over it. An existing file keeps its
/// permissions and is reached through symbolic links. Where that cannot be done the bytes are written in place:
/// when the target exists and is no regular file (`/dev/stdout`, a pipe: renaming over it would replace the device
/// entry) and when its directory takes no new file but the file is writable.
pub fn write_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let existing = std::fs::metadata(path).ok();
    if existing.as_ref().is_some_and(|m| !m.is_file()) {
        return std::fs::write(path, bytes);
    }
    let target = match existing {
        Some(_) => std::fs::canonicalize(path)?,
        None => path.to_path_buf(),
    };
    let temp = temporary_beside(&target);
    let mut file = match std::fs::File::create(&temp) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied && existing.is_some() => {
            return std::fs::write(&target, bytes);
        }
        Err(e) => return Err(e),
    };
    let written = (|| {
        file.write_all(bytes)?;
        file.sync_all()?;
        if let Some(m) = &existing {
            std::fs::set_permissions(&temp, m.permissions())?;
        }
        std::fs::rename(&temp, &target)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    written
}

/// A hidden file name in the target's directory, unique to this process.
fn temporary_beside(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{name}.bgc-{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::write_whole;

    /// A fresh directory of the test's own, removed with everything in it when the test ends (passed or not).
    struct Scratch(std::path::PathBuf);

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    impl std::ops::Deref for Scratch {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            &self.0
        }
    }

    fn scratch(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("bgc-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        Scratch(dir)
    }

    fn entries(dir: &std::path::Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map(|r| {
                r.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        names
    }

    #[test]
    fn a_new_file_and_a_replaced_one_hold_the_bytes_and_nothing_is_left_beside_them() {
        let dir = scratch("new");
        let path = dir.join("out.svg");
        write_whole(&path, b"first").unwrap_or_else(|e| panic!("{e}"));
        write_whole(&path, b"second").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read(&path).ok().as_deref(), Some(&b"second"[..]));
        assert_eq!(entries(&dir), ["out.svg"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions_and_its_link() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("link");
        let real = dir.join("real.dot");
        std::fs::write(&real, "old").unwrap_or_else(|e| panic!("{e}"));
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640))
            .unwrap_or_else(|e| panic!("{e}"));
        let link = dir.join("link.dot");
        std::os::unix::fs::symlink(&real, &link).unwrap_or_else(|e| panic!("{e}"));
        write_whole(&link, b"new").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read_to_string(&real).ok().as_deref(), Some("new"));
        assert!(std::fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink()));
        let mode = std::fs::metadata(&real)
            .map(|m| m.permissions().mode() & 0o777)
            .ok();
        assert_eq!(mode, Some(0o640));
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = scratch("fail");
        // The target is a directory: nothing is written over it.
        let target = dir.join("taken");
        std::fs::create_dir_all(target.join("inside")).unwrap_or_else(|e| panic!("{e}"));
        assert!(write_whole(&target, b"x").is_err());
        assert_eq!(entries(&dir), ["taken"]);
        // A missing directory: nothing is created.
        assert!(write_whole(&dir.join("no/such/dir.svg"), b"x").is_err());
        assert_eq!(entries(&dir), ["taken"]);
    }
}
