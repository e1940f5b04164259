//! Differential test of mechanisms written with modulated transformers against Lagrange's equations.
//!
//! A random mechanism has one to three generalised coordinates `θ_k = ∫ f(a_k)` (`var`s) of 1-junctions `a_k`,
//! each with an effort source `u_k`, and maybe an inertia `J_k` and a damper `b_k`; and one to three bodies, each an
//! inertia `m_i` on a 1-junction `b_i` whose velocity is `Σ_k n_ik(θ) f(a_k)` over one or two coordinates (a 0-junction
//! sums the outputs of MTFs, or of a TF for a constant `n`), maybe with a damper `d_i` and a force
//! `w_i (1 + 0.5 cos θ_l)` of a modulated source. The moduli are `n`, `n (1 + 0.5 cos θ_l)`, `n sin θ_l` or
//! `n cos θ_l`: the last two vanish at some configurations, where a body's velocity stops determining a
//! coordinate's, which is where dividing by a modulus (plain sequential causality) fails and bgc's mass-matrix form
//! (`kinematic.rs`) must hold.
//!
//! The reference is built from that description alone: `T = ½ Σ_k J_k v_k² + ½ Σ_i m_i (J_i(θ) v)²` gives the
//! inertia matrix `M(θ)`, the generalised force is `Q_k = u_k − b_k v_k + Σ_i n_ik (w_i(θ) − d_i (J_i v))`, and
//! `M v̇ = Q − Ṁ v + ∂T/∂θ` ([`lagrange::accelerations`], `∂M/∂θ` by differences). bgc's state is whatever it
//! chooses (the `θ_k` and velocities of its own choosing); at a random state, `v = f(a_k)` is read from bgc's
//! outputs, and bgc's `v̇` is the derivative of those outputs along bgc's rates (extrapolated central differences).
//! bgc's stored energy must be the description's `½ v' M(θ) v`, and its energy terms must balance power.

use crate::equations_support::lagrange;
use crate::equations_support::power::{energy_total, power_balance};
use crate::equations_support::*;

use bgc::causality::analyse;
use bgc::equations::{EnergyKind, Equations, derive};
use bgc::ir::{Expr, Func, Model, Relation};
use bgc::syntax::ast::ElementKind as K;
use petgraph::graph::NodeIndex;

/// A modulus in the coordinates: `n`, `n (1 + 0.5 cos θ_l)`, `n sin θ_l` or `n cos θ_l`.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Constant,
    Offset(usize),
    Sine(usize),
    Cosine(usize),
}

impl Shape {
    fn at(self, n: f64, theta: &[f64]) -> f64 {
        match self {
            Shape::Constant => n,
            Shape::Offset(l) => n * (1.0 + 0.5 * theta[l].cos()),
            Shape::Sine(l) => n * theta[l].sin(),
            Shape::Cosine(l) => n * theta[l].cos(),
        }
    }

    /// The rate of the modulus along `θ̇`.
    fn rate(self, n: f64, theta: &[f64], theta_dot: &[f64]) -> f64 {
        match self {
            Shape::Constant => 0.0,
            Shape::Offset(l) => -0.5 * n * theta[l].sin() * theta_dot[l],
            Shape::Sine(l) => n * theta[l].cos() * theta_dot[l],
            Shape::Cosine(l) => -n * theta[l].sin() * theta_dot[l],
        }
    }

    fn expr(self, n: Expr, theta: &[Expr]) -> Expr {
        let call = |f, l: usize| Expr::Call(f, vec![theta[l].clone()]);
        match self {
            Shape::Constant => n,
            Shape::Offset(l) => mul(n, add(c(1.0), mul(c(0.5), call(Func::Cos, l)))),
            Shape::Sine(l) => mul(n, call(Func::Sin, l)),
            Shape::Cosine(l) => mul(n, call(Func::Cos, l)),
        }
    }
}

/// What the reference knows of a mechanism: its description, not its graph.
#[derive(Debug, Default)]
struct Mechanism {
    /// Per coordinate: the inertia `J_k` (0 for none) and the damping `b_k` (0 for none).
    coordinates: Vec<(f64, f64)>,
    /// Per body: its mass, its damping, its force's amplitude and coordinate (`w (1 + 0.5 cos θ_l)`), and its
    /// velocity's terms `(k, n, shape)`.
    bodies: Vec<Body>,
}

