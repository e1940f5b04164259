//! Energy bookkeeping: the energy stored in each storage, the power dissipated in each resistor and the power
//! supplied by each source, as explicit expressions of states, inputs, parameters and `t`.
//!
//! - Stored: `E = ∫ e dq` for a compliance, `∫ f dp` for an inertia: `q²/(2C)`, `p²/(2I)` for linear ones; for a law
//!   in either form (`e = g(q)`, or `q = g(e)` solved for `e`) the integral is taken symbolically when the effort
//!   (flow) is a polynomial in `q` (`p`) whose coefficients do not depend on it; in derivative causality, from the
//!   law `q = g(e)` as `e g(e) − ∫ g de`. Other laws are reported (`BG0607`) and get no expression.
//! - Dissipated: `e·f` of each resistor (its own effort and flow, so positive for a passive resistor).
//! - Supplied: `e·f` of each source, its own effort and flow (the flow out of it), so positive when it delivers power.
//!
//! A source that drives a storage in derivative causality (a flow source imposing an inertia's velocity) has an
//! effort with the time derivative of its input in it (`e = J·dω/dt`): its power keeps that derivative as
//! [`Sym::InputDot`], so that `dE/dt = supplied − dissipated` holds for every input, not only constant ones.

use super::build::{Ctx, effort_var, flow_var};
use super::codes;
use super::resolve::{ResolveError, Resolver};
use super::symbols::{self, Sym, SymExt, add, div, mul, pow};
use crate::diagnostic::Diagnostic;
use crate::ir::{Model, Relation};
use crate::symbolic::{Expr, Node};
use crate::syntax::ast::ElementKind;
use petgraph::graph::{EdgeIndex, NodeIndex};

/// What an energy term measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnergyKind {
    /// Energy stored in a C or I.
    Stored,
    /// Power dissipated in an R.
    Dissipated,
    /// Power delivered by a source.
    Supplied,
}

impl EnergyKind {
    pub fn name(self) -> &'static str {
        match self {
            EnergyKind::Stored => "stored",
            EnergyKind::Dissipated => "dissipated",
            EnergyKind::Supplied => "supplied",
        }
    }
}

/// The energy or power of one element.
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyTerm {
    pub element: String,
    pub kind: EnergyKind,
    /// Explicit in states, inputs, parameters and `t`, and, for the power of an element next to a storage in
    /// derivative causality, the inputs' time derivatives ([`Sym::InputDot`]); `None` when it has no closed form
    /// here (a diagnostic says why).
    pub value: Option<Expr>,
}

/// `∫ g dq` when `g` is a polynomial in `q` with coefficients free of `q`.
pub(crate) fn integrate_polynomial(g: &Expr, q: Sym) -> Option<Expr> {
    let terms: Vec<Expr> = match g.node() {
        Node::Add(ts) => ts.clone(),
        _ => vec![g.clone()],
    };
    let mut out = Vec::new();
    for t in terms {
        let factors: Vec<Expr> = match t.node() {
            Node::Mul(fs) => fs.clone(),
            _ => vec![t.clone()],
        };
        let mut power = 0.0;
        let mut coef = Vec::new();
        for f in factors {
            match f.node() {
                _ if f.as_sym() == Some(q) => power += 1.0,
                Node::Pow(b, x) if b.as_sym() == Some(q) => match x.num() {
                    Some(n) if n.fract() == 0.0 && n >= 0.0 => power += n,
                    _ => return None,
                },
                _ if f.contains(q) => return None,
                _ => coef.push(f),
            }
        }
        coef.push(div(
            pow(symbols::leaf(q), symbols::num(power + 1.0)),
            symbols::num(power + 1.0),
        ));
        out.push(mul(coef));
    }
    Some(add(out))
}

