//! Configuration-dependent dependent storage: inertias rigidly coupled through a modulated transformer or gyrator
//! whose modulus varies with the state (a cart-pole written with MTFs, a pendulum's `l cos θ` lever).
//!
//! Sequential causality makes one of the coupled inertias dependent and computes the others' flows from the
//! independent one's by dividing by the modulus (`ω = v_x / (l cos θ)`). Where the modulus vanishes the state no
//! longer determines the motion: the rates hold a removable singularity (`/(m l sin²θ)`) and are non-finite at a
//! regular configuration. The remedy is the mass-matrix form that I-fields already have: the flows of the
//! 1-junctions behind the dividing moduli, and of the independent inertias of the group, become the states
//! (generalised velocities, `f_<junction>`). Every coupled inertia is then in derivative causality with its flow a
//! product of moduli and velocities, never a quotient, and each velocity's junction gives one row of
//! `M(q) ẋ = F`: `M = −∂R/∂ẋ`, `F = R(ẋ = 0)` for the junction's effort balance `R = 0`. `M` is the symmetric
//! `Σ Jᵀ m J` of the textbook, positive definite wherever the model is, and its consumers solve it numerically.
//!
//! The velocities are introduced as massless inertias (`I` of value 0) bonded to those junctions with a preferred
//! causality hint, and the causality is assigned again on that augmented graph; the user's diagnostics are those of
//! the original graph.