#[derive(Debug)]
struct Body {
    mass: f64,
    damping: f64,
    force: Option<(f64, usize)>,
    terms: Vec<(usize, f64, Shape)>,
}

impl Body {
    /// `J_i(θ)`: the body's velocity per unit velocity of each coordinate.
    fn row(&self, theta: &[f64]) -> Vec<f64> {
        let mut row = vec![0.0; theta.len()];
        for &(k, n, shape) in &self.terms {
            row[k] += shape.at(n, theta);
        }
        row
    }

    /// `J̇_i v`: the part of the body's acceleration that the changing moduli give (`θ̇ = v`).
    fn drift(&self, theta: &[f64], v: &[f64]) -> f64 {
        let terms = self.terms.iter();
        terms
            .map(|&(k, n, shape)| shape.rate(n, theta, v) * v[k])
            .sum()
    }
}

impl Mechanism {
    fn mass_matrix(&self, theta: &[f64]) -> Vec<f64> {
        let n = theta.len();
        let mut m = vec![0.0; n * n];
        for (k, &(inertia, _)) in self.coordinates.iter().enumerate() {
            m[k * n + k] += inertia;
        }
        for body in &self.bodies {
            let row = body.row(theta);
            for i in 0..n {
                for j in 0..n {
                    m[i * n + j] += body.mass * row[i] * row[j];
                }
            }
        }
        m
    }

    /// `Q(θ, v, u)`: the sources, the dampers and the bodies' forces, each through its velocity's row.
    fn forces(&self, theta: &[f64], v: &[f64], u: &[f64]) -> Vec<f64> {
        let mut q: Vec<f64> = (0..theta.len())
            .map(|k| u[k] - self.coordinates[k].1 * v[k])
            .collect();
        for body in &self.bodies {
            let row = body.row(theta);
            let speed: f64 = row.iter().zip(v).map(|(a, b)| a * b).sum();
            let push = body
                .force
                .map_or(0.0, |(w, l)| w * (1.0 + 0.5 * theta[l].cos()));
            for k in 0..theta.len() {
                q[k] += row[k] * (push - body.damping * speed);
            }
        }
        q
    }

    /// `v̇` from `M v̇ = Q − Σ_i m_i J_iᵀ (J̇_i v)`: each body's momentum `m_i J_i v` changes at the rate of the
    /// forces on it, and the coordinates take those forces through `J_iᵀ` (d'Alembert); `None` for a singular `M`.
    fn accelerations(&self, theta: &[f64], v: &[f64], u: &[f64]) -> Option<Vec<f64>> {
        let n = theta.len();
        let mut rhs = self.forces(theta, v, u);
        for body in &self.bodies {
            let (row, drift) = (body.row(theta), body.drift(theta, v));
            for k in 0..n {
                rhs[k] -= body.mass * row[k] * drift;
            }
        }
        lagrange::solve_dense(&self.mass_matrix(theta), rhs)
    }

    /// `v̇` by Lagrange's equations for `T(θ, v)` (`∂M/∂θ` by differences): the same as
    /// [`Mechanism::accelerations`] when every body's velocity is the rate of a position, `J_i = ∂x_i/∂θ`.
    fn lagrange(&self, theta: &[f64], v: &[f64], u: &[f64]) -> Option<Vec<f64>> {
        let mass = |t: &[f64]| Some(self.mass_matrix(t));
        lagrange::accelerations(&mass, theta, v, &self.forces(theta, v, u))
    }

    /// Whether `M(θ)` is well away from singular: `det M / (tr M)^(n−1)`, a lower bound of its smallest
    /// eigenvalue, at least 0.05 (the masses and moduli are of order 1). A coordinate without an inertia of its own
    /// whose bodies' moduli all vanish has a singular `M` there, in the mechanism itself.
    fn regular_at(&self, theta: &[f64]) -> bool {
        let n = theta.len();
        let mut m = self.mass_matrix(theta);
        let trace: f64 = (0..n).map(|k| m[k * n + k]).sum();
        let mut det = 1.0;
        for col in 0..n {
            let pivot = m[col * n + col];
            det *= pivot;
            if pivot.abs() < 1e-12 {
                return false;
            }
            for row in col + 1..n {
                let factor = m[row * n + col] / pivot;
                for k in col..n {
                    m[row * n + k] -= factor * m[col * n + k];
                }
            }
        }
        det / trace.powi(n as i32 - 1) >= 0.05
    }

