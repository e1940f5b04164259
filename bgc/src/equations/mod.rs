//! The equations stage: from a causal bond graph to state equations `ẋ = f(x, u, p, t)` and outputs
//! `y = h(x, u, p, t)`.
//!
//! Steps ([`derive()`]):
//! 1. States are the energy variables of the storages in integral causality (`p_rotor`, `q_hd_spring`), then the
//!    integrated flows (`var`s, named as declared); their rates are `ṗ = e`, `q̇ = f`, `θ̇ = integrand`.
//! 2. Every node writes the causal equation of each bond variable it computes (`build.rs`).
//! 3. The rates and outputs are expressed in states, inputs, parameters and `t` by substitution in dependency order
//!    (`resolve.rs`; each resolved value is multiplied out when that makes it no larger, so that the solutions of
//!    chained algebraic loops do not nest); algebraic loops are torn and solved exactly when affine, storages in
//!    derivative causality contribute `ẋ` terms, solved for by a symbolic linear solve (`solve.rs`). An output
//!    defined through earlier outputs refers to them ([`Sym::Output`]) rather than copying them. Multiport fields are in `field`:
//!    an I-field gives the mass-matrix form `M(q) ẋ = F` for its flow states ([`Equations::mass`]), solved
//!    numerically by its consumers ([`Equations::rates_at`]).
//! 4. A nonlinear algebraic loop stays implicit (`tear.rs`): its tear variable `z` (`Sym::Tear`, printed
//!    `loop_<variable>`) is an unknown of the equations, defined by a residual equation `0 = r(z, x, u, p, t)` in
//!    [`Equations::tear_blocks`]. Rates, outputs and energy terms hold `z`; `bgc simulate` solves the blocks by
//!    Newton's method ([`newton`]) at every evaluation (so do [`Equations::rates_at`] and `outputs_at`),
//!    [`linearise`] uses the implicit function theorem, and generated code solves them in its functions.
//! 5. Readable forms keep intermediates (one per bond variable that is computed and not a mere copy of another).
//!
//! # Calling it
//! ```text
//! let (causality, _) = bgc::causality::analyse(&model);
//! let (eqs, diags) = bgc::equations::derive(&model, &causality);      // check has_errors(&diags)
//! bgc::equations::to_text(&eqs) / to_latex(&eqs) / to_json(&eqs)      // `bgc equations`
//! let p = eqs.default_params();
//! numeric_state_space(&eqs, StateSelection::Energy, &p)               // `bgc statespace` (energy states)
//! declared_state_space(&eqs, &p)                                      // ... in the model's `coords`
//! declared_state_space_symbolic(&eqs)                                 // ... as expressions of the parameters
//! linear_state_space(&eqs, StateSelection::Energy)                    // symbolic A, B, C, D
//! jacobians(&eqs, sel) / linearise(&eqs, sel, &p, &x0, &u0, t0)       // nonlinear models
//! eqs.f[i], eqs.outputs[k].explicit                                  // `bgc simulate`, code generation
//! eqs.tear_blocks, solve_all(&eqs, &values)                          // nonlinear loops: 0 = r(z, x, u, p, t)
//! ```
//! The states are `eqs.states` (energy states first, `eqs.energy_states` of them, then one per `var`); symbols
//! in expressions are named by [`Equations::sym_name`].
//!
//! The expressions are those of the shared engine [`crate::symbolic`], a hash-consed DAG (equal subexpressions are
//! one node), over the stage's indexed symbols ([`symbols::Sym`]: parameters, inputs, states, bond variables,
//! outputs, tears and rates, each an index into a table of this stage; [`Equations::sym_name`] names them). Nothing
//! here recurses along the model: the resolver follows dependency chains on an explicit stack and every walk of an
//! expression is a walk of its distinct nodes, so derivation needs no large stack however long the model's chains.
//!
//! Diagnostics of this stage:
//!
//! | code | finding |
//! |---|---|
//! | BG0600 | the causality has conflicts: no equations |
//! | BG0601 | a nonlinear law must be inverted for its causality and is not affine in the unknown |
//! | BG0602 | an output needs the time derivative of an input |
//! | BG0603 | a singular algebraic loop (its loop gain is one), or a nonlinear one through a storage in derivative causality (nonlinear loops are otherwise kept as tear blocks) |
//! | BG0604 | derivative causality that cannot be resolved (nonlinear in the rates, singular, or a state rate needing the derivative of an input) |
//! | BG0605 | a construct the equations stage does not support (a field port in derivative causality, an R-field with mixed causality, an inertia matrix depending on more than the field's displacements, ambiguous references) |
//! | BG0606 | declared coordinates that are not a linear, invertible function of the states |
//! | BG0607 | the stored energy of a law that cannot be integrated symbolically (warning) |

