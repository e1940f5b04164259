//! A layered layout that follows the junction structure.
//!
//! The "backbone" (junctions, two-ports, fields, and 1-ports not hanging on a junction) is laid out left to right
//! in layers: the power direction of the bonds gives a longest-path layering (after reversing the back edges of a
//! depth-first search so that it is acyclic), bonds spanning several layers get dummy points, and the order within
//! each layer is improved by barycentric sweeps. Each 1-port attached to a junction (its satellites) is placed
//! above or below that junction, alternately, so that storage, resistors and sources sit next to the junction
//! they belong to, as drawn in textbooks. Every backbone node owns a cell as wide as its satellites: bonds between
//! layers leave a cell horizontally, so they never run through another element.

use super::label::{NodeLabel, node_label};
use crate::ir::Model;
use crate::syntax::ast::ElementKind;
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;

/// Character width and line height of the monospace font used, in pixels.
pub const CHAR_W: f64 = 7.3;
pub const LINE_H: f64 = 15.0;
const CAPTION_CHAR_W: f64 = 6.1;
/// Vertical distance from a junction's centre to its satellites' centres.
const SAT_ROW: f64 = 70.0;
/// Horizontal gap between satellites of one row, between columns, and between cells of one column.
const SAT_GAP: f64 = 28.0;
const COL_GAP: f64 = 70.0;
/// Horizontal distance between a junction's box and a source placed beside it.
const SIDE: f64 = 45.0;
const CELL_GAP: f64 = 30.0;
pub const MARGIN: f64 = 30.0;

/// A placed node: its centre and box size.
pub struct Placed {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
    pub label: NodeLabel,
}

/// A laid-out model: nodes by `NodeIndex::index()`, each bond as a polyline from its `from` node to its `to` node
/// (end points on the nodes' box borders).
pub struct Layout {
    pub nodes: Vec<Placed>,
    pub bonds: Vec<Vec<(f64, f64)>>,
    pub width: f64,
    pub height: f64,
}

fn box_size(label: &NodeLabel, junction: bool) -> (f64, f64) {
    let main = label.main.chars().count() as f64 * CHAR_W;
    if junction {
        // The junction symbol with its name as a subscript.
        let sub = label
            .caption
            .as_ref()
            .map_or(0.0, |c| c.chars().count() as f64 * CAPTION_CHAR_W);
        return (main + sub + 12.0, LINE_H + 10.0);
    }
    let cap = label
        .caption
        .as_ref()
        .map_or(0.0, |c| c.chars().count() as f64 * CAPTION_CHAR_W);
    let lines = if label.caption.is_some() { 2.0 } else { 1.0 };
    (main.max(cap) + 14.0, lines * LINE_H + 8.0)
}

/// How far a cell reaches from its node's centre.
struct Extent {
    l: f64,
    r: f64,
    u: f64,
    d: f64,
}

/// A layer slot: a backbone node or a dummy point of a long bond.
#[derive(Clone, Copy, PartialEq)]
enum Slot {
    Node(usize),
    Dummy(usize),
}

