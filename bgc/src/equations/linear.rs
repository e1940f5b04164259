//! Linear state space and Jacobians.
//!
//! For `ẋ = f(x, u, p, t)`, `y = h(x, u, p, t)`: `A = ∂f/∂x`, `B = ∂f/∂u`, `C = ∂h/∂x`, `D = ∂h/∂u` as symbolic
//! expressions of the parameters (and, for a nonlinear model, of the operating point). A model is linear when
//! every entry is free of states, inputs and time and `f(0, 0) = 0`, `h(0, 0) = 0`; then [`linear_state_space`]
//! gives `A, B, C, D` exactly. For any model, [`linearise`] evaluates the Jacobians at an operating point.

use super::Equations;
use super::symbols::{self, Sym, SymExt};
use crate::symbolic::{Expr, Symbol, SymbolKind};
use std::collections::{BTreeSet, HashMap};

/// Which states make up the state vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateSelection {
    /// The energy variables of the storages in integral causality only (the minimal state of the bond graph).
    Energy,
    /// The energy states followed by every integrated flow (`var`).
    All,
}

/// Why a state space could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinearError {
    #[error("the equations are incomplete: {what} could not be derived")]
    Incomplete { what: String },
    #[error(
        "{what} depends on the integrated flow `{state}`, which the energy state vector leaves out"
    )]
    NeedsIntegratedState { what: String, state: String },
    #[error("{what} is not linear: {entry} depends on `{symbol}`")]
    NotLinear {
        what: String,
        entry: String,
        symbol: String,
    },
    #[error(
        "the model is time-varying: {entry} depends on `t` through {elements}; a state space ẋ = A x + B u has \
         constant matrices. Linearise at an operating point (`--at`), which takes the coefficients at t = 0, or \
         simulate the model"
    )]
    TimeVarying { entry: String, elements: String },
    #[error(
        "{what} has a constant part (an affine model): linearise it at an operating point instead"
    )]
    Affine { what: String },
    #[error("cannot differentiate {what}: it uses `{func}`")]
    NotDifferentiable { what: String, func: &'static str },
    #[error("cannot evaluate {what}: `{symbol}` has no value")]
    Unbound { what: String, symbol: String },
    #[error("{what} evaluates to a non-finite number")]
    NonFinite { what: String },
    #[error(
        "the rates of `{element}` come from its mass matrix M(q) ẋ = F: they have no symbolic state space; linearise at an operating point instead"
    )]
    MassMatrix { element: String },
    #[error(
        "{what} depends on time through {elements}: the state space ẋ = A x + B u has no column for a signal of time. Make it an input: declare `input NAME [UNIT];`, write the element's value in it (`Se mains = NAME;`), and give the signal at run time (`bgc simulate --input 'NAME=V0*sin(w*t)'`)"
    )]
    TimeDependent { what: String, elements: String },
    #[error("the mass matrix of `{element}` is singular at this point")]
    SingularMass { element: String },
    #[error("expected {expected} {what} values, got {got}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error(
        "the model has an algebraic loop solved numerically (for {tears}): its Jacobians have no closed form; linearise it at an operating point instead"
    )]
    ImplicitLoop {
        /// The tear variables, as messages list them ([`super::tear::tear_names`]), here and below.
        tears: String,
    },
    #[error(
        "the algebraic loop for {tears} could not be solved at the operating point: {reason} (largest residual {residual:e})"
    )]
    LoopNotSolved {
        tears: String,
        reason: &'static str,
        residual: f64,
    },
    #[error(
        "the algebraic loop for {tears} is singular at the operating point: its solution does not depend smoothly on the states and inputs"
    )]
    SingularLoop { tears: String },
}

/// Symbolic Jacobians of `f` and `h`.
#[derive(Clone, Debug, PartialEq)]
pub struct Jacobians {
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// `∂f/∂x`, `n × n`.
    pub dfdx: Vec<Vec<Expr>>,
    /// `∂f/∂u`, `n × m`.
    pub dfdu: Vec<Vec<Expr>>,
    /// `∂h/∂x`, `p × n`.
    pub dhdx: Vec<Vec<Expr>>,
    /// `∂h/∂u`, `p × m`.
    pub dhdu: Vec<Vec<Expr>>,
}

