//! Substitution of the causal definitions: every bond variable that a state rate or an output needs is expressed in
//! states, inputs, parameters and time, in dependency order (depth-first, on demand, so that variables nothing
//! needs are never computed: a storage in derivative causality that only loads a source costs nothing).
//!
//! - A storage in derivative causality defines `v = d/dt(P)`; once `P` is resolved to `P(x, u, t)`,
//!   `d/dt P = Σ ∂P/∂x_i ẋ_i + Σ ∂P/∂u_j u̇_j + ∂P/∂t`, with `ẋ_i` and `u̇_j` kept as symbols. The `ẋ` are solved
//!   for afterwards ([`super::solve`]); a `u̇` left in a state rate or an output is an error there.
//! - An algebraic loop shows up as a variable needed while it is being computed. It is torn there: the inner use
//!   gets the symbol `Tear(v)`, and when `v = E(Tear(v))` is complete it is solved exactly if `E` is affine in the
//!   tear (`v = b / (1 - a)` for `E = a·v + b`) and writing that solution into the values computed inside the loop
//!   costs at most [`REWRITE_BUDGET`]. Otherwise the loop stays implicit: `v` is the unknown `Tear(v)` everywhere
//!   and the residual `0 = E(Tear(v)) − Tear(v)` is kept ([`Resolver::implicit_loops`]) for a numeric solve
//!   ([`super::tear`]); an affine loop kept so is a block of linear equations, and the model stays linear
//!   ([`super::linear_through_loops`]). A nonlinear loop through a storage in derivative causality is refused.

use super::build::{Built, Def};
use super::symbols::{self, Expander, Sym, SymExt, add, div, mul};
use crate::ir::Func;
use crate::symbolic::{Expr, Node, ProductTails};

/// Why a variable could not be resolved.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ResolveError {
    /// A bond variable that no node defines (only after a causality conflict).
    Undefined(usize),
    /// A nonlinear algebraic loop through this variable whose residual holds a state or input derivative (a storage
    /// in derivative causality on the loop).
    NonlinearLoop(usize),
    /// An algebraic loop through this variable whose gain is exactly one (a singular loop).
    SingularLoop(usize),
    /// The derivative of an expression that already holds a derivative or a loop variable.
    HigherOrder(usize),
    /// A function without a derivative (min, max) under a derivative-causality storage.
    NotDifferentiable(usize, Func),
}

#[derive(Clone, Copy, PartialEq)]
enum Mark {
    New,
    Busy,
    Done,
}

/// The resolver of one model.
pub(crate) struct Resolver<'a> {
    built: &'a Built,
    nstates: usize,
    ninputs: usize,
    cache: Vec<Option<Expr>>,
    mark: Vec<Mark>,
    torn: Vec<bool>,
    /// The variables in the order their values were completed (a variable forgotten and computed again is listed
    /// again).
    completed: Vec<usize>,
    /// Per variable: the length of `completed` when it was last opened.
    opened_at: Vec<usize>,
    /// The variables whose value holds a tear, an algebraic loop's solution or the rate of a storage in derivative
    /// causality, directly or through others: the values that are multiplied out.
    looped: Vec<bool>,
    /// Per variable: how many loops solved in closed form its value holds one inside the other.
    nesting: Vec<usize>,
    /// The torn variables kept implicit, with their residuals `E(Tear(v)) − Tear(v)`, in the order they closed.
    implicit: Vec<(usize, Expr)>,
    /// Multiplies out the values; it remembers the expansions of earlier values, which later values hold.
    expander: Expander,
    /// The derivatives of long products' tails, shared by the time derivatives of all storages in derivative
    /// causality (the flows along a chain of modulated transformers are products with common tails).
    tails: ProductTails,
}