mod build;
mod coords;
mod coords_symbolic;
mod copies;
pub(crate) mod dense;
mod dogleg;
mod energy;
mod field;
mod implicit_linear;
mod kinematic;
mod linear;
mod linear_loops;
mod naming;
pub mod newton;
mod numeric;
mod param_chain;
mod print;
mod resolve;
mod sensitivity;
mod shared;
mod solve;
mod sparse_linear;
pub mod symbols;
pub mod tear;
mod time;

pub use coords::{CoordsError, declared_state_space};
pub use coords_symbolic::declared_state_space_symbolic;
pub use energy::{EnergyKind, EnergyTerm};
pub use field::MassBlock;
pub use linear::{
    Jacobians, LinearError, NumericStateSpace, StateSelection, SymbolicStateSpace, evaluate_at,
    jacobians, linear_state_space, linearise, numeric_state_space,
};
pub use linear_loops::{linear_through_loops, time_in_loops};
pub use param_chain::ParamChain;
pub use print::{expr_latex, expr_text, to_json, to_latex, to_text};
pub use sensitivity::{PointJacobians, Rows, Sensitivity};
pub use sparse_linear::{
    ModelRows, NumericSparse, SparseJacobians, SparseMatrix, SparseNumericStateSpace,
    dense_is_cheap, evaluate_sparse, linearise_sparse, sparse_jacobians, sparse_linear_state_space,
    state_selection,
};
pub(crate) use tear::block_jacobian;
pub use tear::{LoopFailure, TearBlock, residual_scale, solve_all};

use crate::causality::Causality;
use crate::diagnostic::Diagnostic;
use crate::ir::{Expr as IrExpr, Model, VarId};
use crate::symbolic::Expr;
use petgraph::graph::NodeIndex;
use resolve::{ResolveError, Resolver};
use symbols::{Sym, SymExt};

/// The diagnostic codes of this stage.
pub mod codes {
    pub const CAUSALITY_CONFLICT: &str = "BG0600";
    pub const NOT_INVERTIBLE: &str = "BG0601";
    pub const INPUT_DERIVATIVE: &str = "BG0602";
    pub const ALGEBRAIC_LOOP: &str = "BG0603";
    pub const DERIVATIVE_CAUSALITY: &str = "BG0604";
    pub const UNSUPPORTED: &str = "BG0605";
    pub const COORDS: &str = "BG0606";
    pub const ENERGY: &str = "BG0607";
    pub const NOT_FINITE: &str = "BG0608";
}

/// What a state is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateKind {
    /// The momentum `p` of an inertia.
    Momentum,
    /// The displacement `q` of a compliance.
    Displacement,
    /// A declared integrated flow (`var`).
    Integrated,
    /// The flow of an I-field port (a generalised velocity; its rate comes from the mass-matrix form).
    Velocity,
}

/// One state.
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpec {
    /// `p_<element>`, `q_<element>` or the `var`'s name.
    pub name: String,
    pub kind: StateKind,
    /// The storage element (energy states).
    pub node: Option<NodeIndex>,
    /// The integrated flow (integrated states).
    pub var: Option<VarId>,
    /// The port (0-based) of a multiport field's state.
    pub port: Option<u32>,
}

/// A named intermediate variable in the readable equations.
#[derive(Clone, Debug, PartialEq)]
pub struct Intermediate {
    /// Named after its element, junction or bond: `e_hd_spring`, `f_j_sint`, `e_gear_in`.
    pub name: String,
    /// The right-hand side, in states, inputs, parameters, `t` and earlier intermediates ([`Sym::Var`]).
    pub value: Expr,
    /// True when the intermediate is `d/dt(value)` (the output of a storage in derivative causality).
    pub derivative: bool,
}

/// One output.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputEq {
    pub name: String,
    /// In states, inputs, parameters, `t` and intermediates.
    pub value: Expr,
    /// In states, inputs, parameters, `t`, tear variables and earlier outputs ([`Sym::Output`]`(j)`, `j` less
    /// than this output's index, whose values are computed first): `h(x, u, p, t)`. `None` when it could not be
    /// derived (a diagnostic says why, at this output or at the output it is defined through).
    pub explicit: Option<Expr>,
}