use super::build::{self, Built, Ctx, Def, effort_var, flow_var};
use super::symbols::{Sym, SymExt};
use crate::causality::Causality;
use crate::ir::{Bond, Expr as IrExpr, Hint, Model, Node, Relation};
use crate::symbolic::Expr;
use crate::syntax::ast::ElementKind;
use petgraph::Direction;
use petgraph::graph::{EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;
use std::collections::BTreeSet;

/// Rounds of augmentation per phase: each round can only add junctions, and a model needs more than one only
/// when a new velocity exposes another dividing modulus or couples another inertia.
const MAX_ROUNDS: usize = 4;

/// A model with velocity states at some junctions, and its causality.
pub(crate) struct Augmented {
    pub model: Model,
    pub causality: Causality,
    /// The massless inertias added (one per junction), in the order of their junctions.
    pub velocities: Vec<NodeIndex>,
}

/// The augmented model when the causality of `model` makes some dependent storage's flow a quotient by a
/// state-dependent modulus; `None` when it does not, or when the remedy does not apply (the junctions are not
/// 1-junctions, or the augmented causality has a conflict), in which case the plain derivation stands.
pub(crate) fn augment_if_needed(model: &Model, causality: &Causality) -> Option<Augmented> {
    if causality.derivative().next().is_none() || !has_modulated_two_port(model) {
        return None;
    }
    let mut junctions: Vec<NodeIndex> = Vec::new();
    let mut current: Option<Augmented> = None;
    // First the junctions behind the dividing moduli (their velocities take precedence in the hints), then those
    // of the independent inertias coupled to the new velocities, so that every inertia of the group is dependent
    // and `M` is the symmetric `Σ Jᵀ m J`.
    for phase in [Phase::Dividing, Phase::Coupled] {
        for _ in 0..MAX_ROUNDS {
            let needed = match &current {
                Some(a) => velocity_junctions(&a.model, &a.causality, &a.velocities, phase)?,
                None => velocity_junctions(model, causality, &[], phase)?,
            };
            let before = junctions.len();
            let fresh: Vec<NodeIndex> = needed.into_iter().rev().fold(Vec::new(), |mut acc, j| {
                if !junctions.contains(&j) && !acc.contains(&j) {
                    acc.push(j);
                }
                acc
            });
            // A quotient found later lies further down the causal path: its velocity is hinted first, so that
            // the flows propagate back from it through the moduli as products (a chain of MTFs gets its
            // velocity at the far end). The coupled inertias' velocities come after all of them.
            match phase {
                Phase::Dividing => {
                    junctions.splice(0..0, fresh);
                }
                Phase::Coupled => junctions.extend(fresh),
            }
            if junctions.len() == before {
                break;
            }
            let (m, velocities) = augment(model, &junctions);
            let (c, _) = crate::causality::analyse(&m);
            if !c.consistent {
                return None;
            }
            current = Some(Augmented {
                model: m,
                causality: c,
                velocities,
            });
        }
        current.as_ref()?;
    }
    current
}

/// Which junctions [`velocity_junctions`] looks for.
#[derive(Clone, Copy, PartialEq)]
enum Phase {
    /// Behind a quotient by a varying modulus.
    Dividing,
    /// Of an independent inertia that a dependent storage coupled to a velocity state depends on.
    Coupled,
}

fn has_modulated_two_port(model: &Model) -> bool {
    model
        .graph
        .node_weights()
        .any(|w| matches!(w.kind, ElementKind::MTF | ElementKind::MGY))
}

/// The 1-junctions whose flows must become velocity states: for every storage in derivative causality whose
/// flow or effort depends on a quotient by a modulus that varies with the state, the junction behind each such
/// quotient and the junction of each independent inertia it depends on. `None` when such a junction is not a
/// 1-junction (the remedy does not apply).
fn velocity_junctions(
    model: &Model,
    causality: &Causality,
    velocities: &[NodeIndex],
    phase: Phase,
) -> Option<Vec<NodeIndex>> {
    let (mut ctx, states) = build::context(model, causality, velocities);
    let built = build::build(model, causality, &mut ctx, states, &mut Vec::new());
    let dividing = dividing_flows(model, causality, &ctx);
    let mut out = Vec::new();
    for s in causality.derivative() {
        let Some((b, _)) = ctx.port.get(s.node.index()).copied().flatten() else {
            continue;
        };
        let own = match model.graph[s.node].kind {
            ElementKind::I => effort_var(b),
            _ => flow_var(b),
        };
        let reached = closure(&built, own);
        if phase == Phase::Dividing {
            for &(var, junction) in &dividing {
                if reached.contains(&var) {
                    out.push(one_junction(model, junction)?);
                }
            }
            continue;
        }
        let coupled = velocities.iter().any(|&n| {
            ctx.port
                .get(n.index())
                .copied()
                .flatten()
                .is_some_and(|(b, _)| reached.contains(&flow_var(b)))
        });
        if !coupled {
            continue;
        }
        for &v in &reached {
            let Some(n) = built.definer.get(v).copied().flatten() else {
                continue;
            };
            let independent_inertia = model.graph[n].kind == ElementKind::I
                && ctx.node_state.get(n.index()).copied().flatten().is_some()
                && !velocities.contains(&n);
            if independent_inertia && v % 2 == 1 {
                let (bond, _) = ctx.port.get(n.index()).copied().flatten()?;
                let (a, z) = model.graph.edge_endpoints(bond)?;
                out.push(one_junction(model, if a == n { z } else { a })?);
            }
        }
    }
    Some(out)
}

fn one_junction(model: &Model, n: NodeIndex) -> Option<NodeIndex> {
    (model.graph.node_weight(n)?.kind == ElementKind::One).then_some(n)
}

/// The flow variables a modulated two-port computes as a quotient by a modulus that is not constant, each with
/// the node at the other end of its bond.
fn dividing_flows(model: &Model, causality: &Causality, ctx: &Ctx) -> Vec<(usize, NodeIndex)> {
    let mut out = Vec::new();
    for n in model.graph.node_indices() {
        let w = &model.graph[n];
        let transformer = match w.kind {
            ElementKind::MTF => true,
            ElementKind::MGY => false,
            _ => continue,
        };
        let Relation::Modulus(m) = &w.relation else {
            continue;
        };
        let varies = ctx.convert(m).is_ok_and(|m| {
            m.any_sym(&|s| {
                matches!(
                    s,
                    Sym::State(_) | Sym::Input(_) | Sym::Time | Sym::Var(_) | Sym::Tear(_)
                )
            })
        });
        if !varies {
            continue;
        }
        let input = model.graph.edges_directed(n, Direction::Incoming).next();
        let output = model.graph.edges_directed(n, Direction::Outgoing).next();
        let (Some(i), Some(o)) = (input, output) else {
            continue;
        };
        let sets = |b: EdgeIndex| causality.sets_effort(model, n, b);
        // The table of `build`: a transformer with its flow in divides `f_out = f_in/n`; a gyrator that sets
        // flows divides both.
        if transformer && sets(i.id()) && !sets(o.id()) {
            out.push((flow_var(o.id()), o.target()));
        } else if !transformer && !sets(i.id()) && !sets(o.id()) {
            out.push((flow_var(o.id()), o.target()));
            out.push((flow_var(i.id()), i.source()));
        }
    }
    out
}

/// The bond variables `v` depends on through the definitions (an explicit work stack: no recursion).
fn closure(built: &Built, v: usize) -> BTreeSet<usize> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![v];
    while let Some(w) = stack.pop() {
        if !seen.insert(w) {
            continue;
        }
        if let Some(Some(Def::Plain(e) | Def::Rate(e))) = built.defs.get(w) {
            e.for_each_sym(&mut |s| {
                if let Sym::Var(x) = s {
                    stack.push(x);
                }
            });
        }
    }
    seen
}