impl<'a> Resolver<'a> {
    pub fn new(built: &'a Built, nstates: usize, ninputs: usize) -> Self {
        let n = built.defs.len();
        Resolver {
            built,
            nstates,
            ninputs,
            cache: vec![None; n],
            mark: vec![Mark::New; n],
            torn: vec![false; n],
            looped: vec![false; n],
            nesting: vec![0; n],
            completed: Vec::new(),
            opened_at: vec![0; n],
            implicit: Vec::new(),
            expander: Expander::default(),
            tails: ProductTails::default(),
        }
    }

    /// The bond variables at which algebraic loops were torn and solved exactly.
    pub fn torn(&self) -> Vec<usize> {
        (0..self.torn.len())
            .filter(|&v| self.torn[v] && self.mark[v] == Mark::Done)
            .filter(|&v| !self.implicit.iter().any(|(w, _)| *w == v))
            .collect()
    }

    /// The nonlinear loops kept implicit: each torn variable `v` with its residual `r = E − Tear(v)`, `0 = r`, in
    /// states, inputs, parameters, `t` and tear variables (its own and those of other implicit loops).
    pub fn implicit_loops(&self) -> &[(usize, Expr)] {
        &self.implicit
    }

    /// The value of bond variable `v`. The variables it depends on are resolved first, depth-first on an explicit
    /// stack (a chain of elements makes a dependency chain as long as the model, too deep to recurse along).
    pub fn var(&mut self, v: usize) -> Result<Expr, ResolveError> {
        match self.mark.get(v).copied() {
            None => return Err(ResolveError::Undefined(v)),
            Some(Mark::Done) => return self.cache[v].clone().ok_or(ResolveError::Undefined(v)),
            Some(Mark::Busy) => {
                self.torn[v] = true;
                return Ok(symbols::leaf(Sym::Tear(v)));
            }
            Some(Mark::New) => {}
        }
        // Each frame: a variable being computed, the variables its definition reads, and how many are done.
        let mut stack: Vec<(usize, Vec<usize>, usize)> = vec![self.open(v)];
        while let Some((w, deps, next)) = stack.last_mut() {
            let w = *w;
            if let Some(&d) = deps.get(*next) {
                *next += 1;
                match self.mark.get(d).copied() {
                    None => {
                        // A variable nothing defines: the whole chain fails.
                        for (u, _, _) in stack.iter().rev() {
                            self.forget(*u);
                        }
                        return Err(ResolveError::Undefined(d));
                    }
                    // A variable on the current path: a loop, torn at `d`.
                    Some(Mark::Busy) => self.torn[d] = true,
                    Some(Mark::Done) => {}
                    Some(Mark::New) => stack.push(self.open(d)),
                }
                continue;
            }
            let deps = stack.pop().map(|(_, deps, _)| deps).unwrap_or_default();
            // A value that an algebraic loop or a storage in derivative causality reaches is multiplied out (there
            // like terms cancel), and so is any value of at most `COMPACT_TREE` nodes as a tree; a larger value
            // elsewhere is shared as it is.
            let rate = matches!(self.built.defs.get(w), Some(Some(Def::Rate(_))));
            self.looped[w] =
                rate || self.torn[w] || deps.iter().any(|&d| self.torn[d] || self.looped[d]);
            let looped = self.looped[w];
            self.nesting[w] = deps.iter().map(|&d| self.nesting[d]).max().unwrap_or(0);
            let value = self
                .compute(w)
                .and_then(|value| self.close_loop(w, value))
                .map(|value| {
                    if looped || value.node_count() <= COMPACT_TREE {
                        compact(&mut self.expander, value)
                    } else {
                        value
                    }
                })
                .map(|value| self.kept_local(w, value));
            match value {
                Ok(value) => {
                    self.cache[w] = Some(value);
                    self.mark[w] = Mark::Done;
                    self.completed.push(w);
                }
                Err(e) => {
                    self.forget(w);
                    for (u, _, _) in stack.iter().rev() {
                        self.forget(*u);
                    }
                    return Err(e);
                }
            }
        }
        self.cache[v].clone().ok_or(ResolveError::Undefined(v))
    }