/// The state equations of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Equations {
    pub model: String,
    /// Parameter names and default values (indexed by [`Sym::Param`]).
    pub params: Vec<(String, f64)>,
    /// Per parameter: its expression in earlier parameters when it is derived (see [`crate::ir::Param::derived`]).
    pub derived: Vec<Option<Expr>>,
    /// Input names (indexed by [`Sym::Input`]).
    pub inputs: Vec<String>,
    /// Energy states first, then one integrated state per `var`.
    pub states: Vec<StateSpec>,
    /// The number of energy states (the first entries of `states`).
    pub energy_states: usize,
    /// Readable rates: `ẋ_i = rates[i]` in states, inputs, parameters, `t` and intermediates.
    pub rates: Vec<Expr>,
    /// Explicit rates `f(x, u, p, t)`; `None` for a rate that could not be derived (a diagnostic says why).
    pub f: Vec<Option<Expr>>,
    /// Intermediates in dependency order.
    pub intermediates: Vec<Intermediate>,
    /// Names of the bond variables as intermediates (indexed by [`Sym::Var`]).
    pub var_names: Vec<String>,
    pub outputs: Vec<OutputEq>,
    /// Declared coordinates, explicit in the states (linear, checked), with their names.
    pub coords: Option<Vec<(String, Expr)>>,
    /// Stored energy, dissipated and supplied power of each element.
    pub energy: Vec<EnergyTerm>,
    /// The inertia matrices of the I-fields: for the states of a block, `f` and `rates` hold the generalised
    /// forces `F`, and `M ẋ_block = F` gives the rates ([`Equations::rates_at`] solves it numerically).
    pub mass: Vec<MassBlock>,
    /// The intermediates at which algebraic loops were solved exactly: the readable intermediates around them are
    /// implicit (they refer to each other), the explicit rates and outputs are not.
    pub loops: Vec<String>,
    /// The nonlinear algebraic loops, kept implicit, in solving order: the explicit rates, outputs and energy terms
    /// hold their tear variables ([`Sym::Tear`]), whose values solve `0 = r(z, x, u, p, t)`.
    pub tear_blocks: Vec<TearBlock>,
    /// The elements whose values or laws use time `t` (signals written into the model, such as
    /// `Se mains = V0*sin(w*t);`): the rates hold them, a linear state space cannot ([`LinearError::TimeDependent`]).
    pub time_signals: Vec<String>,
}

impl Equations {
    /// The printable name of a symbol.
    pub fn sym_name(&self, s: Sym) -> String {
        match s {
            Sym::Param(i) => self
                .params
                .get(i)
                .map(|p| p.0.clone())
                .unwrap_or_else(|| format!("param{i}")),
            Sym::Input(i) => self
                .inputs
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("input{i}")),
            Sym::InputDot(i) => format!("d{}_dt", self.sym_name(Sym::Input(i))),
            Sym::State(i) => self
                .states
                .get(i)
                .map(|s| s.name.clone())
                .unwrap_or_else(|| format!("x{i}")),
            Sym::StateDot(i) => format!("d{}_dt", self.sym_name(Sym::State(i))),
            Sym::Var(i) => self
                .var_names
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("v{i}")),
            Sym::Tear(i) => format!("loop_{}", self.sym_name(Sym::Var(i))),
            Sym::Time => "t".to_string(),
            Sym::Output(k) => self
                .outputs
                .get(k)
                .map(|o| o.name.clone())
                .unwrap_or_else(|| format!("output{k}")),
        }
    }

    /// The printable name of a symbol of the engine: the name of the stage's symbol it is, else its own.
    pub fn symbol_name(&self, s: &crate::symbolic::Symbol) -> String {
        match Sym::of(s) {
            Some(t) => self.sym_name(t),
            None => s.name().to_string(),
        }
    }

    /// The explicit outputs with the references to earlier outputs ([`Sym::Output`]) substituted, each in
    /// states, inputs, parameters, `t` and tears only (`None` where an output was not derived). A chain of outputs
    /// defined through each other grows here with every level; evaluating the outputs in order does not.
    pub fn outputs_inlined(&self) -> Vec<Option<Expr>> {
        let mut done: Vec<Option<Expr>> = Vec::with_capacity(self.outputs.len());
        for o in &self.outputs {
            let e = o.explicit.as_ref().and_then(|e| {
                let mut missing = false;
                let v = symbols::subst(e, &mut |s| match s {
                    Sym::Output(j) => {
                        let r = done.get(j).cloned().flatten();
                        missing |= r.is_none();
                        r
                    }
                    _ => None,
                });
                (!missing).then_some(v)
            });
            done.push(e);
        }
        done
    }

    /// True when every explicit rate and output was derived.
    pub fn complete(&self) -> bool {
        self.f.iter().all(Option::is_some) && self.outputs.iter().all(|o| o.explicit.is_some())
    }
}

pub(super) fn with_span(
    d: Diagnostic,
    span: Option<&crate::span::Span>,
    label: &str,
) -> Diagnostic {
    match span {
        Some(s) => d.with_primary(*s, label),
        None => d,
    }
}

