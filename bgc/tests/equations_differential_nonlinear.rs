//! Differential test of modulated and nonlinear bond graphs: bgc's rates and outputs at random points against an
//! acausal reference solved by Newton's method.
//!
//! The graphs: a random tree of 0- and 1-junctions joined by bonds, TFs, GYs, MTFs and MGYs in random directions
//! (an MTF or MGY modulus `n (1 + 0.3 cos(q(C)))`, `n (1 + 0.3 sin(p(I)))` or `n (1 + 0.3 cos(w))` of an input
//! `w`), one-ports hung on them in random directions with linear or cubic laws (`C { e = q/c + k q^3 }`,
//! `I { f = p/m + k p^3 }`, `R { e = r f + k f^3 }` or `R { f = e/r + k e^3 }`), an effort and a flow source.
//!
//! The reference knows nothing of causality. At a point `(x, u, t)` every storage's state is given, so its law
//! gives its effort (C) or its flow (I); every bond's effort and flow is an unknown, solved by Newton's method
//! (dense finite-difference Jacobian, from zero, convergence checked) from the junction equations, the element
//! laws, the TF/MTF/GY/MGY relations (`f_in = n f_out`, `e_out = n e_in`; `e_in = m f_out`, `e_out = m f_in`,
//! the modulus evaluated at the point) and the sources. Then `q̇ = f(C)`, `ṗ = e(I)` and the outputs `e(x)`,
//! `f(x)` of every one-port, with the flow counted into a C, I, R and out of a source (docs/language.md), must
//! agree with bgc's `rates_at` and `outputs_at`.
//!
//! Graphs with a storage in derivative causality are skipped (its state is not free, so the point would have to
//! satisfy its constraint), as are graphs bgc rightly refuses. `most_modulated_graphs_are_compared` checks that a
//! good fraction is compared, and `a_flipped_sign_in_the_reference_is_caught` that the comparison notices a sign
//! error of every element kind, of a junction's sum and of the own flow of a C, I or R whose bond is drawn out of
//! it.

// Index loops read like the textbook elimination they implement.
#![allow(clippy::needless_range_loop)]

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::{Equations, StateKind, derive};
use bgc::ir::{Expr, Func, Law, Model, PortVar, Relation, Target};
use bgc::syntax::ast::{BinOp, ElementKind as K};
use equations_support::*;
use petgraph::Direction;
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;
use proptest::prelude::*;

fn call(func: Func, arg: Expr) -> Expr {
    Expr::Call(func, vec![arg])
}

fn law(lhs: PortVar, rhs: Expr) -> Relation {
    Relation::Laws(vec![Law { lhs, port: 0, rhs }])
}

/// `a/v + k a³` or `v a + k a³`.
fn cubic(a: Expr, v: Expr, k: Expr, divide: bool) -> Expr {
    let first = if divide {
        div(a.clone(), v)
    } else {
        mul(v, a.clone())
    };
    add(first, mul(k, pow(a, c(3.0))))
}

/// A linear law or a cubic one, in a random form for an R; `turn` writes an R's cubic law in the other form.
fn one_port_law(
    b: &mut Builder,
    g: &mut Gen,
    (kind, n, k): (K, NodeIndex, u64),
    turn: bool,
) -> Relation {
    let v = b.param(&format!("v{k}"), g.value());
    if g.coin() {
        return linear(v);
    }
    let k3 = b.param(&format!("k{k}"), 0.1 + g.value() / 5.0);
    match kind {
        K::C => law(PortVar::Effort, cubic(q(n), v, k3, true)),
        K::I => law(PortVar::Flow, cubic(p(n), v, k3, true)),
        _ if g.coin() != turn => law(PortVar::Effort, cubic(f(n), v, k3, false)),
        _ => law(PortVar::Flow, cubic(e(n), v, k3, true)),
    }
}

