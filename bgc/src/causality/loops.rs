//! Zero-order causal paths: algebraic loops of the assigned bond graph.
//!
//! Once every bond has its causality, each element computes its outputs from its inputs. The signal graph has one
//! vertex per bond variable (effort and flow of each bond) and an edge from each input of an element to each output
//! that depends on it without integration:
//! - R (and every port of an RF, whose outputs may depend on all its inputs): resistance `f -> e`, conductance
//!   `e -> f`;
//! - 0-junction with strong bond `k`: `e_k -> e_b` and `f_b -> f_k` for every other bond `b`; 1-junction dually;
//! - TF: effort in to effort out, flow in to flow out (the other way); GY: effort to flow across the ports.
//!
//! Sources and storage in integral causality have outputs that do not depend algebraically on their inputs (known
//! signals and states), so they break every path. Storage in derivative causality is left out as well: its
//! dependency is differential and is reported on its own. A strongly connected component with more than one vertex
//! is an algebraic loop; one representative cycle of each is reported as the ordered list of the elements it goes
//! through. Tarjan's algorithm is run iteratively, so the whole pass is linear and uses no recursion.

use super::engine::{Engine, Role};
use crate::ir::Model;
use crate::syntax::ast::ElementKind;
use petgraph::graph::NodeIndex;

/// Signal edges in compressed rows, each labelled with the element it goes through.
struct Signals {
    offsets: Vec<usize>,
    targets: Vec<u32>,
    through: Vec<u32>,
}

fn effort(b: u32) -> u32 {
    2 * b
}

fn flow(b: u32) -> u32 {
    2 * b + 1
}

fn build(model: &Model, engine: &Engine) -> Signals {
    let mut edges: Vec<(u32, u32, u32)> = Vec::new();
    for node in model.graph.node_indices() {
        let n = node.index() as u32;
        let bonds = engine.incident(n);
        let sets = |b: u32| engine.node_sets(n, b).unwrap_or(false);
        match engine.roles[n as usize] {
            Role::Zero | Role::One => {
                let zero = engine.roles[n as usize] == Role::Zero;
                // The strong bond of a 0-junction is the one it does not set, of a 1-junction the one it sets.
                let mut strong = bonds.iter().copied().filter(|&b| sets(b) != zero);
                let (Some(k), None) = (strong.next(), strong.next()) else {
                    continue;
                };
                for &b in bonds.iter().filter(|&&b| b != k) {
                    if zero {
                        edges.push((effort(k), effort(b), n));
                        edges.push((flow(b), flow(k), n));
                    } else {
                        edges.push((flow(k), flow(b), n));
                        edges.push((effort(b), effort(k), n));
                    }
                }
            }
            Role::Transformer => {
                let (Some(&a), Some(&c)) = (bonds.first(), bonds.get(1)) else {
                    continue;
                };
                // The port the TF does not set receives the effort.
                let (input, output) = if sets(a) { (c, a) } else { (a, c) };
                edges.push((effort(input), effort(output), n));
                edges.push((flow(output), flow(input), n));
            }
            Role::Gyrator => {
                let (Some(&a), Some(&c)) = (bonds.first(), bonds.get(1)) else {
                    continue;
                };
                if sets(a) {
                    edges.push((flow(c), effort(a), n));
                    edges.push((flow(a), effort(c), n));
                } else {
                    edges.push((effort(c), flow(a), n));
                    edges.push((effort(a), flow(c), n));
                }
            }
            Role::Free => {
                if !matches!(model.graph[node].kind, ElementKind::R | ElementKind::RF) {
                    continue;
                }
                for &out in bonds {
                    for &inp in bonds {
                        let (i, o) = if sets(out) {
                            (if sets(inp) { flow(inp) } else { effort(inp) }, effort(out))
                        } else {
                            (if sets(inp) { flow(inp) } else { effort(inp) }, flow(out))
                        };
                        edges.push((i, o, n));
                    }
                }
            }
            Role::EffortSource | Role::FlowSource => {}
        }
    }
    let vertices = 2 * engine.ends.len();
    let mut offsets = vec![0usize; vertices + 1];
    for &(s, _, _) in &edges {
        offsets[s as usize + 1] += 1;
    }
    for i in 0..vertices {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut targets = vec![0u32; edges.len()];
    let mut through = vec![0u32; edges.len()];
    for &(s, t, n) in &edges {
        let slot = &mut fill[s as usize];
        targets[*slot] = t;
        through[*slot] = n;
        *slot += 1;
    }
    Signals {
        offsets,
        targets,
        through,
    }
}

impl Signals {
    fn out(&self, v: u32) -> std::ops::Range<usize> {
        self.offsets[v as usize]..self.offsets[v as usize + 1]
    }
}

/// Strongly connected components (iterative Tarjan): a component number per vertex, and the number of vertices of
/// each component.
fn components(s: &Signals) -> (Vec<u32>, Vec<u32>) {
    const NONE: u32 = u32::MAX;
    let n = s.offsets.len() - 1;
    let mut index = vec![NONE; n];
    let mut low = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut comp = vec![NONE; n];
    let mut sizes = Vec::new();
    let mut stack: Vec<u32> = Vec::new();
    let mut call: Vec<(u32, usize)> = Vec::new();
    let mut next = 0u32;
    for root in 0..n as u32 {
        if index[root as usize] != NONE {
            continue;
        }
        call.push((root, s.offsets[root as usize]));
        index[root as usize] = next;
        low[root as usize] = next;
        next += 1;
        stack.push(root);
        on_stack[root as usize] = true;
        while let Some(&mut (v, ref mut pos)) = call.last_mut() {
            let end = s.offsets[v as usize + 1];
            if *pos < end {
                let w = s.targets[*pos];
                *pos += 1;
                if index[w as usize] == NONE {
                    index[w as usize] = next;
                    low[w as usize] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w as usize] = true;
                    call.push((w, s.offsets[w as usize]));
                } else if on_stack[w as usize] {
                    low[v as usize] = low[v as usize].min(index[w as usize]);
                }
                continue;
            }
            call.pop();
            if let Some(&(parent, _)) = call.last() {
                low[parent as usize] = low[parent as usize].min(low[v as usize]);
            }
            if low[v as usize] == index[v as usize] {
                let id = sizes.len() as u32;
                let mut size = 0;
                while let Some(w) = stack.pop() {
                    on_stack[w as usize] = false;
                    comp[w as usize] = id;
                    size += 1;
                    if w == v {
                        break;
                    }
                }
                sizes.push(size);
            }
        }
    }
    (comp, sizes)
}

