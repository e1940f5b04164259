//! Name resolution and dimension inference of expressions.
//!
//! An expression is resolved in a scope and a context (what it may use) into an [`ir::Expr`] together with its
//! dimension. A bare number has no fixed unit ([`Q::Free`]): it takes whatever unit its place needs, so `1/k`,
//! `TF gear = 160` and `2*m` are all fine. Dimensions are checked as they combine: sums and `min`/`max`/`atan2`
//! need equal dimensions (BG0310), `sin`, `exp`, ... need dimensionless arguments (BG0309), and a quantity with a
//! dimension may only be raised to a constant whole power (or a half power when every exponent is even).

use super::builder::Builder;
use super::consteval::{eval, is_literal, not_finite};
use super::scope::Entity;
use crate::diagnostic::Diagnostic;
use crate::diagnostic::suggest::closest;
use crate::ir::{self, Func, PortVar};
use crate::syntax::ast::{self, BinOp, ExprKind};
use crate::units::{Dim, Unit};
use petgraph::graph::NodeIndex;

/// The dimension of an expression: known, or free (a pure number that adapts to its place).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Q {
    Free,
    Dim(Dim),
}

impl Q {
    /// The dimension, treating a free number as dimensionless.
    pub fn dim(self) -> Dim {
        match self {
            Q::Free => Dim::NONE,
            Q::Dim(d) => d,
        }
    }

    /// True when this can stand where `want` is needed.
    pub fn fits(self, want: Dim) -> bool {
        match self {
            Q::Free => true,
            Q::Dim(d) => d == want,
        }
    }
}

/// What an expression may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Allow {
    /// Numbers, `pi` and earlier parameters of its scope: parameter defaults and overrides.
    Constant,
    /// Constants and parameters: the values of C, I, R, TF, GY.
    Parameters,
    /// Parameters, inputs and `t`: the values of Se and Sf.
    Signals,
    /// Everything that is known at run time; outputs with index below the bound when given.
    States { outputs_before: Option<usize> },
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Cx {
    pub scope: usize,
    pub allow: Allow,
    /// The element whose laws these are: its bare `e`, `f`, `p`, `q` (or `e[i]` ... for a field) are in scope.
    pub host: Option<NodeIndex>,
    /// "a parameter default", "the value of a `C`": for messages.
    pub what: &'static str,
}

