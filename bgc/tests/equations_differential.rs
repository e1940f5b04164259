//! Differential test: random linear bond graphs, bgc's state space against an acausal descriptor formulation
//! built straight from the graph.
//!
//! The reference knows nothing of causality: every bond's effort and flow is an unknown, every node contributes its
//! equations in the Laplace domain (a C: `s_own f = s c e`; an I: `e = s m s_own f`; an R: `e = r s_own f`; sources
//! their value; a 0-junction equal efforts and `Σ ±f = 0`; a 1-junction equal flows and `Σ ±e = 0`; TF
//! `f_in = n f_out`, `e_out = n e_in`; GY `e_in = m f_out`, `e_out = m f_in`), and the dense complex system is solved
//! by LU for each input at several complex `s`. The outputs are `e(x)` and `f(x)` of every one-port, the flow
//! counted into a C, I, R and out of a source (docs/language.md), and the effort and flow (as the bond is drawn) of
//! the bond on each port of a field. bgc's `C (sI − A)⁻¹ B + D` must agree.
//!
//! The graphs: a random tree of 0- and 1-junctions joined by bonds, TFs or GYs in random directions, one-ports of
//! every kind hung on them in random directions, an effort and a flow source, and up to two more bonds, TFs or GYs
//! between junctions that close loops in the junction structure, and in half the graphs a two-port `IF`, `CF` or
//! `RF` with a constant symmetric matrix on random junctions (an `IF`: `e = s M f`; a `CF`: `s e = K f`; an `RF`:
//! `e = R f`, with each port's flow counted into the field); structures that give storages in
//! derivative causality and resistive loops occur. Cases that bgc rightly refuses (an output that needs an input's
//! derivative, causal conflicts) are skipped. A linear graph whose loops bgc keeps as a block solved numerically
//! (larger graphs, `LARGE`) is compared through its linearisation at the origin.

// Index loops read like the textbook elimination and matrix products they implement.
#![allow(clippy::needless_range_loop)]

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::{
    StateSelection, derive, linear_through_loops, linearise, numeric_state_space,
};
use bgc::ir::Model;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;
use petgraph::Direction;
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;
use proptest::prelude::*;

/// The one-ports of the model, with their kind, for the outputs.
fn random_model(seed: u64, sizes: Sizes) -> (Model, Vec<(String, K)>) {
    let mut g = Gen(seed);
    let mut b = Builder::new("random");
    let junctions: Vec<_> = (0..2 + g.below(sizes.junctions))
        .map(|k| {
            let kind = if g.coin() { K::Zero } else { K::One };
            b.junction(kind, &format!("j{k}"))
        })
        .collect();
    let bond = |b: &mut Builder, g: &mut Gen, x, y| {
        if g.coin() {
            b.bond(x, y)
        } else {
            b.bond(y, x)
        };
    };
    for k in 1..junctions.len() {
        let parent = junctions[g.below(k as u64) as usize];
        let child = junctions[k];
        let (from, to) = if g.coin() {
            (parent, child)
        } else {
            (child, parent)
        };
        match g.below(3) {
            0 => {
                b.bond(from, to);
            }
            kind => {
                let modulus = b.param(&format!("n{k}"), g.value());
                let two = if kind == 1 { K::TF } else { K::GY };
                let node = b.node(two, &format!("tp{k}"), linear_modulus(modulus));
                b.bond(from, node);
                b.bond(node, to);
            }
        }
    }
    let mut ports = Vec::new();
    let count = 2 + g.below(sizes.ports);
    for k in 0..count {
        let kind = [K::C, K::I, K::R][g.below(3) as usize];
        let value = b.param(&format!("v{k}"), g.value());
        let name = format!("x{k}");
        let node = b.node(kind, &name, linear(value));
        let j = junctions[g.below(junctions.len() as u64) as usize];
        bond(&mut b, &mut g, j, node);
        ports.push((name, kind));
    }
    for (k, kind) in [K::Se, K::Sf].into_iter().enumerate() {
        let u = b.input(&format!("u{k}"));
        let name = format!("src{k}");
        let node = b.node(kind, &name, source(u));
        let j = junctions[g.below(junctions.len() as u64) as usize];
        bond(&mut b, &mut g, node, j);
        ports.push((name, kind));
    }
    // Loops in the junction structure: bonds (or TFs and GYs) between junctions the tree already joins.
    for k in 0..g.below(sizes.closing) {
        let x = junctions[g.below(junctions.len() as u64) as usize];
        let y = junctions[g.below(junctions.len() as u64) as usize];
        if x == y {
            continue;
        }
        match g.below(3) {
            0 => bond(&mut b, &mut g, x, y),
            kind => {
                let modulus = b.param(&format!("l{k}"), g.value());
                let two = if kind == 1 { K::TF } else { K::GY };
                let node = b.node(two, &format!("tl{k}"), linear_modulus(modulus));
                b.bond(x, node);
                b.bond(node, y);
            }
        }
    }
    if g.coin() {
        add_field(&mut b, &mut g, &junctions);
    }
    let nodes: Vec<_> = b.model.graph.node_indices().collect();
    for (name, _) in &ports {
        let n = nodes
            .iter()
            .copied()
            .find(|&n| &b.model.graph[n].name == name);
        if let Some(n) = n {
            b.output(&format!("e_{name}_y"), e(n));
            b.output(&format!("f_{name}_y"), f(n));
        }
    }
    (b.finish(), ports)
}

