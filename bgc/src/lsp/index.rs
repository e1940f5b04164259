//! The names of a program and where each is used: declarations (models, components, parameters, inputs, outputs,
//! vars, elements, instances, ports) and the references to them, found in the syntax trees of the root file and
//! the files it imports.
//!
//! Resolution follows the language's scoping (docs/language.md): a name in a model or component body names a
//! declaration of that body; `inst.x` names `x` inside the component that `inst` instantiates (to any depth); an
//! instance's component is a model or component of any file of the program, the first declaration of a name
//! winning as in lowering; an instance's override `k = ...` names the component's parameter. The index is built
//! from the trees alone, so it works while the file has errors; names that do not resolve are left out.

use crate::span::{FileId, Span};
use crate::syntax::ast::{self, ElementBody, Expr, ExprKind, Item, ModelDecl, NodeRef, Stmt};
use std::collections::HashMap;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SymbolKind {
    Model,
    Component,
    Param,
    Input,
    Output,
    Var,
    Element,
    Instance,
    Port,
}

impl SymbolKind {
    pub fn noun(self) -> &'static str {
        match self {
            SymbolKind::Model => "model",
            SymbolKind::Component => "component",
            SymbolKind::Param => "parameter",
            SymbolKind::Input => "input",
            SymbolKind::Output => "output",
            SymbolKind::Var => "integrated flow",
            SymbolKind::Element => "element",
            SymbolKind::Instance => "instance",
            SymbolKind::Port => "port",
        }
    }
}

/// One declaration.
#[derive(Clone, Debug, PartialEq)]
pub struct Symbol {
    pub kind: SymbolKind,
    pub name: String,
    /// The name in the declaration.
    pub name_span: Span,
    /// The whole declaration.
    pub decl_span: Span,
    /// The model or component declaring it (an index into [`Index::symbols`]); `None` for models and components.
    pub parent: Option<usize>,
    pub doc: Vec<String>,
    pub description: Option<String>,
    /// An element's kind keyword, an instance's component.
    pub detail: String,
}

/// A use of a declaration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reference {
    pub span: Span,
    pub symbol: usize,
}

/// The declarations and references of a program.
#[derive(Clone, Debug, Default)]
pub struct Index {
    pub symbols: Vec<Symbol>,
    pub references: Vec<Reference>,
    /// Units as written, with their places (for hover).
    pub units: Vec<ast::UnitExpr>,
    /// Element kind keywords with their places (for hover).
    pub kinds: Vec<(Span, ast::ElementKind)>,
    globals: HashMap<String, usize>,
    scopes: HashMap<usize, HashMap<String, usize>>,
}

/// What is at a place of a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hit<'a> {
    /// A declaration's name or a reference to it, with the span of the name under the cursor.
    Symbol(usize, Span),
    Unit(&'a ast::UnitExpr),
    Kind(Span, ast::ElementKind),
}

impl Index {
    /// Indexes the files of one program (the root first, as lowering loads them).
    pub fn build(files: &[(FileId, ast::File)]) -> Index {
        let mut index = Index::default();
        for (_, file) in files {
            for item in &file.items {
                if let Item::Model(decl) = item {
                    index.declare_model(decl);
                }
            }
        }
        let models: Vec<(usize, &ModelDecl)> = files
            .iter()
            .flat_map(|(_, f)| f.items.iter())
            .filter_map(|i| match i {
                Item::Model(m) => Some(m),
                Item::Import(_) => None,
            })
            .filter_map(|m| index.model_symbol(m).map(|s| (s, m)))
            .collect();
        for (symbol, decl) in models {
            for stmt in &decl.body {
                index.stmt_references(symbol, stmt);
            }
        }
        index
    }

