//! Lowering: from the AST of a file (and the files it imports) to checked bond-graph models ([`ir::Model`]).
//!
//! The stage loads imports through a [`SourceLoader`] (it never touches files itself), resolves names, flattens
//! component instances into qualified names (`sensor.spring`), resolves bonds and their ports, infers each bond's
//! domain, resolves expressions with their units, evaluates parameter defaults, and checks structure, units and
//! values. Diagnostic codes: BG0107, BG0108 (imports), BG0201-BG0208 (names and references), BG0301-BG0314
//! (structure, domains and units), BG0401-BG0403 (parameter values); see docs/language.md.
//!
//! Order of work for each model: flatten (declarations, parameters, nodes, bonds, ports), structure checks (bond
//! counts, TF/GY and field port numbers), domain inference, element relations with unit and value checks,
//! outputs/vars/coordinates, unused parameters.

mod allow;
mod bonds;
mod builder;
mod consteval;
mod domains;
mod elements;
mod exprs;
mod flatten;
mod imports;
mod instances;
mod references;
mod scope;
mod signals;
mod structure;
mod unit_hints;

#[cfg(test)]
mod fixture_tests;
#[cfg(test)]
mod recovery_tests;
#[cfg(test)]
mod tests;

use crate::diagnostic::Diagnostic;
use crate::ir;
use crate::span::{FileId, SourceMap};
use crate::syntax::ast::ModelKind;
use builder::Builder;
use imports::Program;
use petgraph::Direction;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use crate::diagnostic::suggest::closest;
pub use imports::{STD_DISPLAY_NAME, STD_NAME, STD_SOURCE, normalize};
pub use instances::add_instance_context;

/// Where lowering gets the text of imported files. The loader decides which file an import names and what
/// identifies it (its key: two imports with one key are one file, so a diamond of imports loads it once and a file
/// that imports itself under another name is a cycle). The CLI and `bgc::build` use `bgc::build::FsLoader`
/// (canonical paths, only `.bg` files inside the allowed directories); tests serve files from memory.
/// `"std.bg"` never reaches the loader, and an import that does not end in `.bg` is refused before it does.
pub trait SourceLoader {
    /// The key of the root file, whose name in the [`SourceMap`] is `name`. By default the name with `.` and `..`
    /// resolved lexically.
    fn identify_root(&mut self, name: &Path) -> PathBuf {
        imports::normalize(name)
    }

    /// The file that `import` names when written in the file with key `importer_key` and display name
    /// `importer_name`. By default the import joined to the importer's directory, resolved lexically, as key and
    /// name.
    fn resolve(
        &mut self,
        importer_key: &Path,
        importer_name: &str,
        import: &str,
    ) -> std::io::Result<Resolved> {
        let _ = importer_name;
        let dir = importer_key.parent().unwrap_or(Path::new(""));
        let key = imports::normalize(&dir.join(import));
        Ok(Resolved {
            name: key.display().to_string(),
            key,
        })
    }

    /// The text of the file with this key.
    fn load(&mut self, key: &Path) -> std::io::Result<String>;
}

/// The file an import names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Resolved {
    /// What identifies the file (for [`SourceLoader::load`]).
    pub key: PathBuf,
    /// Its name in diagnostics.
    pub name: String,
}

impl Resolved {
    pub fn new(key: PathBuf, name: &Path) -> Resolved {
        Resolved {
            key,
            name: name.display().to_string(),
        }
    }
}

/// A loader that serves files from a map (paths as the importing file names them, joined to its directory).
#[derive(Clone, Debug, Default)]
pub struct MemoryLoader {
    pub files: HashMap<PathBuf, String>,
}

impl MemoryLoader {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a file.
    pub fn with(mut self, path: impl Into<PathBuf>, text: impl Into<String>) -> Self {
        self.files.insert(path.into(), text.into());
        self
    }
}

impl SourceLoader for MemoryLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<String> {
        self.files
            .get(path)
            .cloned()
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
    }
}

