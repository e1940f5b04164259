//! A builder of IR models for the equations tests, independent of the parser and lowering, and the
//! small numeric helpers the tests use to check results against independent references.
#![allow(dead_code)]
// Index loops read like the textbook elimination they implement.
#![allow(clippy::needless_range_loop)]

#[path = "../../benches/support/families.rs"]
pub mod families;
pub mod lagrange;
pub mod power;

use bgc::ir::{
    Bond, Domain, Expr, Input, Model, Node, Output, Param, Relation, SpanTable, Target, Var,
};
use bgc::span::{FileId, Span};
use bgc::syntax::ast::{BinOp, ElementKind};
use bgc::units::Unit;
use petgraph::graph::{DiGraph, EdgeIndex, NodeIndex};

pub struct Builder {
    pub model: Model,
    next: usize,
}

fn span(k: usize) -> Span {
    Span::new(FileId(0), k, k + 1)
}

impl Builder {
    pub fn new(name: &str) -> Builder {
        Builder {
            model: Model {
                name: name.to_string(),
                doc: Vec::new(),
                graph: DiGraph::new(),
                params: Vec::new(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                vars: Vec::new(),
                coords: None,
                spans: SpanTable::default(),
            },
            next: 0,
        }
    }

    fn span(&mut self) -> Span {
        self.next += 2;
        span(self.next)
    }

    pub fn param(&mut self, name: &str, value: f64) -> Expr {
        let s = self.span();
        self.model.params.push(Param {
            name: name.into(),
            default: value,
            unit: Unit::ONE,
            unit_text: "1".into(),
            description: None,
            doc: Vec::new(),
            derived: None,
        });
        self.model.spans.params.push(s);
        Expr::Param(self.model.params.len() - 1)
    }

    pub fn input(&mut self, name: &str) -> Expr {
        let s = self.span();
        self.model.inputs.push(Input {
            name: name.into(),
            unit: Unit::ONE,
            unit_text: "1".into(),
            description: None,
        });
        self.model.spans.inputs.push(s);
        Expr::Input(self.model.inputs.len() - 1)
    }

    pub fn node(&mut self, kind: ElementKind, name: &str, relation: Relation) -> NodeIndex {
        let s = self.span();
        let ports = match kind {
            ElementKind::Zero | ElementKind::One => 0,
            k if k.is_two_port() => 2,
            _ => 1,
        };
        let n = self.model.graph.add_node(Node {
            name: name.into(),
            kind,
            relation,
            ports,
            doc: Vec::new(),
        });
        self.model.spans.nodes.push(s);
        self.model.spans.node_names.push(s);
        self.model.spans.node_relations.push(None);
        self.model.spans.node_instances.push(None);
        n
    }

    pub fn junction(&mut self, kind: ElementKind, name: &str) -> NodeIndex {
        self.node(kind, name, Relation::Junction)
    }

    pub fn bond(&mut self, a: NodeIndex, b: NodeIndex) -> EdgeIndex {
        let s = self.span();
        self.model.spans.bonds.push(s);
        let from_port = u32::from(self.model.graph[a].kind.is_two_port());
        self.model.graph.add_edge(
            a,
            b,
            Bond {
                name: None,
                from_port,
                to_port: 0,
                domain: Domain::Rotational,
                hint: None,
            },
        )
    }

    /// A field of `ports` ports (its relation set by the caller, who needs the node for its laws).
    pub fn field(&mut self, kind: ElementKind, name: &str, ports: u32) -> NodeIndex {
        let n = self.node(kind, name, Relation::Junction);
        self.model.graph[n].ports = ports;
        n
    }

    /// A bond from port `from.1` of `from.0` to port `to.1` of `to.0` (0-based ports).
    pub fn port_bond(&mut self, from: (NodeIndex, u32), to: (NodeIndex, u32)) -> EdgeIndex {
        let e = self.bond(from.0, to.0);
        self.model.graph[e].from_port = from.1;
        self.model.graph[e].to_port = to.1;
        e
    }

    pub fn named_bond(&mut self, name: &str, a: NodeIndex, b: NodeIndex) -> EdgeIndex {
        let e = self.bond(a, b);
        self.model.graph[e].name = Some(name.into());
        e
    }

    pub fn chain(&mut self, nodes: &[NodeIndex]) {
        for w in nodes.windows(2) {
            self.bond(w[0], w[1]);
        }
    }

    pub fn output(&mut self, name: &str, value: Expr) {
        let s = self.span();
        self.model.outputs.push(Output {
            name: name.into(),
            unit: Unit::ONE,
            unit_text: "1".into(),
            value,
            description: None,
        });
        self.model.spans.outputs.push(s);
    }

    pub fn var(&mut self, name: &str, integrand: Expr) -> Expr {
        let s = self.span();
        self.model.vars.push(Var {
            name: name.into(),
            unit: Unit::ONE,
            unit_text: "1".into(),
            integrand,
        });
        self.model.spans.vars.push(s);
        Expr::Var(self.model.vars.len() - 1)
    }

    pub fn coords(&mut self, list: Vec<Expr>) {
        for _ in &list {
            let s = self.span();
            self.model.spans.coords.push(s);
        }
        self.model.coords = Some(list);
    }

    pub fn finish(mut self) -> Model {
        self.model.spans.model = Span::new(FileId(0), 0, self.next + 2);
        self.model
    }
}

/// Whether the junction structure (junctions and two-ports, and the bonds between them) has a loop: it is
/// connected in the generated graphs, so it has one exactly when it has as many bonds as nodes.
pub fn has_junction_loop(model: &bgc::ir::Model) -> bool {
    use ElementKind as K;
    let g = &model.graph;
    let inside = |n: NodeIndex| {
        matches!(
            g[n].kind,
            K::Zero | K::One | K::TF | K::GY | K::MTF | K::MGY
        )
    };
    let nodes = g.node_indices().filter(|&n| inside(n)).count();
    let bonds = g
        .edge_indices()
        .filter_map(|b| g.edge_endpoints(b))
        .filter(|&(x, y)| inside(x) && inside(y))
        .count();
    bonds >= nodes
}

pub fn e(n: NodeIndex) -> Expr {
    Expr::Effort(Target::Node(n))
}
pub fn f(n: NodeIndex) -> Expr {
    Expr::Flow(Target::Node(n))
}
pub fn eb(b: EdgeIndex) -> Expr {
    Expr::Effort(Target::Bond(b))
}
pub fn p(n: NodeIndex) -> Expr {
    Expr::Momentum(n)
}
pub fn q(n: NodeIndex) -> Expr {
    Expr::Displacement(n)
}
pub fn c(v: f64) -> Expr {
    Expr::Const(v)
}
fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
    Expr::Binary(op, Box::new(a), Box::new(b))
}
pub fn add(a: Expr, b: Expr) -> Expr {
    bin(BinOp::Add, a, b)
}
pub fn sub(a: Expr, b: Expr) -> Expr {
    bin(BinOp::Sub, a, b)
}
pub fn mul(a: Expr, b: Expr) -> Expr {
    bin(BinOp::Mul, a, b)
}
pub fn div(a: Expr, b: Expr) -> Expr {
    bin(BinOp::Div, a, b)
}
pub fn pow(a: Expr, b: Expr) -> Expr {
    bin(BinOp::Pow, a, b)
}
pub fn linear(e: Expr) -> Relation {
    Relation::Linear(e)
}
pub fn source(e: Expr) -> Relation {
    Relation::Source(e)
}

