//! Simulation of derived equations at run time, for models whose size is only known when the file is read.
//!
//! The state equations `ẋ = f(x, u, p, t)` of [`crate::equations`] are compiled into flat programs
//! ([`program`]) and integrated with diffsol on dynamic vectors ([`integrate`], behind the `cli` feature). The
//! integrated vector is the model state extended by two quadrature states,
//!
//! ```text
//! Ė_diss = Σ_R e·f          (power dissipated in the resistors)
//! Ė_sup  = Σ_sources e·f    (power delivered by the sources)
//! ```
//!
//! so that the energies dissipated and supplied since the start are integrated to the solver's tolerance instead
//! of being summed from samples. With the stored energy `E(x)`, every trajectory of a model whose terms are all
//! known satisfies `E + E_diss − E_sup = E(x0)`; the CLI prints the three columns so that this balance can be
//! checked.
//!
//! A source that drives a storage in derivative causality (a flow source imposing an inertia's velocity) delivers
//! power through the time derivative of its input (`e·f = J·u̇·u`). The inputs are expressions of `t`, so their
//! derivatives are too ([`Signal::derivative`]): the programs read the input vector `[u, u̇]` and the power is
//! integrated like any other. A jump of an input (`step`) has no derivative; the energy it moves into the storage is
//! the jump of the stored energy at the breakpoint, `E(x, u(b)) − E(x, u(b⁻))` at the (continuous) state, which the
//! integrator adds to `supplied` there ([`System::stored_jump`]). That is the limit of a steep ramp when no
//! resistor's power depends on the input's derivative (a resistor that carries an ideal jump's impulse would
//! dissipate an unbounded energy in that limit; such a model has no meaningful response to a step and the
//! dissipated column counts nothing at the jump).
//!
//! A model with nonlinear algebraic loops ([`Equations::tear_blocks`]) has tear variables `z` in its rates,
//! outputs and energy terms: the programs read them after the inputs (`[u, u̇, z]`), and every evaluation first
//! solves the loops at the current state and time by Newton's method, warm-started from the previous solution
//! ([`newton`]). When that fails the run stops with [`SimError::AlgebraicLoop`], which names the tear variables,
//! the time and the residual. The rates depend on the states also through the loops' solution: the symbolic
//! Jacobian adds that dependence (module `loop_jacobian`) where it stays sparse, else the Jacobian is taken by finite
//! differences.
//!
//! Energy terms the equations stage could not express (a stored energy of a non-polynomial law) are left out of
//! their sums; [`System::new`] returns a warning that names each one.

pub mod input;
pub mod input_rate;
#[cfg(feature = "cli")]
pub mod integrate;
mod jacobian;
mod loop_jacobian;
pub mod newton;
pub mod program;
pub mod samples;
#[cfg(feature = "cli")]
mod sparse_ode;

use crate::equations::newton::Lu;
use crate::equations::symbols::{self, Sym, SymExt, add};
use crate::equations::{EnergyKind, Equations, block_jacobian, residual_scale};
use crate::symbolic::Expr;
use input::Signal;
use jacobian::Jacobian;
use newton::{BlockPrograms, Loops};
use program::{CompileError, Layout, Program, ProgramSeq, Values};
use std::collections::HashMap;

/// From this many states on (with the two energy quadratures), a model with a symbolic Jacobian is solved with a
/// sparse Jacobian and LU (`simulate/sparse_ode.rs`). Below it the dense LU is cheap.
pub const SPARSE_FROM: usize = 200;

/// A Jacobian through algebraic loops is kept when it has at most `n² / DENSE_LOOP_JACOBIAN` entries (or 16 a row,
/// for a small model): denser, the sparse factorisation costs more than finite differences and a dense one.
const DENSE_LOOP_JACOBIAN: usize = 10;