/// The stored energy of a C or I with bond `b` and own-flow sign `s`, in bond variables and states.
///
/// In integral causality it is `∫ e dq` (C) or `∫ f dp` (I) with the element's own effort or flow as its law gives
/// it in the state, whichever form the law is written in (`e = g(q)`, or `q = g(e)` inverted). In derivative
/// causality the law gives the energy variable `x = g(y)` of the own effort or flow `y`, and the energy is
/// `∫ y dx = y g(y) − ∫ g dy`. Both integrals are taken when the integrand is a polynomial in the variable.
fn stored_energy(
    ctx: &Ctx,
    resolver: &mut Resolver,
    node: NodeIndex,
    b: EdgeIndex,
    s: f64,
) -> Result<Expr, &'static str> {
    let w = &ctx.model.graph[node];
    let capacitor = w.kind == ElementKind::C;
    // The own variable conjugate to the energy variable: the effort of a C, the flow of an I.
    let own = if capacitor {
        symbols::leaf(Sym::Var(effort_var(b)))
    } else {
        mul(vec![symbols::num(s), symbols::leaf(Sym::Var(flow_var(b)))])
    };
    if let Some(i) = ctx.node_state.get(node.index()).copied().flatten() {
        let x = Sym::State(i);
        if let Relation::Linear(param) = &w.relation {
            let p = ctx
                .convert(param)
                .map_err(|_| "its value cannot be converted")?;
            return Ok(div(
                pow(symbols::leaf(x), symbols::num(2.0)),
                mul(vec![symbols::num(2.0), p]),
            ));
        }
        let conjugate = resolver
            .expr(&own)
            .map_err(|_| "its effort or flow has no explicit form")?;
        return integrate_polynomial(&symbols::expand(&conjugate), x)
            .ok_or("its law is not a polynomial in its energy variable");
    }
    let energy_var = ctx
        .energy_expr
        .get(node.index())
        .cloned()
        .flatten()
        .ok_or("it has no energy variable")?;
    if let Relation::Linear(param) = &w.relation {
        let p = ctx
            .convert(param)
            .map_err(|_| "its value cannot be converted")?;
        return Ok(div(
            pow(energy_var, symbols::num(2.0)),
            mul(vec![symbols::num(2.0), p]),
        ));
    }
    // x = g(y) with y the own variable: write g in a placeholder for y, integrate, put y back.
    let y = Sym::Tear(symbols::PLACEHOLDER);
    let bond_var = if capacitor {
        effort_var(b)
    } else {
        flow_var(b)
    };
    let in_y = |e: &Expr| {
        symbols::subst(e, &mut |v| match v {
            Sym::Var(k) if k == bond_var => Some(mul(vec![symbols::num(s), symbols::leaf(y)])),
            _ => None,
        })
    };
    let g = symbols::expand(&in_y(&energy_var));
    let integral =
        integrate_polynomial(&g, y).ok_or("its law is not a polynomial in its effort or flow")?;
    let energy = symbols::sub(mul(vec![symbols::leaf(y), g]), integral);
    Ok(symbols::subst(&energy, &mut |v| {
        (v == y).then(|| own.clone())
    }))
}

/// An energy term whose bond variables the equations do not determine: the model is ill-posed there (a singular
/// loop, a chain of storages in derivative causality), even when no rate or output reads those variables.
pub(crate) struct Unresolved {
    pub element: String,
    pub kind: EnergyKind,
    pub why: ResolveError,
}

