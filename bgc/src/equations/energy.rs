//! Energy bookkeeping: the energy stored in each storage, the power dissipated in each resistor and the power
//! supplied by each source, as explicit expressions of states, inputs, parameters and `t`.
//!
//! - Stored: `E = ∫ e dq` for a compliance, `∫ f dp` for an inertia: `q²/(2C)`, `p²/(2I)` for linear ones; for a law
//!   `e = g(q)` (`f = g(p)`) the integral is taken symbolically when `g` is a polynomial in `q` (`p`) whose
//!   coefficients do not depend on it; other laws are reported (`BG0607`) and get no expression.
//! - Dissipated: `e·f` of each resistor (its own effort and flow, so positive for a passive resistor).
//! - Supplied: `e·f` of each source along its bond's direction (positive when the source delivers power).
//!
//! A source that drives a storage in derivative causality (a flow source imposing an inertia's velocity) has an
//! effort with the time derivative of its input in it (`e = J·dω/dt`): its power keeps that derivative as
//! [`Sym::InputDot`], so that `dE/dt = supplied − dissipated` holds for every input, not only constant ones.

use super::build::{Ctx, effort_var, flow_var};
use super::codes;
use super::resolve::Resolver;
use super::sym::{Ex, Sym, add, div, mul, pow};
use crate::diagnostic::Diagnostic;
use crate::ir::{Law, Model, PortVar, Relation};
use crate::syntax::ast::ElementKind;

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
    pub value: Option<Ex>,
}

/// `∫ g dq` when `g` is a polynomial in `q` with coefficients free of `q`.
pub(crate) fn integrate_polynomial(g: &Ex, q: Sym) -> Option<Ex> {
    let terms: Vec<Ex> = match g {
        Ex::Add(ts) => ts.clone(),
        other => vec![other.clone()],
    };
    let mut out = Vec::new();
    for t in terms {
        let factors: Vec<Ex> = match t {
            Ex::Mul(fs) => fs,
            other => vec![other],
        };
        let mut power = 0.0;
        let mut coef = Vec::new();
        for f in factors {
            match &f {
                Ex::S(s) if *s == q => power += 1.0,
                Ex::Pow(b, x) if **b == Ex::S(q) => match x.num() {
                    Some(n) if n.fract() == 0.0 && n >= 0.0 => power += n,
                    _ => return None,
                },
                other if other.contains(q) => return None,
                _ => coef.push(f),
            }
        }
        coef.push(div(
            pow(Ex::S(q), Ex::Num(power + 1.0)),
            Ex::Num(power + 1.0),
        ));
        out.push(mul(coef));
    }
    Some(add(out))
}

fn law(laws: &[Law], lhs: PortVar) -> Option<&Law> {
    laws.iter().find(|l| l.lhs == lhs)
}

/// Every element's energy term.
pub(crate) fn terms(
    model: &Model,
    ctx: &Ctx,
    resolver: &mut Resolver,
    rate_of: &dyn Fn(&Ex) -> Ex,
    mass: &[super::field::MassBlock],
    diags: &mut Vec<Diagnostic>,
) -> Vec<EnergyTerm> {
    let mut out = Vec::new();
    for node in model.graph.node_indices() {
        let w = &model.graph[node];
        if w.kind.is_field() {
            if let Some((kind, raw)) = super::field::energy(model, ctx, node, mass, diags) {
                let value = raw.and_then(|r| resolver.expr(&r).ok().map(|v| rate_of(&v)));
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
        let e_b = Ex::S(Sym::Var(effort_var(b)));
        let f_b = Ex::S(Sym::Var(flow_var(b)));
        let warn = |msg: String| {
            let d = Diagnostic::warning(codes::ENERGY, msg);
            match model.spans.nodes.get(node.index()) {
                Some(span) => d.with_primary(*span, "this element"),
                None => d,
            }
        };
        let (kind, raw): (EnergyKind, Option<Ex>) = match w.kind {
            ElementKind::C | ElementKind::I => {
                let energy_var = match ctx.node_state.get(node.index()).copied().flatten() {
                    Some(i) => Some(Ex::S(Sym::State(i))),
                    None => ctx.energy_expr.get(node.index()).cloned().flatten(),
                };
                let stored = match (&w.relation, energy_var) {
                    (Relation::Linear(param), Some(x)) => ctx
                        .convert(param)
                        .ok()
                        .map(|p| div(pow(x, Ex::Num(2.0)), mul(vec![Ex::Num(2.0), p]))),
                    (Relation::Laws(laws), Some(Ex::S(state @ Sym::State(_)))) => {
                        let form = if w.kind == ElementKind::C {
                            PortVar::Effort
                        } else {
                            PortVar::Flow
                        };
                        let g = law(laws, form).and_then(|l| ctx.convert(&l.rhs).ok());
                        let g = g.map(|g| {
                            if w.kind == ElementKind::I {
                                mul(vec![Ex::Num(s), g])
                            } else {
                                g
                            }
                        });
                        let integral = g.as_ref().and_then(|g| integrate_polynomial(g, state));
                        if integral.is_none() {
                            diags.push(warn(format!(
                                "the stored energy of `{}` is not computed: its law is not a polynomial in its energy variable written in the {} form",
                                w.name,
                                if w.kind == ElementKind::C { "e = g(q)" } else { "f = g(p)" }
                            )));
                        }
                        integral
                    }
                    _ => {
                        diags.push(warn(format!(
                            "the stored energy of `{}` is not computed: its law in derivative causality is not linear",
                            w.name
                        )));
                        None
                    }
                };
                (EnergyKind::Stored, stored)
            }
            ElementKind::R => (
                EnergyKind::Dissipated,
                Some(mul(vec![Ex::Num(s), e_b, f_b])),
            ),
            ElementKind::Se | ElementKind::Sf | ElementKind::MSe | ElementKind::MSf => {
                (EnergyKind::Supplied, Some(mul(vec![Ex::Num(-s), e_b, f_b])))
            }
            _ => continue,
        };
        // A source or resistor next to a storage in derivative causality keeps the inputs' derivatives
        // (`Sym::InputDot`): its power is `e·f` with `e = I·du/dt` (or `f = C·du/dt`), and leaving that out would
        // break the energy balance whenever the input varies. A consumer supplies `du/dt` (the simulator
        // differentiates the input signals) or leaves the term out and says so (generated code).
        let value = raw.and_then(|r| resolver.expr(&r).ok().map(|v| rate_of(&v)));
        out.push(EnergyTerm {
            element: w.name.clone(),
            kind,
            value,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::equations::sym;

    #[test]
    fn polynomial_integral() {
        // ∫ (k q + k3 q^3) dq = k q^2/2 + k3 q^4/4
        let q = Sym::State(0);
        let g = add(vec![
            mul(vec![Ex::S(Sym::Param(0)), Ex::S(q)]),
            mul(vec![Ex::S(Sym::Param(1)), pow(Ex::S(q), Ex::Num(3.0))]),
        ]);
        let e = integrate_polynomial(&g, q).unwrap_or(Ex::zero());
        let v = sym::eval(&e, &|s| match s {
            Sym::Param(0) => Some(2.0),
            Sym::Param(1) => Some(4.0),
            Sym::State(0) => Some(3.0),
            _ => None,
        });
        assert_eq!(v, Ok(2.0 * 9.0 / 2.0 + 4.0 * 81.0 / 4.0));
        assert!(
            integrate_polynomial(&sym::call(crate::ir::Func::Sin, vec![Ex::S(q)]), q).is_none()
        );
    }
}