    /// Whether every body's velocity is the rate of a position: each modulus varies only with its own coordinate.
    fn holonomic(&self) -> bool {
        let own = |&(k, _, shape): &(usize, f64, Shape)| match shape {
            Shape::Constant => true,
            Shape::Offset(l) | Shape::Sine(l) | Shape::Cosine(l) => l == k,
        };
        self.bodies.iter().all(|b| b.terms.iter().all(own))
    }
}

/// A random mechanism as a bond graph, and its description.
fn random_mechanism(seed: u64) -> (Model, Mechanism) {
    let mut g = Gen(seed);
    let mut b = Builder::new("mechanism");
    let mut mech = Mechanism::default();
    let coordinates = 1 + g.below(3) as usize;
    let mut junctions = Vec::new();
    let mut thetas = Vec::new();
    for k in 0..coordinates {
        let (a, theta, description) = add_coordinate(&mut b, &mut g, k);
        junctions.push(a);
        thetas.push(theta);
        mech.coordinates.push(description);
    }
    for i in 0..1 + g.below(3) as usize {
        let body = add_body(&mut b, &mut g, i, (&junctions, &thetas));
        mech.bodies.push(body);
    }
    for (k, &a) in junctions.iter().enumerate() {
        b.output(&format!("v{k}"), f(a));
    }
    (b.finish(), mech)
}

/// Coordinate `k`: its 1-junction with a source, maybe an inertia and a damper; the junction, `θ_k` and its
/// `(J_k, b_k)`.
fn add_coordinate(b: &mut Builder, g: &mut Gen, k: usize) -> (NodeIndex, Expr, (f64, f64)) {
    let a = b.junction(K::One, &format!("a{k}"));
    let theta = b.var(&format!("th{k}"), f(a));
    let u = b.input(&format!("u{k}"));
    let src = b.node(K::Se, &format!("src{k}"), source(u));
    b.bond(src, a);
    let mut one_port = |kind, name: String| -> f64 {
        if g.coin() {
            return 0.0;
        }
        let v = g.value();
        let value = b.param(&format!("v_{name}"), v);
        let node = b.node(kind, &name, linear(value));
        hang(b, g, a, node);
        v
    };
    let inertia = one_port(K::I, format!("ja{k}"));
    let damping = one_port(K::R, format!("ra{k}"));
    (a, theta, (inertia, damping))
}

/// Body `i`: an inertia on a 1-junction whose velocity is the sum of one or two moduli times coordinates' velocities,
/// maybe with a damper and a force.
fn add_body(
    b: &mut Builder,
    g: &mut Gen,
    i: usize,
    (junctions, thetas): (&[NodeIndex], &[Expr]),
) -> Body {
    let coordinates = junctions.len() as u64;
    let body = b.junction(K::One, &format!("b{i}"));
    let mass = g.value();
    let value = b.param(&format!("m{i}"), mass);
    let inertia = b.node(K::I, &format!("mb{i}"), linear(value));
    hang(b, g, body, inertia);
    let first = g.below(coordinates) as usize;
    let mut ks = vec![first];
    if coordinates > 1 && g.coin() {
        ks.push((first + 1 + g.below(coordinates - 1) as usize) % coordinates as usize);
    }
    // The body's velocity: one two-port straight to the coordinate, or a 0-junction summing two.
    let sum = (ks.len() > 1).then(|| {
        let s = b.junction(K::Zero, &format!("s{i}"));
        b.bond(body, s);
        s
    });
    let mut terms = Vec::new();
    for (t, &k) in ks.iter().enumerate() {
        // Half of the moduli vary with their own coordinate (a position's Jacobian, `x = ∫ n(θ_k) dθ_k`).
        let l = if g.coin() {
            k
        } else {
            g.below(coordinates) as usize
        };
        let shape = [
            Shape::Constant,
            Shape::Offset(l),
            Shape::Sine(l),
            Shape::Cosine(l),
        ][g.below(4) as usize];
        let n = g.value();
        let modulus = b.param(&format!("n{i}_{t}"), n);
        let kind = if matches!(shape, Shape::Constant) {
            K::TF
        } else {
            K::MTF
        };
        let relation = Relation::Modulus(shape.expr(modulus, thetas));
        let two = b.node(kind, &format!("tp{i}_{t}"), relation);
        b.bond(sum.unwrap_or(body), two);
        b.bond(two, junctions[k]);
        terms.push((k, n, shape));
    }
    let damping = if g.coin() {
        let d = g.value();
        let value = b.param(&format!("d{i}"), d);
        let r = b.node(K::R, &format!("rb{i}"), linear(value));
        hang(b, g, body, r);
        d
    } else {
        0.0
    };
    let force = g.coin().then(|| {
        let (w, l) = (g.value() - 1.5, g.below(coordinates) as usize);
        let amplitude = b.param(&format!("w{i}"), w);
        let cos = Expr::Call(Func::Cos, vec![thetas[l].clone()]);
        let value = mul(amplitude, add(c(1.0), mul(c(0.5), cos)));
        let push = b.node(K::MSe, &format!("push{i}"), source(value));
        b.bond(push, body);
        (w, l)
    });
    Body {
        mass,
        damping,
        force,
        terms,
    }
}

