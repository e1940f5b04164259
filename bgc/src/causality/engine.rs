//! The propagation engine of the causality assignment: one boolean per bond and unit propagation through the
//! junction structure, with an undo trail for tentative decisions.
//!
//! For a node `n` and an incident bond `b`, write `sets(n, b)` when `n` sets the effort on `b` (the other end then
//! sets the flow). The constraints are:
//! - 0-junction: exactly one incident bond with `!sets` (the strong bond brings the common effort in);
//! - 1-junction: exactly one incident bond with `sets` (the strong bond brings the common flow in);
//! - TF/MTF: `sets(b0) != sets(b1)` (effort in on one port, effort out on the other);
//! - GY/MGY: `sets(b0) == sets(b1)` (a gyrator inverts: effort in gives flow out);
//! - Se/MSe: `sets`; Sf/MSf: `!sets`.
//!
//! Storage, resistors and fields carry no hard constraint here; their preferences are decisions taken by
//! [`super::scap`]. Junction constraints are checked through two counters per node (incident bonds assigned, and
//! among them those the node sets), so a node is scanned only when a counter reaches a triggering value: every
//! bond is assigned once per decision and each junction is scanned a bounded number of times, which keeps the whole
//! assignment linear in the number of bonds.

use crate::ir::Model;
use crate::syntax::ast::ElementKind;

/// Why a bond has its causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    Unassigned,
    /// A source (node) imposes its variable.
    Source(u32),
    /// A fixed hint on the bond.
    FixedHint,
    /// A preferred hint on the bond.
    PreferredHint,
    /// A storage port (node) takes its preferred integral causality.
    Storage(u32),
    /// The preferred choice at this node (storage port, hint, law) could not be met: the other one.
    Fallback(u32),
    /// A resistor (node) takes the causality of its law's form.
    Law(u32),
    /// Nothing decided: an arbitrary choice at this node.
    Arbitrary(u32),
    /// The constraint of `node` forced it after bond `via` was assigned.
    Propagated {
        node: u32,
        via: u32,
    },
}

/// A constraint that cannot be met.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conflict {
    /// The node whose constraint is violated.
    pub node: u32,
    /// The bond whose assignment revealed it.
    pub bond: u32,
}

/// What a node's constraint is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    EffortSource,
    FlowSource,
    Zero,
    One,
    Transformer,
    Gyrator,
    /// Storage, resistors and fields: no hard constraint.
    Free,
}

impl Role {
    pub fn of(kind: ElementKind) -> Role {
        match kind {
            ElementKind::Se | ElementKind::MSe => Role::EffortSource,
            ElementKind::Sf | ElementKind::MSf => Role::FlowSource,
            ElementKind::Zero => Role::Zero,
            ElementKind::One => Role::One,
            ElementKind::TF | ElementKind::MTF => Role::Transformer,
            ElementKind::GY | ElementKind::MGY => Role::Gyrator,
            _ => Role::Free,
        }
    }
}

/// The assignment state.
pub struct Engine {
    /// `(from, to)` node of each bond.
    pub ends: Vec<(u32, u32)>,
    /// Incident bonds of node `n`: `incident[offsets[n]..offsets[n + 1]]`.
    offsets: Vec<usize>,
    incident: Vec<u32>,
    pub roles: Vec<Role>,
    /// Per bond: `Some(true)` when the `from` node sets the effort.
    pub effort_from: Vec<Option<bool>>,
    pub reason: Vec<Reason>,
    /// Per node: incident bonds assigned.
    assigned: Vec<u32>,
    /// Per node: incident bonds on which the node sets the effort.
    sets: Vec<u32>,
    trail: Vec<u32>,
    queue: Vec<(u32, u32)>,
}