impl Builder<'_> {
    /// Resolves `e`. Errors are reported; `None` means the expression is unusable (and its dimension unknown).
    pub fn expr(&mut self, e: &ast::Expr, cx: Cx) -> Option<(ir::Expr, Q)> {
        match &e.kind {
            ExprKind::Number(v) => Some((ir::Expr::Const(*v), Q::Free)),
            ExprKind::Name(name) => self.name(name, e, cx),
            ExprKind::Indexed(name, i) => self.indexed(name, *i, e, cx),
            ExprKind::Node(r) => {
                self.diags.push(
                    Diagnostic::error("BG0201", "a node is not a value")
                        .with_primary(r.span, "this names a node")
                        .with_help("use `e(x)`, `f(x)`, `p(x)` or `q(x)` for its variables"),
                );
                None
            }
            ExprKind::Neg(a) => {
                let (a, q) = self.expr(a, cx)?;
                Some((ir::Expr::Neg(Box::new(a)), q))
            }
            ExprKind::Binary(op, a, b) => self.binary(*op, a, b, e, cx),
            ExprKind::Call(f, args) => self.call(f, args, e, cx),
        }
    }

    pub(super) fn not_allowed(&mut self, e: &ast::Expr, found: &str, cx: Cx) {
        let (may, help) = match cx.allow {
            Allow::Constant => (
                "numbers, `pi` and earlier parameters",
                "a parameter's value is fixed before the model runs",
            ),
            Allow::Parameters => (
                "numbers and parameters",
                "use the modulated kind (`MTF`, `MGY`) or a law in braces for a value that varies",
            ),
            Allow::Signals => (
                "parameters, inputs and `t`",
                "use `MSe` or `MSf` for a source that depends on the state",
            ),
            Allow::States { .. } => (
                "parameters, inputs, `t`, states, integrated flows and earlier outputs",
                "an output may only use outputs declared before it",
            ),
        };
        self.diags.push(
            Diagnostic::error("BG0314", format!("{} cannot use {found}", cx.what))
                .with_primary(e.span, format!("{} may only use {may}", cx.what))
                .with_help(help),
        );
    }

    /// The dimension of a declared name; free when its unit could not be read (already reported).
    fn declared(&self, entity: Entity, d: Dim) -> Q {
        if self.bad_units.contains(&entity) {
            Q::Free
        } else {
            Q::Dim(d)
        }
    }

    fn mark_used(&mut self, id: usize) {
        if let Some(p) = self.params.get_mut(id) {
            p.used = true;
        }
    }

    fn name(&mut self, name: &str, e: &ast::Expr, cx: Cx) -> Option<(ir::Expr, Q)> {
        if name == "pi" {
            return Some((ir::Expr::Const(std::f64::consts::PI), Q::Free));
        }
        let found = self.scopes.get(cx.scope).and_then(|s| s.get(name));
        if name == "t" && found.is_none() {
            if !matches!(cx.allow, Allow::Signals | Allow::States { .. }) {
                self.not_allowed(e, "the time `t`", cx);
                return None;
            }
            return Some((ir::Expr::Time, Q::Dim(Dim::new(0, 0, 1, 0, 0, 0, 0))));
        }
        // Inside laws, `e`, `f`, `p`, `q` are the element's own variables, whatever else has those names.
        if let Some(host) = cx.host
            && let Some(var) = port_var(name)
        {
            return self.law_var(host, var, None, e);
        }
        match found {
            Some(Entity::Param(id)) => {
                self.mark_used(id);
                let d = self
                    .model
                    .params
                    .get(id)
                    .map(|p| p.unit.dim)
                    .unwrap_or_default();
                Some((ir::Expr::Param(id), self.declared(Entity::Param(id), d)))
            }
            Some(Entity::Input(id)) => {
                if matches!(cx.allow, Allow::Constant | Allow::Parameters) {
                    self.not_allowed(e, &format!("the input `{name}`"), cx);
                    return None;
                }
                let unit = self
                    .model
                    .inputs
                    .get(id)
                    .map(|p| p.unit)
                    .unwrap_or(Unit::ONE);
                let q = self.declared(Entity::Input(id), unit.dim);
                Some((to_si(ir::Expr::Input(id), unit), q))
            }
            Some(Entity::Output(id)) => {
                let ok = matches!(cx.allow, Allow::States { outputs_before: Some(n) } if id < n);
                if !ok {
                    self.not_allowed(e, &format!("the output `{name}`"), cx);
                    return None;
                }
                let unit = self
                    .model
                    .outputs
                    .get(id)
                    .map(|p| p.unit)
                    .unwrap_or(Unit::ONE);
                let q = self.declared(Entity::Output(id), unit.dim);
                Some((to_si(ir::Expr::Output(id), unit), q))
            }
            Some(Entity::Var(id)) => {
                if !matches!(cx.allow, Allow::States { .. }) {
                    self.not_allowed(e, &format!("the integrated flow `{name}`"), cx);
                    return None;
                }
                let unit = self.model.vars.get(id).map(|p| p.unit).unwrap_or(Unit::ONE);
                let q = self.declared(Entity::Var(id), unit.dim);
                Some((to_si(ir::Expr::Var(id), unit), q))
            }
            Some(other) => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0201",
                        format!("`{name}` is {}, not a value", other.describe()),
                    )
                    .with_primary(e.span, "not a value")
                    .with_help(format!(
                        "write `e({name})` or `f({name})` for its effort or flow"
                    )),
                );
                None
            }
            // A name with letters outside ASCII (`π`) is already an error of its own (BG0104, with its ASCII
            // spelling); "unknown name" would only repeat it.
            None if crate::syntax::foreign::reported_by_lexer(name) => None,
            // Declared by a statement that did not parse: its syntax error is the one to fix.
            None if self.scopes.get(cx.scope).is_some_and(|s| s.unparsed(name)) => None,
            None => {
                let mut d = Diagnostic::error("BG0201", format!("unknown name `{name}`"))
                    .with_primary(e.span, "not declared in this scope");
                let suggestion = self.scopes.get(cx.scope).and_then(|s| {
                    s.suggest(name, |x| {
                        matches!(
                            x,
                            Entity::Param(_)
                                | Entity::Input(_)
                                | Entity::Output(_)
                                | Entity::Var(_)
                        )
                    })
                });
                // The parameter a misspelling meant is not "unused": that would only repeat this error.
                match suggestion
                    .as_ref()
                    .and_then(|c| self.scopes.get(cx.scope).and_then(|s| s.get(c)))
                {
                    Some(Entity::Param(meant)) => self.mark_used(meant),
                    Some(_) => {}
                    None => self.unmatched_name = true,
                }
                d = match (suggestion, other_tool_constant(name), cx.allow) {
                    (Some(c), _, _) => d.with_help(format!("did you mean `{c}`?")),
                    (None, Some((help, Some(fix))), _) => d.with_help(help).with_fix(fix),
                    (None, Some((help, None)), _) => d.with_help(help),
                    (None, None, Allow::Constant) => d.with_help(
                        "a parameter default may use only parameters declared before it",
                    ),
                    (None, None, _) => {
                        d.with_help("declare it as a `param`, `input`, `output` or `var`")
                    }
                };
                self.diags.push(d);
                None
            }
        }
    }

    fn indexed(&mut self, name: &str, i: u32, e: &ast::Expr, cx: Cx) -> Option<(ir::Expr, Q)> {
        let var = port_var(name);
        match (cx.host, var) {
            (Some(host), Some(var)) => self.law_var(host, var, Some(i), e),
            _ => {
                self.diags.push(
                    Diagnostic::error("BG0207", format!("`{name}[{i}]` is not defined here"))
                        .with_primary(
                            e.span,
                            "only the laws of a field have indexed port variables",
                        )
                        .with_help("outside a field's laws, name a field port as `e(leg[1])`"),
                );
                None
            }
        }
    }

    fn binary(
        &mut self,
        op: BinOp,
        a: &ast::Expr,
        b: &ast::Expr,
        e: &ast::Expr,
        cx: Cx,
    ) -> Option<(ir::Expr, Q)> {
        let ra = self.expr(a, cx);
        let rb = self.expr(b, cx);
        let ((ea, qa), (eb, qb)) = (ra?, rb?);
        let q = self.binary_dim(op, (qa, qb), &eb, a, b, e)?;
        self.finite(ir::Expr::Binary(op, Box::new(ea), Box::new(eb)), e, cx)
            .map(|x| (x, q))
    }

    /// BG0403: `x` (resolved from `e`) with a part that has no finite value ([`not_finite`]), which would put an
    /// infinite or NaN coefficient into the equations. A parameter's default (or override) is checked whole, by its
    /// value, in a message that names the parameter.
    fn finite(&mut self, x: ir::Expr, e: &ast::Expr, cx: Cx) -> Option<ir::Expr> {
        if matches!(cx.allow, Allow::Constant) {
            return Some(x);
        }
        let Some(why) = not_finite(&x) else {
            return Some(x);
        };
        self.diags.push(
            Diagnostic::error("BG0403", format!("{} has a part with no finite value", cx.what))
                .with_primary(e.span, why)
                .with_help(
                    "check for a division by zero, the logarithm of zero, the square root of a negative number or an \
                     overflow",
                ),
        );
        None
    }

    /// The dimension of `a op b` from those of its operands (`eb` is `b` resolved, for the exponent of a power).
    fn binary_dim(
        &mut self,
        op: BinOp,
        (qa, qb): (Q, Q),
        eb: &ir::Expr,
        a: &ast::Expr,
        b: &ast::Expr,
        e: &ast::Expr,
    ) -> Option<Q> {
        match op {
            BinOp::Add | BinOp::Sub => self.same_dims(qa, qb, a, b, e, "added"),
            // A number times a dimensionless quantity is still a number that takes its place's unit:
            // `0.001 * sign(f(x))` may be a torque.
            BinOp::Mul | BinOp::Div if is_free_scale(qa, qb) => Some(Q::Free),
            BinOp::Mul => combine(qa, qb, Dim::checked_mul),
            BinOp::Div => match (qa, qb) {
                (Q::Free, Q::Dim(d)) => Dim::NONE.checked_div(d).map(Q::Dim),
                _ => combine(qa, qb, Dim::checked_div),
            },
            BinOp::Pow => self.power(qa, eb, qb, a, b),
        }
    }

    /// The argument of a function that needs a dimensionless one (`sin`, `exp`, ...). A bare number that multiplies
    /// or divides a quantity in seconds takes 1/s (or s) here, so `sin(3*t)`, `exp(-t/2)` and `cos(2*pi*5*t + 1)`
    /// are dimensionless. Anything with a declared unit keeps it: `sin(L*t)` with `L` in m is in m s (BG0309).
    fn dimensionless_arg(&mut self, e: &ast::Expr, cx: Cx) -> Option<(ir::Expr, Q)> {
        let second = Q::Dim(Dim::new(0, 0, 1, 0, 0, 0, 0));
        match &e.kind {
            ExprKind::Neg(a) => {
                let (a, q) = self.dimensionless_arg(a, cx)?;
                Some((ir::Expr::Neg(Box::new(a)), q))
            }
            ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), a, b) => {
                let ra = self.dimensionless_arg(a, cx);
                let rb = self.dimensionless_arg(b, cx);
                let ((ea, qa), (eb, qb)) = (ra?, rb?);
                let q = self.same_dims(qa, qb, a, b, e, "added")?;
                self.finite(ir::Expr::Binary(*op, Box::new(ea), Box::new(eb)), e, cx)
                    .map(|x| (x, q))
            }
            ExprKind::Binary(op @ (BinOp::Mul | BinOp::Div), a, b) => {
                let ra = self.expr(a, cx);
                let rb = self.expr(b, cx);
                let ((ea, qa), (eb, qb)) = (ra?, rb?);
                let rate = match op {
                    BinOp::Mul => {
                        (qa == Q::Free && qb == second) || (qa == second && qb == Q::Free)
                    }
                    _ => qa == second && qb == Q::Free,
                };
                // The number took the unit that makes the product dimensionless: what is left is a pure number,
                // free like the number itself (so `sin(3*t)` may be a torque as `0.5` may).
                let q = if rate {
                    Q::Free
                } else {
                    self.binary_dim(*op, (qa, qb), &eb, a, b, e)?
                };
                self.finite(ir::Expr::Binary(*op, Box::new(ea), Box::new(eb)), e, cx)
                    .map(|x| (x, q))
            }
            _ => self.expr(e, cx),
        }
    }

    fn same_dims(
        &mut self,
        qa: Q,
        qb: Q,
        a: &ast::Expr,
        b: &ast::Expr,
        e: &ast::Expr,
        verb: &str,
    ) -> Option<Q> {
        match (qa, qb) {
            (Q::Dim(x), Q::Dim(y)) if x != y => {
                let mut d = Diagnostic::error(
                    "BG0310",
                    format!("quantities of different units are {verb}: {x} and {y}"),
                )
                .with_primary(e.span, "the units differ")
                .with_secondary(a.span, format!("this is in {x}"))
                .with_secondary(b.span, format!("this is in {y}"))
                .with_help("both sides must have one unit; check for a missing factor");
                if [x, y].into_iter().any(angle_like) {
                    d = d.with_note(
                        "angles are pure numbers in SI: `rad` is 1, `rad/s` is 1/s and `rad/s^2` is 1/s^2, so \
                         an angle and an angular velocity show as 1 and 1/s",
                    );
                }
                self.diags.push(d);
                None
            }
            (Q::Free, q) | (q, Q::Free) => Some(q),
            (q, _) => Some(q),
        }
    }

    fn power(&mut self, qa: Q, eb: &ir::Expr, qb: Q, a: &ast::Expr, b: &ast::Expr) -> Option<Q> {
        if let Q::Dim(d) = qb
            && !d.is_dimensionless()
        {
            self.not_dimensionless(b, d, "an exponent");
            return None;
        }
        let Q::Dim(base) = qa else {
            return Some(Q::Free);
        };
        if base.is_dimensionless() {
            return Some(qa);
        }
        let n = if is_literal(eb) { eval(eb, &[]) } else { None };
        let result = n.and_then(|n| {
            if n.fract() == 0.0 && n.abs() <= 127.0 {
                base.powi(n as i32)
            } else if (2.0 * n).fract() == 0.0 && n.abs() <= 63.0 {
                base.sqrt()?.powi((2.0 * n) as i32)
            } else {
                None
            }
        });
        match result {
            Some(d) => Some(Q::Dim(d)),
            None => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0309",
                        format!("a quantity in {base} cannot be raised to this power"),
                    )
                    .with_primary(b.span, "the exponent must be a constant whole number")
                    .with_secondary(a.span, format!("this is in {base}"))
                    .with_help(
                        "raise only dimensionless quantities to variable or fractional powers",
                    ),
                );
                None
            }
        }
    }

    fn not_dimensionless(&mut self, arg: &ast::Expr, d: Dim, role: &str) {
        self.diags.push(
            Diagnostic::error(
                "BG0309",
                format!("{role} must be dimensionless, but this is in {d}"),
            )
            .with_primary(arg.span, format!("this is in {d}"))
            .with_help("divide by a reference quantity of the same unit to make it dimensionless"),
        );
    }

    fn call(
        &mut self,
        f: &ast::Ident,
        args: &[ast::Expr],
        e: &ast::Expr,
        cx: Cx,
    ) -> Option<(ir::Expr, Q)> {
        if let Some(var) = port_var(&f.name) {
            if args.len() != 1 {
                self.arity(f, 1, args.len(), e);
                return None;
            }
            return self.reference(var, &args[0], e, cx);
        }
        if f.name == "int" {
            self.diags.push(
                Diagnostic::error(
                    "BG0208",
                    "`int` is only allowed as the whole value of a `var`",
                )
                .with_primary(f.span, "not allowed here")
                .with_help("declare `var theta [rad] = int(f(x));` and use `theta`"),
            );
            return None;
        }
        let Some(func) = Func::from_name(&f.name) else {
            let names = Func::ALL.map(Func::name);
            let declared = self.scopes.get(cx.scope).and_then(|s| s.get(&f.name));
            let help = match (declared, other_tool_function(&f.name)) {
                // `F(t)`: an input, parameter, output or var is a value, not a function of time.
                (
                    Some(
                        entity @ (Entity::Param(_)
                        | Entity::Input(_)
                        | Entity::Output(_)
                        | Entity::Var(_)),
                    ),
                    _,
                ) => {
                    let now = if matches!(entity, Entity::Input(_)) {
                        ", its value at the current time"
                    } else {
                        ""
                    };
                    format!(
                        "`{}` is {}, a value and not a function: write `{}`{now}",
                        f.name,
                        entity.describe(),
                        f.name
                    )
                }
                (_, Some(help)) => help.to_string(),
                _ => match closest(
                    &f.name,
                    names.iter().copied().chain(["e", "f", "p", "q", "int"]),
                ) {
                    Some(c) => format!("did you mean `{c}`?"),
                    None => format!("the functions are {}", names.join(", ")),
                },
            };
            self.diags.push(
                Diagnostic::error("BG0208", format!("unknown function `{}`", f.name))
                    .with_primary(f.span, "no such function")
                    .with_help(help),
            );
            return None;
        };
        if args.len() != func.arity() {
            self.arity(f, func.arity(), args.len(), e);
            return None;
        }
        let needs_dimensionless = !matches!(
            func,
            Func::Sqrt | Func::Abs | Func::Sign | Func::Min | Func::Max | Func::Atan2
        );
        let resolved: Vec<Option<(ir::Expr, Q)>> = args
            .iter()
            .map(|a| {
                if needs_dimensionless {
                    self.dimensionless_arg(a, cx)
                } else {
                    self.expr(a, cx)
                }
            })
            .collect();
        let resolved: Vec<(ir::Expr, Q)> = resolved.into_iter().collect::<Option<_>>()?;
        let q0 = resolved[0].1;
        let q = match func {
            Func::Sqrt => match q0 {
                Q::Free => Q::Free,
                Q::Dim(d) => match d.sqrt() {
                    Some(r) => Q::Dim(r),
                    None => {
                        self.diags.push(
                            Diagnostic::error(
                                "BG0309",
                                format!("the square root of a quantity in {d} has no unit"),
                            )
                            .with_primary(args[0].span, format!("this is in {d}"))
                            .with_help("every exponent of the unit must be even"),
                        );
                        return None;
                    }
                },
            },
            Func::Abs => q0,
            Func::Sign => match q0 {
                Q::Free => Q::Free,
                Q::Dim(_) => Q::Dim(Dim::NONE),
            },
            Func::Min | Func::Max => {
                self.same_dims(q0, resolved[1].1, &args[0], &args[1], e, "compared")?
            }
            Func::Atan2 => {
                self.same_dims(q0, resolved[1].1, &args[0], &args[1], e, "compared")?;
                Q::Dim(Dim::NONE)
            }
            _ => match q0 {
                Q::Free => Q::Free,
                Q::Dim(d) if d.is_dimensionless() => q0,
                Q::Dim(d) => {
                    self.not_dimensionless(
                        &args[0],
                        d,
                        &format!("the argument of `{}`", func.name()),
                    );
                    return None;
                }
            },
        };
        let exprs = resolved.into_iter().map(|(x, _)| x).collect();
        self.finite(ir::Expr::Call(func, exprs), e, cx)
            .map(|x| (x, q))
    }

    fn arity(&mut self, f: &ast::Ident, want: usize, found: usize, e: &ast::Expr) {
        let s = if want == 1 { "" } else { "s" };
        self.diags.push(
            Diagnostic::error(
                "BG0208",
                format!("`{}` takes {want} argument{s}, found {found}", f.name),
            )
            .with_primary(e.span, "wrong number of arguments")
            .with_help(format!(
                "call it as `{}({})`",
                f.name,
                if want == 1 { "x" } else { "a, b" }
            )),
        );
    }
}

