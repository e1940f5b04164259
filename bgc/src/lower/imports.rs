//! Loading and parsing a file with everything it imports, and the table of model and component declarations.
//!
//! An import names a `.bg` file; the loader resolves it (relative to the importing file, by default lexically; the
//! file system loader canonically and only inside the allowed directories) to the key that identifies the file.
//! `"std.bg"` is the standard library embedded in bgc and never goes through the loader. Each key is loaded once (a
//! diamond of imports is fine); an import that leads back to a file still being processed is a cycle (BG0107); an
//! import that is refused or that the loader cannot read is BG0108, whose message never quotes the file.

use super::{Resolved, SourceLoader};
use crate::diagnostic::Diagnostic;
use crate::span::{FileId, SourceMap};
use crate::syntax::ast::{self, Item, ModelDecl};
use std::collections::{HashMap, HashSet};
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
    /// Loads `root` and its imports. Diagnostics of parsing and importing go to `diags`. The walk keeps its own
    /// stack, so that an import chain of any length cannot overflow the thread's stack, and finds cycles in constant
    /// time per import.
    pub fn load(
        sources: &mut SourceMap,
        root: FileId,
        loader: &mut dyn SourceLoader,
        diags: &mut Vec<Diagnostic>,
    ) -> Program {
        let mut state = LoadState {
            files: Vec::new(),
            stack: Vec::new(),
            on_stack: HashMap::new(),
            done: HashSet::new(),
        };
        let root_key = sources
            .get(root)
            .map(|f| loader.identify_root(Path::new(&f.name)))
            .unwrap_or_default();
        state.enter(sources, root, root_key, diags);
        while let Some(frame) = state.stack.last_mut() {
            let Some(imp) = frame.imports.get(frame.next).cloned() else {
                state.leave();
                continue;
            };
            frame.next += 1;
            state.import(sources, &imp, loader, diags);
        }
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
    /// The files being processed (the import chain), with the imports of each still to follow.
    stack: Vec<Frame>,
    /// The keys on the stack, with their position in it.
    on_stack: HashMap<PathBuf, usize>,
    /// Every key loaded.
    done: HashSet<PathBuf>,
}

struct Frame {
    key: PathBuf,
    id: FileId,
    imports: Vec<ast::Import>,
    next: usize,
}

impl LoadState {
    /// Parses a file and puts it on the stack.
    fn enter(
        &mut self,
        sources: &SourceMap,
        id: FileId,
        key: PathBuf,
        diags: &mut Vec<Diagnostic>,
    ) {
        let Some(file) = sources.get(id) else { return };
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
        self.on_stack.insert(key.clone(), self.stack.len());
        self.done.insert(key.clone());
        self.stack.push(Frame {
            key,
            id,
            imports,
            next: 0,
        });
    }

    fn leave(&mut self) {
        if let Some(frame) = self.stack.pop() {
            self.on_stack.remove(&frame.key);
        }
    }

    /// Follows one import of the file on top of the stack.
    fn import(
        &mut self,
        sources: &mut SourceMap,
        imp: &ast::Import,
        loader: &mut dyn SourceLoader,
        diags: &mut Vec<Diagnostic>,
    ) {
        let Some(top) = self.stack.last() else { return };
        let importer_name = sources
            .get(top.id)
            .map(|f| f.name.clone())
            .unwrap_or_default();
        let resolved = if imp.path == STD_NAME {
            Resolved {
                key: PathBuf::from("<std>"),
                name: STD_DISPLAY_NAME.to_string(),
            }
        } else if !imp.path.ends_with(".bg") {
            diags.push(refused(
                imp,
                &importer_name,
                "an import names a `.bg` source file",
            ));
            return;
        } else {
            match loader.resolve(&top.key, &importer_name, &imp.path) {
                Ok(r) => r,
                Err(err) => {
                    diags.push(refused(imp, &importer_name, &err.to_string()));
                    return;
                }
            }
        };
        if let Some(&pos) = self.on_stack.get(&resolved.key) {
            diags.push(self.cycle(sources, pos, &resolved.name, imp));
            return;
        }
        if self.done.contains(&resolved.key) {
            return;
        }
        let text = if imp.path == STD_NAME {
            STD_SOURCE.to_string()
        } else {
            match loader.load(&resolved.key) {
                Ok(t) => t,
                Err(err) => {
                    diags.push(refused(imp, &importer_name, &err.to_string()));
                    return;
                }
            }
        };
        let child = sources.add(resolved.name, text);
        self.enter(sources, child, resolved.key, diags);
    }

    /// BG0107 for an import of the file at `pos` on the stack.
    fn cycle(&self, sources: &SourceMap, pos: usize, name: &str, imp: &ast::Import) -> Diagnostic {
        let chain: Vec<String> = self.stack[pos..]
            .iter()
            .filter_map(|f| sources.get(f.id).map(|s| s.name.clone()))
            .chain(std::iter::once(name.to_string()))
            .collect();
        Diagnostic::error("BG0107", format!("import cycle: `{}`", chain.join("` -> `")))
            .with_primary(imp.span, format!("`{name}` is already being imported"))
            .with_help("remove one of the imports of the cycle; move shared components to a file that imports neither")
    }
}

/// BG0108: an import that cannot be followed. The message says why, never what the file holds.
fn refused(imp: &ast::Import, importer: &str, why: &str) -> Diagnostic {
    Diagnostic::error(
        "BG0108",
        format!("cannot import `{}`: {why}", imp.path),
    )
    .with_primary(imp.span, "imported here")
    .with_help(format!(
        "an import names a `.bg` file relative to the importing file (`{importer}`), under its directory or an include \
         directory; `\"std.bg\"` is the standard library"
    ))
}

/// Removes `.` and resolves `..` lexically, so that `a/../b.bg` and `b.bg` are one file.
pub fn normalize(path: &Path) -> PathBuf {
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
