//! Parameter terms: the subexpressions of `rhs`, `outputs` and the Jacobians that read parameters and literals
//! only (`1/J_m`, `J_m/(J_m + J_g)`, `m_1 l_1 l_2`, `sqrt(k/m)`), computed once per parameter set.
//!
//! The back-support rhs divides by parameters five times per call, and a division costs as much as ten
//! multiplications: the terms turn those into multiplications by reciprocals that `Model` computes when its
//! parameters are set. Each maximal parameter-only subexpression of a body is replaced by a symbol of its own
//! (a parameter-kind symbol whose name starts with [`PREFIX`], printed `c.field`); in a sum or a product the
//! parameter-only operands together make one term (`x J_m/(J_m + J_g)` reads `x * c.k_J_g_J_m`). A bare
//! parameter, a literal and a negated parameter stay as they are: reading them costs what reading a term does.
//!
//! The generated code then has `rhs_with(p, c, t, x, u, dx)` with `c: &ParamTerms` (and the same for `outputs`
//! and each Jacobian that reads a term), `ParamTerms::at(p)` that computes them, and `rhs_into(p, t, x, u, dx)`
//! that computes them at each call and calls `rhs_with`; `Model` holds them. `x * (1/J)` may differ from `x / J`
//! in the last bit; nothing else changes.

use super::super::emit::MAX_LETS;
use super::super::format;
use super::super::layout::Body;
use super::super::names::Namer;
use super::Writer;
use crate::symbolic::{Expr, ExprMap, Node, Symbol, SymbolKind};
use std::collections::HashSet;
use std::fmt::Write;

/// The first character of a term's symbol name (not one a `.bg` name can start with); the rest is its field.
pub(in crate::codegen) const PREFIX: char = '#';

/// The field of `ParamTerms` that the symbol `s` stands for, if it is a term's symbol.
pub(in crate::codegen) fn term_field(s: &Symbol) -> Option<&str> {
    (s.kind() == SymbolKind::Param)
        .then(|| s.name().strip_prefix(PREFIX))
        .flatten()
}

/// The terms found so far, and the rewriting of expressions in terms of them.
#[derive(Clone, Debug)]
pub(in crate::codegen) struct ParamTerms {
    /// Each term's field and expression, in the order found.
    terms: Vec<(String, Expr)>,
    /// The symbol of each term, by its expression.
    by_expr: ExprMap<Symbol>,
    /// The field names taken (with the generated code's own names reserved, so that `ParamTerms::at` can bind
    /// each term to a local of the same name).
    fields: Namer,
    /// The parameters whose value is a method (a derived parameter): worth a term of their own.
    derived: HashSet<Symbol>,
    /// Whether a node reads parameters and literals only.
    pure: ExprMap<bool>,
    /// Rewritten nodes.
    memo: ExprMap<Expr>,
}

impl ParamTerms {
    pub(in crate::codegen) fn new(derived: HashSet<Symbol>) -> ParamTerms {
        ParamTerms {
            terms: Vec::new(),
            by_expr: ExprMap::default(),
            fields: Namer::with_reserved(),
            derived,
            pure: ExprMap::default(),
            memo: ExprMap::default(),
        }
    }

    pub(in crate::codegen) fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Forgets every term and rewriting found.
    fn clear(&mut self) {
        *self = ParamTerms::new(std::mem::take(&mut self.derived));
    }

    pub(in crate::codegen) fn len(&self) -> usize {
        self.terms.len()
    }

    /// `e` with each maximal parameter-only subexpression replaced by its term's symbol.
    pub(in crate::codegen) fn rewrite(&mut self, e: &Expr) -> Expr {
        if let Some(done) = self.memo.get(e) {
            return done.clone();
        }
        let out = if self.is_pure(e) {
            self.term_or_atom(e.clone())
        } else {
            match e.node() {
                Node::Add(ts) => Expr::sum(self.grouped(ts, Expr::sum)),
                Node::Mul(fs) => Expr::product(self.grouped(fs, Expr::product)),
                Node::Pow(b, x) => self.rewrite(b).pow(&self.rewrite(x)),
                Node::Call(f, args) => {
                    let args: Vec<Expr> = args.iter().map(|a| self.rewrite(a)).collect();
                    Expr::call(*f, &args).unwrap_or_else(|| e.clone())
                }
                Node::Const(_) | Node::Sym(_) => e.clone(),
            }
        };
        self.memo.insert(e.clone(), out.clone());
        out
    }

