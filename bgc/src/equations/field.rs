//! Multiport fields: `IF` (an inertia matrix `M(q)`), `CF` (coupled compliances) and `RF` (coupled resistors).
//!
//! Port variables follow the 1-port convention: port `k`'s own effort is its bond's effort, its own flow is the
//! bond's flow taken into the field (`s_k = +1` when the bond points at the field, `-1` otherwise).
//!
//! # I-field: the mass-matrix form
//! An `IF` in integral causality (every port receives its effort) gets two states per port, its displacement
//! `q_k = ∫ f_k` and its flow `f_k` (the generalised velocity), and Lagrange's equations of its co-energy
//! `T = ½ fᵀ M(q) f`:
//!
//! ```text
//! q̇_k = f_k
//! Σ_j M_kj(q) ḟ_j = F_k = e_k + ½ Σ_ij ∂M_ij/∂q_k f_i f_j − Σ_jl ∂M_kj/∂q_l f_l f_j
//! ```
//!
//! The rates of the flow states hold the generalised forces `F_k`; the [`MassBlock`] says which rows they are
//! and holds `M(q)`, so that a consumer solves `M ẋ_block = F` numerically (the generated code and `bgc simulate`
//! do). Velocities rather than momenta are the states because control engineers write the leg's state as
//! `[q, q̇]`, and because `M⁻¹p` would hide a configuration-dependent solve inside every other equation.
//!
//! # C-field and R-field
//! A `CF` in integral causality has one displacement state per port and sets its efforts by its laws
//! `e[k] = g_k(q)`. An `RF` sets all its efforts from `e[k] = g_k(f)` (every port in resistance causality) or all
//! its flows from `f[k] = g_k(e)`. Mixed causalities would need the laws inverted and are refused (BG0605).