/// Lays out a model.
pub fn layout(model: &Model) -> Layout {
    let g = &model.graph;
    let n = g.node_count();
    let mut nodes: Vec<Placed> = g
        .node_indices()
        .map(|i| {
            let label = node_label(model, &g[i]);
            let (w, h) = box_size(&label, g[i].kind.is_junction());
            Placed {
                x: 0.0,
                y: 0.0,
                w,
                h,
                label,
            }
        })
        .collect();

    // Satellites: 1-ports with one bond to a junction.
    let mut host: Vec<Option<usize>> = vec![None; n];
    let mut sats: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in g.node_indices() {
        let w = &g[i];
        if w.kind.is_junction() || w.kind.is_two_port() || w.kind.is_field() {
            continue;
        }
        let neighbours: Vec<NodeIndex> = g.neighbors_undirected(i).collect();
        if let [j] = neighbours[..]
            && j != i
            && g[j].kind.is_junction()
        {
            host[i.index()] = Some(j.index());
            sats[j.index()].push(i.index());
        }
    }
    let backbone: Vec<usize> = (0..n).filter(|&i| host[i].is_none()).collect();

    // Backbone edges (power direction), with back edges of a DFS reversed.
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); n];
    for e in g.edge_references() {
        let (a, b) = (e.source().index(), e.target().index());
        if host[a].is_none() && host[b].is_none() && a != b {
            out[a].push(b);
        }
    }
    let dag = acyclic(&backbone, &out, n);
    let layer = longest_path_layers(&backbone, &dag, n);

    // Slots per layer, with dummies for long edges; `links` are the edges between adjacent layers.
    let layers_count = backbone.iter().map(|&v| layer[v] + 1).max().unwrap_or(0);
    let mut slots: Vec<Vec<Slot>> = vec![Vec::new(); layers_count];
    let mut dummy_layer: Vec<usize> = Vec::new();
    let mut links: Vec<(Slot, Slot)> = Vec::new();
    // Long bonds: (from node, to node) -> dummy slots in between, in order.
    let mut chains: Vec<((usize, usize), Vec<usize>)> = Vec::new();
    for &v in &backbone {
        slots[layer[v]].push(Slot::Node(v));
    }
    for &(a, b) in &dag {
        let (lo, hi) = (layer[a].min(layer[b]), layer[a].max(layer[b]));
        let (first, last) = if layer[a] <= layer[b] { (a, b) } else { (b, a) };
        let mut prev = Slot::Node(first);
        let mut dummies = Vec::new();
        for (l, layer_slots) in slots.iter_mut().enumerate().take(hi).skip(lo + 1) {
            let d = dummy_layer.len();
            dummy_layer.push(l);
            layer_slots.push(Slot::Dummy(d));
            links.push((prev, Slot::Dummy(d)));
            prev = Slot::Dummy(d);
            dummies.push(d);
        }
        links.push((prev, Slot::Node(last)));
        if !dummies.is_empty() {
            chains.push(((first, last), dummies));
        }
    }
    order_layers(&mut slots, &links, n, dummy_layer.len());

    let key = |s: Slot| match s {
        Slot::Node(v) => v,
        Slot::Dummy(d) => n + d,
    };
    let mut preds: Vec<Vec<Slot>> = vec![Vec::new(); n + dummy_layer.len()];
    let mut succs: Vec<Vec<Slot>> = vec![Vec::new(); n + dummy_layer.len()];
    for &(a, b) in &links {
        succs[key(a)].push(b);
        preds[key(b)].push(a);
    }

    // Satellites' places: a source goes to the free left (or right) side of its junction, the others
    // alternately above and below.
    let mut above: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut below: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut left: Vec<Option<usize>> = vec![None; n];
    let mut right: Vec<Option<usize>> = vec![None; n];
    for j in 0..n {
        let mut k = 0;
        for &s in &sats[j] {
            let source = matches!(
                g[NodeIndex::new(s)].kind,
                ElementKind::Se | ElementKind::Sf | ElementKind::MSe | ElementKind::MSf
            );
            if source && left[j].is_none() && preds[j].is_empty() {
                left[j] = Some(s);
            } else if source && right[j].is_none() && succs[j].is_empty() {
                right[j] = Some(s);
            } else {
                if k % 2 == 0 {
                    above[j].push(s);
                } else {
                    below[j].push(s);
                }
                k += 1;
            }
        }
    }
    let row_width = |row: &[usize], nodes: &[Placed]| -> f64 {
        let w: f64 = row.iter().map(|&s| nodes[s].w).sum();
        w + SAT_GAP * row.len().saturating_sub(1) as f64
    };
    let row_height = |row: &[usize], nodes: &[Placed]| -> f64 {
        row.iter().map(|&s| nodes[s].h).fold(0.0, f64::max)
    };
    // A cell's extent from its node's centre: left, right, up, down.
    let cell = |slot: Slot, nodes: &[Placed]| -> Extent {
        match slot {
            Slot::Dummy(_) => Extent {
                l: 0.0,
                r: 0.0,
                u: 8.0,
                d: 8.0,
            },
            Slot::Node(v) => {
                let half = (nodes[v].w / 2.0)
                    .max(row_width(&above[v], nodes) / 2.0)
                    .max(row_width(&below[v], nodes) / 2.0);
                let side =
                    |s: Option<usize>| s.map_or(0.0, |s| nodes[v].w / 2.0 + SIDE + nodes[s].w);
                let side_h = |s: Option<usize>| s.map_or(0.0, |s| nodes[s].h / 2.0);
                let vert = |row: &[usize]| {
                    if row.is_empty() {
                        nodes[v].h / 2.0
                    } else {
                        SAT_ROW + row_height(row, nodes) / 2.0
                    }
                };
                let hh = side_h(left[v]).max(side_h(right[v]));
                Extent {
                    l: half.max(side(left[v])),
                    r: half.max(side(right[v])),
                    u: vert(&above[v]).max(hh),
                    d: vert(&below[v]).max(hh),
                }
            }
        }
    };

    // Columns: the node centres of a layer on one vertical line.
    let mut col_x = Vec::with_capacity(layers_count);
    let mut col_l = Vec::with_capacity(layers_count);
    let mut col_r = Vec::with_capacity(layers_count);
    let mut x = MARGIN;
    for layer_slots in &slots {
        let l = layer_slots
            .iter()
            .map(|&s| cell(s, &nodes).l)
            .fold(0.0, f64::max);
        let r = layer_slots
            .iter()
            .map(|&s| cell(s, &nodes).r)
            .fold(0.0, f64::max);
        col_x.push(x + l);
        col_l.push(l);
        col_r.push(r);
        x += l + r + COL_GAP;
    }

    // Vertical positions: towards the neighbours' mean, left to right then right to left, without overlap.
    let mut y_node = vec![0.0f64; n];
    let mut y_dummy = vec![0.0f64; dummy_layer.len()];
    for pass in 0..4 {
        let forward = pass % 2 == 0;
        let order: Vec<usize> = if forward {
            (0..layers_count).collect()
        } else {
            (0..layers_count).rev().collect()
        };
        for l in order {
            let mut prev_bottom = f64::NEG_INFINITY;
            let mut wanted = Vec::new();
            for &s in &slots[l] {
                let nb = if forward {
                    &preds[key(s)]
                } else {
                    &succs[key(s)]
                };
                let ys: Vec<f64> = nb
                    .iter()
                    .map(|&t| match t {
                        Slot::Node(v) => y_node[v],
                        Slot::Dummy(d) => y_dummy[d],
                    })
                    .collect();
                let current = match s {
                    Slot::Node(v) => y_node[v],
                    Slot::Dummy(d) => y_dummy[d],
                };
                let want = if ys.is_empty() {
                    current
                } else {
                    ys.iter().sum::<f64>() / ys.len() as f64
                };
                wanted.push(want);
            }
            // Place in order, pushing down to avoid overlap, then centre the block on what was wanted.
            let mut placed = Vec::new();
            for (k, &s) in slots[l].iter().enumerate() {
                let ext = cell(s, &nodes);
                let y = wanted[k].max(prev_bottom + ext.u + CELL_GAP);
                prev_bottom = y + ext.d;
                placed.push(y);
            }
            let shift = if placed.is_empty() {
                0.0
            } else {
                let want_mean = wanted.iter().sum::<f64>() / wanted.len() as f64;
                let got_mean = placed.iter().sum::<f64>() / placed.len() as f64;
                want_mean - got_mean
            };
            for (k, &s) in slots[l].iter().enumerate() {
                let y = placed[k] + shift;
                match s {
                    Slot::Node(v) => y_node[v] = y,
                    Slot::Dummy(d) => y_dummy[d] = y,
                }
            }
        }
    }

    // Place nodes and satellites; find the extent.
    let mut min_y = f64::INFINITY;
    let mut max_y = f64::NEG_INFINITY;
    for (l, layer_slots) in slots.iter().enumerate() {
        for &s in layer_slots {
            let ext = cell(s, &nodes);
            let y = match s {
                Slot::Node(v) => y_node[v],
                Slot::Dummy(d) => y_dummy[d],
            };
            min_y = min_y.min(y - ext.u);
            max_y = max_y.max(y + ext.d);
            if let Slot::Node(v) = s {
                nodes[v].x = col_x[l];
                nodes[v].y = y;
                for (row, sign) in [(&above[v], -1.0), (&below[v], 1.0)] {
                    let total = row_width(row, &nodes);
                    let mut sx = col_x[l] - total / 2.0;
                    for &sat in row.iter() {
                        let w = nodes[sat].w;
                        nodes[sat].x = sx + w / 2.0;
                        nodes[sat].y = y + sign * SAT_ROW;
                        sx += w + SAT_GAP;
                    }
                }
                if let Some(sat) = left[v] {
                    nodes[sat].x = col_x[l] - nodes[v].w / 2.0 - SIDE - nodes[sat].w / 2.0;
                    nodes[sat].y = y;
                }
                if let Some(sat) = right[v] {
                    nodes[sat].x = col_x[l] + nodes[v].w / 2.0 + SIDE + nodes[sat].w / 2.0;
                    nodes[sat].y = y;
                }
            }
        }
    }
    if !min_y.is_finite() {
        min_y = 0.0;
        max_y = 0.0;
    }
    let dy = MARGIN - min_y;
    for p in nodes.iter_mut() {
        p.y += dy;
    }
    for y in y_dummy.iter_mut() {
        *y += dy;
    }

    // Bond polylines.
    let mut bonds = Vec::with_capacity(g.edge_count());
    for e in g.edge_references() {
        let (a, b) = (e.source().index(), e.target().index());
        let pa = (nodes[a].x, nodes[a].y);
        let pb = (nodes[b].x, nodes[b].y);
        let mut pts = vec![pa];
        if host[a].is_none() && host[b].is_none() && a != b {
            let (la, lb) = (layer[a], layer[b]);
            let forward = la <= lb;
            let (first, last) = if forward { (a, b) } else { (b, a) };
            let mut mid: Vec<(f64, f64)> = Vec::new();
            // Leave the first cell horizontally, cross the dummies' columns, enter the last cell horizontally.
            let (lf, ll) = (layer[first], layer[last]);
            if lf != ll {
                mid.push((col_x[lf] + col_r[lf], nodes[first].y));
                if let Some(i) = chains.iter().position(|(k, _)| *k == (first, last)) {
                    let (_, ds) = chains.swap_remove(i);
                    for d in ds {
                        let l = dummy_layer[d];
                        mid.push((col_x[l] - col_l[l], y_dummy[d]));
                        mid.push((col_x[l] + col_r[l], y_dummy[d]));
                    }
                }
                mid.push((col_x[ll] - col_l[ll], nodes[last].y));
            }
            if !forward {
                mid.reverse();
            }
            pts.extend(mid);
        }
        pts.push(pb);
        // Clip both ends to the boxes' borders.
        let len = pts.len();
        if len >= 2 {
            pts[0] = clip(&nodes[a], pts[1]);
            pts[len - 1] = clip(&nodes[b], pts[len - 2]);
        }
        // Drop inner points that coincide with the clipped ends' direction reversal (inside a box).
        pts.dedup_by(|p, q| (p.0 - q.0).abs() < 0.5 && (p.1 - q.1).abs() < 0.5);
        bonds.push(pts);
    }

    let width = nodes
        .iter()
        .map(|p| p.x + p.w / 2.0)
        .fold(x - COL_GAP, f64::max)
        + MARGIN;
    let height = nodes
        .iter()
        .map(|p| p.y + p.h / 2.0)
        .fold(max_y - min_y + MARGIN, f64::max)
        + MARGIN;
    Layout {
        nodes,
        bonds,
        width,
        height,
    }
}