    /// Rewrites `roots` in order (finding their terms as [`Self::rewrite`] does), and returns terms that rewrite
    /// each of them the same way, by lookup, without the memo of every other expression met so far: for drafting
    /// bodies of those roots on another thread.
    pub(in crate::codegen) fn rewriting_only(&mut self, roots: &[&Expr]) -> ParamTerms {
        let memo: ExprMap<Expr> = roots
            .iter()
            .map(|&e| (e.clone(), self.rewrite(e)))
            .collect();
        ParamTerms {
            memo,
            ..self.found()
        }
    }

    /// The terms found so far, without the memos: for writing on another thread bodies already drafted.
    pub(in crate::codegen) fn found(&self) -> ParamTerms {
        ParamTerms {
            terms: self.terms.clone(),
            by_expr: self.by_expr.clone(),
            fields: self.fields.clone(),
            derived: self.derived.clone(),
            pure: ExprMap::default(),
            memo: ExprMap::default(),
        }
    }

    /// The operands of a sum or product rewritten, the parameter-only ones combined into one term.
    fn grouped(&mut self, operands: &[Expr], combine: fn(Vec<Expr>) -> Expr) -> Vec<Expr> {
        let mut pure = Vec::new();
        let mut out = Vec::new();
        for o in operands {
            if self.is_pure(o) {
                pure.push(o.clone());
            } else {
                out.push(self.rewrite(o));
            }
        }
        if !pure.is_empty() {
            out.push(self.term_or_atom(combine(pure)));
        }
        out
    }

    /// `e` itself when reading it costs no more than reading a term, else the symbol of its term. A negated
    /// term is the term negated (`-J`, `-(1/m)`): a negation is free where it is used, and `1/m` and `-1/m` are
    /// then one term.
    fn term_or_atom(&mut self, e: Expr) -> Expr {
        if let Node::Mul(fs) = e.node()
            && let [k, rest @ ..] = fs.as_slice()
            && k.as_const() == Some(-1.0)
        {
            let inner = self.term_or_atom(Expr::product(rest.iter().cloned()));
            return Expr::product([Expr::constant(-1.0), inner]);
        }
        let atom = match e.node() {
            Node::Const(_) => true,
            Node::Sym(s) => !self.derived.contains(s),
            _ => false,
        };
        if atom {
            return e;
        }
        if let Some(s) = self.by_expr.get(&e) {
            return Expr::symbol(s.clone());
        }
        let field = self.fields.ident(&field_name(&e));
        let symbol = Symbol::param(format!("{PREFIX}{field}"));
        self.by_expr.insert(e.clone(), symbol.clone());
        self.terms.push((field, e));
        Expr::symbol(symbol)
    }

    fn is_pure(&mut self, e: &Expr) -> bool {
        if let Some(&p) = self.pure.get(e) {
            return p;
        }
        let p = match e.node() {
            Node::Const(_) => true,
            Node::Sym(s) => s.kind() == SymbolKind::Param,
            Node::Add(cs) | Node::Mul(cs) | Node::Call(_, cs) => cs.iter().all(|c| self.is_pure(c)),
            Node::Pow(b, x) => self.is_pure(b) && self.is_pure(x),
        };
        self.pure.insert(e.clone(), p);
        p
    }
}

/// A field name for a term: `inv_J` for `1/J`, `sqrt_k` for `sqrt(k)`, else `k_` and the parameters it reads.
fn field_name(e: &Expr) -> String {
    let names: Vec<String> = e
        .free_symbols()
        .iter()
        .map(|s| s.name().to_string())
        .collect();
    let mut name = match e.node() {
        Node::Pow(b, x) if b.as_symbol().is_some() && x.as_const() == Some(-1.0) => {
            "inv".to_string()
        }
        Node::Pow(b, x) if b.as_symbol().is_some() && x.as_const() == Some(0.5) => {
            "sqrt".to_string()
        }
        _ => "k".to_string(),
    };
    for n in names {
        if name.len() + n.len() > MAX_FIELD {
            break;
        }
        name.push('_');
        name.push_str(&n);
    }
    name
}

/// The Jacobian functions whose entries [`Writer::param_terms_fit`] rewrites, in the order they are written.
const JACOBIANS: [&str; 4] = [
    "jac_x_into",
    "jac_u_into",
    "output_jac_x_into",
    "output_jac_u_into",
];

/// The longest field name [`field_name`] builds from several parameter names.
const MAX_FIELD: usize = 24;