use super::build::{ConvertError, Ctx, Def, effort_var, flow_var, sanitize};
use super::symbols::{self, Sym, SymExt, add, mul};
use super::{StateKind, StateSpec, codes};
use crate::causality::{Causality, StorageForm};
use crate::diagnostic::Diagnostic;
use crate::ir::{Model, PortVar, Relation};
use crate::symbolic::Expr;
use crate::syntax::ast::ElementKind;
use petgraph::Direction;
use petgraph::graph::{EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;

/// The inertia matrix of one I-field: rows `states` of the rates are the generalised forces `F`, and
/// `Σ_j matrix[i][j] · ẋ[states[j]] = F_i`.
#[derive(Clone, Debug, PartialEq)]
pub struct MassBlock {
    /// The I-field's name.
    pub element: String,
    /// The flow states of its ports, in port order.
    pub states: Vec<usize>,
    /// `M(q)`, symmetric, in the field's displacement states and the parameters.
    pub matrix: Vec<Vec<Expr>>,
}

/// The bonds on a field's ports, in port order, with the sign of the port's own flow.
pub(crate) fn ports(model: &Model, node: NodeIndex) -> Option<Vec<(EdgeIndex, f64)>> {
    let n = model.graph.node_weight(node)?.ports as usize;
    let mut out = vec![None; n];
    for e in model.graph.edges_directed(node, Direction::Incoming) {
        *out.get_mut(e.weight().to_port as usize)? = Some((e.id(), 1.0));
    }
    for e in model.graph.edges_directed(node, Direction::Outgoing) {
        *out.get_mut(e.weight().from_port as usize)? = Some((e.id(), -1.0));
    }
    out.into_iter().collect()
}

/// The states of the fields whose storage ports are all in integral causality: for an `IF` the displacements
/// then the flows of its ports, for a `CF` the displacements. Records them in `ctx`.
pub(crate) fn add_states(ctx: &mut Ctx, causality: &Causality, states: &mut Vec<StateSpec>) {
    let model = ctx.model;
    for node in model.graph.node_indices() {
        let w = &model.graph[node];
        if !matches!(w.kind, ElementKind::IF | ElementKind::CF) {
            continue;
        }
        let Some(bonds) = ports(model, node) else {
            continue;
        };
        let integral = causality
            .storage
            .iter()
            .filter(|s| s.node == node)
            .all(|s| s.causality == StorageForm::Integral);
        if !integral {
            continue;
        }
        let name = sanitize(&w.name);
        let push = |prefix: &str, kind: StateKind, port: usize, states: &mut Vec<StateSpec>| {
            states.push(StateSpec {
                name: format!("{prefix}_{name}_{}", port + 1),
                kind,
                node: Some(node),
                var: None,
                port: Some(port as u32),
            });
            states.len() - 1
        };
        let q: Vec<usize> = (0..bonds.len())
            .map(|k| push("q", StateKind::Displacement, k, states))
            .collect();
        if w.kind == ElementKind::IF {
            let f: Vec<usize> = (0..bonds.len())
                .map(|k| push("f", StateKind::Velocity, k, states))
                .collect();
            ctx.field_f.insert(node, f);
        }
        ctx.field_q.insert(node, q);
        ctx.field_ports.insert(node, bonds);
    }
}

fn field_error(model: &Model, node: NodeIndex, msg: String) -> Diagnostic {
    let d = Diagnostic::error(codes::UNSUPPORTED, msg);
    match model.spans.nodes.get(node.index()) {
        Some(span) => d.with_primary(*span, "this field"),
        None => d,
    }
}

/// The definitions a field writes on its bonds.
pub(crate) fn defs(
    model: &Model,
    causality: &Causality,
    ctx: &Ctx,
    node: NodeIndex,
) -> Result<Vec<(usize, Def)>, Diagnostic> {
    let w = &model.graph[node];
    let fail = |what: &str| {
        field_error(
            model,
            node,
            format!("cannot write the equations of `{}`: {what}", w.name),
        )
    };
    let conv = |e: &crate::ir::Expr| {
        ctx.convert(e)
            .map_err(|ConvertError::Unsupported(what)| fail(&what))
    };
    let bonds = ports(model, node).ok_or_else(|| fail("a port without a bond"))?;
    let sets_effort: Vec<bool> = bonds
        .iter()
        .map(|&(b, _)| causality.sets_effort(model, node, b))
        .collect();
    let mut out = Vec::new();
    match w.kind {
        ElementKind::IF => {
            let f = ctx
                .field_f
                .get(&node)
                .filter(|_| sets_effort.iter().all(|s| !s))
                .ok_or_else(|| fail("an I-field needs every port in integral causality (its efforts given by the junctions around it); a port in derivative causality is not supported"))?;
            for (&(b, s), &state) in bonds.iter().zip(f) {
                out.push((
                    flow_var(b),
                    Def::Plain(mul(vec![symbols::num(s), symbols::leaf(Sym::State(state))])),
                ));
            }
        }
        ElementKind::CF => {
            if !ctx.field_q.contains_key(&node) || !sets_effort.iter().all(|s| *s) {
                return Err(fail(
                    "a C-field needs every port in integral causality (it sets every effort); a port in derivative causality is not supported",
                ));
            }
            let Relation::Laws(laws) = &w.relation else {
                return Err(fail("a C-field without laws"));
            };
            for (k, &(b, _)) in bonds.iter().enumerate() {
                let law = laws
                    .iter()
                    .find(|l| l.lhs == PortVar::Effort && l.port as usize == k)
                    .ok_or_else(|| {
                        fail(&format!("no law `e[{}] = ...` for port {}", k + 1, k + 1))
                    })?;
                out.push((effort_var(b), Def::Plain(conv(&law.rhs)?)));
            }
        }
        ElementKind::RF => {
            let Relation::Laws(laws) = &w.relation else {
                return Err(fail("an R-field without laws"));
            };
            let all_effort = sets_effort.iter().all(|s| *s);
            let all_flow = sets_effort.iter().all(|s| !s);
            if !all_effort && !all_flow {
                return Err(fail(
                    "an R-field must set either all its efforts or all its flows; mixed causality needs its laws inverted",
                ));
            }
            let lhs = if all_effort {
                PortVar::Effort
            } else {
                PortVar::Flow
            };
            for (k, &(b, s)) in bonds.iter().enumerate() {
                let law = laws
                    .iter()
                    .find(|l| l.lhs == lhs && l.port as usize == k)
                    .ok_or_else(|| {
                        let v = if all_effort { "e" } else { "f" };
                        fail(&format!(
                            "its causality sets {v}[{}], and it has no law `{v}[{}] = ...`",
                            k + 1,
                            k + 1
                        ))
                    })?;
                let value = conv(&law.rhs)?;
                if all_effort {
                    out.push((effort_var(b), Def::Plain(value)));
                } else {
                    out.push((flow_var(b), Def::Plain(mul(vec![symbols::num(s), value]))));
                }
            }
        }
        _ => return Err(fail("not a multiport field")),
    }
    Ok(out)
}

/// The rates of a field's states and, for an `IF`, its mass block. `rates[i]` is set for each of its states.
pub(crate) fn rates(
    model: &Model,
    ctx: &Ctx,
    node: NodeIndex,
    rates: &mut [Expr],
    diags: &mut Vec<Diagnostic>,
) -> Option<MassBlock> {
    let w = &model.graph[node];
    let (bonds, q) = (ctx.field_ports.get(&node)?, ctx.field_q.get(&node)?);
    let Some(f) = ctx.field_f.get(&node) else {
        // C-field: q̇_k = s_k f_b.
        for (&(b, s), &state) in bonds.iter().zip(q) {
            if let Some(r) = rates.get_mut(state) {
                *r = mul(vec![symbols::num(s), symbols::leaf(Sym::Var(flow_var(b)))]);
            }
        }
        return None;
    };
    for (&qs, &fs) in q.iter().zip(f) {
        if let Some(r) = rates.get_mut(qs) {
            *r = symbols::leaf(Sym::State(fs));
        }
    }
    let mut fail = |msg: String| {
        diags.push(field_error(
            model,
            node,
            format!("cannot write the equations of `{}`: {msg}", w.name),
        ))
    };
    let Relation::MassMatrix { n, entries } = &w.relation else {
        fail("an I-field without an inertia matrix".into());
        return None;
    };
    let n = *n as usize;
    if n != bonds.len() || n != f.len() {
        fail(format!(
            "its inertia matrix is {n}×{n} and it has {} ports",
            bonds.len()
        ));
        return None;
    }
    let mut m = vec![vec![Expr::zero(); n]; n];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, slot) in row.iter_mut().enumerate() {
            let Some(e) = entries.get(i * n + j) else {
                fail("its inertia matrix is incomplete".into());
                return None;
            };
            match ctx.convert(e) {
                Ok(v) => *slot = v,
                Err(ConvertError::Unsupported(what)) => {
                    fail(what);
                    return None;
                }
            }
        }
    }
    // M may depend on the field's own displacements and the parameters only: anything else (an input, time, another
    // element's state) would add ∂M/∂t terms that Lagrange's equations of a scleronomic field do not have.
    let mut stray = None;
    for e in m.iter().flatten() {
        e.for_each_sym(&mut |s| match s {
            Sym::Param(_) => {}
            Sym::State(i) if q.contains(&i) => {}
            other => stray = stray.or(Some(other)),
        });
    }
    if stray.is_some() {
        fail("its inertia matrix may depend only on the parameters and its own port displacements q[i]".into());
        return None;
    }
    let fv: Vec<Expr> = f.iter().map(|&s| symbols::leaf(Sym::State(s))).collect();
    // dm[l][i][j] = ∂M_ij/∂q_l.
    let mut dm = Vec::with_capacity(n);
    for &ql in q {
        let mut d = vec![vec![Expr::zero(); n]; n];
        for (i, row) in d.iter_mut().enumerate() {
            for (j, slot) in row.iter_mut().enumerate() {
                match symbols::diff(&m[i][j], Sym::State(ql)) {
                    Ok(v) => *slot = v,
                    Err(symbols::NotDifferentiable(func)) => {
                        fail(format!(
                            "its inertia matrix uses `{}`, which has no derivative",
                            func.name()
                        ));
                        return None;
                    }
                }
            }
        }
        dm.push(d);
    }
    for (k, (&(b, _), &state)) in bonds.iter().zip(f).enumerate() {
        let mut terms = vec![symbols::leaf(Sym::Var(effort_var(b)))];
        for i in 0..n {
            for j in 0..n {
                // ½ ∂M_ij/∂q_k f_i f_j − ∂M_kj/∂q_i f_i f_j
                let coef = symbols::sub(
                    mul(vec![symbols::num(0.5), dm[k][i][j].clone()]),
                    dm[i][k][j].clone(),
                );
                if !coef.is_zero() {
                    terms.push(mul(vec![coef, fv[i].clone(), fv[j].clone()]));
                }
            }
        }
        if let Some(r) = rates.get_mut(state) {
            *r = symbols::expand(&add(terms));
        }
    }
    Some(MassBlock {
        element: w.name.clone(),
        states: f.clone(),
        matrix: m,
    })
}