    /// Starts computing `v`: marks it busy and lists the variables its definition reads.
    fn open(&mut self, v: usize) -> (usize, Vec<usize>, usize) {
        self.mark[v] = Mark::Busy;
        if let Some(at) = self.opened_at.get_mut(v) {
            *at = self.completed.len();
        }
        let deps = match self.built.defs.get(v).and_then(Option::as_ref) {
            Some(Def::Plain(e) | Def::Rate(e)) => vars_read(e),
            None => Vec::new(),
        };
        (v, deps, 0)
    }

    /// The value of a variable whose dependencies are resolved: done ones by their value, busy ones (on the path
    /// of a loop) by their tear.
    fn resolved(&self, e: &Expr) -> Expr {
        symbols::subst(e, &mut |s| match s {
            Sym::Var(w) => match self.mark.get(w) {
                Some(Mark::Done) => self.cache.get(w).cloned().flatten(),
                Some(Mark::Busy) => Some(symbols::leaf(Sym::Tear(w))),
                _ => None,
            },
            _ => None,
        })
    }

    /// The value of `v` once computed: unchanged unless a loop was torn at `v`, in which case it is solved exactly
    /// (affine in the tear) or kept implicit (nonlinear).
    fn close_loop(&mut self, v: usize, value: Expr) -> Result<Expr, ResolveError> {
        if !self.torn[v] {
            return Ok(value);
        }
        let tear = Sym::Tear(v);
        let Some((a, b)) = symbols::affine_in(&value, tear) else {
            if has_rates(&value) {
                return Err(ResolveError::NonlinearLoop(v));
            }
            return Ok(self.kept_implicit(v, value));
        };
        let gain = symbols::sub(Expr::one(), a);
        if gain.is_zero() {
            return Err(ResolveError::SingularLoop(v));
        }
        let solved = compact(&mut self.expander, div(b, gain));
        // Values computed inside the loop, and the residuals of implicit loops inside it, hold the tear: replace it
        // there. The tear exists only while `v` is being computed, so only the values completed since `v` was opened
        // can hold it (looking through every value at each loop cost the number of loops times the model).
        let since = self.opened_at.get(v).copied().unwrap_or(0);
        let nesting = self.nesting.get(v).map_or(1, |n| n + 1);
        let too_deep = nesting > MAX_NESTED_CLOSED_FORMS;
        if !has_rates(&value) && (too_deep || !self.closed_form_affordable(since, tear, &solved)) {
            // Nested loops whose closed forms feed each other (a ladder of resistors with parameters of their own)
            // grow geometrically when solved one inside the other: the loop stays a linear block, solved
            // numerically like a nonlinear one (Newton's method takes one exact step on it).
            return Ok(self.kept_implicit(v, value));
        }
        let expander = &mut self.expander;
        let mut replace = |e: &mut Expr| {
            let holds = e.contains(tear);
            if holds {
                *e = compact(
                    expander,
                    symbols::subst(e, &mut |s| (s == tear).then(|| solved.clone())),
                );
            }
            holds
        };
        for &w in self.completed.get(since..).unwrap_or_default() {
            if let Some(Some(e)) = self.cache.get_mut(w)
                && replace(e)
                && let Some(n) = self.nesting.get_mut(w)
            {
                *n = (*n).max(nesting);
            }
        }
        if let Some(n) = self.nesting.get_mut(v) {
            *n = nesting;
        }
        for (_, r) in &mut self.implicit {
            replace(r);
        }
        Ok(solved)
    }

    /// `value` of `w`, or `w`'s tear when `value` sums more than [`LOCAL_TERMS`] terms in the tears of an algebraic
    /// loop: `w` is then one more unknown of the loop's block, with the residual `value − Tear(w)`. A value inside a
    /// loop is multiplied out, so a sum that holds the next one (the currents along a ladder of resistors, each
    /// the sum of all rungs beyond it) would otherwise hold every term beyond it, and the residuals would grow
    /// with the square of the ladder.
    fn kept_local(&mut self, w: usize, value: Expr) -> Expr {
        let many_terms = matches!(value.node(), Node::Add(terms) if terms.len() > LOCAL_TERMS);
        if !many_terms
            || self.torn[w]
            || has_rates(&value)
            || !value.any_sym(&|s| matches!(s, Sym::Tear(_)))
        {
            return value;
        }
        self.kept_implicit(w, value)
    }

