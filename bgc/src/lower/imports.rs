//! Loading and parsing a file with everything it imports, and the table of model and component declarations.
//!
//! Imports are resolved relative to the importing file's name; `"std.bg"` is the standard library embedded in bgc
//! and never goes through the loader. Each file is loaded once (a diamond of imports is fine); an import that leads
//! back to a file still being processed is a cycle (BG0107); a file the loader cannot read is BG0108.

use super::SourceLoader;
use crate::diagnostic::Diagnostic;
use crate::span::{FileId, SourceMap};
use crate::syntax::ast::{self, Item, ModelDecl};
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// The standard library, embedded.
pub const STD_SOURCE: &str = include_str!("../../std/std.bg");
/// The import path that names the standard library.
pub const STD_NAME: &str = "std.bg";
/// The name the standard library has in diagnostics: its path in bgc's sources, where a user can read it.
pub const STD_DISPLAY_NAME: &str = "bgc/std/std.bg";

/// Every parsed file of one compilation, the root first.
pub(crate) struct Program {
    pub files: Vec<(FileId, ast::File)>,
}

impl Program {
    /// Loads `root` and its imports, recursively. Diagnostics of parsing and importing go to `diags`.
    pub fn load(
        sources: &mut SourceMap,
        root: FileId,
        loader: &mut dyn SourceLoader,
        diags: &mut Vec<Diagnostic>,
    ) -> Program {
        let mut state = LoadState {
            files: Vec::new(),
            stack: Vec::new(),
            done: HashMap::new(),
        };
        let root_key = sources
            .get(root)
            .map(|f| normalize(Path::new(&f.name)))
            .unwrap_or_default();
        state.visit(sources, root, root_key, loader, diags);
        Program { files: state.files }
    }

    /// The models and components of all files by name. A name declared twice is BG0202 (the first one is kept).
    pub fn declarations(&self, diags: &mut Vec<Diagnostic>) -> HashMap<String, &ModelDecl> {
        let mut table: HashMap<String, &ModelDecl> = HashMap::new();
        for (_, file) in &self.files {
            for item in &file.items {
                let Item::Model(decl) = item else { continue };
                if let Some(first) = table.get(&decl.name.name) {
                    diags.push(super::scope::duplicate(
                        &decl.name.name,
                        decl.name.span,
                        first.name.span,
                    ));
                } else {
                    table.insert(decl.name.name.clone(), decl);
                }
            }
        }
        table
    }

    /// The declarations of the root file, in order.
    pub fn root_models(&self) -> impl Iterator<Item = &ModelDecl> {
        self.files.first().into_iter().flat_map(|(_, f)| {
            f.items.iter().filter_map(|i| match i {
                Item::Model(m) => Some(m),
                Item::Import(_) => None,
            })
        })
    }
}

struct LoadState {
    files: Vec<(FileId, ast::File)>,
    /// The files being processed (the import chain), by key.
    stack: Vec<(PathBuf, FileId)>,
    done: HashMap<PathBuf, FileId>,
}

impl LoadState {
    fn visit(
        &mut self,
        sources: &mut SourceMap,
        id: FileId,
        key: PathBuf,
        loader: &mut dyn SourceLoader,
        diags: &mut Vec<Diagnostic>,
    ) {
        let Some(file) = sources.get(id) else { return };
        let name = file.name.clone();
        let (ast, parse_diags) = crate::syntax::parse(id, &file.text);
        diags.extend(parse_diags);
        let imports: Vec<ast::Import> = ast
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Import(imp) => Some(imp.clone()),
                Item::Model(_) => None,
            })
            .collect();
        self.files.push((id, ast));
        self.stack.push((key.clone(), id));
        self.done.insert(key, id);
        for imp in imports {
            let (child_key, child_name, text) = if imp.path == STD_NAME {
                (PathBuf::from("<std>"), STD_DISPLAY_NAME.to_string(), None)
            } else {
                let dir = Path::new(&name).parent().unwrap_or(Path::new(""));
                let path = normalize(&dir.join(&imp.path));
                (path.clone(), path.display().to_string(), Some(path))
            };
            if let Some(pos) = self.stack.iter().position(|(k, _)| *k == child_key) {
                let chain: Vec<String> = self.stack[pos..]
                    .iter()
                    .filter_map(|(_, f)| sources.get(*f).map(|s| s.name.clone()))
                    .chain(std::iter::once(child_name.clone()))
                    .collect();
                diags.push(
                    Diagnostic::error("BG0107", format!("import cycle: `{}`", chain.join("` -> `")))
                        .with_primary(imp.span, format!("`{child_name}` is already being imported"))
                        .with_help("remove one of the imports of the cycle; move shared components to a file that imports neither"),
                );
                continue;
            }
            if self.done.contains_key(&child_key) {
                continue;
            }
            let text = match text {
                None => STD_SOURCE.to_string(),
                Some(path) => match loader.load(&path) {
                    Ok(t) => t,
                    Err(err) => {
                        diags.push(
                            Diagnostic::error(
                                "BG0108",
                                format!("cannot read imported file `{child_name}`: {err}"),
                            )
                            .with_primary(imp.span, "imported here")
                            .with_help(format!(
                                "import paths are relative to the importing file (`{name}`); `\"std.bg\"` is the standard library"
                            )),
                        );
                        continue;
                    }
                },
            };
            let child = sources.add(child_name, text);
            self.visit(sources, child, child_key, loader, diags);
        }
        self.stack.pop();
    }
}

/// Removes `.` and resolves `..` lexically, so that `a/../b.bg` and `b.bg` are one file.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                // `file_name` is None when the path is empty or ends in `..`: then `..` must stay.
                if out.file_name().is_some() {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}