/// Relative closeness of two matrices: every entry within `tol` of the other relative to the matrix's largest entry
/// scale per row (so that structurally zero entries compare against the row's magnitude).
pub fn assert_close(what: &str, got: &[Vec<f64>], want: &[Vec<f64>], tol: f64) {
    assert_eq!(got.len(), want.len(), "{what}: row count");
    for (r, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len(), "{what}: column count of row {r}");
        for (k, (a, b)) in g.iter().zip(w).enumerate() {
            let scale = b.abs().max(a.abs());
            let ok = if *b == 0.0 {
                a.abs() <= tol * w.iter().fold(1e-300f64, |m, v| m.max(v.abs()))
            } else {
                (a - b).abs() <= tol * scale
            };
            assert!(ok, "{what}[{r}][{k}]: got {a:e}, want {b:e}");
        }
    }
}

/// `(plus − minus) / 2h`: the central difference of two evaluations at `±h`.
pub fn central_difference(plus: &[f64], minus: &[f64], h: f64) -> Vec<f64> {
    plus.iter()
        .zip(minus)
        .map(|(p, m)| (p - m) / (2.0 * h))
        .collect()
}

/// Richardson's extrapolation of central differences at a step (`coarse`) and at half of it (`fine`): the error
/// of order `h²` cancels.
pub fn richardson(coarse: &[f64], fine: &[f64]) -> Vec<f64> {
    coarse
        .iter()
        .zip(fine)
        .map(|(c, f)| (4.0 * f - c) / 3.0)
        .collect()
}