/// Every element's energy term, and the terms left without a value because their variables are not determined.
pub(crate) fn terms(
    model: &Model,
    ctx: &Ctx,
    resolver: &mut Resolver,
    rates_of: &dyn Fn(&[Expr]) -> Vec<Expr>,
    mass: &[super::field::MassBlock],
    diags: &mut Vec<Diagnostic>,
) -> (Vec<EnergyTerm>, Vec<Unresolved>) {
    let mut out = Vec::new();
    let mut unresolved = Vec::new();
    for node in model.graph.node_indices() {
        let w = &model.graph[node];
        if ctx.velocity.get(node.index()).copied().unwrap_or(false) {
            // A massless inertia of a velocity state stores nothing; it is not the user's element.
            continue;
        }
        if w.kind.is_field() {
            if let Some((kind, raw)) = super::field::energy(model, ctx, node, mass, diags) {
                let value = resolved(resolver, &mut unresolved, &w.name, kind, raw);
                out.push(EnergyTerm {
                    element: w.name.clone(),
                    kind,
                    value,
                });
            }
            continue;
        }
        let Some((b, s)) = ctx.port.get(node.index()).copied().flatten() else {
            continue;
        };
        let e_b = symbols::leaf(Sym::Var(effort_var(b)));
        let f_b = symbols::leaf(Sym::Var(flow_var(b)));
        let warn = |msg: String| {
            let d = Diagnostic::warning(codes::ENERGY, msg);
            match model.spans.nodes.get(node.index()) {
                Some(span) => d.with_primary(*span, "this element"),
                None => d,
            }
        };
        let (kind, raw): (EnergyKind, Option<Expr>) = match w.kind {
            ElementKind::C | ElementKind::I => {
                let stored = stored_energy(ctx, resolver, node, b, s);
                if let Err(why) = &stored {
                    diags.push(warn(format!(
                        "the stored energy of `{}` is not computed: {why}",
                        w.name
                    )));
                }
                (EnergyKind::Stored, stored.ok())
            }
            ElementKind::R => (
                EnergyKind::Dissipated,
                Some(mul(vec![symbols::num(s), e_b, f_b])),
            ),
            ElementKind::Se | ElementKind::Sf | ElementKind::MSe | ElementKind::MSf => (
                EnergyKind::Supplied,
                Some(mul(vec![symbols::num(s), e_b, f_b])),
            ),
            _ => continue,
        };
        // A source or resistor next to a storage in derivative causality keeps the inputs' derivatives
        // (`Sym::InputDot`): its power is `e·f` with `e = I·du/dt` (or `f = C·du/dt`), and leaving that out would
        // break the energy balance whenever the input varies. A consumer supplies `du/dt` (the simulator
        // differentiates the input signals) or leaves the term out and says so (generated code).
        let value = resolved(resolver, &mut unresolved, &w.name, kind, raw);
        out.push(EnergyTerm {
            element: w.name.clone(),
            kind,
            value,
        });
    }
    // The state rates substituted into all terms at once: terms that share a large subexpression (a junction's
    // flow in the power of each of its many sources) cost its size once.
    let present: Vec<Expr> = out.iter().filter_map(|t| t.value.clone()).collect();
    let mut substituted = rates_of(&present).into_iter();
    for t in out.iter_mut().filter(|t| t.value.is_some()) {
        t.value = substituted.next();
    }
    drop_needing_acceleration(model, &mut out, diags);
    (out, unresolved)
}

/// `raw` in states, inputs and parameters, or `None` (recorded in `unresolved`) when its variables are not
/// determined.
fn resolved(
    resolver: &mut Resolver,
    unresolved: &mut Vec<Unresolved>,
    element: &str,
    kind: EnergyKind,
    raw: Option<Expr>,
) -> Option<Expr> {
    match resolver.expr(&raw?) {
        Ok(value) => Some(value),
        Err(why) => {
            unresolved.push(Unresolved {
                element: element.to_string(),
                kind,
                why,
            });
            None
        }
    }
}

/// Leaves out (with a warning) the power of each element that needs an acceleration the equations give only
/// through a mass matrix.
fn drop_needing_acceleration(model: &Model, terms: &mut [EnergyTerm], diags: &mut Vec<Diagnostic>) {
    let values: Vec<Expr> = terms.iter().filter_map(|t| t.value.clone()).collect();
    let mut needs = symbols::each_has_sym(&values, &|s| matches!(s, Sym::StateDot(_))).into_iter();
    for term in terms {
        if term.value.is_some() && needs.next().unwrap_or(false) {
            term.value = None;
            let d = Diagnostic::warning(
                codes::ENERGY,
                format!(
                    "the power of `{}` is not computed: it needs an acceleration that the equations give only through a mass matrix",
                    term.element
                ),
            );
            let span = model
                .node_by_name(&term.element)
                .and_then(|n| model.spans.nodes.get(n.index()));
            diags.push(super::with_span(d, span, "this element"));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_integral() {
        // ∫ (k q + k3 q^3) dq = k q^2/2 + k3 q^4/4
        let q = Sym::State(0);
        let g = add(vec![
            mul(vec![symbols::leaf(Sym::Param(0)), symbols::leaf(q)]),
            mul(vec![
                symbols::leaf(Sym::Param(1)),
                pow(symbols::leaf(q), symbols::num(3.0)),
            ]),
        ]);
        let e = integrate_polynomial(&g, q).unwrap_or(Expr::zero());
        let v = symbols::eval(&e, &|s| match s {
            Sym::Param(0) => Some(2.0),
            Sym::Param(1) => Some(4.0),
            Sym::State(0) => Some(3.0),
            _ => None,
        });
        assert_eq!(v, Ok(2.0 * 9.0 / 2.0 + 4.0 * 81.0 / 4.0));
        assert!(
            integrate_polynomial(
                &symbols::call(crate::ir::Func::Sin, vec![symbols::leaf(q)]),
                q
            )
            .is_none()
        );
    }
}