fn empty_equations(model: &Model) -> Equations {
    Equations {
        model: model.name.clone(),
        params: model
            .params
            .iter()
            .map(|p| (p.name.clone(), p.default))
            .collect(),
        derived: vec![None; model.params.len()],
        inputs: model.inputs.iter().map(|i| i.name.clone()).collect(),
        states: Vec::new(),
        energy_states: 0,
        rates: Vec::new(),
        f: Vec::new(),
        intermediates: Vec::new(),
        var_names: Vec::new(),
        outputs: Vec::new(),
        coords: None,
        energy: Vec::new(),
        mass: Vec::new(),
        loops: Vec::new(),
        tear_blocks: Vec::new(),
        time_signals: time::time_elements(model),
    }
}

/// An output converted to the stage's symbols with its explicit form (or why it has none), or why it could not be
/// converted.
type ResolvedOutput = Result<(Expr, Result<Expr, ResolveError>), String>;

/// Derives the state equations of `model` with the causality `causality`.
///
/// Returns the equations (as complete as possible) and the findings; an error diagnostic means some rate or output
/// is missing (`None` in [`Equations::f`] or [`OutputEq::explicit`]).
pub fn derive(model: &Model, causality: &Causality) -> (Equations, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut eqs = empty_equations(model);
    if !causality.consistent {
        diags.push(with_span(
            Diagnostic::error(
                codes::CAUSALITY_CONFLICT,
                format!(
                    "no equations for `{}`: its causality has conflicts",
                    model.name
                ),
            ),
            Some(&model.spans.model),
            "this model",
        ));
        return (eqs, diags);
    }
    // Dependent storage behind a modulus that varies with the state: derive on the graph with velocity states.
    let augmented = kinematic::augment_if_needed(model, causality);
    let (model, causality, velocities) = match &augmented {
        Some(a) => (&a.model, &a.causality, a.velocities.as_slice()),
        None => (model, causality, &[][..]),
    };
    let (mut ctx, states) = build::context(model, causality, velocities);
    eqs.derived = model
        .params
        .iter()
        .map(|p| p.derived.as_ref().and_then(|e| ctx.convert(e).ok()))
        .collect();
    let built = build::build(model, causality, &mut ctx, states, &mut diags);
    eqs.energy_states = built
        .states
        .iter()
        .filter(|s| s.kind != StateKind::Integrated)
        .count();
    let nstates = built.states.len();
    let mut resolver = Resolver::new(&built, nstates, model.inputs.len());

    // Explicit rates, with ẋ of derivative-causality storages still symbolic.
    let mut implicit = Vec::with_capacity(nstates);
    let mut rate_ok = vec![true; nstates];
    // Whether a rate or an output could not be resolved (an energy term then reports no cause of its own).
    let mut reported = false;
    for (i, rate) in built.rates.iter().enumerate() {
        match resolver.expr(rate) {
            Ok(e) => implicit.push(e),
            Err(e) => {
                reported = true;
                diags.push(resolve_diag(
                    model,
                    &built,
                    &e,
                    &format!("the rate of state `{}`", built.states[i].name),
                ));
                rate_ok[i] = false;
                implicit.push(Expr::zero());
            }
        }
    }
    for (i, e) in implicit.iter().enumerate() {
        if rate_ok[i] && e.any_sym(&|s| matches!(s, Sym::InputDot(_))) {
            rate_ok[i] = false;
            let d = Diagnostic::error(
                codes::DERIVATIVE_CAUSALITY,
                format!("the rate of state `{}` needs the time derivative of an input", built.states[i].name),
            )
            .with_help("a storage in derivative causality is driven by a source through this state's equation; give the source a state (add a compliance or a resistance) or move the storage");
            diags.push(with_span(
                d,
                state_span(model, &built.states[i]),
                "this storage",
            ));
        }
    }
    let mut kinematic_mass: Vec<MassBlock> = Vec::new();
    let solved_rates = if built.implicit_rows.iter().any(|&r| r) {
        solve::mass_form(&implicit, &built.implicit_rows).map(|(f, blocks)| {
            kinematic_mass = kinematic::blocks(model, &built.states, blocks, &built.mass);
            f
        })
    } else {
        solve::solve_rates(&implicit)
    };
    let solved = match solved_rates {
        Ok(x) => x,
        Err(e) => {
            let msg = match e {
                solve::SolveError::Nonlinear(i) => format!(
                    "the storages in derivative causality enter the rate of `{}` nonlinearly in the state rates",
                    built.states.get(i).map(|s| s.name.as_str()).unwrap_or("?")
                ),
                solve::SolveError::Singular => {
                    "the storages in derivative causality make the rate equations singular".into()
                }
                solve::SolveError::NotDifferentiable(_) => {
                    "a law under derivative causality cannot be differentiated".into()
                }
            };
            let mut d = Diagnostic::error(codes::DERIVATIVE_CAUSALITY, msg);
            if let Some(s) = causality
                .derivative()
                .next()
                .and_then(|s| model.spans.nodes.get(s.node.index()))
            {
                d = d.with_primary(*s, "a storage in derivative causality");
            }
            diags.push(d);
            rate_ok.iter_mut().for_each(|ok| *ok = false);
            implicit.clone()
        }
    };
    // A storage in derivative causality whose rate involves an I-field's flows would add to its inertia matrix;
    // that coupling is not supported, and substituting `ẋ` of a mass-matrix row would be wrong.
    let field_states: Vec<usize> = built
        .mass
        .iter()
        .flat_map(|b| b.states.iter().copied())
        .collect();
    let mass_states: Vec<usize> = field_states
        .iter()
        .copied()
        .chain(kinematic_mass.iter().flat_map(|b| b.states.iter().copied()))
        .collect();
    if implicit
        .iter()
        .any(|e| field_states.iter().any(|&j| e.contains(Sym::StateDot(j))))
    {
        diags.push(with_span(
            Diagnostic::error(
                codes::DERIVATIVE_CAUSALITY,
                "a storage in derivative causality is driven by the flows of an I-field; fold it into the field's inertia matrix",
            ),
            causality
                .derivative()
                .next()
                .and_then(|s| model.spans.nodes.get(s.node.index())),
            "this storage is in derivative causality",
        ));
        rate_ok.iter_mut().for_each(|ok| *ok = false);
    }
    // The rate of a mass-matrix row of the velocity states is not `solved[j]` (that holds the generalised force):
    // it stays `ẋ_j`, and whatever still holds it has no closed form.
    let mut kinematic_rows = vec![false; nstates];
    for &j in kinematic_mass.iter().flat_map(|b| b.states.iter()) {
        if let Some(row) = kinematic_rows.get_mut(j) {
            *row = true;
        }
    }
    let rate_value = |s: Sym| match s {
        Sym::StateDot(j) if kinematic_rows.get(j).copied().unwrap_or(false) => None,
        Sym::StateDot(j) => solved.get(j).cloned(),
        _ => None,
    };
    let rate_of = |e: &Expr| symbols::subst(e, &mut |s| rate_value(s));
    let rates_of = |es: &[Expr]| symbols::subst_all(es, &mut |s| rate_value(s));
    eqs.f = solved
        .iter()
        .zip(&rate_ok)
        .map(|(e, ok)| ok.then(|| e.clone()))
        .collect();
    let all_rates_ok = rate_ok.iter().all(|&ok| ok);

    // Outputs: each resolved in turn, then what each reads found in one walk of them all (an output that holds
    // the next one's value, as the efforts along a gear train do, would otherwise be walked once per check).
    let resolved: Vec<ResolvedOutput> = model
        .outputs
        .iter()
        .enumerate()
        .map(|(k, out)| match ctx.convert_output(&out.value, k) {
            Ok(v) => {
                let explicit = resolver.expr(&v);
                Ok((v, explicit))
            }
            Err(build::ConvertError::Unsupported(what)) => Err(what),
        })
        .collect();
    let explicit_values: Vec<Expr> = resolved
        .iter()
        .map(|r| match r {
            Ok((_, Ok(e))) => e.clone(),
            _ => Expr::zero(),
        })
        .collect();
    let mass_set: std::collections::HashSet<usize> = mass_states.iter().copied().collect();
    let reads = |pred: &dyn Fn(Sym) -> bool| symbols::each_has_sym(&explicit_values, pred);
    let reads_output = reads(&|s| matches!(s, Sym::Output(_)));
    let reads_input_rate = reads(&|s| matches!(s, Sym::InputDot(_)));
    let reads_rate = reads(&|s| matches!(s, Sym::StateDot(_)));
    let reads_mass_rate = reads(&|s| matches!(s, Sym::StateDot(j) if mass_set.contains(&j)));
    for (k, (out, r)) in model.outputs.iter().zip(resolved).enumerate() {
        let (value, explicit) = match r {
            Ok(x) => x,
            Err(what) => {
                let d = Diagnostic::error(
                    codes::UNSUPPORTED,
                    format!("cannot derive output `{}`: {what}", out.name),
                );
                diags.push(with_span(d, model.spans.outputs.get(k), "this output"));
                eqs.outputs.push(OutputEq {
                    name: out.name.clone(),
                    value: Expr::zero(),
                    explicit: None,
                });
                continue;
            }
        };
        let underived = |e: &Expr| {
            reads_output[k]
                && e.any_sym(&|s| matches!(s, Sym::Output(j) if eqs.outputs.get(j).is_none_or(|o| o.explicit.is_none())))
        };
        let explicit = match explicit {
            // The output it is defined through has a diagnostic already.
            Ok(e) if underived(&e) => None,
            Ok(e) if reads_input_rate[k] => {
                let names: Vec<String> = (0..model.inputs.len())
                    .filter(|&j| e.contains(Sym::InputDot(j)))
                    .map(|j| model.inputs[j].name.clone())
                    .collect();
                let d = Diagnostic::error(
                    codes::INPUT_DERIVATIVE,
                    format!("output `{}` needs the time derivative of input `{}`", out.name, names.join("`, `")),
                )
                .with_note("a storage in derivative causality behind a source makes its effort or flow the derivative of the source's value")
                .with_help("measure a variable that does not depend on that storage, or give the input's derivative as an input");
                diags.push(with_span(d, model.spans.outputs.get(k), "this output"));
                None
            }
            Ok(_) if reads_rate[k] && !all_rates_ok => None,
            Ok(_) if reads_mass_rate[k] => {
                let d = Diagnostic::error(
                    codes::UNSUPPORTED,
                    format!("output `{}` needs the acceleration of an I-field's port, which the equations give only through its mass matrix", out.name),
                )
                .with_help("measure a velocity or a displacement of the field, or an effort at a junction");
                diags.push(with_span(d, model.spans.outputs.get(k), "this output"));
                None
            }
            // Only a rate is replaced: an output that reads none is its own explicit form, without a walk.
            Ok(e) if reads_rate[k] => Some(rate_of(&e)),
            Ok(e) => Some(e),
            Err(e) => {
                diags.push(resolve_diag(
                    model,
                    &built,
                    &e,
                    &format!("output `{}`", out.name),
                ));
                reported = true;
                None
            }
        };
        eqs.outputs.push(OutputEq {
            name: out.name.clone(),
            value,
            explicit,
        });
    }

    // Declared coordinates.
    if let Some(list) = &model.coords {
        eqs.coords = coords::derive_coords(
            model,
            &ctx,
            &mut resolver,
            list,
            &rate_of,
            &built.states,
            &mut diags,
        );
    }

    // Readable forms.
    let output_values: Vec<Expr> = eqs.outputs.iter().map(|o| o.value.clone()).collect();
    let mut taken = naming::user_names(model);
    for s in &built.states {
        taken.reserve(&s.name);
    }
    let mut shown_rates = resolver_rates(&built, &solved, &implicit);
    // The generalised forces of the mass-matrix rows are shown explicit (the junction's balance holds `ẋ`).
    for &i in kinematic_mass.iter().flat_map(|b| b.states.iter()) {
        if let (Some(slot), Some(v)) = (shown_rates.get_mut(i), solved.get(i)) {
            *slot = v.clone();
        }
    }
    // The readable form and the check for values that cannot be finite on a second thread, while this one derives
    // the energy terms: neither reads what the other makes, and the two halves take about the same time.
    let ((readable, finite_diags), terms) = crate::concurrent::join(
        || {
            let mut found = Vec::new();
            not_finite(model, &built.states, &eqs.f, &eqs.outputs, &mut found);
            let readable = print::readable(&built, &shown_rates, &output_values, taken.clone());
            (readable, found)
        },
        || {
            energy::terms(
                model,
                &ctx,
                &mut resolver,
                &rates_of,
                &built.mass,
                &mut diags,
            )
        },
    );
    let (energy, unresolved) = terms;
    eqs.energy = energy;
    // A variable that only an energy term reads is as undetermined as one a rate reads: the model is ill-posed.
    // One cause is reported, and none when a rate or an output has reported one already: the terms of the
    // elements around one singular loop or derivative chain fail through different variables of the same cause.
    if let Some(u) = unresolved.first().filter(|_| !reported) {
        let what = match u.kind {
            EnergyKind::Stored => format!("the stored energy of `{}`", u.element),
            kind => format!("the {} power of `{}`", kind.name(), u.element),
        };
        diags.push(resolve_diag(model, &built, &u.why, &what));
    }
    diags.extend(finite_diags);
    for o in &mut eqs.outputs {
        o.value = readable.alias(&o.value);
    }
    eqs.rates = readable.rates;
    eqs.intermediates = readable.intermediates;
    eqs.var_names = readable.names;
    eqs.loops = resolver
        .torn()
        .into_iter()
        .map(|v| eqs.sym_name(Sym::Var(v)))
        .collect();
    eqs.tear_blocks = tear::blocks(resolver.implicit_loops(), &|s| eqs.sym_name(s));
    eqs.states = built.states;
    eqs.mass = built.mass;
    eqs.mass.extend(kinematic_mass);
    (eqs, diags)
}