/// The two ports of field `node` bonded to random junctions in random directions, the effort and flow of each
/// port's bond as outputs `e_fld{k}_y`, `f_fld{k}_y`.
pub fn bond_field_ports(b: &mut Builder, g: &mut Gen, node: NodeIndex, junctions: &[NodeIndex]) {
    use bgc::ir::Target;
    for k in 0..2 {
        let j = junctions[g.below(junctions.len() as u64) as usize];
        let bond = if g.coin() {
            b.port_bond((j, 0), (node, k))
        } else {
            b.port_bond((node, k), (j, 0))
        };
        b.output(&format!("e_fld{k}_y"), Expr::Effort(Target::Bond(bond)));
        b.output(&format!("f_fld{k}_y"), Expr::Flow(Target::Bond(bond)));
    }
}

/// A deterministic pseudo-random generator (SplitMix64) for parameter values.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A value in `[lo, hi)`, spread logarithmically.
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + self.next() * (hi.ln() - lo.ln())).exp()
    }
}

/// A complex number for frequency responses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cx(pub f64, pub f64);

impl Cx {
    pub fn add(self, o: Cx) -> Cx {
        Cx(self.0 + o.0, self.1 + o.1)
    }
    pub fn sub(self, o: Cx) -> Cx {
        Cx(self.0 - o.0, self.1 - o.1)
    }
    pub fn mul(self, o: Cx) -> Cx {
        Cx(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    pub fn div(self, o: Cx) -> Cx {
        let d = o.0 * o.0 + o.1 * o.1;
        Cx(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    pub fn abs(self) -> f64 {
        self.0.hypot(self.1)
    }

    /// The real number `v`.
    pub fn re(v: f64) -> Cx {
        Cx(v, 0.0)
    }
}

/// Solves `a x = b` by Gaussian elimination with partial pivoting; `None` when singular.
pub fn solve(mut a: Vec<Vec<Cx>>, mut b: Vec<Cx>) -> Option<Vec<Cx>> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for r in col + 1..n {
            let factor = a[r][col].div(a[col][col]);
            let pivot_row = a[col].clone();
            for (x, p) in a[r].iter_mut().zip(&pivot_row).skip(col) {
                *x = x.sub(factor.mul(*p));
            }
            b[r] = b[r].sub(factor.mul(b[col]));
        }
    }
    let mut x = vec![Cx::re(0.0); n];
    for r in (0..n).rev() {
        let mut acc = b[r];
        for c in r + 1..n {
            acc = acc.sub(a[r][c].mul(x[c]));
        }
        x[r] = acc.div(a[r][r]);
    }
    Some(x)
}

/// The sizes of the differential tests' random graphs: up to `junctions + 1` junctions, `ports + 1` one-ports besides the two sources,
/// and `closing - 1` bonds that close loops in the junction structure.
#[derive(Clone, Copy)]
pub struct Sizes {
    pub junctions: u64,
    pub ports: u64,
    pub closing: u64,
}

/// The graphs the property test draws: small enough for their loops to be solved in closed form.
pub const SMALL: Sizes = Sizes {
    junctions: 3,
    ports: 4,
    closing: 3,
};

/// Larger graphs, among which some keep their resistive loops as a block solved numerically.
pub const LARGE: Sizes = Sizes {
    junctions: 12,
    ports: 14,
    closing: 8,
};

/// A small deterministic generator driven by proptest's seed.
pub struct Gen(pub u64);
impl Gen {
    pub fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    pub fn coin(&mut self) -> bool {
        self.below(2) == 0
    }
    pub fn value(&mut self) -> f64 {
        0.5 + (self.below(1000) as f64) / 400.0
    }
}

/// `G(jω) = C (jωI - A)⁻¹ B + D` by Gaussian elimination with partial pivoting in complex arithmetic.
pub fn freq_response(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    c: &[Vec<f64>],
    d: &[Vec<f64>],
    w: f64,
) -> Vec<Vec<Cx>> {
    let n = a.len();
    let m = b.first().map_or(0, Vec::len);
    let mut mat: Vec<Vec<Cx>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| Cx(-a[i][j], if i == j { w } else { 0.0 }))
                .collect()
        })
        .collect();
    let mut rhs: Vec<Vec<Cx>> = (0..n)
        .map(|i| (0..m).map(|k| Cx(b[i][k], 0.0)).collect())
        .collect();
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| mat[i][col].abs().total_cmp(&mat[j][col].abs()))
            .unwrap_or(col);
        mat.swap(col, piv);
        rhs.swap(col, piv);
        for r in col + 1..n {
            let fct = mat[r][col].div(mat[col][col]);
            for k in col..n {
                let v = mat[col][k];
                mat[r][k] = mat[r][k].sub(fct.mul(v));
            }
            for k in 0..m {
                let v = rhs[col][k];
                rhs[r][k] = rhs[r][k].sub(fct.mul(v));
            }
        }
    }
    let mut x = vec![vec![Cx(0.0, 0.0); m]; n];
    for r in (0..n).rev() {
        for k in 0..m {
            let mut acc = rhs[r][k];
            for j in r + 1..n {
                acc = acc.sub(mat[r][j].mul(x[j][k]));
            }
            x[r][k] = acc.div(mat[r][r]);
        }
    }
    c.iter()
        .zip(d)
        .map(|(crow, drow)| {
            (0..m)
                .map(|k| {
                    let mut acc = Cx(drow[k], 0.0);
                    for j in 0..n {
                        acc = acc.add(Cx(crow[j], 0.0).mul(x[j][k]));
                    }
                    acc
                })
                .collect()
        })
        .collect()
}

