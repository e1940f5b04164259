//! What the generated functions compute, as symbolic-engine expressions: the explicit rates and outputs, the
//! readable blocks (intermediates, then rates or outputs) that the function bodies print, the Jacobians, the state
//! spaces, the energy terms, the I-fields' mass matrices ([`super::mass`]) and the nonlinear algebraic loops
//! ([`super::loops`]). With loops, the rates, outputs and energy terms hold the tear variables (intermediates
//! `loop_<variable>`, bound from the loops' solution in each function), `dfdx` and the other Jacobians are partial
//! derivatives at fixed tears, and the printer adds the loops' contribution.
//!
//! A block uses the readable form of the equations stage (one `let` per named bond variable, then the rates) when
//! every intermediate it needs is defined before use and is not a derivative; otherwise (an algebraic loop, a
//! storage in derivative causality behind an output) it falls back to the explicit `f(x, u, p, t)`, which the
//! stage always provides for a complete model, and also when it would need more than [`MAX_LETS`] intermediates. Both are the same function; the tests check the generated code
//! against the stage's own evaluation of `f`.

use super::adapter::{AdaptError, explicit_outputs, named_chain, named_matrix, to_symbolic};
use super::shared::{Lets, share};
use crate::equations::{
    EnergyKind, Equations, ModelRows, ParamChain, SparseMatrix, StateSelection,
    declared_state_space_symbolic, sparse_linear_state_space, state_selection,
};
use crate::symbolic::{Expr, Symbol, SymbolKind};
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// Let-bindings then results.
#[derive(Clone, Debug)]
pub(crate) struct Block {
    pub lets: Vec<(Symbol, Expr)>,
    pub results: Vec<Expr>,
}

/// A state space with symbolic entries (free of states, inputs and time), sparse.
#[derive(Clone, Debug)]
pub(crate) struct StateSpace {
    pub states: Vec<String>,
    pub a: SparseMatrix,
    pub b: SparseMatrix,
    pub c: SparseMatrix,
    pub d: SparseMatrix,
}

/// The `(element, value)` terms of one kind of energy, or the elements without a closed form.
pub(crate) type EnergyTerms = Result<Vec<(String, Expr)>, Vec<String>>;

/// Everything the generator prints for one model.
#[derive(Clone, Debug)]
pub(crate) struct Plan {
    pub states: Vec<Symbol>,
    pub inputs: Vec<Symbol>,
    pub rhs: Block,
    pub outputs: Block,
    /// The Jacobians, sparse: each row differentiated only by the variables it reads.
    pub dfdx: SparseMatrix,
    pub dfdu: SparseMatrix,
    pub dhdx: SparseMatrix,
    pub dhdu: SparseMatrix,
    /// `∂f/∂p` and `∂h/∂p` with respect to the free parameters (`PARAM_NAMES` order), total through the derived
    /// parameters ([`ParamChain`]); partial at fixed tears, and the mass-matrix rows hold `∂F/∂p`, as in `dfdx`.
    pub dfdp: Vec<Vec<Expr>>,
    pub dhdp: Vec<Vec<Expr>>,
    /// For each Jacobian function (`jac_x_into`, ..., `output_jac_p_into`), energy function (`stored_energy`,
    /// `dissipated_power`, `supplied_power`) and `state_space`, the shared subexpressions its entries are written
    /// over ([`super::shared`]): empty unless an entry would print as a huge tree.
    pub shared: BTreeMap<&'static str, Lets>,
    /// `A, B, C, D` in the energy states, or (when the rates or outputs read an integrated flow) in all states,
    /// or why there is none.
    pub linear_ss: Result<StateSpace, String>,
    /// The states of `linear_ss`.
    pub linear_selection: StateSelection,
    /// No symbolic `linear_ss`, but a linear model whose algebraic loops are solved numerically
    /// ([`crate::equations::linear_through_loops`]): its Jacobians are its `A, B, C, D`.
    pub linear_through_loops: bool,
    /// `A, B, C, D` in the declared coordinates (`None`: the model declares none), or why there is none.
    pub declared_ss: Option<Result<StateSpace, String>>,
    /// Stored energy, dissipated and supplied power: the terms `(element, value)`, or the elements without a closed
    /// form.
    pub energy: Vec<(EnergyKind, EnergyTerms)>,
    /// The nonlinear algebraic loops (`None` without any): rates, outputs and energy terms hold their tears.
    pub loops: Option<super::loops::LoopPlan>,
    /// The I-fields' mass-matrix blocks (their rows of `rhs`, `dfdx` and `dfdu` hold the forces `F`).
    pub mass: Vec<super::mass::MassPlan>,
}

