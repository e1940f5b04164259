//! The server's side of the outside world: document URIs as paths, and a source loader that reads the editor's
//! unsaved text of open documents before the files on disk.
//!
//! The analysis itself never touches files; it gets its imports through this loader, which wraps
//! [`FsLoader`] (the CLI's rules: canonical paths, only `.bg` files inside the root's directory and the include
//! directories) and serves an open document's text in place of the file, so that an importer sees the unsaved
//! text of the file it imports.

use crate::build::FsLoader;
use crate::lower::{Resolved, STD_DISPLAY_NAME, STD_SOURCE, SourceLoader};
use lsp_types::Uri;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The path of a `file:` URI, percent-decoded; `None` for other schemes or a malformed URI.
pub fn uri_to_path(uri: &Uri) -> Option<PathBuf> {
    let rest = uri.as_str().strip_prefix("file://")?;
    // An authority (`file://host/path`) is dropped: the path is what names the file on this machine.
    let path = &rest[rest.find('/')?..];
    let path = path.split(['?', '#']).next().unwrap_or(path);
    let decoded = percent_decode(path)?;
    // `file:///C:/x` on Windows: the path is `C:/x`.
    let bytes = decoded.as_bytes();
    if cfg!(windows) && bytes.len() > 2 && bytes[2] == b':' {
        return Some(PathBuf::from(&decoded[1..]));
    }
    Some(PathBuf::from(decoded))
}

/// The `file:` URI of an absolute path.
pub fn path_to_uri(path: &Path) -> Option<Uri> {
    let text = path.to_str()?.replace('\\', "/");
    let mut out = String::from("file://");
    if !text.starts_with('/') {
        out.push('/');
    }
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/:".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    Uri::from_str(&out).ok()
}

fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The key under which an open document stands in for its file: the canonical path when the file exists (as
/// [`FsLoader`] identifies files), else the path with `.` and `..` resolved.
pub fn document_key(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| crate::lower::normalize(path))
}

/// [`FsLoader`] with the open documents' text in front of the files.
pub struct OverlayLoader<'a> {
    pub fs: FsLoader,
    /// Open documents by [`document_key`].
    pub overlay: &'a HashMap<PathBuf, String>,
}

impl SourceLoader for OverlayLoader<'_> {
    fn identify_root(&mut self, name: &Path) -> PathBuf {
        let key = self.fs.identify_root(name);
        if self.overlay.contains_key(&key) {
            key
        } else {
            document_key(name)
        }
    }

    fn resolve(
        &mut self,
        importer_key: &Path,
        importer_name: &str,
        import: &str,
    ) -> std::io::Result<Resolved> {
        match self.fs.resolve(importer_key, importer_name, import) {
            Ok(r) => Ok(r),
            Err(e) => {
                // A document open in the editor but not yet saved to disk.
                let dir = importer_key.parent().unwrap_or(Path::new(""));
                let key = crate::lower::normalize(&dir.join(import));
                if self.overlay.contains_key(&key) {
                    Ok(Resolved::new(key.clone(), &key))
                } else {
                    Err(e)
                }
            }
        }
    }

    fn load(&mut self, key: &Path) -> std::io::Result<String> {
        match self.overlay.get(key) {
            Some(text) => Ok(text.clone()),
            None => self.fs.load(key),
        }
    }
}

/// Where locations in the embedded standard library point: a copy of it written once per bgc version under the
/// system's temporary directory, so that the editor can open it. `None` when it cannot be written.
pub fn std_library_path() -> Option<PathBuf> {
    let dir = std::env::temp_dir().join(format!("bgc-std-{}", env!("CARGO_PKG_VERSION")));
    let path = dir.join("std.bg");
    if std::fs::read_to_string(&path).is_ok_and(|t| t == STD_SOURCE) {
        return Some(path);
    }
    std::fs::create_dir_all(&dir).ok()?;
    std::fs::write(&path, STD_SOURCE).ok()?;
    Some(path)
}

/// The URI of a file of the source map, by its name there (absolute paths, or the standard library's name).
pub fn source_uri(name: &str) -> Option<Uri> {
    if name == STD_DISPLAY_NAME {
        return path_to_uri(&std_library_path()?);
    }
    path_to_uri(Path::new(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_and_paths_round_trip_with_escapes() {
        let path = Path::new("/home/me/exo models/back µ.bg");
        let uri = path_to_uri(path);
        assert_eq!(
            uri.as_ref().map(|u| u.as_str().to_string()),
            Some("file:///home/me/exo%20models/back%20%C2%B5.bg".to_string())
        );
        assert_eq!(uri.as_ref().and_then(uri_to_path), Some(path.to_path_buf()));
        let other = Uri::from_str("untitled:Untitled-1").ok();
        assert_eq!(other.as_ref().and_then(uri_to_path), None);
    }
}
