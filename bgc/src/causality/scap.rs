//! The sequential causality assignment procedure (SCAP) with priorities, on top of [`super::engine`].
//!
//! Decisions are taken in this order, each followed by full propagation before the next:
//! 1. sources (their causality is fixed), then fixed hints (`stroke!`): hard constraints; a violation is a conflict;
//! 2. preferred hints (`stroke`) on the bonds of storage ports: the user's choice of which storage keeps its state
//!    (which of two rigidly coupled inertias goes derivative) beats the default below;
//! 3. storage ports (C, I, and every port of CF and IF) in declaration order: integral causality preferred; then
//!    the other preferred hints, where storage left a choice;
//! 4. resistors with a nonlinear law: the causality of the law's form (`e = g(f)` resistance, `f = g(e)`
//!    conductance);
//! 5. whatever is left (linear resistors, then junction-to-junction bonds in loops): an arbitrary choice.
//!
//! A decision of steps 2–5 is tentative: when its propagation meets a conflict it is undone and the other choice is
//! taken; only when both fail is the conflict kept and reported.

use super::engine::{Conflict, Engine, Reason, Role};
use crate::ir::{Model, PortVar, Relation};
use crate::syntax::ast::ElementKind;

/// A hint's fate.
#[derive(Clone, Copy, Debug)]
pub struct HintRecord {
    pub bond: u32,
    pub fixed: bool,
    /// True when the `from` node should set the effort.
    pub wants_effort_from: bool,
}

/// The result of the procedure, before it is turned into the public result and diagnostics.
pub struct Assignment {
    pub engine: Engine,
    /// Conflicts met by forced propagation.
    pub conflicts: Vec<Conflict>,
    /// Sources whose bond was already assigned against them: `(source, bond)`.
    pub forced_sources: Vec<(u32, u32)>,
    /// Fixed hints whose bond was already assigned against them.
    pub violated_hints: Vec<u32>,
    pub hints: Vec<HintRecord>,
    /// Arbitrary choices: `(node, bond)`.
    pub arbitrary: Vec<(u32, u32)>,
    /// Preferences that were overruled and the conflict that overruled them: `(bond, conflict)`.
    pub fallbacks: Vec<(u32, Conflict)>,
    /// Resistor law preferences: `(node, port, bond, prefers R to set the effort)`.
    pub laws: Vec<(u32, u32, u32, bool)>,
}

/// A storage port: `(node, port, bond, integral means the node sets the effort)`.
pub fn storage_ports(model: &Model, engine: &Engine) -> Vec<(u32, u32, u32, bool)> {
    let mut out = Vec::new();
    for node in model.graph.node_indices() {
        let n = node.index() as u32;
        let sets_when_integral = match model.graph[node].kind {
            ElementKind::C | ElementKind::CF => true,
            ElementKind::I | ElementKind::IF => false,
            _ => continue,
        };
        for &b in engine.incident(n) {
            out.push((n, port_at(model, engine, n, b), b, sets_when_integral));
        }
    }
    out
}

/// The port of `node` that `bond` attaches to.
pub fn port_at(model: &Model, engine: &Engine, node: u32, bond: u32) -> u32 {
    let Some(w) = model
        .graph
        .edge_weight(petgraph::graph::EdgeIndex::new(bond as usize))
    else {
        return 0;
    };
    if engine.ends[bond as usize].0 == node {
        w.from_port
    } else {
        w.to_port
    }
}

