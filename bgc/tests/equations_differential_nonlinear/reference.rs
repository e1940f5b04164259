//! The acausal reference of the nonlinear differential test.
//!
//! At a point `(x, u, t)` every storage in integral causality has its state given. The unknowns are every bond's
//! effort and flow (`z[2b]`, `z[2b + 1]`) and, for each storage in derivative causality, its energy variable `s`;
//! the equations are the junction sums and equalities, the element laws (a storage's law in its energy variable,
//! given or unknown), the two-port relations with the modulus evaluated at the point, the sources, and, for each
//! storage in derivative causality, that its rate (`f` into a C, `e` on an I) equals a given value `r`.
//!
//! A storage in derivative causality has the rate its energy variable has along the motion,
//! `r = ṡ = (∂s/∂x) ẋ(r) + ∂s/∂t`, with the inputs held. The reference finds `∂s/∂x` and `∂s/∂t` by Richardson-extrapolated central
//! differences of the static solution, then solves `r - (∂s/∂x) ẋ(r) - ∂s/∂t = 0` by Newton's method. This holds
//! when `s` does not depend on `r` (its constraint is kinematic, as for an inertia tied to another through
//! transformers); a case where it does is not compared.

use super::fields::port_bond;
use super::{Case, Flip, Point};
use crate::equations_support::lagrange;
use crate::equations_support::*;

use bgc::equations::StateKind;
use bgc::ir::{Expr, Func, Model, PortVar, Relation, Target};
use bgc::syntax::ast::{BinOp, ElementKind as K};
use petgraph::Direction;
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;

