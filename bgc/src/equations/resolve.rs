//! Substitution of the causal definitions: every bond variable that a state rate or an output needs is expressed in
//! states, inputs, parameters and time, in dependency order (depth-first, on demand, so that variables nothing
//! needs are never computed: a storage in derivative causality that only loads a source costs nothing).
//!
//! - A storage in derivative causality defines `v = d/dt(P)`; once `P` is resolved to `P(x, u, t)`,
//!   `d/dt P = Σ ∂P/∂x_i ẋ_i + Σ ∂P/∂u_j u̇_j + ∂P/∂t`, with `ẋ_i` and `u̇_j` kept as symbols. The `ẋ` are solved
//!   for afterwards ([`super::solve`]); a `u̇` left in a state rate or an output is an error there.
//! - An algebraic loop shows up as a variable needed while it is being computed. It is torn there: the inner use
//!   gets the symbol `Tear(v)`, and when `v = E(Tear(v))` is complete it is solved exactly if `E` is affine in the
//!   tear (`v = b / (1 - a)` for `E = a·v + b`); a nonlinear loop is refused.

use super::build::{Built, Def};
use super::sym::{self, Ex, Sym, add, div, mul};
use crate::ir::Func;

/// Why a variable could not be resolved.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ResolveError {
    /// A bond variable that no node defines (only after a causality conflict).
    Undefined(usize),
    /// An algebraic loop through this variable that is not affine in it.
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
    depth: usize,
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
            depth: 0,
        }
    }

    /// The bond variables at which algebraic loops were torn (and solved).
    pub fn torn(&self) -> Vec<usize> {
        (0..self.torn.len())
            .filter(|&v| self.torn[v] && self.mark[v] == Mark::Done)
            .collect()
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
        let mut value = match result {
            Ok(value) => value,
            Err(e) => {
                self.mark[v] = Mark::New;
                return Err(e);
            }
        };
        if self.torn[v] {
            let tear = Sym::Tear(v);
            let (a, b) = sym::affine_in(&value, tear).ok_or(ResolveError::NonlinearLoop(v))?;
            let gain = sym::sub(Ex::one(), a);
            if gain.is_zero() {
                return Err(ResolveError::SingularLoop(v));
            }
            value = div(b, gain);
            // Values computed inside the loop hold the tear: replace it everywhere.
            let solved = value.clone();
            for slot in self.cache.iter_mut().flatten() {
                if slot.contains(tear) {
                    *slot = sym::subst(slot, &mut |s| (s == tear).then(|| solved.clone()));
                }
            }
        }
        self.cache[v] = Some(value.clone());
        self.mark[v] = Mark::Done;
        Ok(value)
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
        let mut terms = Vec::new();
        for i in 0..self.nstates {
            if e.contains(Sym::State(i)) {
                terms.push(mul(vec![d(Sym::State(i))?, Ex::S(Sym::StateDot(i))]));
            }
        }
        for j in 0..self.ninputs {
            if e.contains(Sym::Input(j)) {
                terms.push(mul(vec![d(Sym::Input(j))?, Ex::S(Sym::InputDot(j))]));
            }
        }
        if e.contains(Sym::Time) {
            terms.push(d(Sym::Time)?);
        }
        Ok(add(terms))
    }
}