/// The rates to show: the readable rate when it needs no solve, the solved explicit rate for rates coupled through
/// derivative causality.
fn resolver_rates(built: &build::Built, solved: &[Expr], implicit: &[Expr]) -> Vec<Expr> {
    let coupled = solve::rates_appearing(implicit);
    if coupled.is_empty() {
        // No derivative causality: every rate is readable as built.
        return built.rates.clone();
    }
    // The coupled rates in intermediates: inline the intermediates that lead to a derivative-causality output,
    // drop those outputs (their ẋ terms are on the left-hand side), and solve the same block.
    let inlined = inline_leading(built);
    let f0: Vec<Expr> = built
        .rates
        .iter()
        .map(|r| {
            symbols::subst(r, &mut |s| match s {
                Sym::Var(v) => inlined.get(v).cloned().flatten(),
                _ => None,
            })
        })
        .collect();
    let readable = solve::solve_rates_with(implicit, Some(&f0)).unwrap_or_else(|_| solved.to_vec());
    built
        .rates
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if coupled.binary_search(&i).is_ok() {
                readable.get(i).cloned().unwrap_or_else(|| r.clone())
            } else {
                r.clone()
            }
        })
        .collect()
}

/// Per bond variable that leads to the output of a storage in derivative causality: its definition with every such
/// variable inlined (and those outputs, whose `ẋ` terms are on the left-hand side, as zero). One depth-first walk
/// on an explicit stack; a variable met again on its own path (an algebraic loop) is left as it is there.
fn inline_leading(built: &build::Built) -> Vec<Option<Expr>> {
    let n = built.defs.len();
    let deps = |v: usize| -> Vec<usize> {
        match built.defs.get(v).and_then(Option::as_ref) {
            Some(build::Def::Plain(e)) => e
                .syms()
                .into_iter()
                .filter_map(|s| match s {
                    Sym::Var(w) => Some(w),
                    _ => None,
                })
                .collect(),
            _ => Vec::new(),
        }
    };
    // `leads[v]`: `None` unvisited, `Some(false)` on the path or leading nowhere, `Some(true)` leading.
    let mut leads: Vec<Option<bool>> = vec![None; n];
    let mut inlined: Vec<Option<Expr>> = vec![None; n];
    for root in 0..n {
        if leads[root].is_some() {
            continue;
        }
        leads[root] = Some(false);
        let mut stack = vec![(root, deps(root), 0usize)];
        while let Some((v, ds, next)) = stack.last_mut() {
            if let Some(&w) = ds.get(*next) {
                *next += 1;
                if leads.get(w).is_some_and(Option::is_none) {
                    leads[w] = Some(false);
                    let dw = deps(w);
                    stack.push((w, dw, 0));
                }
                continue;
            }
            let v = *v;
            let ds = std::mem::take(ds);
            stack.pop();
            let (lead, value) = match built.defs.get(v).and_then(Option::as_ref) {
                Some(build::Def::Rate(_)) => (true, Expr::zero()),
                Some(build::Def::Plain(e)) => {
                    let lead = ds
                        .iter()
                        .any(|&w| leads.get(w).copied().flatten() == Some(true));
                    let value = symbols::subst(e, &mut |s| match s {
                        Sym::Var(w) => inlined.get(w).cloned().flatten(),
                        _ => None,
                    });
                    (lead, value)
                }
                None => (false, Expr::zero()),
            };
            leads[v] = Some(lead);
            if lead {
                inlined[v] = Some(value);
            }
        }
    }
    inlined
}