/// One cycle through `start` inside its component (breadth-first, so a shortest one), as the elements it passes.
fn cycle_through(s: &Signals, comp: &[u32], start: u32) -> Vec<u32> {
    let c = comp[start as usize];
    // parent[v] = (previous vertex, element) on the search tree.
    let mut parent: std::collections::HashMap<u32, (u32, u32)> = std::collections::HashMap::new();
    let mut frontier = std::collections::VecDeque::from([start]);
    let mut closing: Option<(u32, u32)> = None;
    'search: while let Some(v) = frontier.pop_front() {
        for i in s.out(v) {
            let w = s.targets[i];
            if comp[w as usize] != c {
                continue;
            }
            if w == start {
                closing = Some((v, s.through[i]));
                break 'search;
            }
            if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(w) {
                e.insert((v, s.through[i]));
                frontier.push_back(w);
            }
        }
    }
    let Some((mut v, last)) = closing else {
        return Vec::new();
    };
    let mut elements = vec![last];
    while v != start {
        let Some(&(p, through)) = parent.get(&v) else {
            break;
        };
        elements.push(through);
        v = p;
    }
    elements.reverse();
    elements.dedup();
    if elements.len() > 1 && elements.first() == elements.last() {
        elements.pop();
    }
    elements
}

/// The algebraic loops of an assigned graph, each as the ordered elements on one of its cycles, starting at a
/// resistor when the loop has one.
pub fn find(model: &Model, engine: &Engine) -> Vec<Vec<NodeIndex>> {
    let s = build(model, engine);
    let (comp, sizes) = components(&s);
    let mut done = vec![false; sizes.len()];
    let mut loops = Vec::new();
    // Start each loop at the output of its first resistor (in vertex order), else at its first vertex.
    let mut starts: Vec<Option<u32>> = vec![None; sizes.len()];
    for v in 0..comp.len() as u32 {
        let c = comp[v as usize] as usize;
        if sizes[c] < 2 && !s.out(v).any(|i| s.targets[i] == v) {
            continue;
        }
        let through_r = s.out(v).any(|i| {
            comp[s.targets[i] as usize] as usize == c
                && matches!(
                    model.graph[NodeIndex::new(s.through[i] as usize)].kind,
                    ElementKind::R | ElementKind::RF
                )
        });
        if starts[c].is_none() || (through_r && !done[c]) {
            starts[c] = Some(v);
            done[c] = through_r;
        }
    }
    for start in starts.into_iter().flatten() {
        let mut cycle = cycle_through(&s, &comp, start);
        // Rotate so that the loop begins with a resistor.
        if let Some(p) = cycle.iter().position(|&n| {
            matches!(
                model.graph[NodeIndex::new(n as usize)].kind,
                ElementKind::R | ElementKind::RF
            )
        }) {
            cycle.rotate_left(p);
        }
        if !cycle.is_empty() {
            loops.push(
                cycle
                    .into_iter()
                    .map(|n| NodeIndex::new(n as usize))
                    .collect(),
            );
        }
    }
    loops
}