/// Runs the procedure.
pub fn assign(model: &Model) -> Assignment {
    let mut a = Assignment {
        engine: Engine::new(model),
        conflicts: Vec::new(),
        forced_sources: Vec::new(),
        violated_hints: Vec::new(),
        hints: Vec::new(),
        arbitrary: Vec::new(),
        fallbacks: Vec::new(),
        laws: Vec::new(),
    };
    let node_count = model.graph.node_count() as u32;

    // 1. Sources.
    for n in 0..node_count {
        let want = match a.engine.roles[n as usize] {
            Role::EffortSource => true,
            Role::FlowSource => false,
            _ => continue,
        };
        for b in a.engine.incident(n).to_vec() {
            match a.engine.node_sets(n, b) {
                None => {
                    a.engine.assign(b, n, want, Reason::Source(n));
                    let c = a.engine.propagate(false);
                    a.conflicts.extend(c);
                }
                Some(s) if s != want => a.forced_sources.push((n, b)),
                Some(_) => {}
            }
        }
    }

    // Hints, in bond order.
    for e in model.graph.edge_indices() {
        if let Some(h) = model.graph[e].hint {
            a.hints.push(HintRecord {
                bond: e.index() as u32,
                fixed: h.fixed,
                wants_effort_from: h.stroke_at_to,
            });
        }
    }
    // 1b. Fixed hints.
    for h in a.hints.clone().iter().filter(|h| h.fixed) {
        let from = a.engine.ends[h.bond as usize].0;
        match a.engine.effort_from[h.bond as usize] {
            None => {
                a.engine
                    .assign(h.bond, from, h.wants_effort_from, Reason::FixedHint);
                let c = a.engine.propagate(false);
                a.conflicts.extend(c);
            }
            Some(f) if f != h.wants_effort_from => a.violated_hints.push(h.bond),
            Some(_) => {}
        }
    }
    // 2. Preferred hints on storage bonds: the user's choice of which storage keeps its state.
    let storage = storage_ports(model, &a.engine);
    let on_storage = |b: u32| storage.iter().any(|&(_, _, sb, _)| sb == b);
    let preferred: Vec<HintRecord> = a.hints.iter().filter(|h| !h.fixed).copied().collect();
    for h in preferred.iter().filter(|h| on_storage(h.bond)) {
        prefer_hint(&mut a, h);
    }
    // 3. Storage.
    for &(n, _port, b, sets) in &storage {
        decide(&mut a, b, n, sets, Reason::Storage(n));
    }
    // 3b. The other preferred hints, where storage left a choice.
    for h in preferred.iter().filter(|h| !on_storage(h.bond)) {
        prefer_hint(&mut a, h);
    }
    // 4. Resistor laws.
    for (n, port, b, sets) in law_preferences(model, &a.engine) {
        a.laws.push((n, port, b, sets));
        decide(&mut a, b, n, sets, Reason::Law(n));
    }
    // 5. Arbitrary: resistors first, then any bond left.
    for n in 0..node_count {
        let kind = model.graph[petgraph::graph::NodeIndex::new(n as usize)].kind;
        if !matches!(kind, ElementKind::R | ElementKind::RF) {
            continue;
        }
        for b in a.engine.incident(n).to_vec() {
            if a.engine.effort_from[b as usize].is_none() {
                a.arbitrary.push((n, b));
                decide(&mut a, b, n, true, Reason::Arbitrary(n));
            }
        }
    }
    for b in 0..a.engine.ends.len() as u32 {
        if a.engine.effort_from[b as usize].is_none() {
            let from = a.engine.ends[b as usize].0;
            a.arbitrary.push((from, b));
            decide(&mut a, b, from, true, Reason::Arbitrary(from));
        }
    }
    a
}

fn prefer_hint(a: &mut Assignment, h: &HintRecord) {
    let from = a.engine.ends[h.bond as usize].0;
    decide(a, h.bond, from, h.wants_effort_from, Reason::PreferredHint);
}

/// Takes a tentative decision: `node` sets the effort on `bond` when `sets`, else the other way round.
fn decide(a: &mut Assignment, bond: u32, node: u32, sets: bool, reason: Reason) {
    if a.engine.effort_from[bond as usize].is_some() {
        return;
    }
    let mark = a.engine.mark();
    a.engine.assign(bond, node, sets, reason);
    let Some(&first) = a.engine.propagate(true).first() else {
        return;
    };
    a.engine.undo(mark);
    a.engine.assign(bond, node, !sets, Reason::Fallback(node));
    if a.engine.propagate(true).is_empty() {
        a.fallbacks.push((bond, first));
        return;
    }
    // Neither choice can be met: keep the preferred one and report what it violates.
    a.engine.undo(mark);
    a.engine.assign(bond, node, sets, reason);
    let c = a.engine.propagate(false);
    a.conflicts.extend(c);
}

/// Resistor ports whose nonlinear law prefers a causality: `(node, port, bond, R sets the effort)`.
fn law_preferences(model: &Model, engine: &Engine) -> Vec<(u32, u32, u32, bool)> {
    let mut out = Vec::new();
    for node in model.graph.node_indices() {
        let w = &model.graph[node];
        if !matches!(w.kind, ElementKind::R | ElementKind::RF) {
            continue;
        }
        let Relation::Laws(laws) = &w.relation else {
            continue;
        };
        let n = node.index() as u32;
        for &b in engine.incident(n) {
            let port = port_at(model, engine, n, b);
            let form = laws.iter().find(|l| l.port == port).map(|l| l.lhs);
            match form {
                Some(PortVar::Effort) => out.push((n, port, b, true)),
                Some(PortVar::Flow) => out.push((n, port, b, false)),
                _ => {}
            }
        }
    }
    out
}