impl Plan {
    /// The bytes (and what its rows are) of the largest matrix that the generated Jacobian functions of the states
    /// and inputs keep on the stack besides the one they fill, when it exceeds the generated code's bound for dense
    /// matrices ([`super::rust::MAX_CONSTANT_JACOBIAN_BYTES`]): each loop block's `∂r/∂z`, and its `∂r/∂v` and
    /// `∂g/∂z` at the columns and rows where its correction can be ([`super::loops::block_supports`]), and each
    /// mass block's rows by the states ([`super::mass`]). Warned about by `compile` (BG0703) and refused by an FMU,
    /// whose solver keeps `JacX` itself off the stack.
    pub(crate) fn oversized_stack_matrix(&self) -> Option<(usize, &'static str)> {
        let f64s = std::mem::size_of::<f64>();
        let block = self.mass.iter().map(|b| b.rows.len()).max().unwrap_or(0) * self.states.len();
        let loops = self.loops.as_ref().map_or(0, |l| {
            let pairs = [
                (&l.dfdz, &l.drdx),
                (&l.dfdz, &l.drdu),
                (&l.dhdz, &l.drdx),
                (&l.dhdz, &l.drdu),
            ];
            let square = l
                .blocks
                .iter()
                .map(|b| b.residuals.len().pow(2))
                .max()
                .unwrap_or(0);
            pairs
                .iter()
                .flat_map(|(g_z, r_v)| {
                    let supports = super::loops::block_supports(l, g_z, r_v);
                    l.blocks
                        .iter()
                        .zip(supports)
                        .map(|(b, s)| b.residuals.len() * s.rows.len().max(s.cols.len()))
                })
                .fold(square, usize::max)
        });
        let (bytes, rows) = if loops >= block {
            (loops * f64s, "the algebraic loops' tear variables")
        } else {
            (block * f64s, "a mass block's rows")
        };
        (bytes > super::rust::MAX_CONSTANT_JACOBIAN_BYTES).then_some((bytes, rows))
    }
}

fn convert_all(eqs: &Equations, es: &[Expr]) -> Result<Vec<Expr>, AdaptError> {
    crate::concurrent::map_halves(es, |e| to_symbolic(eqs, e))
        .into_iter()
        .collect()
}

fn convert_matrix(eqs: &Equations, m: &[Vec<Expr>]) -> Result<Vec<Vec<Expr>>, AdaptError> {
    m.iter().map(|row| convert_all(eqs, row)).collect()
}