/// Why a simulation could not be set up or run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error("{what} could not be derived, so the model cannot be simulated")]
    Incomplete { what: String },
    #[error("{what} cannot be simulated: {reason}")]
    Compile { what: String, reason: CompileError },
    #[error("expected {expected} {what} values, got {got}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{name} = {value:?} is not allowed: {reason}")]
    BadSetting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error(
        "the sampling gives {rows:.3e} rows, more than the limit of {limit}; choose a larger --dt-out"
    )]
    TooManyRows { rows: f64, limit: usize },
    #[error("the initial {what} is not finite")]
    NonFiniteStart { what: String },
    #[error("the derivative of `{state}` became non-finite at t = {time:?}")]
    NonFiniteDerivative { time: f64, state: String },
    /// The rates of a mass block have no solution: its `M` is singular (or not finite) at the state reached.
    #[error(
        "the mass matrix of `{element}` is singular at t = {time:?}, so the rates of its flow states have no solution there; check the inertias (a zero or negative mass) or the configuration reached"
    )]
    SingularMass { time: f64, element: String },
    /// The model's values became non-finite because an input signal is (`1/0`, `sqrt(t - 1)` before t = 1).
    #[error("the {what} is {value:?} at t = {time:?}")]
    NonFiniteInput { time: f64, what: String, value: f64 },
    #[error("`{state}` became non-finite at t = {time:?}")]
    NonFiniteState { time: f64, state: String },
    #[error(
        "the algebraic loop for {tears} could not be solved at t = {time:?}: after {iterations} Newton iterations {reason}; the residual of `{worst}` is {residual:.3e}"
    )]
    AlgebraicLoop {
        /// The tear variables, as messages list them ([`crate::equations::tear::tear_names`]).
        tears: String,
        time: f64,
        reason: &'static str,
        iterations: usize,
        worst: String,
        residual: f64,
    },
    #[error("the algebraic loop for {tears} cannot be solved: {reason}")]
    LoopSetup { tears: String, reason: String },
    #[error("the solver failed at t = {time:?}: {message}")]
    Solver { time: f64, message: String },
    #[error(
        "the solver took {max_steps} steps between t = {from:?} and t = {to:?} and stopped at t = {time:?}"
    )]
    TooManySteps {
        from: f64,
        to: f64,
        time: f64,
        max_steps: usize,
    },
    #[error(
        "the solver advanced too slowly: {steps} steps from t = {from:?} reached t = {time:?}, and at that pace t = {to:?} \
         needs more than the {max_steps} steps allowed ({hint})"
    )]
    TooSlow {
        from: f64,
        to: f64,
        time: f64,
        steps: usize,
        max_steps: usize,
        /// What to try, for the method that stalled.
        hint: &'static str,
    },
}

/// The compiled equations of a model at fixed parameter values, with its input signals.
#[derive(Clone, Debug)]
pub struct System {
    /// The state names (all states: energy states, then integrated flows).
    pub states: Vec<String>,
    /// The output names.
    pub outputs: Vec<String>,
    params: Vec<f64>,
    inputs: Vec<Signal>,
    input_names: Vec<String>,
    /// `d/dt` of each input signal.
    input_rates: Vec<Signal>,
    /// `f_i` for the model states, then the dissipated and the supplied power.
    rates: Vec<Program>,
    /// The Jacobian of the rates (with the mass blocks' rows solved, and through the algebraic loops); `None` when
    /// a rate uses a function without a derivative or the loops make it dense (the Jacobian is then taken by
    /// finite differences).
    jacobian: Option<Jacobian>,
    outputs_h: ProgramSeq,
    stored: Program,
    /// The terms of `stored`, by element.
    stored_terms: Vec<(String, Program)>,
    /// The mass blocks (I-fields, inertias coupled through a varying modulus), in the order of
    /// [`Equations::mass`].
    mass: Vec<MassPrograms>,
    /// The nonlinear algebraic loops, solved before every evaluation.
    loops: Loops,
    /// The length of the programs' input vector `[u, u̇, z]`.
    ext_len: usize,
}

/// One mass block compiled: the states whose rates solve `M ẋ_B = F` (their `rates` give `F`), `M` row-major,
/// and the element (or junctions) the block is named after.
#[derive(Clone, Debug)]
struct MassPrograms {
    states: Vec<usize>,
    matrix: Vec<Program>,
    element: String,
}

impl MassPrograms {
    /// `M` at the point.
    fn at(&self, v: &Values<'_>, stack: &mut Vec<f64>) -> Vec<Vec<f64>> {
        self.matrix
            .chunks(self.states.len().max(1))
            .map(|row| row.iter().map(|p| p.eval(v, stack)).collect())
            .collect()
    }
}