/// `A, B, C, D` of a linear model as expressions of the parameters.
pub type SymbolicStateSpace = Jacobians;

/// A numeric state space `ẋ = A x + B u`, `y = C x + D u`.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericStateSpace {
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub a: Vec<Vec<f64>>,
    pub b: Vec<Vec<f64>>,
    pub c: Vec<Vec<f64>>,
    pub d: Vec<Vec<f64>>,
}

impl Equations {
    /// The default parameter values, in parameter order.
    pub fn default_params(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.1).collect()
    }

    /// The number of states of a selection.
    pub fn state_count(&self, selection: StateSelection) -> usize {
        match selection {
            StateSelection::Energy => self.energy_states,
            StateSelection::All => self.states.len(),
        }
    }
}

/// The tear variables (names) that the selected rates or the outputs hold, and where the first one is.
pub(super) fn implicit_in(
    eqs: &Equations,
    f: &[Expr],
    h: &[Expr],
) -> Option<(String, String, String)> {
    let tear = |e: &Expr| {
        let mut found = None;
        e.for_each_sym(&mut |s| {
            if found.is_none() && matches!(s, Sym::Tear(_)) {
                found = Some(s);
            }
        });
        found
    };
    let names = || {
        let all: Vec<String> = eqs
            .tear_blocks
            .iter()
            .flat_map(|b| b.names.iter().cloned())
            .collect();
        super::tear::tear_names(&all)
    };
    for (i, e) in f.iter().enumerate() {
        if let Some(z) = tear(e) {
            let what = format!("the rate of `{}`", eqs.sym_name(Sym::State(i)));
            return Some((what, eqs.sym_name(z), names()));
        }
    }
    for (o, e) in eqs.outputs.iter().zip(h) {
        if let Some(z) = tear(e) {
            return Some((format!("output `{}`", o.name), eqs.sym_name(z), names()));
        }
    }
    None
}

/// The selected rates and all outputs, explicit, checked for use of left-out states.
pub(super) fn selected(
    eqs: &Equations,
    selection: StateSelection,
) -> Result<(Vec<Expr>, Vec<Expr>), LinearError> {
    let n = eqs.state_count(selection);
    let mut f = Vec::with_capacity(n);
    for i in 0..n {
        let name = eqs
            .states
            .get(i)
            .map(|s| s.name.clone())
            .unwrap_or_default();
        let e = eqs
            .f
            .get(i)
            .cloned()
            .flatten()
            .ok_or_else(|| LinearError::Incomplete {
                what: format!("the rate of `{name}`"),
            })?;
        f.push(e);
    }
    let mut h = Vec::with_capacity(eqs.outputs.len());
    for (o, e) in eqs.outputs.iter().zip(eqs.outputs_inlined()) {
        h.push(e.ok_or_else(|| LinearError::Incomplete {
            what: format!("output `{}`", o.name),
        })?);
    }
    let what_f = |i: usize| {
        format!(
            "the rate of `{}`",
            eqs.states.get(i).map(|s| s.name.as_str()).unwrap_or("?")
        )
    };
    let what_h = |k: usize| {
        format!(
            "output `{}`",
            eqs.outputs.get(k).map(|o| o.name.as_str()).unwrap_or("?")
        )
    };
    let check = |e: &Expr, what: String| -> Result<(), LinearError> {
        // The first left-out state the expression reads, found in one walk.
        let mut first: Option<usize> = None;
        e.for_each_sym(&mut |s| {
            if let Sym::State(j) = s
                && j >= n
                && j < eqs.states.len()
            {
                first = Some(first.map_or(j, |f| f.min(j)));
            }
        });
        match first {
            Some(j) => Err(LinearError::NeedsIntegratedState {
                what,
                state: eqs.sym_name(Sym::State(j)),
            }),
            None => Ok(()),
        }
    };
    for (i, e) in f.iter().enumerate() {
        check(e, what_f(i))?;
    }
    for (k, e) in h.iter().enumerate() {
        check(e, what_h(k))?;
    }
    Ok((f, h))
}