/// BG0608 for each rate and output that holds a constant that is not finite: a part that reads no parameter or
/// variable and has no value, such as a division by `big − big`, which simplifies to `1/0`. Lowering refuses such
/// parts as written (BG0403); these appear only once the equations are simplified.
fn not_finite(
    model: &Model,
    states: &[StateSpec],
    rates: &[Option<Expr>],
    outputs: &[OutputEq],
    diags: &mut Vec<Diagnostic>,
) {
    // The explicit forms: a readable one holds intermediates, whose definitions hold the constant.
    let values: Vec<Expr> = rates
        .iter()
        .map(|r| r.clone().unwrap_or_else(Expr::zero))
        .chain(
            outputs
                .iter()
                .map(|o| o.explicit.clone().unwrap_or_else(Expr::zero)),
        )
        .collect();
    let held = Expr::non_finite_constants(&values);
    let (rates_held, outputs_held) = held.split_at(rates.len().min(held.len()));
    let why = "it divides by a part that is zero whatever the parameters are, or takes a function outside its domain there";
    let help = "look for an element whose value is 0 where the causality divides by it (a resistance of 0 that \
                an effort drives: f = e/R; a compliance or inertia of 0), or a difference of equal terms in a \
                denominator or under a logarithm";
    for (s, _) in states.iter().zip(rates_held).filter(|(_, v)| v.is_some()) {
        let d = Diagnostic::error(
            codes::NOT_FINITE,
            format!("the rate of `{}` has no finite value: {why}", s.name),
        );
        diags.push(with_span(d, state_span(model, s), "this element").with_help(help));
    }
    for (k, (o, _)) in outputs
        .iter()
        .zip(outputs_held)
        .enumerate()
        .filter(|(_, (_, v))| v.is_some())
    {
        let d = Diagnostic::error(
            codes::NOT_FINITE,
            format!("output `{}` has no finite value: {why}", o.name),
        );
        diags.push(with_span(d, model.spans.outputs.get(k), "this output").with_help(help));
    }
}