/// A one-port's bond and the sign of its own flow relative to the bond's flow (docs/language.md).
fn own(model: &Model, n: NodeIndex, flip: Flip) -> Option<(usize, f64)> {
    let source = matches!(model.graph[n].kind, K::Se | K::Sf | K::MSe | K::MSf);
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

/// The value of a storage's energy variable at a point: a one-port's (`port` None), a field port's displacement or
/// an `IF` port's flow (`velocity`).
#[derive(Clone, Copy)]
struct Given {
    node: NodeIndex,
    port: Option<u32>,
    velocity: bool,
    value: f64,
}

fn given(states: &[Given], node: NodeIndex, port: Option<u32>, velocity: bool) -> Option<f64> {
    let found = states
        .iter()
        .find(|s| (s.node, s.port, s.velocity) == (node, port, velocity));
    Some(found?.value)
}

/// A point and the bond unknowns `z` (`z[2b]` the effort, `z[2b + 1]` the flow of bond `b`).
struct At<'a> {
    model: &'a Model,
    params: &'a [f64],
    states: &'a [Given],
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
            Expr::Displacement(n) | Expr::Momentum(n) => given(self.states, *n, None, false)?,
            Expr::FieldPort { node, var, port } => match var {
                PortVar::Displacement => given(self.states, *node, Some(*port), false)?,
                PortVar::Effort => self.z[2 * port_bond(self.model, *node, *port)?.0],
                PortVar::Flow => {
                    let (b, sign) = port_bond(self.model, *node, *port)?;
                    sign * self.z[2 * b + 1]
                }
                PortVar::Momentum => return None,
            },
            Expr::Effort(Target::Bond(b)) => self.z[2 * b.index()],
            Expr::Flow(Target::Bond(b)) => self.z[2 * b.index() + 1],
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
                (K::Se | K::MSe, Relation::Source(x)) => {
                    rows.push(own_effort()? - sign * self.eval(x)?)
                }
                (K::Sf | K::MSf, Relation::Source(x)) => {
                    rows.push(own_flow()? - sign * self.eval(x)?)
                }
                (K::C, Relation::Linear(c)) => {
                    let q = given(self.states, n, None, false)?;
                    rows.push(own_effort()? - sign * q / self.eval(c)?);
                }
                (K::I, Relation::Linear(m)) => {
                    let p = given(self.states, n, None, false)?;
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
                (K::CF | K::RF, Relation::Laws(laws)) => {
                    for law in laws {
                        let (b, so) = port_bond(self.model, n, law.port)?;
                        let lhs = match law.lhs {
                            PortVar::Effort => z[ef(b)],
                            PortVar::Flow => so * z[fl(b)],
                            _ => return None,
                        };
                        rows.push(lhs - sign * self.eval(&law.rhs)?);
                    }
                }
                // An `IF`'s port flows are its velocity states; its efforts are set by the rest of the graph.
                (K::IF, Relation::MassMatrix { n: ports, .. }) => {
                    for k in 0..*ports {
                        let (b, so) = port_bond(self.model, n, k)?;
                        let v = given(self.states, n, Some(k), true)?;
                        rows.push(so * z[fl(b)] - sign * v);
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

/// The convergence bound of the static solve (largest residual).
const STATIC_TOL: f64 = 1e-11;

/// Newton's method from `start` with a central-difference Jacobian and step halving, until the largest residual
/// is below `tol`; `None` when it does not converge or the Jacobian is singular.
fn newton(
    start: Vec<f64>,
    tol: f64,
    residual: impl Fn(&[f64]) -> Option<Vec<f64>>,
) -> Option<Vec<f64>> {
    let n = start.len();
    let mut z = start;
    let mut r = residual(&z)?;
    if r.len() != n {
        return None;
    }
    for _ in 0..60 {
        if max_abs(&r) < tol {
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
    (max_abs(&r) < tol).then_some(z)
}

/// The static problem of a case: its unknowns are `z` (the bonds) followed by `s` (the storages in derivative
/// causality, in the order of [`Case::dependent`]).
struct Static<'a> {
    case: &'a Case,
    flip: Flip,
    u: &'a [f64],
}

impl Static<'_> {
    fn bonds(&self) -> usize {
        2 * self.case.model.graph.edge_count()
    }

    /// The node of every storage with its energy variable: the given states `x`, then the unknowns `s`.
    fn states(&self, x: &[f64], s: &[f64]) -> Option<Vec<Given>> {
        let known = self.case.eqs.states.iter().zip(x).map(|(spec, &value)| {
            Some(Given {
                node: spec.node?,
                port: spec.port,
                velocity: spec.kind == StateKind::Velocity,
                value,
            })
        });
        let unknown = self.case.dependent.iter().zip(s).map(|(&node, &value)| {
            Some(Given {
                node,
                port: None,
                velocity: false,
                value,
            })
        });
        known.chain(unknown).collect()
    }

    fn at<'b>(&'b self, states: &'b [Given], t: f64, z: &'b [f64]) -> At<'b> {
        At {
            model: &self.case.model,
            params: &self.case.params,
            states,
            u: self.u,
            t,
            z,
            flip: self.flip,
        }
    }

    /// The rate of a storage: the flow into a C, the effort on an I.
    fn rate(at: &At, n: NodeIndex) -> Option<f64> {
        match at.model.graph[n].kind {
            K::C => at.eval(&f(n)),
            _ => at.eval(&e(n)),
        }
    }

    /// Solves for `z` and `s` at `(x, t)` with the rates `r` of the storages in derivative causality given.
    fn solve(&self, x: &[f64], t: f64, r: &[f64], start: &[f64]) -> Option<Vec<f64>> {
        let bonds = self.bonds();
        newton(start.to_vec(), STATIC_TOL, |w| {
            let (z, s) = w.split_at(bonds);
            let states = self.states(x, s)?;
            let at = self.at(&states, t, z);
            let mut rows = at.residuals()?;
            for (&n, &r) in self.case.dependent.iter().zip(r) {
                rows.push(Self::rate(&at, n)? - r);
            }
            Some(rows)
        })
    }

    /// The rates of the given states at the solution `w`.
    fn rates(&self, x: &[f64], t: f64, w: &[f64]) -> Option<Vec<f64>> {
        let (z, s) = w.split_at(self.bonds());
        let states = self.states(x, s)?;
        let at = self.at(&states, t, z);
        let specs = self.case.eqs.states.iter();
        specs
            .map(|spec| match (spec.kind, spec.port) {
                (StateKind::Displacement | StateKind::Momentum, None) => {
                    Self::rate(&at, spec.node?)
                }
                (StateKind::Displacement, Some(k)) => at.eval(&Expr::FieldPort {
                    node: spec.node?,
                    var: PortVar::Flow,
                    port: k,
                }),
                (StateKind::Velocity, Some(k)) => Self::accelerations(&at, spec.node?)?
                    .get(k as usize)
                    .copied(),
                _ => None,
            })
            .collect()
    }

    /// The rates of an `IF`'s port flows at `at`, from its definition (see `fields.rs`).
    fn accelerations(at: &At, node: NodeIndex) -> Option<Vec<f64>> {
        let Relation::MassMatrix { n, entries } = &at.model.graph[node].relation else {
            return None;
        };
        let ports = 0..*n;
        let q: Vec<f64> = ports
            .clone()
            .map(|k| given(at.states, node, Some(k), false))
            .collect::<Option<_>>()?;
        let v: Vec<f64> = ports
            .clone()
            .map(|k| given(at.states, node, Some(k), true))
            .collect::<Option<_>>()?;
        let e: Vec<f64> = ports
            .map(|k| Some(at.z[2 * port_bond(at.model, node, k)?.0]))
            .collect::<Option<_>>()?;
        let mass = |shifted: &[f64]| -> Option<Vec<f64>> {
            let states: Vec<Given> = at
                .states
                .iter()
                .map(|s| match s.port {
                    Some(k) if s.node == node && !s.velocity => Given {
                        value: shifted[k as usize],
                        ..*s
                    },
                    _ => *s,
                })
                .collect();
            let at = At {
                states: &states,
                ..*at
            };
            entries.iter().map(|m| at.eval(m)).collect()
        };
        lagrange::accelerations(&mass, &q, &v, &e)
    }

    /// `∂s/∂v` along a direction of `(x, t)`, by central differences at steps `h` and `h/2`, extrapolated.
    fn slope(&self, x: &[f64], t: f64, dx: &[f64], dt: f64, w: &[f64]) -> Option<Vec<f64>> {
        let bonds = self.bonds();
        let zero = vec![0.0; self.case.dependent.len()];
        let central = |h: f64| -> Option<Vec<f64>> {
            let shifted = |sign: f64| {
                let x: Vec<f64> = x.iter().zip(dx).map(|(a, d)| a + sign * h * d).collect();
                let w = self.solve(&x, t + sign * h * dt, &zero, w)?;
                Some(w[bonds..].to_vec())
            };
            Some(central_difference(&shifted(1.0)?, &shifted(-1.0)?, h))
        };
        Some(richardson(&central(1e-2)?, &central(5e-3)?))
    }

    /// The solution at a point with the storages in derivative causality at their consistent rates.
    fn consistent(&self, x: &[f64], t: f64) -> Option<Vec<f64>> {
        let bonds = self.bonds();
        let d = self.case.dependent.len();
        let zero = vec![0.0; d];
        let w0 = self.solve(x, t, &zero, &vec![0.0; bonds + d])?;
        if d == 0 {
            return Some(w0);
        }
        // `s` must not depend on the rates given, or `ṡ` is not a function of `(x, t)` alone.
        let w1 = self.solve(x, t, &vec![1.0; d], &w0)?;
        if max_abs(&diff(&w1[bonds..], &w0[bonds..])) > 1e-9 {
            return None;
        }
        let columns: Vec<Vec<f64>> = (0..x.len())
            .map(|j| {
                let unit: Vec<f64> = (0..x.len()).map(|k| f64::from(k == j)).collect();
                self.slope(x, t, &unit, 0.0, &w0)
            })
            .collect::<Option<_>>()?;
        let in_time = self.slope(x, t, &vec![0.0; x.len()], 1.0, &w0)?;
        let r = newton(zero, 1e-10, |r| {
            let xdot = self.rates(x, t, &self.solve(x, t, r, &w0)?)?;
            let drift = (0..d).map(|i| {
                let along: f64 = columns.iter().zip(&xdot).map(|(col, v)| col[i] * v).sum();
                r[i] - along - in_time[i]
            });
            Some(drift.collect())
        })?;
        self.solve(x, t, &r, &w0)
    }
}

fn diff(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

/// The reference's rates and outputs at a point, with `flip` applied; `None` when it has no solution.
pub(super) fn reference(case: &Case, point: &Point, flip: Flip) -> Option<(Vec<f64>, Vec<f64>)> {
    let problem = Static {
        case,
        flip,
        u: &point.u,
    };
    let (x, t) = (&point.x, point.t);
    let w = problem.consistent(x, t)?;
    let rates = problem.rates(x, t, &w)?;
    let (z, s) = w.split_at(problem.bonds());
    let states = problem.states(x, s)?;
    let at = problem.at(&states, t, z);
    let outputs = case.model.outputs.iter().map(|o| at.eval(&o.value));
    Some((rates, outputs.collect::<Option<_>>()?))
}