    /// The declaration or reference at a byte offset of a file (a cursor just after a name is on it).
    pub fn at(&self, file: FileId, offset: usize) -> Option<Hit<'_>> {
        let inside =
            |s: Span| s.file == file && (s.start as usize) <= offset && offset <= s.end as usize;
        if let Some(r) = self.references.iter().find(|r| inside(r.span)) {
            return Some(Hit::Symbol(r.symbol, r.span));
        }
        if let Some((i, s)) = self
            .symbols
            .iter()
            .enumerate()
            .find(|(_, s)| inside(s.name_span))
        {
            return Some(Hit::Symbol(i, s.name_span));
        }
        if let Some(&(span, kind)) = self.kinds.iter().find(|(s, _)| inside(*s)) {
            return Some(Hit::Kind(span, kind));
        }
        self.units.iter().find(|u| inside(u.span)).map(Hit::Unit)
    }

    /// The references to a symbol.
    pub fn references_to(&self, symbol: usize) -> impl Iterator<Item = Span> + '_ {
        self.references
            .iter()
            .filter(move |r| r.symbol == symbol)
            .map(|r| r.span)
    }

    /// The members of a model or component, in declaration order.
    pub fn members(&self, parent: usize) -> impl Iterator<Item = (usize, &Symbol)> {
        self.symbols
            .iter()
            .enumerate()
            .filter(move |(_, s)| s.parent == Some(parent))
    }

    /// The model or component declared with this name.
    pub fn global(&self, name: &str) -> Option<usize> {
        self.globals.get(name).copied()
    }

    /// The innermost model or component whose declaration holds the offset.
    pub fn enclosing(&self, file: FileId, offset: usize) -> Option<usize> {
        self.symbols
            .iter()
            .enumerate()
            .filter(|(_, s)| s.parent.is_none() && s.decl_span.file == file)
            .find(|(_, s)| {
                (s.decl_span.start as usize) <= offset && offset <= s.decl_span.end as usize
            })
            .map(|(i, _)| i)
    }

    fn model_symbol(&self, decl: &ModelDecl) -> Option<usize> {
        self.symbols
            .iter()
            .position(|s| s.parent.is_none() && s.name_span == decl.name.span)
    }

    fn push(&mut self, symbol: Symbol) -> usize {
        self.symbols.push(symbol);
        self.symbols.len() - 1
    }

    fn declare_model(&mut self, decl: &ModelDecl) {
        let kind = match decl.kind {
            ast::ModelKind::Model => SymbolKind::Model,
            ast::ModelKind::Component => SymbolKind::Component,
        };
        let id = self.push(Symbol {
            kind,
            name: decl.name.name.clone(),
            name_span: decl.name.span,
            decl_span: decl.span,
            parent: None,
            doc: decl.doc.clone(),
            description: None,
            detail: String::new(),
        });
        self.globals.entry(decl.name.name.clone()).or_insert(id);
        let mut scope = HashMap::new();
        for stmt in &decl.body {
            if let Some(member) = member_of(stmt, id) {
                let name = member.name.clone();
                let sid = self.push(member);
                scope.entry(name).or_insert(sid);
            }
        }
        self.scopes.insert(id, scope);
    }

    fn lookup(&self, scope: usize, name: &str) -> Option<usize> {
        self.scopes.get(&scope)?.get(name).copied()
    }

    fn refer(&mut self, span: Span, symbol: usize) {
        self.references.push(Reference { span, symbol });
    }

    fn stmt_references(&mut self, model: usize, stmt: &Stmt) {
        match stmt {
            Stmt::Param(p) => {
                self.units.push(p.unit.clone());
                self.expr(model, &p.default);
            }
            Stmt::Input(i) => self.units.push(i.unit.clone()),
            Stmt::Output(o) => {
                self.units.push(o.unit.clone());
                self.expr(model, &o.value);
            }
            Stmt::Var(v) => {
                self.units.push(v.unit.clone());
                self.expr(model, &v.integrand);
            }
            Stmt::Coords(c) => c.coords.iter().for_each(|e| self.expr(model, e)),
            Stmt::Element(e) => {
                self.kinds.push((e.kind_span, e.kind));
                match &e.body {
                    ElementBody::None => {}
                    ElementBody::Value(v) => self.expr(model, v),
                    ElementBody::Laws(laws) => laws.iter().for_each(|l| self.expr(model, &l.rhs)),
                }
            }
            Stmt::Instance(inst) => {
                let component = self.global(&inst.component.name);
                if let Some(c) = component {
                    self.refer(inst.component.span, c);
                }
                for (name, value) in &inst.overrides {
                    if let Some(p) = component.and_then(|c| self.lookup(c, &name.name)) {
                        self.refer(name.span, p);
                    }
                    self.expr(model, value);
                }
            }
            Stmt::Bond(b) => {
                for node in b.chain.iter().flatten() {
                    self.node(model, node);
                }
                if let Some(h) = &b.hint {
                    self.node(model, &h.at);
                }
            }
            Stmt::Port(p) => self.node(model, &p.target),
            Stmt::Allow(a) => self.node(model, &a.target),
            Stmt::Domain(_) => {}
        }
    }

    /// `inst.sub.x`: each part in the scope the previous one opens.
    fn node(&mut self, model: usize, node: &NodeRef) {
        let mut scope = model;
        for part in &node.path {
            let Some(symbol) = self.lookup(scope, &part.name) else {
                return;
            };
            self.refer(part.span, symbol);
            let s = &self.symbols[symbol];
            if s.kind != SymbolKind::Instance {
                return;
            }
            match self.global(&s.detail) {
                Some(component) => scope = component,
                None => return,
            }
        }
    }

    fn expr(&mut self, model: usize, e: &Expr) {
        match &e.kind {
            ExprKind::Name(name) => {
                let value = self.lookup(model, name).filter(|&s| {
                    matches!(
                        self.symbols[s].kind,
                        SymbolKind::Param
                            | SymbolKind::Input
                            | SymbolKind::Output
                            | SymbolKind::Var
                    )
                });
                if let Some(s) = value {
                    self.refer(e.span, s);
                }
            }
            ExprKind::Node(n) => self.node(model, n),
            ExprKind::Call(_, args) => args.iter().for_each(|a| self.expr(model, a)),
            ExprKind::Neg(a) => self.expr(model, a),
            ExprKind::Binary(_, a, b) => {
                self.expr(model, a);
                self.expr(model, b);
            }
            ExprKind::Number(_) | ExprKind::Indexed(..) => {}
        }
    }
}