impl System {
    /// Compiles the equations at parameter values `params` (in [`Equations::params`] order) with one signal per
    /// input. Returns the system and the warnings about energy terms left out of the energy columns.
    ///
    /// The programs read the inputs as `[u, u̇, z]`: [`Sym::InputDot`]`(j)` is compiled as input `n_inputs + j`,
    /// the `k`-th tear variable of the loops (in block order) as input `2 n_inputs + k`; the outputs read an
    /// earlier output `j` ([`Sym::Output`]) as input `2 n_inputs + n_tears + j`, written there by [`System::row`]
    /// in output order.
    pub fn new(
        eqs: &Equations,
        params: Vec<f64>,
        inputs: Vec<Signal>,
    ) -> Result<(System, Vec<String>), SimError> {
        check_len("parameter", eqs.params.len(), params.len())?;
        check_len("input", eqs.inputs.len(), inputs.len())?;
        let n = eqs.states.len();
        let n_inputs = inputs.len();
        let tears: Vec<Sym> = eqs
            .tear_blocks
            .iter()
            .flat_map(|b| b.tears.iter().copied())
            .collect();
        let ext_len = 2 * n_inputs + tears.len();
        let exogenous = Exogenous::new(n_inputs, &tears);
        let layout = Layout {
            params: params.len(),
            states: n,
            inputs: ext_len,
        };
        let output_layout = Layout {
            inputs: ext_len + eqs.outputs.len(),
            ..layout
        };
        let name = |s: Sym| match s {
            Sym::Input(j) if j >= ext_len => eqs.sym_name(Sym::Output(j - ext_len)),
            Sym::Input(j) if j >= 2 * n_inputs => tears
                .get(j - 2 * n_inputs)
                .map_or_else(|| format!("input{j}"), |&z| eqs.sym_name(z)),
            Sym::Input(j) if j >= n_inputs => eqs.sym_name(Sym::InputDot(j - n_inputs)),
            other => eqs.sym_name(other),
        };
        let compile = |e: &Expr, what: &str| {
            Program::compile(&exogenous.one(e), layout, &name).map_err(|reason| SimError::Compile {
                what: what.to_string(),
                reason,
            })
        };
        let mut rate_exprs = Vec::with_capacity(n + 2);
        for (i, f) in eqs.f.iter().enumerate() {
            let state = eqs.sym_name(Sym::State(i));
            let e = f.clone().ok_or_else(|| SimError::Incomplete {
                what: format!("the rate of `{state}`"),
            })?;
            rate_exprs.push((e, format!("the rate of `{state}`")));
        }
        let mut warnings = Vec::new();
        // Each stored energy's program is kept, to name the term when the sum is not finite.
        let mut stored_terms = Vec::new();
        let mut sum =
            |kind: EnergyKind| {
                let mut terms = Vec::new();
                for term in eqs.energy.iter().filter(|t| t.kind == kind) {
                    match term.value.as_ref().map(|v| (v, compile(v, ""))) {
                    Some((v, Ok(program))) => {
                        terms.push(v.clone());
                        if kind == EnergyKind::Stored {
                            stored_terms.push((term.element.clone(), program));
                        }
                    }
                    _ => warnings.push(format!(
                        "the {} {} of `{}` has no expression and is left out of the `{}` column",
                        kind.name(),
                        if kind == EnergyKind::Stored { "energy" } else { "power" },
                        term.element,
                        match kind {
                            EnergyKind::Stored => "energy",
                            EnergyKind::Dissipated => "dissipated",
                            EnergyKind::Supplied => "supplied",
                        }
                    )),
                }
                }
                add(terms)
            };
        let stored = sum(EnergyKind::Stored);
        rate_exprs.push((sum(EnergyKind::Dissipated), "the dissipated power".into()));
        rate_exprs.push((sum(EnergyKind::Supplied), "the supplied power".into()));
        let rates = rate_exprs
            .iter()
            .map(|(e, what)| compile(e, what))
            .collect::<Result<Vec<_>, _>>()?;
        let loops = compile_loops(eqs, (2 * n_inputs, &params), &compile)?;
        // With loops, the Jacobian takes their tears' derivatives; kept only where it stays sparse (a loop that
        // reads many states makes every rate that reads its tear a dense row), else finite differences.
        let compile_seq = |es: &[Expr], what: &str| {
            let es = exogenous.all(es);
            ProgramSeq::compile(&es, layout, &name).map_err(|(_, reason)| SimError::Compile {
                what: what.to_string(),
                reason,
            })
        };
        // Only the sparse path uses the Jacobian through loops (the dense one takes finite differences): below it,
        // the loops' derivatives are not built (a block of 400 linear loops has 160,000).
        let through_loops = if eqs.tear_blocks.is_empty() || n + 2 < SPARSE_FROM {
            None
        } else {
            let all = loop_jacobian::Tears::new(&eqs.tear_blocks);
            loop_jacobian::LoopCorrection::new(&eqs.tear_blocks, n, &all, &compile_seq)
                .map(|correction| (all, correction))
        };
        let loop_entries = (n.saturating_mul(n) / DENSE_LOOP_JACOBIAN).max(n.saturating_mul(16));
        let jacobian = match (eqs.tear_blocks.is_empty(), through_loops) {
            (false, None) => None,
            (_, loops) => Jacobian::new(&rate_exprs, n, &eqs.mass, loops, loop_entries, &compile),
        };
        let mut mass = Vec::with_capacity(eqs.mass.len());
        for b in &eqs.mass {
            let mut matrix = Vec::new();
            for (i, row) in b.matrix.iter().enumerate() {
                for (j, e) in row.iter().enumerate() {
                    matrix.push(compile(
                        e,
                        &format!("M_{}[{},{}]", b.element, i + 1, j + 1),
                    )?);
                }
            }
            mass.push(MassPrograms {
                states: b.states.clone(),
                matrix,
                element: b.element.clone(),
            });
        }
        let mut output_exprs = Vec::with_capacity(eqs.outputs.len());
        for o in &eqs.outputs {
            let e = o.explicit.as_ref().ok_or_else(|| SimError::Incomplete {
                what: format!("output `{}`", o.name),
            })?;
            let e = symbols::subst(e, &mut |s| match s {
                Sym::Output(j) => Some(symbols::leaf(Sym::Input(ext_len + j))),
                _ => None,
            });
            output_exprs.push(exogenous.one(&e));
        }
        // One program for all outputs: what they share (the efforts along a gear train hold one another) is
        // computed once per row.
        let outputs_h =
            ProgramSeq::compile(&output_exprs, output_layout, &name).map_err(|(k, reason)| {
                SimError::Compile {
                    what: format!(
                        "output `{}`",
                        eqs.outputs.get(k).map_or("?", |o| o.name.as_str())
                    ),
                    reason,
                }
            })?;
        let system = System {
            states: (0..n).map(|i| eqs.sym_name(Sym::State(i))).collect(),
            outputs: eqs.outputs.iter().map(|o| o.name.clone()).collect(),
            params,
            input_rates: inputs.iter().map(Signal::derivative).collect(),
            inputs,
            input_names: eqs.inputs.clone(),
            rates,
            jacobian,
            outputs_h,
            stored: compile(&stored, "the stored energy")?,
            stored_terms,
            mass,
            loops,
            ext_len,
        };
        Ok((system, warnings))
    }