/// A two-port `IF`, `CF` or `RF` with the constant symmetric matrix `[[a, c], [c, d]]` (`c` small enough for it to
/// be definite), its ports bonded to random junctions in random directions, and the effort and flow of each port's
/// bond as outputs.
fn add_field(b: &mut Builder, g: &mut Gen, junctions: &[NodeIndex]) {
    use bgc::ir::{Expr, Law, PortVar, Relation};
    let kind = [K::IF, K::CF, K::RF][g.below(3) as usize];
    let node = b.field(kind, "fld", 2);
    let a = b.param("fa", g.value());
    let c = b.param("fc", 0.1 * g.value());
    let d = b.param("fd", g.value());
    let port = |var, port| Expr::FieldPort { node, var, port };
    let row =
        |x: &Expr, y: &Expr, var| add(mul(x.clone(), port(var, 0)), mul(y.clone(), port(var, 1)));
    let laws = |var| {
        Relation::Laws(vec![
            Law {
                lhs: PortVar::Effort,
                port: 0,
                rhs: row(&a, &c, var),
            },
            Law {
                lhs: PortVar::Effort,
                port: 1,
                rhs: row(&c, &d, var),
            },
        ])
    };
    b.model.graph[node].relation = match kind {
        K::IF => Relation::MassMatrix {
            n: 2,
            entries: vec![a.clone(), c.clone(), c.clone(), d.clone()],
        },
        K::CF => laws(PortVar::Displacement),
        _ => laws(PortVar::Flow),
    };
    bond_field_ports(b, g, node, junctions);
}

/// The rows of a two-port field at `s`: with `X` its matrix, `v` the own flow of each port (into the field) and
/// `w = v / s` its displacement, an `IF` has `e = s X v`, a `CF` `e = X w` and an `RF` `e = X v`; `None` for
/// another relation.
fn field_rows(model: &Model, n: NodeIndex, params: &[f64], s: Cx) -> Option<Vec<Vec<Cx>>> {
    use bgc::ir::{Expr, Law, Relation};
    let value = |e: &Expr| match e {
        Expr::Param(p) => params.get(*p).copied(),
        _ => None,
    };
    let x: Vec<f64> = match &model.graph[n].relation {
        Relation::MassMatrix { entries, .. } => entries.iter().map(value).collect::<Option<_>>()?,
        Relation::Laws(laws) => laws
            .iter()
            .flat_map(|Law { rhs, .. }| match rhs {
                Expr::Binary(_, l, r) => [l, r].map(|t| match &**t {
                    Expr::Binary(_, coefficient, _) => value(coefficient),
                    _ => None,
                }),
                _ => [None, None],
            })
            .collect::<Option<_>>()?,
        _ => return None,
    };
    // The bond and own-flow sign of each port.
    let mut ports = [(usize::MAX, 0.0); 2];
    for e in model.graph.edges_directed(n, Direction::Incoming) {
        *ports.get_mut(e.weight().to_port as usize)? = (e.id().index(), 1.0);
    }
    for e in model.graph.edges_directed(n, Direction::Outgoing) {
        *ports.get_mut(e.weight().from_port as usize)? = (e.id().index(), -1.0);
    }
    if ports.iter().any(|p| p.0 == usize::MAX) {
        return None;
    }
    let nb = model.graph.edge_count();
    let kind = model.graph[n].kind;
    let rows = (0..2)
        .map(|k| {
            let mut r = vec![Cx::re(0.0); 2 * nb];
            r[2 * ports[k].0] = if kind == K::CF { s } else { Cx::re(1.0) };
            for (j, &(bond, so)) in ports.iter().enumerate() {
                let coefficient = Cx::re(-x[2 * k + j] * so);
                r[2 * bond + 1] = if kind == K::IF {
                    s.mul(coefficient)
                } else {
                    coefficient
                };
            }
            r
        })
        .collect();
    Some(rows)
}