/// The kinetic co-energy `½ fᵀ M f` of an I-field, the stored energy of a C-field whose laws are affine in its
/// displacements with constant coefficients (`½ qᵀ K q + e₀ᵀ q`, `K` symmetric), the dissipated power `Σ e_k f_k`
/// of an R-field. `None` with a warning when the C-field's energy has no closed form here.
pub(crate) fn energy(
    model: &Model,
    ctx: &Ctx,
    node: NodeIndex,
    mass: &[MassBlock],
    diags: &mut Vec<Diagnostic>,
) -> Option<(super::EnergyKind, Option<Expr>)> {
    let w = &model.graph[node];
    let bonds = ports(model, node)?;
    match w.kind {
        ElementKind::IF => {
            let block = mass.iter().find(|b| b.element == w.name)?;
            let mut terms = Vec::new();
            for (i, &si) in block.states.iter().enumerate() {
                for (j, &sj) in block.states.iter().enumerate() {
                    terms.push(mul(vec![
                        symbols::num(0.5),
                        block.matrix[i][j].clone(),
                        symbols::leaf(Sym::State(si)),
                        symbols::leaf(Sym::State(sj)),
                    ]));
                }
            }
            Some((super::EnergyKind::Stored, Some(add(terms))))
        }
        ElementKind::CF => {
            let q = ctx.field_q.get(&node)?;
            let Relation::Laws(laws) = &w.relation else {
                return None;
            };
            // g_k = Σ_j K_kj q_j + e0_k with K, e0 free of q.
            let n = q.len();
            let mut k_mat = vec![vec![Expr::zero(); n]; n];
            let mut e0 = vec![Expr::zero(); n];
            let mut ok = true;
            for (k, row) in k_mat.iter_mut().enumerate() {
                let g = laws
                    .iter()
                    .find(|l| l.lhs == PortVar::Effort && l.port as usize == k)
                    .and_then(|l| ctx.convert(&l.rhs).ok());
                let Some(mut rest) = g else {
                    ok = false;
                    break;
                };
                for (slot, &qj) in row.iter_mut().zip(q) {
                    match symbols::affine_in(&rest, Sym::State(qj)) {
                        Some((a, b)) if !q.iter().any(|&x| a.contains(Sym::State(x))) => {
                            *slot = a;
                            rest = b;
                        }
                        _ => ok = false,
                    }
                }
                e0[k] = rest;
            }
            // A conservative field has a symmetric stiffness (Maxwell's reciprocity); otherwise its energy depends
            // on the path and has no closed form.
            ok = ok && (0..n).all(|i| (0..n).all(|j| k_mat[i][j] == k_mat[j][i]));
            let mut terms = Vec::new();
            for (i, row) in k_mat.iter().enumerate() {
                let qi = symbols::leaf(Sym::State(q[i]));
                for (j, kij) in row.iter().enumerate() {
                    terms.push(mul(vec![
                        symbols::num(0.5),
                        kij.clone(),
                        qi.clone(),
                        symbols::leaf(Sym::State(q[j])),
                    ]));
                }
                terms.push(mul(vec![e0[i].clone(), qi]));
            }
            if !ok {
                let d = Diagnostic::warning(
                    codes::ENERGY,
                    format!(
                        "the stored energy of `{}` is not computed: its laws are not affine in its displacements with a constant, symmetric stiffness",
                        w.name
                    ),
                );
                diags.push(match model.spans.nodes.get(node.index()) {
                    Some(span) => d.with_primary(*span, "this field"),
                    None => d,
                });
                return Some((super::EnergyKind::Stored, None));
            }
            Some((super::EnergyKind::Stored, Some(add(terms))))
        }
        ElementKind::RF => {
            let terms = bonds
                .iter()
                .map(|&(b, s)| {
                    mul(vec![
                        symbols::num(s),
                        symbols::leaf(Sym::Var(effort_var(b))),
                        symbols::leaf(Sym::Var(flow_var(b))),
                    ])
                })
                .collect();
            Some((super::EnergyKind::Dissipated, Some(add(terms))))
        }
        _ => None,
    }
}