/// The plan of a complete model.
pub(crate) fn plan(eqs: &Equations) -> Result<Plan, String> {
    let mut f_ex = Vec::with_capacity(eqs.f.len());
    for (i, f) in eqs.f.iter().enumerate() {
        let name = eqs.states.get(i).map(|s| s.name.as_str()).unwrap_or("?");
        f_ex.push(
            f.clone()
                .ok_or_else(|| format!("the rate of `{name}` was not derived"))?,
        );
    }
    let mut h = Vec::with_capacity(eqs.outputs.len());
    let explicit = explicit_outputs(eqs).map_err(|e| e.to_string())?;
    for (o, e) in eqs.outputs.iter().zip(explicit) {
        h.push(e.ok_or_else(|| format!("output `{}` was not derived", o.name))?);
    }
    let f = convert_all(eqs, &f_ex).map_err(|e| e.to_string())?;
    let states: Vec<Symbol> = eqs
        .states
        .iter()
        .map(|s| Symbol::state(s.name.as_str()))
        .collect();
    let inputs: Vec<Symbol> = eqs
        .inputs
        .iter()
        .map(|i| Symbol::input(i.as_str()))
        .collect();
    let free: Vec<usize> = (0..eqs.params.len())
        .filter(|&k| eqs.derived.get(k).is_none_or(Option::is_none))
        .collect();
    let chain = ParamChain::new(eqs, &free, &[]).map_err(|e| e.to_string())?;
    let chain = named_chain(eqs, chain).map_err(|e| e.to_string())?;
    let mut mass = super::mass::plan(eqs, &states, &chain)?;
    let loops = super::loops::plan(eqs, &f, &h, (&states, &inputs), &chain)?;
    if let Some(l) = &loops {
        let in_mass = mass
            .iter()
            .flat_map(|b| b.matrix.iter().flatten())
            .any(|e| e.free_symbols().iter().any(|s| l.tears.contains(s)));
        if in_mass {
            return Err(
                "an inertia matrix depends on the tear of a nonlinear algebraic loop".into(),
            );
        }
    }
    // The linear state space, the parameter Jacobians and the rest at once: three passes of about the same
    // length on a large model, which two cores finish in about half their sum.
    let (((linear_selection, linear_ss), params), mut p) = crate::concurrent::join(
        || {
            crate::concurrent::join(
                || linear_state_space(eqs),
                || ParamJacobians::new(&chain, &f, &h),
            )
        },
        || PointPlan::new(eqs, (&f, &h), (&states, &inputs), &mut mass),
    );
    // The mass blocks' `dM/dp` (printed in `jac_p_into` beside `∂F/∂p`) under names of their own.
    let mut dfdp_shared = params.dfdp_shared;
    dfdp_shared.extend(share(
        "dmdp_",
        mass_slopes(&mut mass, |b| &mut b.param_derivatives),
    ));
    p.shared.insert("jac_p_into", dfdp_shared);
    p.shared.insert("output_jac_p_into", params.dhdp_shared);
    // Entries of `A, B, C, D` that would print as huge trees (nested loops solved in closed form) are written over
    // `let`s of their shared subexpressions too.
    let mut linear_ss = linear_ss;
    if let Ok(ss) = &mut linear_ss {
        let entries = [&mut ss.a, &mut ss.b, &mut ss.c, &mut ss.d]
            .into_iter()
            .flat_map(sparse_entries);
        p.shared.insert("state_space", share("ss_", entries));
    }
    Ok(Plan {
        loops,
        mass,
        dfdx: p.dfdx,
        dfdu: p.dfdu,
        dhdx: p.dhdx,
        dhdu: p.dhdu,
        dfdp: params.dfdp,
        dhdp: params.dhdp,
        shared: p.shared,
        states,
        inputs,
        rhs: p.rhs,
        outputs: p.outputs,
        linear_through_loops: linear_ss.is_err()
            && crate::equations::linear_through_loops(eqs, linear_selection),
        linear_ss,
        linear_selection,
        declared_ss: p.declared_ss,
        energy: p.energy,
    })
}

/// The linear state space `A, B, C, D` and the states it is in.
fn linear_state_space(eqs: &Equations) -> (StateSelection, Result<StateSpace, String>) {
    let rows = ModelRows::new(eqs);
    let selection = state_selection(eqs, &rows);
    let linear_ss = sparse_linear_state_space(eqs, &rows, selection)
        .map_err(|e| e.to_string())
        .and_then(|j| {
            let named = |m| named_matrix(eqs, m).map_err(|e| e.to_string());
            Ok(StateSpace {
                states: j.states,
                a: named(j.dfdx)?,
                b: named(j.dfdu)?,
                c: named(j.dhdx)?,
                d: named(j.dhdu)?,
            })
        });
    (selection, linear_ss)
}

/// `∂f/∂p` and `∂h/∂p`, with their shared subexpressions.
struct ParamJacobians {
    dfdp: Vec<Vec<Expr>>,
    dhdp: Vec<Vec<Expr>>,
    dfdp_shared: Lets,
    dhdp_shared: Lets,
}

impl ParamJacobians {
    fn new(chain: &ParamChain, f: &[Expr], h: &[Expr]) -> ParamJacobians {
        let mut dfdp = chain.jacobian(f);
        let mut dhdp = chain.jacobian(h);
        let dfdp_shared = share("dfdp_", dfdp.iter_mut().flatten());
        let dhdp_shared = share("dhdp_", dhdp.iter_mut().flatten());
        ParamJacobians {
            dfdp,
            dhdp,
            dfdp_shared,
            dhdp_shared,
        }
    }
}