    /// The number of model states.
    pub fn state_count(&self) -> usize {
        self.states.len()
    }

    /// Writes the input values at `t` and their time derivatives into the programs' input vector `[u, u̇, z]`,
    /// sized to fit; the tear slots `z` keep their values (the next loop solve starts from them).
    pub fn inputs_at(&self, t: f64, out: &mut Vec<f64>) {
        out.resize(self.ext_len, 0.0);
        let values = self
            .inputs
            .iter()
            .chain(&self.input_rates)
            .map(|s| s.eval(t));
        for (slot, v) in out.iter_mut().zip(values) {
            *slot = v;
        }
    }

    /// The first input signal, or time derivative of one, that is not finite at `t`: the cause to name when the
    /// model's values become non-finite there.
    pub fn non_finite_input(&self, t: f64) -> Option<SimError> {
        let named = |signals: &[Signal], rate: bool| {
            signals.iter().zip(&self.input_names).find_map(|(s, name)| {
                let value = s.eval(t);
                (!value.is_finite()).then(|| SimError::NonFiniteInput {
                    time: t,
                    what: match rate {
                        false => format!("input `{name}`"),
                        true => format!("time derivative of the input `{name}`"),
                    },
                    value,
                })
            })
        };
        named(&self.inputs, false).or_else(|| named(&self.input_rates, true))
    }

