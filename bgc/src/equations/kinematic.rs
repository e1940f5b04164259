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
use crate::syntax::ast::ElementKind;
use petgraph::Direction;
use petgraph::graph::{EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;
use std::collections::{HashMap, HashSet};

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
            let mut seen: HashSet<NodeIndex> = junctions.iter().copied().collect();
            let fresh: Vec<NodeIndex> = needed
                .into_iter()
                .rev()
                .filter(|&j| seen.insert(j))
                .collect();
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
///
/// Each junction is listed once, at its last place in the order "storage by storage (as the causality lists them),
/// then quotient by quotient, or variable by variable": the caller orders the new velocities by that place. One
/// walk of the definitions finds, for every variable, the last storage that depends on it, so the cost is linear
/// in the model, not one walk per storage.
fn velocity_junctions(
    model: &Model,
    causality: &Causality,
    velocities: &[NodeIndex],
    phase: Phase,
) -> Option<Vec<NodeIndex>> {
    let (mut ctx, states) = build::context(model, causality, velocities);
    let built = build::build(model, causality, &mut ctx, states, &mut Vec::new());
    let port_var = |n: NodeIndex, var: fn(EdgeIndex) -> usize| {
        ctx.port
            .get(n.index())
            .copied()
            .flatten()
            .map(|(b, _)| var(b))
    };
    // The own variable of each storage in derivative causality, numbered in the causality's order.
    let owns: Vec<(usize, usize)> = causality
        .derivative()
        .filter_map(|s| match model.graph[s.node].kind {
            ElementKind::I => port_var(s.node, effort_var),
            _ => port_var(s.node, flow_var),
        })
        .enumerate()
        .collect();
    // `(place, junction)` for each time the junction is found.
    let mut found: Vec<((usize, usize), NodeIndex)> = Vec::new();
    match phase {
        Phase::Dividing => {
            let last = last_depending(built.defs.len(), &|v| reads(&built, v), &owns);
            for (d, &(var, junction)) in dividing_flows(model, causality, &ctx).iter().enumerate() {
                if let Some(s) = last.get(var).copied().flatten() {
                    found.push(((s, d), one_junction(model, junction)?));
                }
            }
        }
        Phase::Coupled => {
            // Only the storages that depend on a velocity state's flow are coupled to it.
            let flows: Vec<usize> = velocities
                .iter()
                .filter_map(|&n| port_var(n, flow_var))
                .collect();
            let reaches = depends_on_any(built.defs.len(), &|v| reads(&built, v), &flows);
            let coupled: Vec<(usize, usize)> = owns
                .iter()
                .copied()
                .filter(|&(_, own)| reaches.get(own).copied().unwrap_or(false))
                .collect();
            let last = last_depending(built.defs.len(), &|v| reads(&built, v), &coupled);
            for (v, s) in last.iter().enumerate() {
                let (Some(s), Some(n)) = (*s, built.definer.get(v).copied().flatten()) else {
                    continue;
                };
                let independent_inertia = model.graph[n].kind == ElementKind::I
                    && ctx.node_state.get(n.index()).copied().flatten().is_some()
                    && !velocities.contains(&n);
                if independent_inertia && v % 2 == 1 {
                    let (bond, _) = ctx.port.get(n.index()).copied().flatten()?;
                    let (a, z) = model.graph.edge_endpoints(bond)?;
                    found.push(((s, v), one_junction(model, if a == n { z } else { a })?));
                }
            }
        }
    }
    Some(at_last_place(found))
}

/// The junctions in the order of their last places, each once.
fn at_last_place(found: Vec<((usize, usize), NodeIndex)>) -> Vec<NodeIndex> {
    let mut last: HashMap<NodeIndex, (usize, usize)> = HashMap::new();
    for (place, junction) in found {
        let at = last.entry(junction).or_insert(place);
        *at = (*at).max(place);
    }
    let mut placed: Vec<((usize, usize), NodeIndex)> =
        last.into_iter().map(|(j, p)| (p, j)).collect();
    placed.sort_unstable();
    placed.into_iter().map(|(_, j)| j).collect()
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

/// The bond variables the definition of `v` reads.
fn reads(built: &Built, v: usize) -> Vec<usize> {
    let mut out = Vec::new();
    if let Some(Some(Def::Plain(e) | Def::Rate(e))) = built.defs.get(v) {
        e.for_each_sym(&mut |s| {
            if let Sym::Var(x) = s {
                out.push(x);
            }
        });
    }
    out
}

/// Per variable (of `n`, each reading those `reads` gives), the largest number among `sources` (`(number, variable)`, numbers increasing) whose
/// variable depends on it through the definitions (itself included), or `None`.
///
/// The sources are walked from the last: a variable already reached was reached from a larger number, and so was
/// everything it depends on, so each variable is visited once (an explicit work stack: no recursion).
fn last_depending(
    n: usize,
    reads: &dyn Fn(usize) -> Vec<usize>,
    sources: &[(usize, usize)],
) -> Vec<Option<usize>> {
    let mut last: Vec<Option<usize>> = vec![None; n];
    for &(number, root) in sources.iter().rev() {
        let mut stack = vec![root];
        while let Some(v) = stack.pop() {
            match last.get_mut(v) {
                Some(slot @ None) => *slot = Some(number),
                _ => continue,
            }
            stack.extend(reads(v));
        }
    }
    last
}

/// Per variable (of `n`, each reading those `reads` gives), whether it depends on any of `targets` through the definitions (itself included): one walk
/// of the definitions backwards from the targets.
fn depends_on_any(n: usize, reads: &dyn Fn(usize) -> Vec<usize>, targets: &[usize]) -> Vec<bool> {
    let mut readers: Vec<Vec<usize>> = vec![Vec::new(); n];
    for v in 0..n {
        for x in reads(v) {
            if let Some(r) = readers.get_mut(x) {
                r.push(v);
            }
        }
    }
    let mut reached = vec![false; n];
    let mut stack: Vec<usize> = targets.to_vec();
    while let Some(v) = stack.pop() {
        match reached.get_mut(v) {
            Some(seen @ false) => *seen = true,
            _ => continue,
        }
        if let Some(r) = readers.get(v) {
            stack.extend(r.iter().copied());
        }
    }
    reached
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

/// The mass blocks of the velocity states, each named after its junctions (`cart_pivot`), or `kinematics` when it
/// holds none; a name another block (or an I-field's) already has gets the block's number after it.
pub(crate) fn blocks(
    model: &Model,
    states: &[super::StateSpec],
    blocks: Vec<super::solve::MassRows>,
    fields: &[super::MassBlock],
) -> Vec<super::MassBlock> {
    let mut taken: HashSet<String> = fields.iter().map(|b| b.element.clone()).collect();
    let mut out = Vec::with_capacity(blocks.len());
    for (k, (rows, matrix)) in blocks.into_iter().enumerate() {
        let names: Vec<String> = rows
            .iter()
            .filter_map(|&i| states.get(i))
            .filter(|s| s.kind == super::StateKind::Velocity)
            .filter_map(|s| s.node.and_then(|n| model.graph.node_weight(n)))
            .map(|w| build::sanitize(&w.name))
            .collect();
        let base = match names.is_empty() {
            true => "kinematics".to_string(),
            false => names.join("_"),
        };
        let mut element = base.clone();
        let mut suffix = k + 1;
        while !taken.insert(element.clone()) {
            element = format!("{base}_{suffix}");
            suffix += 1;
        }
        out.push(super::MassBlock {
            element,
            states: rows,
            matrix,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{depends_on_any, last_depending};

    /// Everything `root` depends on, one walk per root: the definition the linear walks must agree with.
    fn closure(reads: &[Vec<usize>], root: usize) -> Vec<bool> {
        let mut seen = vec![false; reads.len()];
        let mut stack = vec![root];
        while let Some(v) = stack.pop() {
            if !std::mem::replace(&mut seen[v], true) {
                stack.extend(reads[v].iter().copied());
            }
        }
        seen
    }

    #[test]
    fn one_walk_finds_what_a_walk_per_source_finds_on_graphs_with_cycles() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move |below: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % below as u64) as usize
        };
        for _ in 0..200 {
            let n = 1 + next(40);
            let reads: Vec<Vec<usize>> = (0..n)
                .map(|_| (0..next(3)).map(|_| next(n)).collect())
                .collect();
            let read = |v: usize| reads[v].clone();
            // Sources numbered in increasing order, some variables twice, some not at all.
            let sources: Vec<(usize, usize)> =
                (0..next(6)).map(|k| (3 * k + next(3), next(n))).collect();
            let last = last_depending(n, &read, &sources);
            for (v, got) in last.iter().enumerate() {
                let want = sources
                    .iter()
                    .filter(|&&(_, root)| closure(&reads, root)[v])
                    .map(|&(number, _)| number)
                    .max();
                assert_eq!(*got, want, "variable {v} of {reads:?} from {sources:?}");
            }
            let targets: Vec<usize> = (0..next(3)).map(|_| next(n)).collect();
            let depends = depends_on_any(n, &read, &targets);
            for (v, got) in depends.iter().enumerate() {
                let want = targets.iter().any(|&t| closure(&reads, v)[t]);
                assert_eq!(*got, want, "variable {v} of {reads:?} to {targets:?}");
            }
        }
    }
}
