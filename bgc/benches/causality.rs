//! Causality assignment on a chain of 1,000,000 bonds: `Se -> 1 -> {I, R} -> 0 -> C -> 1 -> ...`, five bonds per
//! stage. The IR is generated directly (no parsing), so the time is the analysis alone.

use bgc::ir::{Bond, Domain, Expr, Model, Node, Relation, SpanTable};
use bgc::syntax::ast::ElementKind;
use criterion::{Criterion, criterion_group, criterion_main};
use petgraph::graph::{DiGraph, NodeIndex};
use std::hint::black_box;

const STAGES: usize = 200_000;

fn node(g: &mut DiGraph<Node, Bond>, kind: ElementKind, name: String) -> NodeIndex {
    let relation = match kind {
        ElementKind::Se => Relation::Source(Expr::Const(1.0)),
        ElementKind::I | ElementKind::C | ElementKind::R => Relation::Linear(Expr::Const(1.0)),
        _ => Relation::Junction,
    };
    let ports = u32::from(!kind.is_junction());
    g.add_node(Node {
        name,
        kind,
        relation,
        ports,
        doc: Vec::new(),
    })
}

fn bond(g: &mut DiGraph<Node, Bond>, a: NodeIndex, b: NodeIndex) {
    g.add_edge(
        a,
        b,
        Bond {
            name: None,
            from_port: 0,
            to_port: 0,
            domain: Domain::Translational,
            hint: None,
        },
    );
}

fn chain() -> Model {
    let mut g = DiGraph::with_capacity(4 * STAGES + 1, 5 * STAGES);
    let mut prev = node(&mut g, ElementKind::Se, "src".into());
    for k in 0..STAGES {
        let one = node(&mut g, ElementKind::One, format!("v{k}"));
        let i = node(&mut g, ElementKind::I, format!("m{k}"));
        let r = node(&mut g, ElementKind::R, format!("d{k}"));
        let zero = node(&mut g, ElementKind::Zero, format!("f{k}"));
        let c = node(&mut g, ElementKind::C, format!("k{k}"));
        bond(&mut g, prev, one);
        bond(&mut g, one, i);
        bond(&mut g, one, r);
        bond(&mut g, one, zero);
        bond(&mut g, zero, c);
        prev = zero;
    }
    let spans = SpanTable {
        nodes: vec![Default::default(); g.node_count()],
        bonds: vec![Default::default(); g.edge_count()],
        ..Default::default()
    };
    Model {
        name: "chain".into(),
        doc: Vec::new(),
        graph: g,
        params: Vec::new(),
        inputs: Vec::new(),
        outputs: Vec::new(),
        vars: Vec::new(),
        coords: None,
        spans,
    }
}

fn bench(c: &mut Criterion) {
    let model = chain();
    assert_eq!(model.graph.edge_count(), 1_000_000);
    let (causality, diags) = bgc::causality::analyse(&model);
    assert!(diags.is_empty());
    assert_eq!(causality.independent_states(), 2 * STAGES);
    let mut group = c.benchmark_group("causality");
    group.sample_size(10);
    group.bench_function("chain_1M_bonds", |b| {
        b.iter(|| bgc::causality::analyse(black_box(&model)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