/// `model` with a massless inertia bonded to each junction, hinted to integral causality; returns the new nodes.
fn augment(model: &Model, junctions: &[NodeIndex]) -> (Model, Vec<NodeIndex>) {
    let mut m = model.clone();
    let mut added = Vec::with_capacity(junctions.len());
    for &j in junctions {
        let Some(w) = model.graph.node_weight(j) else {
            continue;
        };
        let domain = model
            .graph
            .edges_directed(j, Direction::Incoming)
            .chain(model.graph.edges_directed(j, Direction::Outgoing))
            .next()
            .map(|e| e.weight().domain);
        let Some(domain) = domain else {
            continue;
        };
        let node = m.graph.add_node(Node {
            name: w.name.clone(),
            kind: ElementKind::I,
            relation: Relation::Linear(IrExpr::Const(0.0)),
            ports: 1,
            doc: Vec::new(),
        });
        // The stroke at the inertia's end: it receives the effort, which is integral causality.
        m.graph.add_edge(
            j,
            node,
            Bond {
                name: None,
                from_port: 0,
                to_port: 0,
                domain,
                hint: Some(Hint {
                    stroke_at_to: true,
                    fixed: false,
                }),
            },
        );
        let span = model
            .spans
            .nodes
            .get(j.index())
            .copied()
            .unwrap_or_default();
        m.spans.nodes.push(span);
        m.spans.node_names.push(
            model
                .spans
                .node_names
                .get(j.index())
                .copied()
                .unwrap_or(span),
        );
        m.spans.node_relations.push(None);
        m.spans.node_instances.push(None);
        m.spans.bonds.push(span);
        added.push(node);
    }
    (m, added)
}

/// The junction a velocity node is bonded to.
pub(crate) fn junction_of(model: &Model, velocity: NodeIndex) -> Option<NodeIndex> {
    model
        .graph
        .edges_directed(velocity, Direction::Incoming)
        .next()
        .map(|e| e.source())
}

/// The mass block of the velocity states: named after their junctions (`cart_pivot`).
pub(crate) fn block(
    model: &Model,
    states: &[super::StateSpec],
    rows: Vec<usize>,
    matrix: Vec<Vec<Expr>>,
) -> super::MassBlock {
    let mut names: Vec<String> = rows
        .iter()
        .filter_map(|&i| states.get(i))
        .filter(|s| s.kind == super::StateKind::Velocity)
        .filter_map(|s| s.node.and_then(|n| model.graph.node_weight(n)))
        .map(|w| build::sanitize(&w.name))
        .collect();
    if names.is_empty() {
        names.push("kinematics".into());
    }
    super::MassBlock {
        element: names.join("_"),
        states: rows,
        matrix,
    }
}