fn state_span<'m>(model: &'m Model, s: &StateSpec) -> Option<&'m crate::span::Span> {
    match (s.node, s.var) {
        (Some(n), _) => model.spans.nodes.get(n.index()),
        (_, Some(v)) => model.spans.vars.get(v),
        _ => None,
    }
}

/// The diagnostic of a resolution failure while deriving `what`.
fn resolve_diag(model: &Model, built: &build::Built, e: &ResolveError, what: &str) -> Diagnostic {
    let var_name = |v: usize| {
        built
            .names
            .get(v)
            .cloned()
            .unwrap_or_else(|| format!("v{v}"))
    };
    let definer_span = |v: usize| {
        built
            .definer
            .get(v)
            .copied()
            .flatten()
            .and_then(|n| model.spans.nodes.get(n.index()))
    };
    match e {
        ResolveError::Undefined(v) => Diagnostic::error(
            codes::UNSUPPORTED,
            format!("cannot derive {what}: nothing computes `{}`", var_name(*v)),
        ),
        ResolveError::NonlinearLoop(v) => {
            let d = Diagnostic::error(codes::ALGEBRAIC_LOOP, format!("cannot derive {what}: a nonlinear algebraic loop through `{}` passes a storage in derivative causality", var_name(*v)))
                .with_note("a nonlinear loop is solved numerically for its torn variable, which needs the loop free of state and input derivatives")
                .with_help("break the loop with a small storage element, or give the storage in derivative causality its own state");
            with_span(d, definer_span(*v), "the loop passes here")
        }
        ResolveError::SingularLoop(v) => {
            let d = Diagnostic::error(codes::ALGEBRAIC_LOOP, format!("cannot derive {what}: a singular algebraic loop (its loop gain is one) through `{}`", var_name(*v)))
                .with_note("the loop's equations do not determine its variables: they are dependent or contradictory")
                .with_help("break the loop with a small storage element, or change a resistance so that the loop gain differs from one");
            with_span(d, definer_span(*v), "the loop passes here")
        }
        ResolveError::HigherOrder(v) => with_span(
            Diagnostic::error(
                codes::DERIVATIVE_CAUSALITY,
                format!(
                    "cannot derive {what}: `{}` is the derivative of a variable that itself holds a derivative or an algebraic loop",
                    var_name(*v)
                ),
            ),
            definer_span(*v),
            "this storage is in derivative causality",
        ),
        ResolveError::NotDifferentiable(v, f) => with_span(
            Diagnostic::error(
                codes::DERIVATIVE_CAUSALITY,
                format!(
                    "cannot derive {what}: `{}` is in derivative causality and its law uses `{}`, which has no derivative",
                    var_name(*v),
                    f.name()
                ),
            ),
            definer_span(*v),
            "this storage",
        ),
    }
}

/// The name of a declared coordinate: a `var`'s name, `f_x`, `p_x`, `q_x`, or `z<k>`.
pub(crate) fn coord_name(model: &Model, e: &IrExpr, k: usize) -> String {
    use crate::ir::Target;
    let node = |n: NodeIndex| model.graph.node_weight(n).map(|w| build::sanitize(&w.name));
    let name = match e {
        IrExpr::Var(v) => model.vars.get(*v).map(|v| build::sanitize(&v.name)),
        IrExpr::Flow(Target::Node(n)) => node(*n).map(|s| format!("f_{s}")),
        IrExpr::Effort(Target::Node(n)) => node(*n).map(|s| format!("e_{s}")),
        IrExpr::Momentum(n) => node(*n).map(|s| format!("p_{s}")),
        IrExpr::Displacement(n) => node(*n).map(|s| format!("q_{s}")),
        _ => None,
    };
    name.unwrap_or_else(|| format!("z{k}"))
}