    /// Solves the nonlinear algebraic loops at the extended state `y` and time `t`, with the inputs already in
    /// `u` ([`System::inputs_at`]), writing the tear variables into `u`'s tear slots.
    pub fn solve_loops(
        &self,
        y: &[f64],
        u: &mut [f64],
        t: f64,
        stack: &mut Vec<f64>,
    ) -> Result<(), SimError> {
        if self.loops.is_empty() {
            return Ok(());
        }
        let values = Values {
            params: &self.params,
            states: y.get(..self.states.len()).unwrap_or(y),
            inputs: &[],
            t,
        };
        self.loops
            .solve(&values, u, stack)
            .map_err(|e| SimError::AlgebraicLoop {
                tears: e.tear_list(),
                time: t,
                reason: e.failure.kind.describe(),
                iterations: e.failure.iterations,
                worst: e.worst.clone(),
                residual: e.failure.residual,
            })
    }

    /// The jump of the stored energy at the extended state `y` when the inputs go from their values at `before`
    /// to those at `after` (a breakpoint): the energy a jump of an input moves into the storages in derivative
    /// causality, which the input's derivative cannot carry.
    pub fn stored_jump(
        &self,
        y: &[f64],
        before: f64,
        after: f64,
        stack: &mut Vec<f64>,
    ) -> Result<f64, SimError> {
        let mut u = Vec::new();
        self.inputs_at(after, &mut u);
        self.solve_loops(y, &mut u, after, stack)?;
        let e_after = self.stored.eval(&self.values(y, &u, after), stack);
        self.inputs_at(before, &mut u);
        self.solve_loops(y, &mut u, before, stack)?;
        let e_before = self.stored.eval(&self.values(y, &u, before), stack);
        Ok(e_after - e_before)
    }

    /// The times in `(0, t_end)` at which an input may jump or kink, sorted, without repeats.
    pub fn breakpoints(&self, t_end: f64) -> Vec<f64> {
        let mut b = Vec::new();
        self.inputs.iter().for_each(|s| s.breakpoints(&mut b));
        b.retain(|t| t.is_finite() && *t > 0.0 && *t < t_end);
        b.sort_by(f64::total_cmp);
        b.dedup();
        b
    }