/// What the plan holds about the model at a point: the blocks, the declared state space, the energy terms, and the
/// Jacobians in the states and inputs with their shared subexpressions.
struct PointPlan {
    rhs: Block,
    outputs: Block,
    declared_ss: Option<Result<StateSpace, String>>,
    energy: Vec<(EnergyKind, EnergyTerms)>,
    dfdx: SparseMatrix,
    dfdu: SparseMatrix,
    dhdx: SparseMatrix,
    dhdu: SparseMatrix,
    shared: BTreeMap<&'static str, Lets>,
}

impl PointPlan {
    /// The plan at a point; the mass blocks' `∂M/∂x`, which `jac_x_into` prints beside `∂f/∂x`, share its names.
    fn new(
        eqs: &Equations,
        (f, h): (&[Expr], &[Expr]),
        (states, inputs): (&[Symbol], &[Symbol]),
        mass: &mut [super::mass::MassPlan],
    ) -> PointPlan {
        let rhs = block(eqs, &eqs.rates, f);
        let readable_outputs: Vec<Expr> = eqs.outputs.iter().map(|o| o.value.clone()).collect();
        let outputs = block(eqs, &readable_outputs, h);
        let declared_ss = eqs.coords.as_ref().map(|_| {
            declared_state_space_symbolic(eqs)
                .map_err(|e| e.to_string())
                .and_then(|j| state_space(eqs, j.states, &j.dfdx, &j.dfdu, &j.dhdx, &j.dhdu))
        });
        let mut energy = energy_terms(eqs);
        let mut dfdx = SparseMatrix::jacobian(f, states);
        let mut dfdu = SparseMatrix::jacobian(f, inputs);
        let mut dhdx = SparseMatrix::jacobian(h, states);
        let mut dhdu = SparseMatrix::jacobian(h, inputs);
        let mut shared = BTreeMap::from([
            (
                "jac_x_into",
                share(
                    "dfdx_",
                    sparse_entries(&mut dfdx)
                        .into_iter()
                        .chain(mass_slopes(mass, |b| &mut b.derivatives)),
                ),
            ),
            (
                "jac_u_into",
                share("dfdu_", sparse_entries(&mut dfdu).into_iter()),
            ),
            (
                "output_jac_x_into",
                share("dhdx_", sparse_entries(&mut dhdx).into_iter()),
            ),
            (
                "output_jac_u_into",
                share("dhdu_", sparse_entries(&mut dhdu).into_iter()),
            ),
        ]);
        // Energy terms that would print as huge trees (the powers of the resistors of nested loops solved in
        // closed form) are written over `let`s of their shared subexpressions, as the Jacobians' entries are.
        for (kind, terms) in &mut energy {
            if let Ok(terms) = terms {
                let (function, prefix) = match kind {
                    EnergyKind::Stored => ("stored_energy", "stored_"),
                    EnergyKind::Dissipated => ("dissipated_power", "dissipated_"),
                    EnergyKind::Supplied => ("supplied_power", "supplied_"),
                };
                shared.insert(function, share(prefix, terms.iter_mut().map(|(_, e)| e)));
            }
        }
        PointPlan {
            rhs,
            outputs,
            declared_ss,
            energy,
            dfdx,
            dfdu,
            dhdx,
            dhdu,
            shared,
        }
    }
}

/// Stored energy, dissipated and supplied power: each kind's terms, or the elements without a closed form.
fn energy_terms(eqs: &Equations) -> Vec<(EnergyKind, EnergyTerms)> {
    let mut energy = Vec::new();
    for kind in [
        EnergyKind::Stored,
        EnergyKind::Dissipated,
        EnergyKind::Supplied,
    ] {
        let mut terms = Vec::new();
        let mut missing = Vec::new();
        for t in eqs.energy.iter().filter(|t| t.kind == kind) {
            // A term with an input's derivative (`Sym::InputDot`, the power of a source driving a storage in
            // derivative causality) has no value in the generated functions, which take `u` but not `du/dt`: it
            // does not convert and counts as missing, so no partial sum is generated.
            match t.value.as_ref().map(|v| to_symbolic(eqs, v)) {
                Some(Ok(v)) => terms.push((t.element.clone(), v)),
                _ => missing.push(t.element.clone()),
            }
        }
        energy.push((
            kind,
            if missing.is_empty() {
                Ok(terms)
            } else {
                Err(missing)
            },
        ));
    }
    energy
}