fn jacobian(
    rows: &[Expr],
    vars: &[Sym],
    what: &dyn Fn(usize) -> String,
) -> Result<Vec<Vec<Expr>>, LinearError> {
    let column: HashMap<Sym, usize> = vars.iter().enumerate().map(|(j, &v)| (v, j)).collect();
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            // Only the columns of the symbols the row reads (one walk) are differentiated, in column order; every
            // other entry is zero.
            let mut read = BTreeSet::new();
            r.for_each_sym(&mut |s| {
                if let Some(&j) = column.get(&s) {
                    read.insert(j);
                }
            });
            let read: Vec<usize> = read.into_iter().collect();
            let wrt: Vec<Sym> = read.iter().map(|&j| vars[j]).collect();
            let slopes = symbols::gradient(r, &wrt).map_err(|symbols::NotDifferentiable(f)| {
                LinearError::NotDifferentiable {
                    what: what(i),
                    func: f.name(),
                }
            })?;
            let mut row = vec![Expr::zero(); vars.len()];
            for (j, d) in read.into_iter().zip(slopes) {
                row[j] = d;
            }
            Ok(row)
        })
        .collect()
}

/// The symbolic Jacobians `∂f/∂x, ∂f/∂u, ∂h/∂x, ∂h/∂u` of the selected state vector. For the mass-matrix rows of
/// an I-field (see [`Equations::mass`]) the rows are those of the generalised forces `F`, not of the rates.
pub fn jacobians(eqs: &Equations, selection: StateSelection) -> Result<Jacobians, LinearError> {
    let (f, h) = selected(eqs, selection)?;
    if let Some((_, _, tears)) = implicit_in(eqs, &f, &h) {
        return Err(LinearError::ImplicitLoop { tears });
    }
    let n = f.len();
    let xs: Vec<Sym> = (0..n).map(Sym::State).collect();
    let us: Vec<Sym> = (0..eqs.inputs.len()).map(Sym::Input).collect();
    let wf = |i: usize| format!("the rate of `{}`", eqs.sym_name(Sym::State(i)));
    let wh = |k: usize| {
        format!(
            "output `{}`",
            eqs.outputs.get(k).map(|o| o.name.as_str()).unwrap_or("?")
        )
    };
    Ok(Jacobians {
        states: (0..n).map(|i| eqs.sym_name(Sym::State(i))).collect(),
        inputs: eqs.inputs.clone(),
        outputs: eqs.outputs.iter().map(|o| o.name.clone()).collect(),
        dfdx: jacobian(&f, &xs, &wf)?,
        dfdu: jacobian(&f, &us, &wf)?,
        dhdx: jacobian(&h, &xs, &wh)?,
        dhdu: jacobian(&h, &us, &wh)?,
    })
}