impl Writer<'_> {
    /// Whether the terms of the rhs, the outputs and the Jacobians are at most [`MAX_LETS`]: `ParamTerms::at`
    /// binds each to a `let`, and rustc's stack overflows on a few thousand `let`s in one function (a chain of a
    /// thousand masses has a term `1/m` for each). Larger models read their parameters at each call.
    pub(super) fn param_terms_fit(&self) -> bool {
        let plan = self.plan;
        // The bodies meet these expressions in this order when nothing is written before `rhs` (the loops' and mass
        // blocks' functions) and no Jacobian has shared subexpressions (rewritten after its entries). Then the
        // terms are found here as the bodies would find them, and the bodies find them again by lookup (a large
        // model's rewriting takes seconds); otherwise they are counted on a copy.
        let in_place = plan.loops.is_none()
            && plan.mass.is_empty()
            && JACOBIANS
                .iter()
                .all(|name| self.shared_lets(name).is_empty());
        let mut copy;
        let mut own;
        let terms: &mut ParamTerms = if in_place {
            own = self.terms.borrow_mut();
            &mut own
        } else {
            copy = self.terms.borrow().clone();
            &mut copy
        };
        let blocks = [&plan.rhs, &plan.outputs];
        let exprs = blocks
            .iter()
            .flat_map(|b| b.lets.iter().map(|l| &l.1).chain(&b.results))
            .chain(
                [&plan.dfdx, &plan.dfdu, &plan.dhdx, &plan.dhdu]
                    .into_iter()
                    .flat_map(|m| m.iter().map(|(_, _, e)| e)),
            );
        for e in exprs {
            terms.rewrite(e);
            if terms.len() > MAX_LETS {
                terms.clear();
                return false;
            }
        }
        true
    }

    /// `ParamTerms` and `ParamTerms::at`, when any body reads a term.
    pub(super) fn param_terms_struct(&mut self) {
        let terms = self.terms.borrow().clone();
        if terms.is_empty() {
            return;
        }
        self.out.push('\n');
        self.doc(
            0,
            "The subexpressions of `rhs`, `outputs` and the Jacobians that read the parameters only, computed \
             once per parameter set: `Model` holds them, `rhs_with(p, &ParamTerms::at(p), ...)` takes them, and \
             `rhs_into` computes them at each call.",
        );
        let _ = writeln!(self.out, "#[derive(Clone, Copy, Debug, PartialEq)]");
        if terms.terms.iter().any(|(f, _)| !format::is_snake_case(f)) {
            self.out.push_str("#[allow(non_snake_case)]\n");
        }
        self.out.push_str("pub struct ParamTerms {\n");
        for (field, e) in &terms.terms {
            // The expression, broken at its operators where it is longer than a line.
            let text = super::params::doc_safe(&crate::symbolic::to_text(e));
            for line in format::comment(4, "///", &text, format::Wrap::Equation, self.width) {
                self.out.push_str(&line);
                self.out.push('\n');
            }
            let _ = writeln!(self.out, "    {field}: f64,");
        }
        self.out.push_str("}\n\nimpl ParamTerms {\n");
        self.doc(4, "The terms at the parameters `p`.");
        let mut namer = terms.fields.clone();
        let mut body = String::new();
        let mut next = 1;
        let mut locals: Vec<String> = Vec::new();
        for (field, e) in &terms.terms {
            let mut b = Body::new(&mut namer, 8, self.width).first_temp(next);
            b.statement(&format!("let {field} = "), &self.code(e), ";");
            next = b.next_temp();
            body.push_str(&b.finish());
            locals.push(field.clone());
        }
        let list = locals.join(", ");
        // rustfmt keeps a struct literal on one line while its fields take at most 18 columns.
        if list.len() <= format::STRUCT_LIT_WIDTH {
            let _ = writeln!(body, "        ParamTerms {{ {list} }}");
        } else {
            body.push_str("        ParamTerms {\n");
            for f in &locals {
                let _ = writeln!(body, "            {f},");
            }
            body.push_str("        }\n");
        }
        let mut lints = Vec::new();
        if locals.iter().any(|l| !format::is_snake_case(l)) {
            lints.push("non_snake_case");
        }
        if format::may_look_like_a_constant(&body) {
            lints.push("clippy::approx_constant");
        }
        self.out.push_str("    #[inline]\n");
        if !lints.is_empty() {
            let _ = writeln!(self.out, "    #[allow({})]", lints.join(", "));
        }
        self.out
            .push_str("    pub fn at(p: &Params) -> ParamTerms {\n");
        self.out
            .push_str(&super::scopes::flatten_lets(&body, "        ", self.width));
        self.out.push_str("    }\n}\n");
    }
}