/// A random modulated or nonlinear graph; outputs `e(x)` and `f(x)` of every one-port. The cubic laws of the Rs in
/// `turn` are written in the other causal form (bgc does not invert a law that is not affine, `BG0601`).
fn random_model(seed: u64, turn: &[NodeIndex]) -> Model {
    let mut g = Gen(seed);
    let mut b = Builder::new("modulated");
    let w = b.input("w");
    let junctions: Vec<NodeIndex> = (0..2 + g.below(3))
        .map(|k| {
            let kind = if g.coin() { K::Zero } else { K::One };
            b.junction(kind, &format!("j{k}"))
        })
        .collect();
    let mut modulated = Vec::new();
    for k in 1..junctions.len() {
        let parent = junctions[g.below(k as u64) as usize];
        let child = junctions[k];
        let (from, to) = if g.coin() {
            (parent, child)
        } else {
            (child, parent)
        };
        let kind =
            [None, Some(K::TF), Some(K::GY), Some(K::MTF), Some(K::MGY)][g.below(5) as usize];
        let Some(kind) = kind else {
            b.bond(from, to);
            continue;
        };
        let modulus = b.param(&format!("n{k}"), g.value());
        let node = b.node(kind, &format!("tp{k}"), Relation::Modulus(modulus));
        b.bond(from, node);
        b.bond(node, to);
        if matches!(kind, K::MTF | K::MGY) {
            modulated.push(node);
        }
    }
    let mut one_ports = Vec::new();
    let mut storages = Vec::new();
    for k in 0..2 + g.below(4) {
        let kind = [K::C, K::I, K::R][g.below(3) as usize];
        let node = b.node(kind, &format!("x{k}"), Relation::Junction);
        b.model.graph[node].relation =
            one_port_law(&mut b, &mut g, (kind, node, k), turn.contains(&node));
        let j = junctions[g.below(junctions.len() as u64) as usize];
        if g.coin() {
            b.bond(j, node);
        } else {
            b.bond(node, j);
        }
        one_ports.push(node);
        if kind != K::R {
            storages.push((node, kind));
        }
    }
    for (k, kind) in [K::Se, K::Sf].into_iter().enumerate() {
        let u = b.input(&format!("u{k}"));
        let node = b.node(kind, &format!("src{k}"), source(u));
        let j = junctions[g.below(junctions.len() as u64) as usize];
        if g.coin() {
            b.bond(node, j);
        } else {
            b.bond(j, node);
        }
        one_ports.push(node);
    }
    for node in modulated {
        let pick = g.below(storages.len() as u64 + 1) as usize;
        let wave = match storages.get(pick) {
            Some(&(s, K::C)) => call(Func::Cos, q(s)),
            Some(&(s, _)) => call(Func::Sin, p(s)),
            None => call(Func::Cos, w.clone()),
        };
        let Relation::Modulus(n) = b.model.graph[node].relation.clone() else {
            continue;
        };
        b.model.graph[node].relation = Relation::Modulus(mul(n, add(c(1.0), mul(c(0.3), wave))));
    }
    for node in one_ports {
        let name = b.model.graph[node].name.clone();
        b.output(&format!("e_{name}_y"), e(node));
        b.output(&format!("f_{name}_y"), f(node));
    }
    b.finish()
}

/// The sign error the reference is given, to show that the comparison notices it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Flip {
    Nothing,
    /// The law of every element of this kind (for two-ports: its first relation) with the opposite sign.
    Kind(K),
    /// The first bond of every junction's sum counted the wrong way.
    JunctionSum,
    /// The flow of a C, I or R counted along its bond whichever way the bond is drawn (`f(x)` is the flow into it).
    OwnFlow,
}

const FLIPS: [Flip; 11] = [
    Flip::Kind(K::C),
    Flip::Kind(K::I),
    Flip::Kind(K::R),
    Flip::Kind(K::Se),
    Flip::Kind(K::Sf),
    Flip::Kind(K::TF),
    Flip::Kind(K::GY),
    Flip::Kind(K::MTF),
    Flip::Kind(K::MGY),
    Flip::JunctionSum,
    Flip::OwnFlow,
];

/// A one-port's bond and the sign of its own flow relative to the bond's flow (docs/language.md).
fn own(model: &Model, n: NodeIndex, flip: Flip) -> Option<(usize, f64)> {
    let source = matches!(model.graph[n].kind, K::Se | K::Sf);
    if let Some(b) = model.graph.edges_directed(n, Direction::Incoming).next() {
        return Some((b.id().index(), if source { -1.0 } else { 1.0 }));
    }
    let b = model.graph.edges_directed(n, Direction::Outgoing).next()?;
    // A C, I or R drawn with its bond pointing out of it: its own flow is minus the bond's.
    let wrong = flip == Flip::OwnFlow && !source;
    Some((b.id().index(), if source || wrong { 1.0 } else { -1.0 }))
}

/// The effort or the flow unknown of a bond.
type BondVar = fn(usize) -> usize;