fn linear_modulus(e: bgc::ir::Expr) -> bgc::ir::Relation {
    bgc::ir::Relation::Modulus(e)
}

/// The effort or the flow unknown of a bond.
type VarOf = fn(usize) -> usize;

/// The transfer matrix of the descriptor formulation at `s`: outputs × inputs.
fn descriptor_transfer(model: &Model, params: &[f64], s: Cx) -> Option<Vec<Vec<Cx>>> {
    let nb = model.graph.edge_count();
    let (ei, fi) = (|b: usize| 2 * b, |b: usize| 2 * b + 1);
    let value = |e: &bgc::ir::Expr| match e {
        bgc::ir::Expr::Param(p) => params[*p],
        _ => f64::NAN,
    };
    let mut rows: Vec<(Vec<Cx>, Option<usize>)> = Vec::new();
    let zero_row = || vec![Cx::re(0.0); 2 * nb];
    // Per one-port: its bond and own-flow sign.
    let own = |n: petgraph::graph::NodeIndex| {
        let kind = model.graph[n].kind;
        let source = matches!(kind, K::Se | K::Sf);
        let incoming = model.graph.edges_directed(n, Direction::Incoming).next();
        let outgoing = model.graph.edges_directed(n, Direction::Outgoing).next();
        match (incoming, outgoing) {
            (Some(e), _) => (e.id().index(), if source { -1.0 } else { 1.0 }),
            (_, Some(e)) => (e.id().index(), if source { 1.0 } else { -1.0 }),
            _ => (usize::MAX, 0.0),
        }
    };
    for n in model.graph.node_indices() {
        let w = &model.graph[n];
        let incident: Vec<(usize, f64)> = model
            .graph
            .edges_directed(n, Direction::Incoming)
            .map(|e| (e.id().index(), 1.0))
            .chain(
                model
                    .graph
                    .edges_directed(n, Direction::Outgoing)
                    .map(|e| (e.id().index(), -1.0)),
            )
            .collect();
        match w.kind {
            K::Zero | K::One => {
                let (common, summed): (VarOf, VarOf) = if w.kind == K::Zero {
                    (|b| 2 * b, |b| 2 * b + 1)
                } else {
                    (|b| 2 * b + 1, |b| 2 * b)
                };
                for pair in incident.windows(2) {
                    let mut r = zero_row();
                    r[common(pair[0].0)] = Cx::re(1.0);
                    r[common(pair[1].0)] = Cx::re(-1.0);
                    rows.push((r, None));
                }
                let mut r = zero_row();
                for &(b, dir) in &incident {
                    r[summed(b)] = Cx::re(dir);
                }
                rows.push((r, None));
            }
            K::Se | K::Sf => {
                let (b, so) = own(n);
                let input = match &w.relation {
                    bgc::ir::Relation::Source(bgc::ir::Expr::Input(i)) => *i,
                    _ => return None,
                };
                let mut r = zero_row();
                if w.kind == K::Se {
                    r[ei(b)] = Cx::re(1.0);
                } else {
                    r[fi(b)] = Cx::re(so);
                }
                rows.push((r, Some(input)));
            }
            K::C | K::I | K::R => {
                let (b, so) = own(n);
                let v = match &w.relation {
                    bgc::ir::Relation::Linear(e) => value(e),
                    _ => return None,
                };
                let mut r = zero_row();
                match w.kind {
                    K::C => {
                        r[fi(b)] = Cx::re(so);
                        r[ei(b)] = s.mul(Cx::re(-v));
                    }
                    K::I => {
                        r[ei(b)] = Cx::re(1.0);
                        r[fi(b)] = s.mul(Cx::re(-v * so));
                    }
                    _ => {
                        r[ei(b)] = Cx::re(1.0);
                        r[fi(b)] = Cx::re(-v * so);
                    }
                }
                rows.push((r, None));
            }
            K::TF | K::GY => {
                let m = match &w.relation {
                    bgc::ir::Relation::Modulus(e) => value(e),
                    _ => return None,
                };
                let i = incident.iter().find(|x| x.1 > 0.0)?.0;
                let o = incident.iter().find(|x| x.1 < 0.0)?.0;
                let mut r1 = zero_row();
                let mut r2 = zero_row();
                if w.kind == K::TF {
                    r1[fi(i)] = Cx::re(1.0);
                    r1[fi(o)] = Cx::re(-m);
                    r2[ei(o)] = Cx::re(1.0);
                    r2[ei(i)] = Cx::re(-m);
                } else {
                    r1[ei(i)] = Cx::re(1.0);
                    r1[fi(o)] = Cx::re(-m);
                    r2[ei(o)] = Cx::re(1.0);
                    r2[fi(i)] = Cx::re(-m);
                }
                rows.push((r1, None));
                rows.push((r2, None));
            }
            K::IF | K::CF | K::RF => {
                rows.extend(
                    field_rows(model, n, params, s)?
                        .into_iter()
                        .map(|r| (r, None)),
                );
            }
            _ => return None,
        }
    }
    if rows.len() != 2 * nb {
        return None;
    }
    let a: Vec<Vec<Cx>> = rows.iter().map(|r| r.0.clone()).collect();
    let mut columns = Vec::new();
    for input in 0..model.inputs.len() {
        let rhs: Vec<Cx> = rows
            .iter()
            .map(|r| Cx::re(if r.1 == Some(input) { 1.0 } else { 0.0 }))
            .collect();
        columns.push(solve(a.clone(), rhs)?);
    }
    // Outputs: e(x), f(x) of every one-port, in the order the model declares them.
    let mut out = Vec::new();
    for o in &model.outputs {
        let (is_effort, node) = match &o.value {
            bgc::ir::Expr::Effort(bgc::ir::Target::Node(n)) => (true, *n),
            bgc::ir::Expr::Flow(bgc::ir::Target::Node(n)) => (false, *n),
            // A bond's effort and its flow as the bond is drawn.
            bgc::ir::Expr::Effort(bgc::ir::Target::Bond(b)) => {
                out.push(columns.iter().map(|x| x[ei(b.index())]).collect());
                continue;
            }
            bgc::ir::Expr::Flow(bgc::ir::Target::Bond(b)) => {
                out.push(columns.iter().map(|x| x[fi(b.index())]).collect());
                continue;
            }
            _ => return None,
        };
        let (b, so) = own(node);
        out.push(
            columns
                .iter()
                .map(|x| {
                    if is_effort {
                        x[ei(b)]
                    } else {
                        x[fi(b)].mul(Cx::re(so))
                    }
                })
                .collect(),
        );
    }
    Some(out)
}