fn state_space(
    eqs: &Equations,
    states: Vec<String>,
    a: &[Vec<Expr>],
    b: &[Vec<Expr>],
    c: &[Vec<Expr>],
    d: &[Vec<Expr>],
) -> Result<StateSpace, String> {
    let m = |x: &[Vec<Expr>], cols: usize| {
        convert_matrix(eqs, x)
            .map(|dense| SparseMatrix::from_dense(&dense, cols))
            .map_err(|e| e.to_string())
    };
    let (n, inputs) = (states.len(), eqs.inputs.len());
    Ok(StateSpace {
        a: m(a, n)?,
        b: m(b, inputs)?,
        c: m(c, n)?,
        d: m(d, inputs)?,
        states,
    })
}

/// The entries of the mass blocks' derivatives that `of` picks (`∂M/∂x` or `dM/dp`), to rewrite in place. Along a
/// chain of modulated transformers they are nested sums whose levels share the powers of the moduli: printed as
/// trees, `∂M/∂θ` took 363,772 nodes at 200 links.
fn mass_slopes(
    mass: &mut [super::mass::MassPlan],
    of: fn(&mut super::mass::MassPlan) -> &mut super::mass::Derivatives,
) -> impl Iterator<Item = &mut Expr> {
    mass.iter_mut()
        .flat_map(move |b| of(b).iter_mut())
        .flat_map(|(_, d)| d.iter_mut().flatten())
}

/// The entries of a sparse matrix, to rewrite in place.
fn sparse_entries(m: &mut SparseMatrix) -> Vec<&mut Expr> {
    m.entries
        .iter_mut()
        .flat_map(|row| row.iter_mut().map(|(_, e)| e))
        .collect()
}

/// The most `let`s a generated function gets. rustc's stack grows with the number of nested `let` scopes of one
/// function, and a few thousand overflow its default stack (a 1000-state chain has 3000 intermediates), so larger
/// models compute the explicit `f(x, u, p, t)` directly.
pub(crate) const MAX_LETS: usize = 256;

/// The readable block for `roots` (in intermediates), or the explicit expressions when the readable form cannot be
/// computed in order or needs more than [`MAX_LETS`] intermediates.
fn block(eqs: &Equations, roots: &[Expr], explicit: &[Expr]) -> Block {
    readable_block(eqs, roots).unwrap_or_else(|| Block {
        lets: Vec::new(),
        results: explicit.to_vec(),
    })
}

fn intermediates_of(e: &Expr) -> impl Iterator<Item = Symbol> {
    e.free_symbols()
        .into_iter()
        .filter(|s| s.kind() == SymbolKind::Intermediate)
}

fn readable_block(eqs: &Equations, roots: &[Expr]) -> Option<Block> {
    let results = convert_all(eqs, roots).ok()?;
    let position: HashMap<&str, usize> = eqs
        .intermediates
        .iter()
        .enumerate()
        .map(|(k, i)| (i.name.as_str(), k))
        .collect();
    // The intermediates needed, transitively.
    let mut needed: BTreeSet<usize> = BTreeSet::new();
    let mut converted: HashMap<usize, Expr> = HashMap::new();
    let mut stack: Vec<Symbol> = results.iter().flat_map(intermediates_of).collect();
    while let Some(s) = stack.pop() {
        let k = *position.get(s.name())?;
        if !needed.insert(k) {
            continue;
        }
        if needed.len() > MAX_LETS {
            return None;
        }
        let def = eqs.intermediates.get(k)?;
        if def.derivative {
            return None;
        }
        let value = to_symbolic(eqs, &def.value).ok()?;
        stack.extend(intermediates_of(&value));
        converted.insert(k, value);
    }
    // In list order, each defined before use.
    let mut lets = Vec::with_capacity(needed.len());
    for &k in &needed {
        let value = converted.remove(&k)?;
        if intermediates_of(&value).any(|s| position.get(s.name()).is_none_or(|&j| j >= k)) {
            return None;
        }
        let name = eqs.intermediates.get(k)?.name.as_str();
        lets.push((Symbol::intermediate(name), value));
    }
    Some(Block { lets, results })
}