/// Parameter names of [`back_support`], in declaration order, and their default values (Shojaei Barjuei et al.,
/// Designs 2020, 4, 53, Section 4; J_g, J_sint, J_sext from the component data sheets; d_s and d_eh, neglected in
/// the paper, get small non-zero values so that every term of Eq. 3 is exercised).
pub const BACK_SUPPORT_PARAMS: [(&str, f64); 15] = [
    ("J_m", 3.06e-4),
    ("J_g", 4e-5),
    ("b_f", 0.48e-3),
    ("r_g", 160.0),
    ("b_g", 0.65),
    ("k_g", 26400.0),
    ("d_g", 6.0),
    ("J_sint", 1e-4),
    ("k_s", 33800.0),
    ("d_s", 0.1),
    ("J_sext", 1.19e-3),
    ("k_eh", 1125.0),
    ("d_eh", 0.2),
    ("J_h", 0.0491),
    ("b_h", 0.75),
];

/// The back-support actuation chain of Fig. 6 of the paper: motor torque source, rotor and gearbox input inertias
/// on one 1-junction (so one of them is in derivative causality), motor friction, gear TF, gear friction on the
/// gearbox-output junction, the harmonic-drive spring-damper, the sensor's inner and outer flanges with the sensor
/// spring-damper, the exoskeleton-trunk coupling, and the trunk (inertia and hip damping) driven by the trunk
/// velocity as a flow source (so the trunk inertia is in derivative causality too).
pub fn back_support(with_coords: bool) -> Model {
    use bgc::syntax::ast::ElementKind as K;
    let mut b = Builder::new("back_support");
    let ps: Vec<Expr> = BACK_SUPPORT_PARAMS
        .iter()
        .map(|(n, v)| b.param(n, *v))
        .collect();
    let [
        j_m,
        j_g,
        b_f,
        r_g,
        b_g,
        k_g,
        d_g,
        j_sint,
        k_s,
        d_s,
        j_sext,
        k_eh,
        d_eh,
        j_h,
        b_h,
    ] = <[Expr; 15]>::try_from(ps).unwrap_or_else(|_| unreachable!());
    let tau_m = b.input("tau_m");
    let omega_h = b.input("omega_h");
    let motor = b.node(K::Se, "motor", source(tau_m));
    let j_motor = b.junction(K::One, "j_motor");
    let rotor = b.node(K::I, "rotor", linear(j_m));
    let gear_in = b.node(K::I, "gear_inertia", linear(j_g));
    let friction = b.node(K::R, "motor_friction", linear(b_f));
    let gear = b.node(K::TF, "gear", Relation::Modulus(r_g));
    let j_out = b.junction(K::One, "j_gear_out");
    let gear_friction = b.node(K::R, "gear_friction", linear(b_g));
    let j_gear = b.junction(K::Zero, "j_gear");
    let j_hd = b.junction(K::One, "j_hd");
    let hd_spring = b.node(K::C, "hd_spring", linear(div(c(1.0), k_g)));
    let hd_damper = b.node(K::R, "hd_damper", linear(d_g));
    let j_sint_n = b.junction(K::One, "j_sint");
    let sensor_in = b.node(K::I, "sensor_in", linear(j_sint));
    let j_sensor = b.junction(K::Zero, "j_sensor");
    let j_s = b.junction(K::One, "j_s");
    let s_spring = b.node(K::C, "s_spring", linear(div(c(1.0), k_s)));
    let s_damper = b.node(K::R, "s_damper", linear(d_s));
    let j_sext_n = b.junction(K::One, "j_sext");
    let sensor_out = b.node(K::I, "sensor_out", linear(j_sext));
    let j_coupling = b.junction(K::Zero, "j_coupling");
    let j_eh = b.junction(K::One, "j_eh");
    let eh_spring = b.node(K::C, "eh_spring", linear(div(c(1.0), k_eh)));
    let eh_damper = b.node(K::R, "eh_damper", linear(d_eh));
    let j_trunk = b.junction(K::One, "j_trunk");
    let trunk = b.node(K::I, "trunk", linear(j_h));
    let trunk_damping = b.node(K::R, "trunk_damping", linear(b_h));
    let wearer = b.node(K::Sf, "wearer", source(omega_h));
    b.chain(&[motor, j_motor, rotor]);
    b.bond(j_motor, gear_in);
    b.bond(j_motor, friction);
    b.chain(&[j_motor, gear, j_out, gear_friction]);
    b.chain(&[j_out, j_gear, j_hd, hd_spring]);
    b.bond(j_hd, hd_damper);
    b.chain(&[j_gear, j_sint_n, sensor_in]);
    b.chain(&[j_sint_n, j_sensor, j_s, s_spring]);
    b.bond(j_s, s_damper);
    b.chain(&[j_sensor, j_sext_n, sensor_out]);
    b.chain(&[j_sext_n, j_coupling, j_eh, eh_spring]);
    b.bond(j_eh, eh_damper);
    let coupling = b.named_bond("coupling", j_coupling, j_trunk);
    b.bond(j_trunk, trunk);
    b.bond(j_trunk, trunk_damping);
    b.bond(wearer, j_trunk);
    let theta_m = b.var("theta_m", f(rotor));
    let theta_sint = b.var("theta_sint", f(j_sint_n));
    let theta_sext = b.var("theta_sext", f(j_sext_n));
    let theta_h = b.var("theta_h", f(trunk));
    if with_coords {
        b.coords(vec![
            theta_m,
            f(rotor),
            theta_sint,
            f(j_sint_n),
            theta_sext,
            f(j_sext_n),
            theta_h,
        ]);
    }
    b.output("omega_m", f(rotor));
    b.output("tau_s", add(e(s_spring), e(s_damper)));
    b.output("tau_h", eb(coupling));
    b.finish()
}
