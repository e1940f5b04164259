//! Long bodies split into parts. A model of thousands of states has bodies of tens of thousands of statements
//! (`jac_x_into` of a chain of 10,000 masses sets 60,000 entries), and rustc's time and memory grow faster than
//! linearly with the size of one function: the 10,000-mass chain's module ran LLVM out of memory. A body of more
//! than [`MAX_PART_STATEMENTS`] independent statements is therefore written as `#[inline(never)]` functions
//! `{stem}_part_{k}` of at most that many statements each, which take the function's arguments and bind only the
//! states, inputs and elementary functions their own statements read; the function calls them in order. The
//! statements and their order are those of the single body, so the results are the same bits.
//!
//! A function of many parts has the later half of them drafted on a second thread (a large model's writer
//! spends most of its time drafting statements), by a copy of the writer with its own caches. The parameter
//! terms are found first, on the calling thread and in statement order, so that the terms and their names are
//! those of drafting the parts in turn. The later half is written on the second thread too, into text of its
//! own that then follows the first half's.
//!
//! Only bodies of independent statements are split: entries of a matrix, rates and outputs without `let`s (a
//! large model's are explicit, see `emit::MAX_LETS`), terms of a sum. A model with nonlinear algebraic loops keeps
//! single bodies (each solves its loops first).

use super::functions::Draft;
use super::{Arg, Function, Uses, Writer};
use crate::symbolic::Expr;

/// The most statements one part computes (each under its comment, with the `let`s its layout needs).
pub(in crate::codegen) const MAX_PART_STATEMENTS: usize = 256;

/// The fewest parts of one function that are drafted on two threads: below, a second thread costs more than it
/// saves.
const PARALLEL_PARTS: usize = 8;

/// One statement of a body: `{head}{expr}{tail}` under the comment `{label}{expr}`.
pub(super) struct Statement<'e> {
    pub label: String,
    pub expr: &'e Expr,
    pub head: String,
    pub tail: &'static str,
}

/// The argument every part writes through and how the calling function passes it (`jac`, or `&mut total`).
#[derive(Clone, Copy)]
pub(super) struct Out {
    pub name: &'static str,
    pub ty: &'static str,
    pub passed: &'static str,
}