/// A one-port on a junction, its bond drawn either way.
fn hang(b: &mut Builder, g: &mut Gen, junction: NodeIndex, node: NodeIndex) {
    if g.coin() {
        b.bond(junction, node);
    } else {
        b.bond(node, junction);
    }
}

/// The index of state `name`.
fn state(eqs: &Equations, name: &str) -> Option<usize> {
    eqs.states.iter().position(|s| s.name == name)
}

/// bgc's `θ`, `v`, `θ̇` and `v̇` at state `x` (`v̇` the outputs' derivative along the rates, central differences at
/// two steps, extrapolated).
type Motion = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

fn bgc_motion(eqs: &Equations, p: &[f64], x: &[f64], u: &[f64]) -> Option<Motion> {
    let coordinates = eqs.outputs.len();
    let index: Vec<usize> = (0..coordinates)
        .map(|k| state(eqs, &format!("th{k}")))
        .collect::<Option<_>>()?;
    let rates = eqs.rates_at(p, x, u, 0.0).ok()?;
    let v = eqs.outputs_at(p, x, u, 0.0).ok()?;
    let along = |h: f64| -> Option<Vec<f64>> {
        let shifted = |sign: f64| -> Vec<f64> {
            x.iter()
                .zip(&rates)
                .map(|(a, r)| a + sign * h * r)
                .collect()
        };
        let plus = eqs.outputs_at(p, &shifted(1.0), u, 0.0).ok()?;
        let minus = eqs.outputs_at(p, &shifted(-1.0), u, 0.0).ok()?;
        Some(central_difference(&plus, &minus, h))
    };
    // Steps of at most 1e-3 in any state.
    let h = 1e-3 / (1.0 + rates.iter().fold(0.0f64, |m, r| m.max(r.abs())));
    let vdot = richardson(&along(2.0 * h)?, &along(h)?);
    let theta = index.iter().map(|&i| x[i]).collect();
    let theta_dot = index.iter().map(|&i| rates[i]).collect();
    Some((theta, v, theta_dot, vdot))
}

/// bgc's stored energy at `x` against the description's `T = ½ v' M(θ) v`, and the power balance along bgc's
/// motion (a central difference of the stored energy along `ẋ`, steps of at most 1e-6) against the supplied minus
/// the dissipated power.
fn energy_agrees(
    eqs: &Equations,
    mech: &Mechanism,
    (x, u): (&[f64], &[f64]),
    (theta, v): (&[f64], &[f64]),
) -> Result<(), String> {
    let p = eqs.default_params();
    let kinetic = 0.5 * lagrange::quadratic_form(&mech.mass_matrix(theta), v);
    let stored =
        energy_total(eqs, &p, EnergyKind::Stored, (x, u, 0.0)).ok_or("no stored energy")?;
    if (stored - kinetic).abs() > 1e-9 * (1.0 + kinetic.abs()) {
        return Err(format!("stored energy {stored}, T = {kinetic}"));
    }
    power_balance(eqs, &p, (x, u, 0.0)).ok_or("no rates or energy terms")?
}