/// `A, B, C, D` of a linear model, as expressions of the parameters; an error names the first nonlinear or affine
/// entry. A rate or output that holds the unknown of a nonlinear algebraic loop is not linear.
pub fn linear_state_space(
    eqs: &Equations,
    selection: StateSelection,
) -> Result<SymbolicStateSpace, LinearError> {
    // An I-field with a configuration-dependent inertia matrix has no symbolic state space; a constant one is
    // solved below.
    let variable = |s: Sym| matches!(s, Sym::State(_) | Sym::Input(_) | Sym::Time);
    if let Some(b) = eqs
        .mass
        .iter()
        .find(|b| b.matrix.iter().flatten().any(|m| m.any_sym(&variable)))
    {
        return Err(LinearError::MassMatrix {
            element: b.element.clone(),
        });
    }
    let (f, h) = selected(eqs, selection)?;
    if let Some((entry, symbol, _)) = implicit_in(eqs, &f, &h) {
        let what = if entry.starts_with("output") {
            "h"
        } else {
            "f"
        };
        return Err(LinearError::NotLinear {
            what: what.to_string(),
            entry,
            symbol,
        });
    }
    let mut j = jacobians(eqs, selection)?;
    solve_constant_mass(eqs, &mut j)?;
    let check = |m: &[Vec<Expr>], name: &str, what: &str| -> Result<(), LinearError> {
        for (r, row) in m.iter().enumerate() {
            for (c, e) in row.iter().enumerate() {
                let mut found = None;
                e.for_each_sym(&mut |s| {
                    if found.is_none() && variable(s) {
                        found = Some(s);
                    }
                });
                if let Some(s) = found {
                    let entry = format!("{name}[{r}][{c}]");
                    return Err(not_linear(eqs, what, entry, &s.symbol()));
                }
            }
        }
        Ok(())
    };
    check(&j.dfdx, "A", "f")?;
    check(&j.dfdu, "B", "f")?;
    check(&j.dhdx, "C", "h")?;
    check(&j.dhdu, "D", "h")?;
    // Linear, not affine: f(0, 0, t) = 0 and h(0, 0, t) = 0 for every t. A term in `t` alone (a signal written into
    // the model) would vanish from A and B, so it is an error of its own.
    let at_zero = |e: &Expr| {
        symbols::subst(e, &mut |s| {
            matches!(s, Sym::State(_) | Sym::Input(_)).then(Expr::zero)
        })
    };
    let remainder = |e: &Expr, what: String| -> Result<(), LinearError> {
        let rest = at_zero(e);
        if rest.contains(Sym::Time) {
            return Err(LinearError::TimeDependent {
                what,
                elements: time_elements_text(eqs),
            });
        }
        if !rest.is_zero() {
            return Err(LinearError::Affine { what });
        }
        Ok(())
    };
    for (i, e) in f.iter().enumerate() {
        remainder(e, format!("the rate of `{}`", eqs.sym_name(Sym::State(i))))?;
    }
    for (k, e) in h.iter().enumerate() {
        let name = j.outputs.get(k).cloned().unwrap_or_default();
        remainder(e, format!("output `{name}`"))?;
    }
    Ok(j)
}

/// The error for an entry `entry` of the Jacobians of `what` (`f`, `h`) that depends on the variable `symbol`.
pub(super) fn not_linear(
    eqs: &Equations,
    what: &str,
    entry: String,
    symbol: &Symbol,
) -> LinearError {
    match symbol.kind() {
        SymbolKind::Time => LinearError::TimeVarying {
            entry,
            elements: time_elements_text(eqs),
        },
        _ => LinearError::NotLinear {
            what: what.to_string(),
            entry,
            symbol: eqs.symbol_name(symbol),
        },
    }
}

/// Where `t` comes from, as a phrase: "`mains`, whose value uses `t`", "`a`, `b`, whose values use `t`", or a term
/// written with `t` (an output's) when no element's value uses it.
pub(super) fn time_elements_text(eqs: &Equations) -> String {
    let names: Vec<String> = eqs.time_signals.iter().map(|n| format!("`{n}`")).collect();
    match names.len() {
        0 => "a term written with `t`".into(),
        1 => format!("{}, whose value uses `t`", names[0]),
        _ => format!("{}, whose values use `t`", names.join(", ")),
    }
}

/// The rows of the I-fields' flow states in `j`, solved: for a constant inertia matrix `M`, `M ẋ = F` gives
/// `∂ẋ/∂v = M⁻¹ ∂F/∂v` (symbolic elimination; `M` is symmetric positive definite for a physical field, so its pivots
/// are positive). The callers have checked that every `M` is free of states, inputs and time.
// Column loops read like the elimination they feed.
#[allow(clippy::needless_range_loop)]
fn solve_constant_mass(eqs: &Equations, j: &mut Jacobians) -> Result<(), LinearError> {
    let n = j.dfdx.len();
    for block in &eqs.mass {
        if block.states.iter().any(|&s| s >= n) {
            return Err(LinearError::MassMatrix {
                element: block.element.clone(),
            });
        }
        for m in [&mut j.dfdx, &mut j.dfdu] {
            let columns = m.first().map_or(0, Vec::len);
            for c in 0..columns {
                let mut a = block.matrix.clone();
                let mut rhs: Vec<Expr> = block.states.iter().map(|&r| m[r][c].clone()).collect();
                let solved = super::solve::gauss(&mut a, &mut rhs).ok_or_else(|| {
                    LinearError::SingularMass {
                        element: block.element.clone(),
                    }
                })?;
                for (&r, v) in block.states.iter().zip(solved) {
                    m[r][c] = v;
                }
            }
        }
    }
    Ok(())
}