/// An input, output or integrated flow holds its value in its declared unit (a `[rpm]` output is in rpm, in every
/// printed and generated form); expressions compute in SI, so a reference to it is multiplied by the unit's scale.
fn to_si(e: ir::Expr, unit: Unit) -> ir::Expr {
    if unit.scale == 1.0 {
        e
    } else {
        ir::Expr::Binary(
            BinOp::Mul,
            Box::new(ir::Expr::Const(unit.scale)),
            Box::new(e),
        )
    }
}

/// An SI value `e` expressed in `unit` (the value an output or integrated flow declared in `unit` holds).
pub(super) fn from_si(e: ir::Expr, unit: Unit) -> ir::Expr {
    if unit.scale == 1.0 {
        e
    } else {
        ir::Expr::Binary(
            BinOp::Div,
            Box::new(e),
            Box::new(ir::Expr::Const(unit.scale)),
        )
    }
}

/// One side a free number and the other free or dimensionless.
fn is_free_scale(a: Q, b: Q) -> bool {
    let free_or_none = |q: Q| q == Q::Free || q == Q::Dim(Dim::NONE);
    (a == Q::Free && free_or_none(b)) || (b == Q::Free && free_or_none(a))
}

fn combine(a: Q, b: Q, op: impl Fn(Dim, Dim) -> Option<Dim>) -> Option<Q> {
    Some(match (a, b) {
        (Q::Free, Q::Free) => Q::Free,
        (Q::Free, q) | (q, Q::Free) => q,
        (Q::Dim(x), Q::Dim(y)) => Q::Dim(op(x, y)?),
    })
}