    fn values<'a>(&'a self, y: &'a [f64], u: &'a [f64], t: f64) -> Values<'a> {
        Values {
            params: &self.params,
            states: y.get(..self.states.len()).unwrap_or(y),
            inputs: u,
            t,
        }
    }

    /// The derivative of the extended state `y = [x, E_diss, E_sup]` at time `t` with the inputs in `u`
    /// ([`System::inputs_at`]); the algebraic loops are solved first (into `u`).
    pub fn rhs(
        &self,
        y: &[f64],
        u: &mut [f64],
        t: f64,
        dy: &mut [f64],
        stack: &mut Vec<f64>,
    ) -> Result<(), SimError> {
        self.solve_loops(y, u, t, stack)?;
        let v = self.values(y, u, t);
        for (d, p) in dy.iter_mut().zip(&self.rates) {
            *d = p.eval(&v, stack);
        }
        for block in &self.mass {
            let forces: Vec<Vec<f64>> = block
                .states
                .iter()
                .map(|&j| vec![dy.get(j).copied().unwrap_or(f64::NAN)])
                .collect();
            // A singular mass matrix leaves non-finite rates, which the integrator reports with the time.
            let solved = crate::equations::dense::solve(&block.at(&v, stack), &forces);
            for (k, &j) in block.states.iter().enumerate() {
                if let Some(d) = dy.get_mut(j) {
                    *d = solved
                        .as_ref()
                        .and_then(|x| x.get(k))
                        .and_then(|r| r.first().copied())
                        .unwrap_or(f64::NAN);
                }
            }
        }
        Ok(())
    }

    /// The mass block of state `index` when its `M` is singular or not finite at the extended state `y` and time
    /// `t`: the element it is named after.
    pub fn singular_mass(&self, y: &[f64], t: f64, index: usize) -> Option<String> {
        let block = self.mass.iter().find(|b| b.states.contains(&index))?;
        let mut u = Vec::new();
        self.inputs_at(t, &mut u);
        let mut stack = Vec::new();
        if self.solve_loops(y, &mut u, t, &mut stack).is_err() {
            return None;
        }
        let m = block.at(&self.values(y, &u, t), &mut stack);
        let n = block.states.len();
        let singular = m.iter().flatten().any(|x| !x.is_finite())
            || crate::equations::dense::solve(&m, &vec![vec![1.0]; n]).is_none();
        singular.then(|| block.element.clone())
    }

    /// `J v` for the Jacobian `J = ∂rhs/∂y`; `None` when it has no symbolic form (a rate uses a function without a
    /// derivative) or takes the loops' derivatives: the dense path asks for one product per column, and each would
    /// solve every loop's derivatives again, where finite differences cost two evaluations of the rates.
    pub fn jacobian_times(
        &self,
        y: &[f64],
        u: &[f64],
        t: f64,
        v: &[f64],
        jv: &mut [f64],
        stack: &mut Vec<f64>,
    ) -> Option<()> {
        let jacobian = self.jacobian.as_ref().filter(|j| !j.through_loops())?;
        jv.iter_mut().for_each(|x| *x = 0.0);
        jacobian.for_each(
            &self.values(y, u, t),
            (&self.rates, &self.mass),
            stack,
            |r, c, value| {
                if let (Some(out), Some(vc)) = (jv.get_mut(r), v.get(c)) {
                    *out += value * vc;
                }
            },
        );
        Some(())
    }

    /// The positions `(row, column)` of the symbolic Jacobian's entries over the model states, row by row (the
    /// energy quadratures' rows last); `None` when it has no symbolic form (see [`System::jacobian_times`]).
    pub fn jacobian_pattern(&self) -> Option<Vec<(usize, usize)>> {
        Some(self.jacobian.as_ref()?.pattern())
    }

    /// The values of the Jacobian's first `out.len()` entries at `(y, u, t)`, in the order of
    /// [`System::jacobian_pattern`]; `None` when it has no symbolic form.
    pub fn jacobian_values(
        &self,
        y: &[f64],
        u: &[f64],
        t: f64,
        out: &mut [f64],
        stack: &mut Vec<f64>,
    ) -> Option<()> {
        let jacobian = self.jacobian.as_ref()?;
        let mut slots = out.iter_mut();
        // The loops solved at the point, in a copy of the inputs' vector (its tear slots start the iteration).
        let mut solved;
        let u = if jacobian.through_loops() {
            solved = u.to_vec();
            if self.solve_loops(y, &mut solved, t, stack).is_err() {
                out.iter_mut().for_each(|v| *v = f64::NAN);
                return Some(());
            }
            &solved[..]
        } else {
            u
        };
        jacobian.for_each(
            &self.values(y, u, t),
            (&self.rates, &self.mass),
            stack,
            |_, _, value| {
                if let Some(slot) = slots.next() {
                    *slot = value;
                }
            },
        );
        Some(())
    }

    /// One row of output: the states, the outputs, the stored energy, then the dissipated and supplied energy.
    pub fn row(
        &self,
        y: &[f64],
        t: f64,
        u: &mut Vec<f64>,
        stack: &mut Vec<f64>,
    ) -> Result<Vec<f64>, SimError> {
        self.inputs_at(t, u);
        self.solve_loops(y, u, t, stack)?;
        let n = self.states.len();
        let mut row = Vec::with_capacity(n + self.outputs.len() + 3);
        row.extend(y.iter().take(n));
        // Each output is written after the inputs before the next is evaluated (outputs defined through earlier
        // outputs read them there).
        u.truncate(self.ext_len);
        // The programs read the inputs from `u` itself, where each output is appended.
        self.outputs_h
            .eval_appending(&self.values(y, &[], t), u, stack);
        row.extend(u.iter().skip(self.ext_len));
        u.truncate(self.ext_len);
        let v = self.values(y, u, t);
        row.push(self.stored.eval(&v, stack));
        row.extend(y.iter().skip(n).take(2));
        Ok(row)
    }

    /// What makes the stored energy at `y` not finite, when it is not: the first element whose stored energy is
    /// not finite, or the sum of finite terms. Reads the inputs (and the loops' solution) [`System::row`] left in
    /// `u`.
    pub fn stored_energy_fault(
        &self,
        y: &[f64],
        t: f64,
        u: &[f64],
        stack: &mut Vec<f64>,
    ) -> Option<String> {
        let v = self.values(y, u, t);
        if self.stored.eval(&v, stack).is_finite() {
            return None;
        }
        let culprit = self.stored_terms.iter().find_map(|(element, p)| {
            let e = p.eval(&v, stack);
            (!e.is_finite()).then(|| format!("stored energy of `{element}`"))
        });
        Some(culprit.unwrap_or_else(|| "energy (its terms are finite; their sum overflows)".into()))
    }

    /// The CSV header matching [`System::row`], after `t`.
    pub fn columns(&self) -> Vec<String> {
        let mut c = self.states.clone();
        c.extend(self.outputs.iter().cloned());
        c.extend(["energy", "dissipated", "supplied"].map(String::from));
        c
    }
}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), SimError> {
    if expected == got {
        Ok(())
    } else {
        Err(SimError::Dimension {
            what,
            expected,
            got,
        })
    }
}

