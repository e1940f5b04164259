//! The analysis of one document: the compiler's front end on the text in memory, and what the editor features
//! read from it.
//!
//! [`analyse`] is a pure function of the text and what the loader serves for the imports. It runs what `bgc
//! check` runs (parse, lower with the imports, causality of each model when lowering found no error;
//! [`analyse_front`]) and then the equations stage on each model whose causality has no error
//! ([`derive_equations`]), so that the editor shows the equation stage's findings too; it keeps the syntax trees of
//! every file for the index of names, and each model's causality and equations for hover.

use super::index::Index;
use crate::causality::Causality;
use crate::diagnostic::{Diagnostic, has_errors};
use crate::equations::Equations;
use crate::ir;
use crate::lower::SourceLoader;
use crate::span::{FileId, SourceMap};
use crate::syntax::ast;

/// One model of the root file and what the later stages derived for it.
#[derive(Clone, Debug)]
pub struct ModelFacts {
    pub model: ir::Model,
    /// `None` when lowering found errors.
    pub causality: Option<Causality>,
    /// True when the causality has no error, so that the equations can be derived.
    pub causal: bool,
    /// `None` when an earlier stage found errors or the equations are not derived yet.
    pub equations: Option<Equations>,
}

/// Everything known about one document.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The root file (id 0) and every file it imports.
    pub sources: SourceMap,
    pub root: FileId,
    /// The syntax tree of every file of `sources`.
    pub files: Vec<(FileId, ast::File)>,
    /// The findings of every stage, in the order found.
    pub diagnostics: Vec<Diagnostic>,
    pub models: Vec<ModelFacts>,
    pub index: Index,
    /// True once [`derive_equations`] ran: `diagnostics` then hold the equation stage's findings too.
    pub equations_done: bool,
}

impl Analysis {
    pub fn root_text(&self) -> &str {
        self.sources
            .get(self.root)
            .map(|f| f.text.as_str())
            .unwrap_or("")
    }

    /// The file of `sources` with this name.
    pub fn file_named(&self, name: &str) -> Option<FileId> {
        self.sources
            .files()
            .find(|(_, f)| f.name == name)
            .map(|(id, _)| id)
    }
}

/// Analyses the text of the file named `name` (a path; imports are resolved relative to it by `loader`): the
/// front end ([`analyse_front`]) and then the equations ([`derive_equations`]).
pub fn analyse(name: &str, text: &str, loader: &mut dyn SourceLoader) -> Analysis {
    let mut analysis = analyse_front(name, text, loader);
    derive_equations(&mut analysis);
    analysis
}

/// The models of the root file: the equations of each model whose causality has no error, and their findings.
/// The equations stage is the expensive one (seconds for ten thousand elements), so the server may run it apart
/// from the rest.
pub fn derive_equations(analysis: &mut Analysis) {
    for facts in &mut analysis.models {
        let Some(causality) = facts.causality.as_ref().filter(|_| facts.causal) else {
            continue;
        };
        let (equations, mut found) = crate::equations::derive(&facts.model, causality);
        crate::lower::add_instance_context(&facts.model, &mut found);
        analysis.diagnostics.extend(found);
        facts.equations = Some(equations);
    }
    analysis.equations_done = true;
}

/// Parse, lowering and causality of the text (what `bgc check` runs), and the index of names.
pub fn analyse_front(name: &str, text: &str, loader: &mut dyn SourceLoader) -> Analysis {
    let mut sources = SourceMap::new();
    let root = sources.add(name, text);
    let (lowered, mut diagnostics) = crate::lower::lower(&mut sources, root, loader);
    let lowering_failed = has_errors(&diagnostics);
    let mut models = Vec::with_capacity(lowered.len());
    for model in lowered {
        if lowering_failed {
            models.push(ModelFacts {
                model,
                causality: None,
                causal: false,
                equations: None,
            });
            continue;
        }
        let (causality, mut found) = crate::causality::analyse(&model);
        crate::lower::add_instance_context(&model, &mut found);
        let causal = !has_errors(&found);
        diagnostics.extend(found);
        models.push(ModelFacts {
            model,
            causality: Some(causality),
            causal,
            equations: None,
        });
    }
    let files: Vec<(FileId, ast::File)> = sources
        .files()
        .map(|(id, f)| (id, crate::syntax::parse(id, &f.text).0))
        .collect();
    let index = Index::build(&files);
    Analysis {
        sources,
        root,
        files,
        diagnostics,
        models,
        index,
        equations_done: false,
    }
}