/// The declaration a statement makes in its model or component, if any.
fn member_of(stmt: &Stmt, parent: usize) -> Option<Symbol> {
    let symbol = |kind,
                  name: &ast::Ident,
                  decl_span,
                  doc: &[String],
                  description: &Option<String>,
                  detail: &str| {
        Symbol {
            kind,
            name: name.name.clone(),
            name_span: name.span,
            decl_span,
            parent: Some(parent),
            doc: doc.to_vec(),
            description: description.clone(),
            detail: detail.to_string(),
        }
    };
    Some(match stmt {
        Stmt::Param(p) => symbol(
            SymbolKind::Param,
            &p.name,
            p.span,
            &p.doc,
            &p.description,
            "",
        ),
        Stmt::Input(i) => symbol(
            SymbolKind::Input,
            &i.name,
            i.span,
            &i.doc,
            &i.description,
            "",
        ),
        Stmt::Output(o) => symbol(
            SymbolKind::Output,
            &o.name,
            o.span,
            &o.doc,
            &o.description,
            "",
        ),
        Stmt::Var(v) => symbol(SymbolKind::Var, &v.name, v.span, &v.doc, &None, ""),
        Stmt::Element(e) => symbol(
            SymbolKind::Element,
            &e.name,
            e.span,
            &e.doc,
            &None,
            e.kind.keyword(),
        ),
        Stmt::Instance(i) => symbol(
            SymbolKind::Instance,
            &i.name,
            i.span,
            &i.doc,
            &None,
            &i.component.name,
        ),
        Stmt::Port(p) => symbol(SymbolKind::Port, &p.name, p.span, &[], &None, ""),
        Stmt::Domain(_) | Stmt::Coords(_) | Stmt::Bond(_) | Stmt::Allow(_) => return None,
    })
}