pub(crate) fn check_len(
    what: &'static str,
    expected: usize,
    got: usize,
) -> Result<(), LinearError> {
    if expected == got {
        Ok(())
    } else {
        Err(LinearError::Dimension {
            what,
            expected,
            got,
        })
    }
}

fn evaluate(
    eqs: &Equations,
    m: &[Vec<Expr>],
    name: &str,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<Vec<Vec<f64>>, LinearError> {
    m.iter()
        .enumerate()
        .map(|(r, row)| {
            row.iter()
                .enumerate()
                .map(|(c, e)| {
                    let what = format!("{name}[{r}][{c}]");
                    let v = symbols::eval(e, value).map_err(|err| match err {
                        symbols::EvalError::Unbound(s) => LinearError::Unbound {
                            what: what.clone(),
                            symbol: eqs.sym_name(s),
                        },
                        symbols::EvalError::Foreign(f) => LinearError::Unbound {
                            what: what.clone(),
                            symbol: f,
                        },
                    })?;
                    if v.is_finite() {
                        Ok(v)
                    } else {
                        Err(LinearError::NonFinite { what })
                    }
                })
                .collect()
        })
        .collect()
}

/// Evaluates a symbolic state space (or Jacobians) at parameter values, operating point `x0`, `u0` and time `t0`.
pub fn evaluate_at(
    eqs: &Equations,
    j: &Jacobians,
    params: &[f64],
    x0: &[f64],
    u0: &[f64],
    t0: f64,
) -> Result<NumericStateSpace, LinearError> {
    check_len("parameter", eqs.params.len(), params.len())?;
    check_len("state", j.states.len(), x0.len())?;
    check_len("input", eqs.inputs.len(), u0.len())?;
    let value = |s: Sym| super::numeric::point(s, params, x0, u0, t0);
    Ok(NumericStateSpace {
        states: j.states.clone(),
        inputs: j.inputs.clone(),
        outputs: j.outputs.clone(),
        a: evaluate(eqs, &j.dfdx, "A", &value)?,
        b: evaluate(eqs, &j.dfdu, "B", &value)?,
        c: evaluate(eqs, &j.dhdx, "C", &value)?,
        d: evaluate(eqs, &j.dhdu, "D", &value)?,
    })
}

/// The numeric `A, B, C, D` of a linear model at parameter values (in [`Equations::params`] order).
pub fn numeric_state_space(
    eqs: &Equations,
    selection: StateSelection,
    params: &[f64],
) -> Result<NumericStateSpace, LinearError> {
    let ss = linear_state_space(eqs, selection)?;
    let n = ss.states.len();
    evaluate_at(
        eqs,
        &ss,
        params,
        &vec![0.0; n],
        &vec![0.0; eqs.inputs.len()],
        0.0,
    )
}

/// The linearisation of any model at the operating point `(x0, u0, t0)`: the Jacobians evaluated there (for the
/// mass-matrix rows of I-fields, those of the solved rates). A model with nonlinear algebraic loops has them solved
/// at that point and differentiated by the implicit function theorem ([`super::tear`]).
pub fn linearise(
    eqs: &Equations,
    selection: StateSelection,
    params: &[f64],
    x0: &[f64],
    u0: &[f64],
    t0: f64,
) -> Result<NumericStateSpace, LinearError> {
    let (f, h) = selected(eqs, selection)?;
    if implicit_in(eqs, &f, &h).is_some() {
        check_len("parameter", eqs.params.len(), params.len())?;
        check_len("state", f.len(), x0.len())?;
        check_len("input", eqs.inputs.len(), u0.len())?;
        return super::implicit_linear::linearise(eqs, (&f, &h), (params, x0, u0, t0));
    }
    let j = jacobians(eqs, selection)?;
    let mut ss = evaluate_at(eqs, &j, params, x0, u0, t0)?;
    let value = |s: Sym| super::numeric::point(s, params, x0, u0, t0);
    super::numeric::correct_mass_rows(eqs, &value, &mut ss)?;
    Ok(ss)
}
