//! Substitution of the causal definitions: every bond variable that a state rate or an output needs is expressed in
//! states, inputs, parameters and time, in dependency order (depth-first, on demand, so that variables nothing
//! needs are never computed: a storage in derivative causality that only loads a source costs nothing).
//!
//! - A storage in derivative causality defines `v = d/dt(P)`; once `P` is resolved to `P(x, u, t)`,
//!   `d/dt P = Σ ∂P/∂x_i ẋ_i + Σ ∂P/∂u_j u̇_j + ∂P/∂t`, with `ẋ_i` and `u̇_j` kept as symbols. The `ẋ` are solved
//!   for afterwards ([`super::solve`]); a `u̇` left in a state rate or an output is an error there.
//! - An algebraic loop shows up as a variable needed while it is being computed. It is torn there: the inner use
//!   gets the symbol `Tear(v)`, and when `v = E(Tear(v))` is complete it is solved exactly if `E` is affine in the
//!   tear (`v = b / (1 - a)` for `E = a·v + b`). Otherwise the loop stays implicit: `v` is the unknown `Tear(v)`
//!   everywhere and the residual `0 = E(Tear(v)) − Tear(v)` is kept ([`Resolver::implicit_loops`]) for a numeric
//!   solve ([`super::tear`]). A nonlinear loop through a storage in derivative causality is refused.

use super::build::{Built, Def};
use super::sym::{self, Ex, Expander, Sym, add, div, mul};
use crate::ir::Func;

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
    /// The dependency chain is too deep to follow.
    TooDeep,
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
    cache: Vec<Option<Ex>>,
    mark: Vec<Mark>,
    torn: Vec<bool>,
    /// The torn variables kept implicit, with their residuals `E(Tear(v)) − Tear(v)`, in the order they closed.
    implicit: Vec<(usize, Ex)>,
    depth: usize,
    /// Multiplies out the values; it remembers the expansions of earlier values, which later values hold.
    expander: Expander,
}

/// Dependency chains longer than this are refused rather than overflowing the stack.
const MAX_DEPTH: usize = 20_000;

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
            implicit: Vec::new(),
            depth: 0,
            expander: Expander::default(),
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
    pub fn implicit_loops(&self) -> &[(usize, Ex)] {
        &self.implicit
    }

    /// The value of bond variable `v`.
    pub fn var(&mut self, v: usize) -> Result<Ex, ResolveError> {
        match self.mark.get(v).copied() {
            None => return Err(ResolveError::Undefined(v)),
            Some(Mark::Done) => return self.cache[v].clone().ok_or(ResolveError::Undefined(v)),
            Some(Mark::Busy) => {
                self.torn[v] = true;
                return Ok(Ex::S(Sym::Tear(v)));
            }
            Some(Mark::New) => {}
        }
        if self.depth > MAX_DEPTH {
            return Err(ResolveError::TooDeep);
        }
        self.depth += 1;
        self.mark[v] = Mark::Busy;
        let result = self.compute(v);
        self.depth -= 1;
        let value = match result.and_then(|value| self.close_loop(v, value)) {
            Ok(value) => compact(&mut self.expander, value),
            Err(e) => {
                self.forget(v);
                return Err(e);
            }
        };
        self.cache[v] = Some(value.clone());
        self.mark[v] = Mark::Done;
        Ok(value)
    }

    /// The value of `v` once computed: unchanged unless a loop was torn at `v`, in which case it is solved exactly
    /// (affine in the tear) or kept implicit (nonlinear).
    fn close_loop(&mut self, v: usize, value: Ex) -> Result<Ex, ResolveError> {
        if !self.torn[v] {
            return Ok(value);
        }
        let tear = Sym::Tear(v);
        let Some((a, b)) = sym::affine_in(&value, tear) else {
            if value.any_sym(&|s| matches!(s, Sym::StateDot(_) | Sym::InputDot(_))) {
                return Err(ResolveError::NonlinearLoop(v));
            }
            let residual = sym::sub(value, Ex::S(tear));
            self.implicit.push((v, residual));
            return Ok(Ex::S(tear));
        };
        let gain = sym::sub(Ex::one(), a);
        if gain.is_zero() {
            return Err(ResolveError::SingularLoop(v));
        }
        let solved = compact(&mut self.expander, div(b, gain));
        // Values computed inside the loop, and the residuals of implicit loops inside it, hold the tear: replace it
        // everywhere.
        let expander = &mut self.expander;
        let mut replace = |e: &mut Ex| {
            if e.contains(tear) {
                *e = compact(
                    expander,
                    sym::subst(e, &mut |s| (s == tear).then(|| solved.clone())),
                );
            }
        };
        self.cache.iter_mut().flatten().for_each(&mut replace);
        self.implicit.iter_mut().for_each(|(_, r)| replace(r));
        Ok(solved)
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

    fn compute(&mut self, v: usize) -> Result<Ex, ResolveError> {
        let built = self.built;
        match built.defs.get(v).and_then(Option::as_ref) {
            None => Err(ResolveError::Undefined(v)),
            Some(Def::Plain(e)) => self.expr(e),
            Some(Def::Rate(p)) => {
                let p = self.expr(p)?;
                self.time_derivative(&p, v)
            }
        }
    }

    /// Substitutes every bond variable of `e`.
    pub fn expr(&mut self, e: &Ex) -> Result<Ex, ResolveError> {
        Ok(match e {
            Ex::S(Sym::Var(w)) => self.var(*w)?,
            Ex::Num(_) | Ex::S(_) => e.clone(),
            Ex::Add(ts) => add(ts.iter().map(|t| self.expr(t)).collect::<Result<_, _>>()?),
            Ex::Mul(fs) => mul(fs.iter().map(|t| self.expr(t)).collect::<Result<_, _>>()?),
            Ex::Pow(b, x) => sym::pow(self.expr(b)?, self.expr(x)?),
            Ex::Call(f, args) => sym::call(
                *f,
                args.iter()
                    .map(|a| self.expr(a))
                    .collect::<Result<_, _>>()?,
            ),
        })
    }

    /// `d/dt e` for `e` in states, inputs, parameters and time.
    fn time_derivative(&self, e: &Ex, v: usize) -> Result<Ex, ResolveError> {
        if e.any_sym(&|s| {
            matches!(
                s,
                Sym::StateDot(_) | Sym::InputDot(_) | Sym::Tear(_) | Sym::Var(_)
            )
        }) {
            return Err(ResolveError::HigherOrder(v));
        }
        let d = |s: Sym| {
            sym::diff(e, s)
                .map_err(|sym::NotDifferentiable(f)| ResolveError::NotDifferentiable(v, f))
        };
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
        let mut terms = Vec::new();
        for s in read {
            terms.push(match s {
                Sym::State(i) => mul(vec![d(s)?, Ex::S(Sym::StateDot(i))]),
                Sym::Input(j) => mul(vec![d(s)?, Ex::S(Sym::InputDot(j))]),
                _ => d(s)?,
            });
        }
        Ok(add(terms))
    }
}

/// `e` multiplied out when that makes it no larger. A value is copied into every variable that uses it: in a chain
/// of algebraic loops each rung's solution `b / (1 − a)` holds the previous ones as nested products of sums, which
/// grow geometrically; multiplied out, the like terms collect and the size stays that of the model's symbols.
fn compact(expander: &mut Expander, e: Ex) -> Ex {
    let expanded = expander.expand(&e);
    if expanded == e {
        return e;
    }
    if expanded.key_len() <= e.key_len() {
        expanded
    } else {
        e
    }
}