pub(crate) fn port_var(name: &str) -> Option<PortVar> {
    Some(match name {
        "e" => PortVar::Effort,
        "f" => PortVar::Flow,
        "p" => PortVar::Momentum,
        "q" => PortVar::Displacement,
        _ => return None,
    })
}

pub(crate) fn var_letter(v: PortVar) -> &'static str {
    match v {
        PortVar::Effort => "e",
        PortVar::Flow => "f",
        PortVar::Momentum => "p",
        PortVar::Displacement => "q",
    }
}

/// What bgc writes for a constant of other tools and languages (`PI`, `M_PI`, Euler's `e`), with the certain fix.
fn other_tool_constant(name: &str) -> Option<(&'static str, Option<&'static str>)> {
    Some(match name {
        "PI" | "Pi" | "M_PI" => ("write `pi`", Some("pi")),
        "e" | "E" | "M_E" => (
            "Euler's number is `exp(1)`, and `e^x` is `exp(x)` (`e(x)` is the effort of element `x`)",
            None,
        ),
        _ => return None,
    })
}

/// What bgc writes for a function name of other modelling tools and languages, or `None`.
fn other_tool_function(name: &str) -> Option<&'static str> {
    Some(match name {
        "flow" => "the flow of element or port `x` is `f(x)`",
        "effort" => "the effort of element or port `x` is `e(x)`",
        "momentum" => "the momentum of an inertia `x` is `p(x)`",
        "displacement" | "charge" => "the displacement of a compliance `x` is `q(x)`",
        "log" => "write `ln` for the natural logarithm, `log10` for the decimal one",
        "pow" | "power" => "write a power with `^`, as in `x^2`",
        "sgn" | "signum" => "did you mean `sign`?",
        "fabs" => "did you mean `abs`?",
        "arcsin" => "did you mean `asin`?",
        "arccos" => "did you mean `acos`?",
        "arctan" => "did you mean `atan`?",
        "integ" | "integral" | "integrate" => {
            "an integral is a `var`: declare `var theta [rad] = int(f(x));` and use `theta`"
        }
        "der" | "diff" | "ddt" | "derivative" => {
            "expressions have no time derivatives: a storage element (`C`, `I`) holds a state and its rate"
        }
        _ => return None,
    })
}

/// Whether `d` is what an angle, an angular velocity or acceleration shows as (1, 1/s, 1/s^2), whose `rad` SI
/// leaves out of the displayed unit.
fn angle_like(d: Dim) -> bool {
    let [m, kg, s, a, k, mol, cd] = d.0;
    [m, kg, a, k, mol, cd] == [0; 6] && (-2..=0).contains(&s)
}
