//! Layering of the backbone: cycle breaking, longest-path layers and barycentric ordering within layers.

use super::layout::Slot;

/// The edges of the backbone with the back edges of an iterative depth-first search reversed.
pub fn acyclic(backbone: &[usize], out: &[Vec<usize>], n: usize) -> Vec<(usize, usize)> {
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
pub fn longest_path_layers(backbone: &[usize], dag: &[(usize, usize)], n: usize) -> Vec<usize> {
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
pub fn order_layers(slots: &mut [Vec<Slot>], links: &[(Slot, Slot)], n: usize, dummies: usize) {
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