/// Compares a seed's mechanism at three random states, those where `M` is nearly singular left out: `Ok(false)`
/// when bgc refuses the mechanism or no state is left, else `Ok(true)` or the first difference beyond 1e-6
/// (relative to `1 + |want|`).
fn compare(seed: u64) -> Result<bool, String> {
    let (model, mech) = random_mechanism(seed);
    let (causality, _) = analyse(&model);
    if !causality.consistent {
        return Ok(false);
    }
    let (eqs, diags) = derive(&model, &causality);
    if bgc::diagnostic::has_errors(&diags) {
        return Ok(false);
    }
    let p = eqs.default_params();
    let mut rng = Rng(seed);
    let mut compared = false;
    for _ in 0..3 {
        let x: Vec<f64> = (0..eqs.states.len())
            .map(|_| 4.0 * rng.next() - 2.0)
            .collect();
        let u: Vec<f64> = (0..model.inputs.len())
            .map(|_| 2.0 * rng.next() - 1.0)
            .collect();
        let (theta, v, theta_dot, vdot) = bgc_motion(&eqs, &p, &x, &u)
            .ok_or_else(|| format!("seed {seed}: bgc could not evaluate at {x:?}"))?;
        if !mech.regular_at(&theta) {
            continue;
        }
        let want = mech.accelerations(&theta, &v, &u).ok_or("no solution")?;
        compared = true;
        energy_agrees(&eqs, &mech, (&x, &u), (&theta, &v))
            .map_err(|e| format!("seed {seed}: {e} at x = {x:?}"))?;
        if mech.holonomic() {
            let lagrange = mech
                .lagrange(&theta, &v, &u)
                .ok_or("no Lagrange solution")?;
            let gap = lagrange
                .iter()
                .zip(&want)
                .map(|(a, b)| (a - b).abs() / (1.0 + b.abs()))
                .fold(0.0, f64::max);
            assert!(
                gap < 1e-7,
                "seed {seed}: d'Alembert and Lagrange differ by {gap}"
            );
        }
        let pairs = theta_dot.iter().zip(&v).chain(vdot.iter().zip(&want));
        for (k, (got, want)) in pairs.enumerate() {
            if (got - want).abs() > 1e-6 * (1.0 + want.abs()) {
                return Err(format!(
                    "seed {seed}: {} {}: bgc {got}, reference {want} at x = {x:?} (states {:?})",
                    if k < theta.len() { "dθ/dt" } else { "dv/dt" },
                    k % theta.len(),
                    eqs.states.iter().map(|s| &s.name).collect::<Vec<_>>()
                ));
            }
        }
    }
    Ok(compared)
}

/// Random mechanisms (300 seeds) give the reference's `θ̇` and `v̇` at random states: those bgc keeps in momenta
/// and those it puts in the mass-matrix form, with moduli that vanish and with bodies whose velocity is or is not
/// the rate of a position. A sweep of 5,000 seeds (3,844 compared, 970 in the mass-matrix form) found no
/// difference; the seeds bgc refuses have causal conflicts (a coordinate no inertia, damper or body sets the flow
/// of, for one).
#[test]
fn mechanisms_of_modulated_transformers_obey_newton_and_lagrange() {
    let (mut compared, mut mass_form, mut holonomic) = (0, 0, 0);
    for seed in 0..300u64 {
        if !compare(seed).unwrap_or_else(|e| panic!("{e}")) {
            continue;
        }
        let (model, mech) = random_mechanism(seed);
        let (causality, _) = analyse(&model);
        let (eqs, _) = derive(&model, &causality);
        compared += 1;
        mass_form += usize::from(!eqs.mass.is_empty());
        holonomic += usize::from(mech.holonomic());
    }
    eprintln!(
        "{compared} mechanisms compared, {mass_form} in the mass-matrix form, {holonomic} holonomic"
    );
    assert!(
        compared >= 200,
        "only {compared} of 300 mechanisms compared"
    );
    assert!(
        mass_form >= 40,
        "only {mass_form} compared in the mass-matrix form"
    );
    assert!(
        holonomic >= 60,
        "only {holonomic} holonomic mechanisms compared"
    );
}
