//! Properties on random graphs: the analysis never panics, always gives a complete result, and when it reports no
//! error every constraint of the junction structure holds (checked here independently of the engine).

use super::test_model::Builder;
use super::*;
use crate::syntax::ast::ElementKind as K;
use proptest::prelude::*;

const KINDS: [K; 13] = [
    K::Se,
    K::Sf,
    K::MSe,
    K::MSf,
    K::C,
    K::I,
    K::R,
    K::TF,
    K::GY,
    K::MTF,
    K::MGY,
    K::Zero,
    K::One,
];

fn build(kinds: &[usize], edges: &[(usize, usize, u8)], self_loops: bool) -> Model {
    let mut b = Builder::new("random");
    let nodes: Vec<_> = kinds
        .iter()
        .enumerate()
        .map(|(i, &k)| b.node(KINDS[k % KINDS.len()], &format!("n{i}")))
        .collect();
    for &(a, c, h) in edges {
        let (a, c) = (nodes[a % nodes.len()], nodes[c % nodes.len()]);
        // A bond from a node to itself breaks the IR's invariants (lowering rejects it).
        if a == c && !self_loops {
            continue;
        }
        match h % 4 {
            0 | 1 => {
                b.bond(a, c);
            }
            2 => {
                b.bond_hint(a, c, h % 8 < 4, false);
            }
            _ => {
                b.bond_hint(a, c, h % 8 < 4, true);
            }
        }
    }
    b.finish().0
}

/// Checks every hard constraint against the final causality.
fn constraints_hold(m: &Model, c: &Causality) -> Result<(), String> {
    for n in m.graph.node_indices() {
        let bonds: Vec<_> = m
            .graph
            .edges_directed(n, petgraph::Direction::Outgoing)
            .chain(m.graph.edges_directed(n, petgraph::Direction::Incoming))
            .map(|e| petgraph::visit::EdgeRef::id(&e))
            .collect();
        let sets: Vec<bool> = bonds.iter().map(|&b| c.sets_effort(m, n, b)).collect();
        let count = sets.iter().filter(|&&s| s).count();
        // A node without bonds breaks the IR's invariants and has nothing to check.
        if bonds.is_empty() {
            continue;
        }
        let ok = match m.graph[n].kind {
            K::Se | K::MSe => sets.iter().all(|&s| s),
            K::Sf | K::MSf => sets.iter().all(|&s| !s),
            K::Zero => bonds.len() - count == 1,
            K::One => count == 1,
            K::TF | K::MTF if bonds.len() == 2 => sets[0] != sets[1],
            K::GY | K::MGY if bonds.len() == 2 => sets[0] == sets[1],
            _ => true,
        };
        if !ok {
            return Err(format!("constraint of {} violated", m.graph[n].name));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_graphs(kinds in prop::collection::vec(0usize..13, 1..14),
                     edges in prop::collection::vec((0usize..14, 0usize..14, 0u8..=255), 0..24)) {
        let m = build(&kinds, &edges, false);
        let (c, d) = analyse(&m);
        prop_assert_eq!(c.effort_set_by.len(), m.graph.edge_count());
        prop_assert_eq!(c.consistent, !crate::diagnostic::has_errors(&d));
        if c.consistent {
            prop_assert!(constraints_hold(&m, &c).is_ok(), "{:?}", constraints_hold(&m, &c));
        }
        // Deterministic.
        let (c2, d2) = analyse(&m);
        prop_assert_eq!(&c, &c2);
        prop_assert_eq!(&d, &d2);
        // Reports and drawings never fail.
        let _ = to_text(&m, &c);
        let _ = to_json(&m, &c, serde_json::Value::Null);
        let _ = crate::draw::svg(&m, Some(&c));
        let _ = crate::draw::dot(&m, Some(&c));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Graphs that break the IR's invariants (bonds from a node to itself, wrong bond counts) still give a
    /// complete result and no panic.
    #[test]
    fn malformed_graphs_do_not_panic(kinds in prop::collection::vec(0usize..13, 1..8),
                                     edges in prop::collection::vec((0usize..8, 0usize..8, 0u8..=255), 0..16)) {
        let m = build(&kinds, &edges, true);
        let (c, _) = analyse(&m);
        prop_assert_eq!(c.effort_set_by.len(), m.graph.edge_count());
        let _ = to_text(&m, &c);
        let _ = crate::draw::svg(&m, Some(&c));
        let _ = crate::draw::dot(&m, None);
    }
}