/// `C (sI − A)⁻¹ B + D` at `s`.
fn state_space_transfer(ss: &bgc::equations::NumericStateSpace, s: Cx) -> Option<Vec<Vec<Cx>>> {
    let n = ss.a.len();
    let m = ss.inputs.len();
    let mut out = vec![vec![Cx::re(0.0); m]; ss.c.len()];
    for j in 0..m {
        let a: Vec<Vec<Cx>> = (0..n)
            .map(|r| {
                (0..n)
                    .map(|c| {
                        let diag = if r == c { s } else { Cx::re(0.0) };
                        diag.sub(Cx::re(ss.a[r][c]))
                    })
                    .collect()
            })
            .collect();
        let x = if n == 0 {
            Vec::new()
        } else {
            solve(a, (0..n).map(|r| Cx::re(ss.b[r][j])).collect())?
        };
        for (k, row) in ss.c.iter().enumerate() {
            let mut acc = Cx::re(ss.d[k][j]);
            for (c, xc) in row.iter().zip(&x) {
                acc = acc.add(Cx::re(*c).mul(*xc));
            }
            out[k][j] = acc;
        }
    }
    Some(out)
}

/// How a graph was compared: not at all (a case bgc rightly refuses), through bgc's state space, or through the
/// linearisation of a linear model whose loops are a block solved numerically (exactly its state space).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Compared {
    No,
    StateSpace,
    ThroughLoops,
}