impl Engine {
    pub fn new(model: &Model) -> Engine {
        let g = &model.graph;
        let n = g.node_count();
        let ends: Vec<(u32, u32)> = g
            .edge_indices()
            .map(|e| {
                g.edge_endpoints(e)
                    .map_or((0, 0), |(a, b)| (a.index() as u32, b.index() as u32))
            })
            .collect();
        let mut degree = vec![0usize; n + 1];
        for &(a, b) in &ends {
            degree[a as usize] += 1;
            degree[b as usize] += 1;
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut acc = 0;
        for d in &degree[..n] {
            offsets.push(acc);
            acc += d;
        }
        offsets.push(acc);
        let mut fill = offsets.clone();
        let mut incident = vec![0u32; acc];
        for (i, &(a, b)) in ends.iter().enumerate() {
            for node in [a, b] {
                let slot = &mut fill[node as usize];
                incident[*slot] = i as u32;
                *slot += 1;
            }
        }
        let roles = g.node_weights().map(|w| Role::of(w.kind)).collect();
        let m = ends.len();
        Engine {
            ends,
            offsets,
            incident,
            roles,
            effort_from: vec![None; m],
            reason: vec![Reason::Unassigned; m],
            assigned: vec![0; n],
            sets: vec![0; n],
            trail: Vec::new(),
            queue: Vec::new(),
        }
    }

    /// The bonds incident to a node (a bond from a node to itself appears twice).
    pub fn incident(&self, node: u32) -> &[u32] {
        let n = node as usize;
        match (self.offsets.get(n), self.offsets.get(n + 1)) {
            (Some(&a), Some(&b)) => self.incident.get(a..b).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Whether `node` sets the effort on `bond`, once assigned.
    pub fn node_sets(&self, node: u32, bond: u32) -> Option<bool> {
        let from = self.ends[bond as usize].0 == node;
        self.effort_from[bond as usize].map(|f| f == from)
    }

    /// Assigns an unassigned bond so that `node` sets its effort or not, and queues both ends.
    pub fn assign(&mut self, bond: u32, node: u32, node_sets: bool, reason: Reason) {
        let b = bond as usize;
        if self.effort_from[b].is_some() {
            return;
        }
        let (from, to) = self.ends[b];
        let from_sets = if from == node { node_sets } else { !node_sets };
        self.effort_from[b] = Some(from_sets);
        self.reason[b] = reason;
        self.trail.push(bond);
        self.count(from, to, from_sets, true);
        self.queue.push((from, bond));
        self.queue.push((to, bond));
    }

    fn count(&mut self, from: u32, to: u32, from_sets: bool, add: bool) {
        for (node, node_sets) in [(from, from_sets), (to, !from_sets)] {
            let n = node as usize;
            if add {
                self.assigned[n] += 1;
                self.sets[n] += u32::from(node_sets);
            } else {
                self.assigned[n] -= 1;
                self.sets[n] -= u32::from(node_sets);
            }
        }
    }

    /// A mark to undo to.
    pub fn mark(&self) -> usize {
        self.trail.len()
    }

    /// Undoes every assignment made after `mark` and drops pending work.
    pub fn undo(&mut self, mark: usize) {
        while self.trail.len() > mark {
            let Some(bond) = self.trail.pop() else { break };
            let b = bond as usize;
            if let Some(from_sets) = self.effort_from[b].take() {
                let (from, to) = self.ends[b];
                self.count(from, to, from_sets, false);
            }
            self.reason[b] = Reason::Unassigned;
        }
        self.queue.clear();
    }

    /// Propagates queued assignments. With `stop_at_first`, returns at the first conflict (for tentative decisions);
    /// otherwise skips past conflicts and returns them all.
    pub fn propagate(&mut self, stop_at_first: bool) -> Vec<Conflict> {
        let mut conflicts = Vec::new();
        while let Some((node, bond)) = self.queue.pop() {
            if let Err(c) = self.check(node, bond) {
                conflicts.push(c);
                if stop_at_first {
                    self.queue.clear();
                    break;
                }
            }
        }
        conflicts
    }

    /// Checks one node's constraint after `bond` changed and forces what it determines.
    fn check(&mut self, node: u32, bond: u32) -> Result<(), Conflict> {
        let n = node as usize;
        let conflict = Conflict { node, bond };
        let degree = self.incident(node).len() as u32;
        match self.roles[n] {
            Role::EffortSource | Role::FlowSource => {
                let want = self.roles[n] == Role::EffortSource;
                match self.node_sets(node, bond) {
                    Some(s) if s != want => Err(conflict),
                    _ => Ok(()),
                }
            }
            Role::Zero | Role::One => {
                // For a 0-junction the strong bonds are those it does not set; for a 1-junction those it sets.
                let (strong, strong_is_set) = if self.roles[n] == Role::Zero {
                    (self.assigned[n] - self.sets[n], false)
                } else {
                    (self.sets[n], true)
                };
                let assigned = self.assigned[n];
                if strong > 1 || (strong == 0 && assigned == degree) {
                    return Err(conflict);
                }
                if strong == 1 && assigned < degree {
                    let via = self
                        .incident(node)
                        .iter()
                        .copied()
                        .find(|&b| self.node_sets(node, b) == Some(strong_is_set))
                        .unwrap_or(bond);
                    self.force_rest(node, !strong_is_set, via);
                } else if strong == 0 && assigned + 1 == degree {
                    self.force_rest(node, strong_is_set, bond);
                }
                Ok(())
            }
            Role::Transformer | Role::Gyrator => {
                let same = self.roles[n] == Role::Gyrator;
                let bonds = self.incident(node);
                let (Some(&a), Some(&b)) = (bonds.first(), bonds.get(1)) else {
                    return Ok(());
                };
                match (self.node_sets(node, a), self.node_sets(node, b)) {
                    (Some(sa), Some(sb)) if (sa == sb) != same => Err(conflict),
                    (Some(sa), None) => {
                        let sb = if same { sa } else { !sa };
                        self.assign(b, node, sb, Reason::Propagated { node, via: a });
                        Ok(())
                    }
                    (None, Some(sb)) => {
                        let sa = if same { sb } else { !sb };
                        self.assign(a, node, sa, Reason::Propagated { node, via: b });
                        Ok(())
                    }
                    _ => Ok(()),
                }
            }
            Role::Free => Ok(()),
        }
    }

    /// Assigns every unassigned incident bond of a junction.
    fn force_rest(&mut self, node: u32, node_sets: bool, via: u32) {
        let start = self.offsets[node as usize];
        let end = self.offsets[node as usize + 1];
        for i in start..end {
            let b = self.incident[i];
            if self.effort_from[b as usize].is_none() {
                self.assign(b, node, node_sets, Reason::Propagated { node, via });
            }
        }
    }

    /// The bonds in the order of their final assignment: a bond's `via` always comes before it.
    pub fn order(&self) -> &[u32] {
        &self.trail
    }

    /// The node that decided `bond` when its reason is not propagation (the origin of a causal path).
    pub fn origin_node(&self, bond: u32) -> u32 {
        match self.reason[bond as usize] {
            Reason::Source(n)
            | Reason::Storage(n)
            | Reason::Fallback(n)
            | Reason::Law(n)
            | Reason::Arbitrary(n)
            | Reason::Propagated { node: n, .. } => n,
            Reason::FixedHint | Reason::PreferredHint | Reason::Unassigned => {
                let (from, to) = self.ends[bond as usize];
                if self.effort_from[bond as usize] == Some(true) {
                    from
                } else {
                    to
                }
            }
        }
    }

    /// The last `limit` steps of the causal path that led to `bond`'s assignment, as `(deciding node, bond)` in
    /// causal order, ending with `bond`; it starts at the origin when the path is no longer than `limit`.
    pub fn path_to(&self, bond: u32, limit: usize) -> Vec<(u32, u32)> {
        let mut steps = Vec::new();
        let mut b = bond;
        // Each step goes to a bond assigned earlier, so the walk ends; the bound also keeps it short.
        for _ in 0..limit.min(self.ends.len() + 1) {
            steps.push((self.origin_node(b), b));
            match self.reason[b as usize] {
                Reason::Propagated { via, .. } => b = via,
                _ => break,
            }
        }
        steps.reverse();
        steps
    }
}
