//! Multiport fields in the nonlinear differential test: the two-port field a graph may get, and what the reference
//! makes of it.
//!
//! The field is an `IF` whose inertia matrix varies with both of its displacements (a two-link arm's
//! `[[c + d + 2b cos q₂, c + b cos q₂], [c + b cos q₂, c + e sin² q₁]]`, definite for every `q`), a `CF` with cubic
//! and coupled laws, or an `RF` with coupled cubic laws in the effort or the flow form. The reference treats an `IF`
//! from its definition alone: the port efforts are `e = d/dt(M(q) f) - ∂T/∂q` with `T = f' M(q) f / 2`, so
//! `M ḟ = e - Σ_l (∂M/∂q_l) f_l f + ½ (f' (∂M/∂q_k) f)_k`, with `∂M/∂q` by extrapolated central differences of
//! `M` as written (`equations_support/lagrange.rs`); nothing of bgc's Lagrange terms is used.

use crate::equations_support::*;

use bgc::ir::{Expr, Func, Law, Model, PortVar, Relation};
use bgc::syntax::ast::ElementKind as K;
use petgraph::Direction;
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;

/// The field's name in the graph.
pub(super) const FIELD: &str = "fld";

fn port(node: NodeIndex, var: PortVar, port: u32) -> Expr {
    Expr::FieldPort { node, var, port }
}

fn cube(x: Expr) -> Expr {
    pow(x, c(3.0))
}

/// `Σ_j r[j] x_j + k x_own³`: one coupled cubic law.
fn coupled(r: [Expr; 2], x: [Expr; 2], k: Expr, own: usize) -> Expr {
    let cubed = cube(x[own].clone());
    let [r0, r1] = r;
    let [x0, x1] = x;
    add(add(mul(r0, x0), mul(r1, x1)), mul(k, cubed))
}

/// An `IF`'s symmetric inertia matrix, row-major, in both of its displacements.
fn inertia(b: &mut Builder, g: &mut Gen, node: NodeIndex) -> Relation {
    let (cc, d) = (b.param("fc", g.value()), b.param("fd", 1.0 + g.value()));
    let (bb, ee) = (
        b.param("fb", 0.2 * g.value()),
        b.param("fe", 0.2 * g.value()),
    );
    let cos2 = Expr::Call(Func::Cos, vec![port(node, PortVar::Displacement, 1)]);
    let sin1 = Expr::Call(Func::Sin, vec![port(node, PortVar::Displacement, 0)]);
    let m11 = add(
        add(cc.clone(), d),
        mul(c(2.0), mul(bb.clone(), cos2.clone())),
    );
    let m12 = add(cc.clone(), mul(bb, cos2));
    let m22 = add(cc, mul(ee, pow(sin1, c(2.0))));
    Relation::MassMatrix {
        n: 2,
        entries: vec![m11, m12.clone(), m12, m22],
    }
}

/// Coupled cubic laws `lhs[k] = Σ_j K_kj x_j + k_k x_k³` with a symmetric `K` whose coupling is small.
fn laws(b: &mut Builder, g: &mut Gen, lhs: PortVar, x: [Expr; 2]) -> Relation {
    let (k11, k22) = (b.param("fk11", g.value()), b.param("fk22", g.value()));
    let k12 = b.param("fk12", 0.2 * g.value());
    let (c1, c2) = (
        b.param("fc1", 0.1 + g.value() / 5.0),
        b.param("fc2", 0.1 + g.value() / 5.0),
    );
    let law = |port, rhs| Law { lhs, port, rhs };
    Relation::Laws(vec![
        law(0, coupled([k11, k12.clone()], x.clone(), c1, 0)),
        law(1, coupled([k12, k22], x, c2, 1)),
    ])
}

/// A two-port `IF`, `CF` or `RF` drawn from `g`, its ports bonded to random junctions in random directions, and the
/// effort and flow of each port's bond as outputs.
pub(super) fn add_field(b: &mut Builder, g: &mut Gen, junctions: &[NodeIndex]) {
    let kind = [K::IF, K::CF, K::RF][g.below(3) as usize];
    let node = b.field(kind, FIELD, 2);
    let of = |var| [port(node, var, 0), port(node, var, 1)];
    b.model.graph[node].relation = match kind {
        K::IF => inertia(b, g, node),
        K::CF => laws(b, g, PortVar::Effort, of(PortVar::Displacement)),
        _ if g.coin() => laws(b, g, PortVar::Effort, of(PortVar::Flow)),
        _ => laws(b, g, PortVar::Flow, of(PortVar::Effort)),
    };
    bond_field_ports(b, g, node, junctions);
}

/// The bond on port `k` of a field and the sign of the port's own flow (into the field) relative to the bond's.
pub(super) fn port_bond(model: &Model, n: NodeIndex, k: u32) -> Option<(usize, f64)> {
    let into = model.graph.edges_directed(n, Direction::Incoming);
    if let Some(b) = into.into_iter().find(|b| b.weight().to_port == k) {
        return Some((b.id().index(), 1.0));
    }
    let out = model.graph.edges_directed(n, Direction::Outgoing);
    let b = out.into_iter().find(|b| b.weight().from_port == k)?;
    Some((b.id().index(), -1.0))
}