/// The renaming into the programs' `[u, u̇, z]` layout: each [`Sym::InputDot`]`(j)` to the input `n_inputs + j`
/// and each tear `tears[k]` to the input `2 n_inputs + k`.
struct Exogenous {
    n_inputs: usize,
    slot: HashMap<Sym, usize>,
}

impl Exogenous {
    fn new(n_inputs: usize, tears: &[Sym]) -> Exogenous {
        let slot = tears.iter().enumerate().map(|(k, &z)| (z, k)).collect();
        Exogenous { n_inputs, slot }
    }

    fn rename(&self, s: Sym) -> Option<Expr> {
        match s {
            Sym::InputDot(j) => Some(symbols::leaf(Sym::Input(self.n_inputs + j))),
            Sym::Tear(_) => self
                .slot
                .get(&s)
                .map(|k| symbols::leaf(Sym::Input(2 * self.n_inputs + k))),
            _ => None,
        }
    }

    /// `e` renamed.
    fn one(&self, e: &Expr) -> Expr {
        if !e.any_sym(&|s| matches!(s, Sym::InputDot(_) | Sym::Tear(_))) {
            return e.clone();
        }
        symbols::subst(e, &mut |s| self.rename(s))
    }

    /// `es` renamed in one walk of their distinct nodes: a loop's derivatives share its residual's nodes.
    fn all(&self, es: &[Expr]) -> Vec<Expr> {
        symbols::subst_all(es, &mut |s| self.rename(s))
    }
}

/// `∂r/∂z` factored at the parameter values `params`, when every entry reads parameters only; `None` otherwise or
/// when it is singular there (Newton's method then reports the loop).
fn constant_jacobian(entries: &[Expr], programs: &[Program], params: &[f64]) -> Option<Lu> {
    let constant = entries
        .iter()
        .all(|e| e.syms().iter().all(|s| matches!(s, Sym::Param(_))));
    if !constant {
        return None;
    }
    let at = Values {
        params,
        states: &[],
        inputs: &[],
        t: 0.0,
    };
    let mut stack = Vec::new();
    let values: Vec<f64> = programs.iter().map(|p| p.eval(&at, &mut stack)).collect();
    let n = values.len().isqrt();
    Lu::factor(values, n)
}

/// The programs of the tear blocks: residuals, their scales and `∂r/∂z`, with the tears at `offset + k`; `∂r/∂z`
/// factored at `params` where it is constant.
fn compile_loops(
    eqs: &Equations,
    (offset, params): (usize, &[f64]),
    compile: &dyn Fn(&Expr, &str) -> Result<Program, SimError>,
) -> Result<Loops, SimError> {
    let mut loops = Loops::default();
    let mut k = offset;
    for block in &eqs.tear_blocks {
        let tears = crate::equations::tear::tear_names(&block.names);
        let what = crate::equations::tear::loop_for(&tears);
        let jacobian = block_jacobian(block).ok_or_else(|| SimError::LoopSetup {
            tears: tears.clone(),
            reason: "its residuals use a function without a derivative (min or max), which Newton's method needs"
                .into(),
        })?;
        let all = |es: &[Expr]| {
            es.iter()
                .map(|e| compile(e, &what))
                .collect::<Result<Vec<_>, _>>()
        };
        let scales: Vec<Expr> = block
            .residuals
            .iter()
            .zip(&block.tears)
            .map(|(r, &z)| residual_scale(r, z))
            .collect();
        let programs = all(&jacobian)?;
        let constant = constant_jacobian(&jacobian, &programs, params);
        loops.push(BlockPrograms {
            slots: (k..k + block.tears.len()).collect(),
            names: block.names.clone(),
            residuals: all(&block.residuals)?,
            scales: all(&scales)?,
            jacobian: programs,
            constant,
        });
        k += block.tears.len();
    }
    Ok(loops)
}
