//! A layered layout that follows the junction structure.
//!
//! The "backbone" (junctions, two-ports, fields, and 1-ports not hanging on a junction) is laid out left to right
//! in layers: the power direction of the bonds gives a longest-path layering (after reversing the back edges of a
//! depth-first search so that it is acyclic), bonds spanning several layers get dummy points, and the order within
//! each layer is improved by barycentric sweeps. Heights follow the neighbours' mean, with the node on the longest
//! chain of each layer kept in place, so that the main chain of junctions is drawn on one straight line. Each
//! 1-port attached to a junction (its satellites) is placed beside it (a source, on a free side) or above or below
//! it, alternately, so that storage, resistors and sources sit next to the junction
//! they belong to, as drawn in textbooks. Every backbone node owns a cell as wide as its satellites: bonds between
//! layers leave a cell horizontally, so they never run through another element.

use super::label::{NodeLabel, node_label};
use super::layers::{acyclic, longest_path_layers, order_layers};
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
pub enum Slot {
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

    // The longest chain through each slot: in each layer the slot on the longest chain is the anchor that keeps
    // the height it wants, so that the main chain of junctions is drawn straight and branches go around it.
    let total_slots = n + dummy_layer.len();
    let mut down = vec![0usize; total_slots];
    let mut up = vec![0usize; total_slots];
    for layer_slots in slots.iter().rev() {
        for &s in layer_slots {
            down[key(s)] = succs[key(s)]
                .iter()
                .map(|&t| down[key(t)] + 1)
                .max()
                .unwrap_or(0);
        }
    }
    for layer_slots in &slots {
        for &s in layer_slots {
            up[key(s)] = preds[key(s)]
                .iter()
                .map(|&t| up[key(t)] + 1)
                .max()
                .unwrap_or(0);
        }
    }
    let anchor: Vec<Option<usize>> = slots
        .iter()
        .map(|layer_slots| {
            (0..layer_slots.len()).max_by_key(|&k| {
                let s = layer_slots[k];
                // Ties go to the node with more bonds (the one with more hanging on it), then to the first.
                let degree = match s {
                    Slot::Node(v) => g.neighbors_undirected(NodeIndex::new(v)).count(),
                    Slot::Dummy(_) => 0,
                };
                (up[key(s)] + down[key(s)], degree, std::cmp::Reverse(k))
            })
        })
        .collect();

    // Vertical positions: towards the neighbours' mean, left to right then right to left, without overlap.
    let mut y_node = vec![0.0f64; n];
    let mut y_dummy = vec![0.0f64; dummy_layer.len()];
    // The last pass goes left to right, so that the power flow's main chain ends up straight.
    for pass in 0..4 {
        let forward = pass % 2 == 1;
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
            // Place in order, pushing down to avoid overlap, then shift the block so the anchor is where it wants.
            let mut placed = Vec::new();
            for (k, &s) in slots[l].iter().enumerate() {
                let ext = cell(s, &nodes);
                let y = wanted[k].max(prev_bottom + ext.u + CELL_GAP);
                prev_bottom = y + ext.d;
                placed.push(y);
            }
            let shift = match anchor[l] {
                Some(k) => wanted[k] - placed[k],
                None => 0.0,
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