impl Writer<'_> {
    /// Whether a body of `count` independent statements is split into parts.
    pub(super) fn splits(&self, count: usize) -> bool {
        count > MAX_PART_STATEMENTS && self.plan.loops.is_none()
    }

    /// Writes the parts of the function `stem` (`rhs`, `jac_x`), each computing up to [`MAX_PART_STATEMENTS`] of
    /// `statements` (with the parameter terms when `cached`), and returns the body that calls them after the lines
    /// `prologue`: its `uses` and parameter terms are those of its parts.
    pub(super) fn parts(
        &mut self,
        stem: &str,
        statements: &[Statement],
        out: Out,
        cached: bool,
        prologue: Vec<String>,
    ) -> Draft {
        let chunks: Vec<&[Statement]> = statements.chunks(MAX_PART_STATEMENTS).collect();
        let drafts = self.part_drafts(&chunks, cached);
        // Every part takes the arguments some part reads, so that the calls pass the same ones.
        let mut all = Uses::default();
        let mut terms = false;
        for d in &drafts {
            all.p |= d.uses.p;
            all.t |= d.uses.t;
            all.x |= d.uses.x;
            all.u |= d.uses.u;
            terms |= d.reads_terms;
        }
        let mut main = self.draft(&[]);
        main.uses = all;
        main.reads_terms = terms;
        main.lines = prologue;
        let count = drafts.len();
        let mut written = Vec::with_capacity(count);
        for (k, d) in drafts.into_iter().enumerate() {
            let name = format!("{stem}_part_{}", k + 1);
            let mut args = Vec::new();
            let mut passed = Vec::new();
            for (arg, ty, used, part) in [
                ("p", "&Params", all.p, d.uses.p),
                ("c", "&ParamTerms", terms, d.reads_terms),
                ("t", "f64", all.t, d.uses.t),
                ("x", "&State", all.x, d.uses.x),
                ("u", "&Inputs", all.u, d.uses.u),
            ] {
                if used {
                    args.push(Arg::new(arg, ty, part));
                    passed.push(arg);
                }
            }
            args.push(Arg::new(out.name, out.ty, true));
            passed.push(out.passed);
            main.lines
                .push(format!("    {name}({});", passed.join(", ")));
            let doc = format!("Part {} of {count} of the statements of `{stem}`.", k + 1);
            written.push((doc, name, args, d));
        }
        self.write_parts(written);
        main
    }

    /// Writes the parts in order: the later half of many into a [`Writer::fork`]'s text on a second thread, which
    /// then follows this writer's.
    fn write_parts(&mut self, mut parts: Vec<(String, String, Vec<Arg>, Draft)>) {
        if parts.len() < PARALLEL_PARTS {
            for (doc, name, args, d) in parts {
                self.private_part(doc, name, args, d);
            }
            return;
        }
        let later = parts.split_off(parts.len() / 2);
        let mut fork = self.fork(self.terms.borrow().found());
        let (fork_text, ()) = crate::concurrent::join(
            move || {
                for (doc, name, args, d) in later {
                    fork.private_part(doc, name, args, d);
                }
                fork.out
            },
            || {
                for (doc, name, args, d) in parts {
                    self.private_part(doc, name, args, d);
                }
            },
        );
        self.out.append(fork_text);
    }

    /// The body of each part: those of the later half drafted on a second thread when there are many, by a
    /// [`Writer::fork`] whose parameter terms were found first, in statement order, so that the terms and their
    /// names are those of drafting the parts one after the other.
    fn part_drafts<'e>(&self, chunks: &[&[Statement<'e>]], cached: bool) -> Vec<Draft> {
        if chunks.len() < PARALLEL_PARTS {
            return chunks.iter().map(|c| self.part_draft(c, cached)).collect();
        }
        let (first, second) = chunks.split_at(chunks.len() / 2);
        let roots = |half: &[&[Statement<'e>]]| -> Vec<&'e Expr> {
            half.iter().flat_map(|c| c.iter().map(|s| s.expr)).collect()
        };
        let fork_terms = {
            let mut terms = self.terms.borrow_mut();
            if cached && self.terms_enabled {
                roots(first).into_iter().for_each(|e| {
                    terms.rewrite(e);
                });
                terms.rewriting_only(&roots(second))
            } else {
                terms.found()
            }
        };
        let fork = self.fork(fork_terms);
        let (later, mut drafts) = crate::concurrent::join(
            move || -> Vec<Draft> { second.iter().map(|c| fork.part_draft(c, cached)).collect() },
            || -> Vec<Draft> { first.iter().map(|c| self.part_draft(c, cached)).collect() },
        );
        drafts.extend(later);
        drafts
    }

    /// The body of one part: its statements, with the parameter terms when `cached`.
    fn part_draft(&self, chunk: &[Statement], cached: bool) -> Draft {
        let exprs: Vec<&Expr> = chunk.iter().map(|s| s.expr).collect();
        let mut d = if cached {
            self.draft_cached(&exprs)
        } else {
            self.draft(&exprs)
        };
        for s in chunk {
            self.statement(&mut d, &s.label, s.expr, &s.head, s.tail);
        }
        d
    }

    /// Writes the draft `d` as a private `#[inline(never)]` function `name(args)` without a result.
    pub(super) fn private_part(&mut self, doc: String, name: String, args: Vec<Arg>, d: Draft) {
        let function = Function {
            doc,
            name,
            args,
            ret: String::new(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        };
        self.write_function(function, Some("#[inline(never)]"), "fn");
    }
}