/// A point and the bond unknowns `z` (`z[2b]` the effort, `z[2b + 1]` the flow of bond `b`).
struct At<'a> {
    model: &'a Model,
    params: &'a [f64],
    states: &'a [(NodeIndex, f64)],
    u: &'a [f64],
    t: f64,
    z: &'a [f64],
    flip: Flip,
}

impl At<'_> {
    fn eval(&self, x: &Expr) -> Option<f64> {
        let v = |x| self.eval(x);
        Some(match x {
            Expr::Const(c) => *c,
            Expr::Time => self.t,
            Expr::Param(i) => *self.params.get(*i)?,
            Expr::Input(i) => *self.u.get(*i)?,
            Expr::Displacement(n) | Expr::Momentum(n) => self.states.iter().find(|s| s.0 == *n)?.1,
            Expr::Effort(Target::Node(n)) => self.z[2 * own(self.model, *n, self.flip)?.0],
            Expr::Flow(Target::Node(n)) => {
                let (b, sign) = own(self.model, *n, self.flip)?;
                sign * self.z[2 * b + 1]
            }
            Expr::Neg(a) => -v(a)?,
            Expr::Binary(op, a, b) => {
                let (a, b) = (v(a)?, v(b)?);
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Pow => a.powf(b),
                }
            }
            Expr::Call(Func::Cos, args) if args.len() == 1 => v(&args[0])?.cos(),
            Expr::Call(Func::Sin, args) if args.len() == 1 => v(&args[0])?.sin(),
            _ => return None,
        })
    }

    /// The residuals of all node equations; `None` for an element the reference does not model.
    fn residuals(&self) -> Option<Vec<f64>> {
        let flip = self.flip;
        let (ef, fl): (BondVar, BondVar) = (|b| 2 * b, |b| 2 * b + 1);
        let z = self.z;
        let mut rows = Vec::with_capacity(z.len());
        for n in self.model.graph.node_indices() {
            let node = &self.model.graph[n];
            let sign = if flip == Flip::Kind(node.kind) {
                -1.0
            } else {
                1.0
            };
            let incident: Vec<(usize, f64)> = self
                .model
                .graph
                .edges_directed(n, Direction::Incoming)
                .map(|b| (b.id().index(), 1.0))
                .chain(
                    self.model
                        .graph
                        .edges_directed(n, Direction::Outgoing)
                        .map(|b| (b.id().index(), -1.0)),
                )
                .collect();
            let own_flow = || own(self.model, n, self.flip).map(|(b, so)| so * z[fl(b)]);
            let own_effort = || own(self.model, n, self.flip).map(|(b, _)| z[ef(b)]);
            match (&node.kind, &node.relation) {
                (K::Zero | K::One, _) => {
                    let (common, summed) = if node.kind == K::Zero {
                        (ef, fl)
                    } else {
                        (fl, ef)
                    };
                    for pair in incident.windows(2) {
                        rows.push(z[common(pair[0].0)] - z[common(pair[1].0)]);
                    }
                    let wrong = |k: usize| k == 0 && flip == Flip::JunctionSum;
                    let sum = incident.iter().enumerate().map(
                        |(k, &(_, dir))| {
                            if wrong(k) { -dir } else { dir }
                        },
                    );
                    rows.push(sum.zip(&incident).map(|(d, i)| d * z[summed(i.0)]).sum());
                }
                (K::Se, Relation::Source(x)) => rows.push(own_effort()? - sign * self.eval(x)?),
                (K::Sf, Relation::Source(x)) => rows.push(own_flow()? - sign * self.eval(x)?),
                (K::C, Relation::Linear(c)) => {
                    let q = self.states.iter().find(|s| s.0 == n)?.1;
                    rows.push(own_effort()? - sign * q / self.eval(c)?);
                }
                (K::I, Relation::Linear(m)) => {
                    let p = self.states.iter().find(|s| s.0 == n)?.1;
                    rows.push(own_flow()? - sign * p / self.eval(m)?);
                }
                (K::R, Relation::Linear(r)) => {
                    rows.push(own_effort()? - sign * self.eval(r)? * own_flow()?);
                }
                (K::C | K::I | K::R, Relation::Laws(laws)) if laws.len() == 1 => {
                    let lhs = match laws[0].lhs {
                        PortVar::Effort => own_effort()?,
                        PortVar::Flow => own_flow()?,
                        _ => return None,
                    };
                    rows.push(lhs - sign * self.eval(&laws[0].rhs)?);
                }
                (K::TF | K::MTF | K::GY | K::MGY, Relation::Modulus(m)) => {
                    let m = self.eval(m)?;
                    let i = incident.iter().find(|x| x.1 > 0.0)?.0;
                    let o = incident.iter().find(|x| x.1 < 0.0)?.0;
                    if matches!(node.kind, K::TF | K::MTF) {
                        rows.push(z[fl(i)] - sign * m * z[fl(o)]);
                        rows.push(z[ef(o)] - m * z[ef(i)]);
                    } else {
                        rows.push(z[ef(i)] - sign * m * z[fl(o)]);
                        rows.push(z[ef(o)] - m * z[fl(i)]);
                    }
                }
                _ => return None,
            }
        }
        Some(rows)
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Newton's method from zero with a central-difference Jacobian and step halving; `None` when it does not
/// converge or the Jacobian is singular.
fn newton(n: usize, residual: impl Fn(&[f64]) -> Option<Vec<f64>>) -> Option<Vec<f64>> {
    let mut z = vec![0.0; n];
    let mut r = residual(&z)?;
    if r.len() != n {
        return None;
    }
    for _ in 0..60 {
        if max_abs(&r) < 1e-11 {
            return Some(z);
        }
        let mut jacobian = vec![vec![Cx::re(0.0); n]; n];
        for j in 0..n {
            let h = 1e-6 * (1.0 + z[j].abs());
            let (mut plus, mut minus) = (z.clone(), z.clone());
            plus[j] += h;
            minus[j] -= h;
            let (rp, rm) = (residual(&plus)?, residual(&minus)?);
            for i in 0..n {
                jacobian[i][j] = Cx::re((rp[i] - rm[i]) / (2.0 * h));
            }
        }
        let step = solve(jacobian, r.iter().map(|&v| Cx::re(v)).collect())?;
        let mut lambda = 1.0;
        loop {
            let trial: Vec<f64> = z.iter().zip(&step).map(|(a, s)| a - lambda * s.0).collect();
            let rt = residual(&trial)?;
            if max_abs(&rt) < max_abs(&r) || lambda < 1e-3 {
                (z, r) = (trial, rt);
                break;
            }
            lambda /= 2.0;
        }
    }
    (max_abs(&r) < 1e-11).then_some(z)
}

struct Point {
    x: Vec<f64>,
    u: Vec<f64>,
    t: f64,
}

/// A model bgc accepts with every storage in integral causality, its equations and points to compare at.
struct Case {
    model: Model,
    eqs: Equations,
    params: Vec<f64>,
    points: Vec<Point>,
}

/// The model of a seed with every R's cubic law in the form its causality needs.
fn model_and_causality(seed: u64) -> (Model, bgc::causality::Causality) {
    let mut turn = Vec::new();
    let mut rounds = 0;
    loop {
        let model = random_model(seed, &turn);
        let (causality, _) = analyse(&model);
        let more: Vec<NodeIndex> = causality.inverted_laws.iter().map(|l| l.0).collect();
        rounds += 1;
        if more.is_empty() || rounds == 4 {
            return (model, causality);
        }
        for n in more {
            if let Some(k) = turn.iter().position(|&t| t == n) {
                turn.remove(k);
            } else {
                turn.push(n);
            }
        }
    }
}

/// The first of up to eight graphs drawn from `seed` that bgc accepts with every storage in integral causality:
/// about a third of the graphs qualify (the others mostly have a storage in derivative causality, whose cubic law
/// bgc cannot invert, `BG0601`, or need an input's derivative, `BG0602`), and the draws keep most seeds useful.
fn prepare(seed: u64) -> Option<Case> {
    (0..8u64)
        .find_map(|draw| prepare_graph(seed.wrapping_add(draw.wrapping_mul(0x9E37_79B9_7F4A_7C15))))
}

fn prepare_graph(seed: u64) -> Option<Case> {
    let (model, causality) = model_and_causality(seed);
    if !causality.consistent {
        return None;
    }
    let (eqs, diags) = derive(&model, &causality);
    if bgc::diagnostic::has_errors(&diags) {
        return None;
    }
    let integral = model
        .graph
        .node_indices()
        .filter(|&n| matches!(model.graph[n].kind, K::C | K::I))
        .all(|n| eqs.states.iter().any(|s| s.node == Some(n)));
    if !integral || eqs.states.len() != eqs.energy_states {
        return None;
    }
    let mut rng = Rng(seed);
    let mut uniform = |n: usize| (0..n).map(|_| 2.0 * rng.next() - 1.0).collect::<Vec<_>>();
    let points = (0..3)
        .map(|_| Point {
            x: uniform(eqs.states.len()),
            u: uniform(model.inputs.len()),
            t: uniform(1)[0] + 1.0,
        })
        .collect();
    let params = eqs.default_params();
    Some(Case {
        model,
        eqs,
        params,
        points,
    })
}

#[derive(Debug)]
enum Mismatch {
    /// The reference has no solution (Newton's method did not converge).
    Unsolved,
    Differs(String),
}

/// The reference's rates and outputs at a point, with `flip` applied.
fn reference(case: &Case, point: &Point, flip: Flip) -> Option<(Vec<f64>, Vec<f64>)> {
    let states: Vec<(NodeIndex, f64)> = case
        .eqs
        .states
        .iter()
        .zip(&point.x)
        .map(|(s, &x)| Some((s.node?, x)))
        .collect::<Option<_>>()?;
    let at = |z| At {
        model: &case.model,
        params: &case.params,
        states: &states,
        u: &point.u,
        t: point.t,
        z,
        flip,
    };
    let z = newton(2 * case.model.graph.edge_count(), |z| {
        At { z, ..at(&[]) }.residuals()
    })?;
    let at = At { z: &z, ..at(&[]) };
    let rates = case
        .eqs
        .states
        .iter()
        .map(|s| {
            let n = s.node?;
            match s.kind {
                StateKind::Displacement => at.eval(&f(n)),
                StateKind::Momentum => at.eval(&e(n)),
                _ => None,
            }
        })
        .collect::<Option<_>>()?;
    let outputs = case
        .model
        .outputs
        .iter()
        .map(|o| at.eval(&o.value))
        .collect::<Option<_>>()?;
    Some((rates, outputs))
}

fn close(what: &str, got: &[f64], want: &[f64]) -> Result<(), Mismatch> {
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        if (g - w).abs() > 1e-7 * (1.0 + w.abs()) {
            return Err(Mismatch::Differs(format!(
                "{what} {k}: bgc {g}, reference {w}"
            )));
        }
    }
    Ok(())
}