/// The point where the segment from the centre of `p`'s box towards `toward` leaves the box (plus a small gap).
fn clip(p: &Placed, toward: (f64, f64)) -> (f64, f64) {
    let (dx, dy) = (toward.0 - p.x, toward.1 - p.y);
    let hw = p.w / 2.0 + 3.0;
    let hh = p.h / 2.0 + 3.0;
    if dx.abs() < 1e-9 && dy.abs() < 1e-9 {
        return (p.x, p.y);
    }
    let tx = if dx.abs() > 1e-9 {
        hw / dx.abs()
    } else {
        f64::INFINITY
    };
    let ty = if dy.abs() > 1e-9 {
        hh / dy.abs()
    } else {
        f64::INFINITY
    };
    let t = tx.min(ty).min(1.0);
    (p.x + dx * t, p.y + dy * t)
}

/// The edges of the backbone with the back edges of an iterative depth-first search reversed.
fn acyclic(backbone: &[usize], out: &[Vec<usize>], n: usize) -> Vec<(usize, usize)> {
    // 0 = unvisited, 1 = on the stack, 2 = done.
    let mut state = vec![0u8; n];
    let mut edges = Vec::new();
    // Start from nodes without incoming backbone edges, so that sources come first.
    let mut indeg = vec![0usize; n];
    for &v in backbone {
        for &w in &out[v] {
            indeg[w] += 1;
        }
    }
    let mut roots: Vec<usize> = backbone
        .iter()
        .copied()
        .filter(|&v| indeg[v] == 0)
        .collect();
    roots.extend(backbone.iter().copied().filter(|&v| indeg[v] != 0));
    for root in roots {
        if state[root] != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        state[root] = 1;
        while let Some(&mut (v, ref mut k)) = stack.last_mut() {
            if let Some(&w) = out[v].get(*k) {
                *k += 1;
                match state[w] {
                    0 => {
                        edges.push((v, w));
                        state[w] = 1;
                        stack.push((w, 0));
                    }
                    1 => edges.push((w, v)),
                    _ => edges.push((v, w)),
                }
            } else {
                state[v] = 2;
                stack.pop();
            }
        }
    }
    edges
}