/// Lowers the models of file `root` (already in `sources`; imported files are added to it).
///
/// Returns every `model` of the root file that could be built (components are flattened into the models that
/// instantiate them; a component of the root file that no model uses is checked on its own) and all diagnostics, in
/// the order found, without duplicates. A model is returned even when
/// diagnostics about it are errors: check [`crate::diagnostic::has_errors`] before using it.
pub fn lower(
    sources: &mut SourceMap,
    root: FileId,
    loader: &mut dyn SourceLoader,
) -> (Vec<ir::Model>, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let program = Program::load(sources, root, loader, &mut diags);
    let decls = program.declarations(&mut diags);
    let mut models = Vec::new();
    let mut instantiated: Vec<String> = Vec::new();
    for decl in program.root_models() {
        if decl.kind != ModelKind::Model {
            continue;
        }
        let mut b = Builder::new(&decls, decl);
        b.instantiate(decl, String::new(), None);
        b.check_structure();
        b.infer_domains();
        b.build_relations();
        b.build_signals();
        b.unused_params();
        add_instance_context(&b.model, &mut b.diags);
        diags.append(&mut b.diags);
        instantiated.append(&mut b.instantiated);
        models.push(b.model);
    }
    // Components of the root file that no model uses are checked on their own (so that `bgc check` of a library
    // finds its errors). What depends on how they are connected is left out: the bond counts of their port nodes
    // and domains that only the outside could fix.
    for decl in program.root_models() {
        if decl.kind != ModelKind::Component || instantiated.contains(&decl.name.name) {
            continue;
        }
        let mut b = Builder::new(&decls, decl);
        let sid = b.instantiate(decl, String::new(), None);
        let ports: Vec<_> = b.scopes[sid]
            .ports
            .values()
            .map(|(end, _)| end.node)
            .collect();
        b.suspect_nodes.extend(ports);
        b.check_structure();
        b.infer_domains();
        b.build_relations();
        b.build_signals();
        b.unused_params();
        diags.extend(b.diags.into_iter().filter(|d| d.code.0 != "BG0311"));
    }
    // A component instantiated twice reports its own problems twice; keep one of each.
    let mut seen = std::collections::HashSet::new();
    let unique: Vec<Diagnostic> = diags
        .into_iter()
        .filter(|d| seen.insert((d.code, d.message.clone(), d.primary_span())))
        .collect();
    (models, unique)
}

/// Checks the invariants of a lowered model that has no errors (see [`crate::ir`]): bond counts per kind, TF/GY and
/// field port numbers, and a span for everything. Returns the first violation found.
pub fn validate(model: &ir::Model) -> Result<(), String> {
    let g = &model.graph;
    for n in g.node_indices() {
        let node = &g[n];
        let ins: Vec<&ir::Bond> = g
            .edges_directed(n, Direction::Incoming)
            .map(|e| e.weight())
            .collect();
        let outs: Vec<&ir::Bond> = g
            .edges_directed(n, Direction::Outgoing)
            .map(|e| e.weight())
            .collect();
        let total = ins.len() + outs.len();
        let ok = match node.kind {
            k if k.is_junction() => total >= 2,
            k if k.is_two_port() => {
                ins.len() == 1
                    && outs.len() == 1
                    && ins.iter().all(|b| b.to_port == 0)
                    && outs.iter().all(|b| b.from_port == 1)
            }
            k if k.is_field() => {
                let mut ports: Vec<u32> = ins
                    .iter()
                    .map(|b| b.to_port)
                    .chain(outs.iter().map(|b| b.from_port))
                    .collect();
                ports.sort_unstable();
                ports == (0..node.ports).collect::<Vec<_>>()
            }
            _ => total == 1,
        };
        if !ok {
            return Err(format!(
                "node `{}` ({}) has {} bonds in and {} out",
                node.name,
                node.kind.keyword(),
                ins.len(),
                outs.len()
            ));
        }
    }
    let s = &model.spans;
    let counts = [
        ("nodes", s.nodes.len(), g.node_count()),
        ("node names", s.node_names.len(), g.node_count()),
        ("node relations", s.node_relations.len(), g.node_count()),
        ("node instances", s.node_instances.len(), g.node_count()),
        ("bonds", s.bonds.len(), g.edge_count()),
        ("params", s.params.len(), model.params.len()),
        ("inputs", s.inputs.len(), model.inputs.len()),
        ("outputs", s.outputs.len(), model.outputs.len()),
        ("vars", s.vars.len(), model.vars.len()),
    ];
    for (what, spans, items) in counts {
        if spans != items {
            return Err(format!("{spans} spans for {items} {what}"));
        }
    }
    Ok(())
}