fn compare(seed: u64, sizes: Sizes) -> Result<Compared, TestCaseError> {
    let (model, _) = random_model(seed, sizes);
    let (causality, _) = analyse(&model);
    if !causality.consistent {
        return Ok(Compared::No);
    }
    let (eqs, diags) = derive(&model, &causality);
    if bgc::diagnostic::has_errors(&diags) {
        return Ok(Compared::No);
    }
    let params = eqs.default_params();
    let (ss, how) = match numeric_state_space(&eqs, StateSelection::Energy, &params) {
        Ok(ss) => (ss, Compared::StateSpace),
        Err(_) if linear_through_loops(&eqs, StateSelection::Energy) => {
            let n = eqs.state_count(StateSelection::Energy);
            let (x0, u0) = (vec![0.0; n], vec![0.0; eqs.inputs.len()]);
            let ss = linearise(&eqs, StateSelection::Energy, &params, &x0, &u0, 0.0)
                .map_err(|e| TestCaseError::fail(format!("seed {seed}: {e}")))?;
            (ss, Compared::ThroughLoops)
        }
        Err(_) => return Ok(Compared::No),
    };
    for s in [Cx(0.3, 1.1), Cx(-0.2, 2.7), Cx(1.5, -0.4)] {
        let Some(want) = descriptor_transfer(&model, &params, s) else {
            return Ok(Compared::No);
        };
        let got =
            state_space_transfer(&ss, s).ok_or_else(|| TestCaseError::fail("sI - A singular"))?;
        for (k, (g_row, w_row)) in got.iter().zip(&want).enumerate() {
            for (j, (g, w)) in g_row.iter().zip(w_row).enumerate() {
                let scale = 1.0 + w.abs();
                prop_assert!(
                    g.sub(*w).abs() <= 1e-8 * scale,
                    "seed {seed}: output {} input {j} at s = {s:?}: bgc {g:?}, descriptor {w:?}",
                    model.outputs[k].name
                );
            }
        }
    }
    Ok(how)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn linear_graphs_match_the_descriptor_formulation(seed in any::<u64>()) {
        compare(seed, SMALL)?;
    }
}

/// The generator produces enough well-posed cases to mean something: of 256 fixed seeds, many are compared, with
/// loops in the junction structure and with fields of each kind among them.
#[test]
fn most_random_graphs_are_compared() {
    let (mut compared, mut loops, mut fields) = (0, 0, [0; 3]);
    for seed in 0..256u64 {
        if compare(seed, SMALL).unwrap_or_else(|e| panic!("{e}")) != Compared::No {
            compared += 1;
            let model = random_model(seed, SMALL).0;
            loops += usize::from(has_junction_loop(&model));
            for (count, kind) in fields.iter_mut().zip([K::IF, K::CF, K::RF]) {
                *count += model
                    .graph
                    .node_weights()
                    .filter(|w| w.kind == kind)
                    .count();
            }
        }
    }
    assert!(
        compared >= 50,
        "only {compared} of 256 graphs were compared"
    );
    assert!(
        loops >= 20,
        "only {loops} compared graphs have a loop in the junction structure"
    );
    assert!(
        fields.iter().all(|&n| n >= 3),
        "compared graphs with an IF, a CF, an RF: {fields:?}"
    );
}

/// Larger graphs whose resistive loops bgc keeps as a linear block solved numerically: their state space, from
/// the Jacobians at the origin through the block, matches the descriptor formulation. These are the 14 such
/// graphs among seeds 5,000 to 24,999 of the large generator (2,973 of those 20,000 graphs were compared, none
/// differed); the property test's small graphs never need a block.
#[test]
fn linear_loop_blocks_match_the_descriptor_formulation() {
    let seeds = [
        7112, 7466, 7543, 8088, 9911, 11992, 14395, 15363, 17253, 17472, 20734, 21135, 22500, 24881,
    ];
    for seed in seeds {
        let how = compare(seed, LARGE).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(how, Compared::ThroughLoops, "seed {seed}");
    }
}