/// bgc's rates and outputs against the reference at every point of the case.
fn check(case: &Case, flip: Flip) -> Result<(), Mismatch> {
    for point in &case.points {
        let (p, x, u, t) = (&case.params, &point.x, &point.u, point.t);
        let rates = case.eqs.rates_at(p, x, u, t);
        let outputs = case.eqs.outputs_at(p, x, u, t);
        let (Ok(rates), Ok(outputs)) = (rates, outputs) else {
            return Err(Mismatch::Differs("bgc could not evaluate".into()));
        };
        let (want_rates, want_outputs) = reference(case, point, flip).ok_or(Mismatch::Unsolved)?;
        close("rate", &rates, &want_rates)?;
        close("output", &outputs, &want_outputs)?;
    }
    Ok(())
}

/// Compares one seed; `Ok(false)` when it is skipped (refused by bgc, derivative causality, no reference solution).
fn compare(seed: u64) -> Result<bool, String> {
    let Some(case) = prepare(seed) else {
        return Ok(false);
    };
    match check(&case, Flip::Nothing) {
        Ok(()) => Ok(true),
        Err(Mismatch::Unsolved) => Ok(false),
        Err(Mismatch::Differs(why)) => Err(format!("seed {seed}: {why}")),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn modulated_graphs_match_the_newton_reference(seed in any::<u64>()) {
        compare(seed).map_err(TestCaseError::fail)?;
    }
}

/// Of 64 fixed seeds, enough are compared (within their eight draws) for the property to mean something.
#[test]
fn most_modulated_graphs_are_compared() {
    let mut compared = 0;
    for seed in 0..64u64 {
        if compare(seed).unwrap_or_else(|e| panic!("{e}")) {
            compared += 1;
        }
    }
    assert!(compared >= 48, "only {compared} of 64 seeds were compared");
}

/// A sign error of any element kind, or of a junction's sum, in the reference makes the comparison fail for some
/// seed: the comparison is sensitive to each of them.
#[test]
fn a_flipped_sign_in_the_reference_is_caught() {
    let cases: Vec<Case> = (0..64u64)
        .filter_map(prepare)
        .filter(|case| check(case, Flip::Nothing).is_ok())
        .collect();
    for flip in FLIPS {
        let caught = cases
            .iter()
            .any(|case| matches!(check(case, flip), Err(Mismatch::Differs(_))));
        assert!(caught, "{flip:?} in the reference went unnoticed");
    }
}