    /// `v`'s tear, with `v` an unknown of its loop's block defined by the residual `value − Tear(v)`.
    fn kept_implicit(&mut self, v: usize, value: Expr) -> Expr {
        let tear = symbols::leaf(Sym::Tear(v));
        self.implicit.push((v, symbols::sub(value, tear.clone())));
        tear
    }

    /// Whether closing the loop of `tear` in closed form costs at most [`REWRITE_BUDGET`], as trees: the values
    /// completed since `since` and the implicit loops' residuals are read (each walk costs at most its tree), and
    /// those that hold the tear are written again with the solution `solved` in them. Counting stops at the budget,
    /// so the check itself costs no more than it.
    fn closed_form_affordable(&self, since: usize, tear: Sym, solved: &Expr) -> bool {
        let values = self.completed.get(since..).unwrap_or_default().iter();
        let read = values
            .filter_map(|&w| self.cache.get(w).and_then(Option::as_ref))
            .chain(self.implicit.iter().map(|(_, r)| r));
        let mut cost = 0usize;
        for e in read {
            cost = cost.saturating_add(e.node_count());
            if cost > REWRITE_BUDGET {
                return false;
            }
            if e.contains(tear) {
                cost = cost
                    .saturating_add(e.node_count())
                    .saturating_add(solved.node_count());
            }
        }
        cost <= REWRITE_BUDGET
    }

    /// Undoes a failed computation of `v`: `v` is new again, and so is everything computed inside it that holds
    /// its tear, transitively through the implicit loops that hold it (they would refer to an unknown nothing
    /// defines).
    fn forget(&mut self, v: usize) {
        self.mark[v] = Mark::New;
        let mut dead = vec![v];
        while let Some(d) = dead.pop() {
            let tear = Sym::Tear(d);
            for w in 0..self.cache.len() {
                if self.cache[w].as_ref().is_some_and(|e| e.contains(tear)) {
                    self.cache[w] = None;
                    self.mark[w] = Mark::New;
                }
            }
            let mut k = 0;
            while k < self.implicit.len() {
                if self.implicit[k].1.contains(tear) {
                    let (w, _) = self.implicit.remove(k);
                    self.cache[w] = None;
                    self.mark[w] = Mark::New;
                    dead.push(w);
                } else {
                    k += 1;
                }
            }
        }
    }

    fn compute(&mut self, v: usize) -> Result<Expr, ResolveError> {
        let built = self.built;
        match built.defs.get(v).and_then(Option::as_ref) {
            None => Err(ResolveError::Undefined(v)),
            Some(Def::Plain(e)) => Ok(self.resolved(e)),
            Some(Def::Rate(p)) => {
                let p = self.resolved(p);
                self.time_derivative(&p, v)
            }
        }
    }

    /// Substitutes every bond variable of `e`.
    pub fn expr(&mut self, e: &Expr) -> Result<Expr, ResolveError> {
        for w in vars_read(e) {
            self.var(w)?;
        }
        Ok(self.resolved(e))
    }