/// Longest-path layers of an acyclic edge list (Kahn's order).
fn longest_path_layers(backbone: &[usize], dag: &[(usize, usize)], n: usize) -> Vec<usize> {
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut indeg = vec![0usize; n];
    for &(a, b) in dag {
        out[a].push(b);
        indeg[b] += 1;
    }
    let mut layer = vec![0usize; n];
    let mut ready: Vec<usize> = backbone
        .iter()
        .copied()
        .filter(|&v| indeg[v] == 0)
        .collect();
    while let Some(v) = ready.pop() {
        for &w in &out[v] {
            layer[w] = layer[w].max(layer[v] + 1);
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.push(w);
            }
        }
    }
    layer
}

/// Orders each layer by barycentric sweeps over the links between adjacent layers.
fn order_layers(slots: &mut [Vec<Slot>], links: &[(Slot, Slot)], n: usize, dummies: usize) {
    let key = |s: Slot| match s {
        Slot::Node(v) => v,
        Slot::Dummy(d) => n + d,
    };
    let mut pos = vec![0.0f64; n + dummies];
    let refresh = |slots: &[Vec<Slot>], pos: &mut Vec<f64>| {
        for layer in slots {
            for (i, &s) in layer.iter().enumerate() {
                pos[key(s)] = i as f64;
            }
        }
    };
    refresh(slots, &mut pos);
    let mut up: Vec<Vec<usize>> = vec![Vec::new(); n + dummies];
    let mut down: Vec<Vec<usize>> = vec![Vec::new(); n + dummies];
    for &(a, b) in links {
        down[key(a)].push(key(b));
        up[key(b)].push(key(a));
    }
    for sweep in 0..8 {
        let forward = sweep % 2 == 0;
        let range: Vec<usize> = if forward {
            (1..slots.len()).collect()
        } else {
            (0..slots.len().saturating_sub(1)).rev().collect()
        };
        for l in range {
            let nb = if forward { &up } else { &down };
            let mut keyed: Vec<(f64, usize, Slot)> = slots[l]
                .iter()
                .enumerate()
                .map(|(i, &s)| {
                    let ns = &nb[key(s)];
                    let bary = if ns.is_empty() {
                        pos[key(s)]
                    } else {
                        ns.iter().map(|&k| pos[k]).sum::<f64>() / ns.len() as f64
                    };
                    (bary, i, s)
                })
                .collect();
            keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            slots[l] = keyed.into_iter().map(|(_, _, s)| s).collect();
            for (i, &s) in slots[l].iter().enumerate() {
                pos[key(s)] = i as f64;
            }
        }
    }
}