    /// `d/dt e` for `e` in states, inputs, parameters and time.
    fn time_derivative(&mut self, e: &Expr, v: usize) -> Result<Expr, ResolveError> {
        if e.any_sym(&|s| {
            matches!(
                s,
                Sym::StateDot(_) | Sym::InputDot(_) | Sym::Tear(_) | Sym::Var(_)
            )
        }) {
            return Err(ResolveError::HigherOrder(v));
        }
        // The symbols `e` reads, in one walk (not one walk per state of the model), in the order of the sum.
        let mut read = std::collections::BTreeSet::new();
        e.for_each_sym(&mut |s| {
            if matches!(s, Sym::State(i) if i < self.nstates)
                || matches!(s, Sym::Input(j) if j < self.ninputs)
                || s == Sym::Time
            {
                read.insert(s);
            }
        });
        let read: Vec<Sym> = read.into_iter().collect();
        let slopes = symbols::gradient_sharing(e, &read, &mut self.tails)
            .map_err(|symbols::NotDifferentiable(f)| ResolveError::NotDifferentiable(v, f))?;
        let terms = read.into_iter().zip(slopes).map(|(s, d)| match s {
            Sym::State(i) => mul(vec![d, symbols::leaf(Sym::StateDot(i))]),
            Sym::Input(j) => mul(vec![d, symbols::leaf(Sym::InputDot(j))]),
            _ => d,
        });
        Ok(add(terms.collect()))
    }
}

/// The bond variables `e` reads, in the engine's symbol order.
fn vars_read(e: &Expr) -> Vec<usize> {
    e.syms()
        .into_iter()
        .filter_map(|s| match s {
            Sym::Var(w) => Some(w),
            _ => None,
        })
        .collect()
}

/// The most terms a sum in the tears of an algebraic loop holds before it is made an unknown of the loop's block
/// ([`Resolver::kept_local`]): a residual then holds at most about this many terms, however long the chain of sums
/// that feed each other.
const LOCAL_TERMS: usize = 16;

/// Values outside algebraic loops up to this size as a tree are multiplied out too: a small model's values keep one
/// form however they are reached, and multiplying out a value this size costs at most this much, so a chain of
/// values that each hold the next stays linear (only the first few links are this small).
const COMPACT_TREE: usize = 1024;

/// The most a loop's closed form may cost, as trees ([`Resolver::closed_form_affordable`]), before the loop is kept as a
/// block of linear equations instead. Nested loops whose solutions hold each other grow geometrically (a ladder with
/// a resistance per resistor doubles per rung); with this bound a four-rung one keeps its closed form, a longer one
/// has its outer rungs' loops in one linear block, and the cost stays polynomial.
const REWRITE_BUDGET: usize = 100_000;

/// The most loops solved in closed form one inside the other: each level's closed form holds the previous one
/// several times (a ladder with a resistance per resistor: 29, 58, 104, 199 nodes as a tree for four rungs), and so
/// do its derivatives, which generated code prints per entry. A loop nested deeper is kept as a linear block.
const MAX_NESTED_CLOSED_FORMS: usize = 4;

/// Whether `e` holds the rate of a state or of an input (a storage in derivative causality on a loop).
fn has_rates(e: &Expr) -> bool {
    e.any_sym(&|s| matches!(s, Sym::StateDot(_) | Sym::InputDot(_)))
}

/// `e` multiplied out when that makes it no larger as a tree and smaller as stored (a tie keeps `e`, whose levels
/// are shared with the values it holds). A value is copied into every variable that uses it: in a chain of algebraic
/// loops each rung's solution `b / (1 − a)` holds the previous ones as nested products of sums, which
/// grow geometrically; multiplied out, the like terms collect and the size stays that of the model's symbols.
fn compact(expander: &mut Expander, e: Expr) -> Expr {
    let expanded = expander.expand(&e);
    if expanded == e {
        return e;
    }
    // Sizes are compared as trees (cheap, kept in the nodes) and as stored: a product of `k` factors
    // `1 + c·cos θ` (a chain of modulated transformers) is as small a tree as the polynomial of degree `k` it
    // multiplies out to, but it shares its levels with the values before it and the polynomial shares nothing,
    // so keeping the polynomials made every later stage quadratic in the chain.
    let smaller = expanded.node_count() <= e.node_count()
        && Expr::distinct_nodes(std::slice::from_ref(&expanded))
            < Expr::distinct_nodes(std::slice::from_ref(&e));
    if smaller { expanded } else { e }
}
