//! Expansion of products over sums, and extraction of linear coefficients.
//!
//! [`Expr::linear_form`] splits `e = Σᵢ cᵢ xᵢ + rest` where no `cᵢ` and not `rest` depends on any `xⱼ`. It walks the
//! expression: a sum is linear when its terms are, a product when at most one factor depends on the `xⱼ` and that
//! factor is linear; any other occurrence of an `xⱼ` (in a power, a function argument, a product of two of them)
//! makes `e` non-linear. When the direct walk fails, it retries on [`Expr::expand`]`(e)`, so `x*(x + 1) - x^2` is
//! recognised as linear. Coefficients that expand to 0 are reported as exactly 0.

use super::SymbolicError;
use super::expr::{Expr, Node, Symbol};

/// Products with more terms than this are left partly unexpanded (a guard against exponential growth).
pub const MAX_EXPANDED_TERMS: usize = 4096;

/// Integer powers of sums up to this exponent are expanded; higher ones are left as powers.
pub const MAX_EXPANDED_POWER: i32 = 16;

/// `e = Σᵢ coefficients[i] * vars[i] + rest`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearForm {
    pub coefficients: Vec<Expr>,
    pub rest: Expr,
}

impl Expr {
    /// Distributes products over sums and expands positive integer powers of sums (up to
    /// [`MAX_EXPANDED_POWER`]), recursively, also inside function arguments and exponents.
    pub fn expand(&self) -> Expr {
        match self.node() {
            Node::Const(_) | Node::Sym(_) => self.clone(),
            Node::Add(xs) => Expr::sum(xs.iter().map(Expr::expand)),
            Node::Mul(xs) => expand_product(xs.iter().map(Expr::expand)),
            Node::Pow(b, e) => {
                let b = b.expand();
                let e = e.expand();
                match e.as_const().and_then(super::eval::as_i32) {
                    Some(n)
                        if (2..=MAX_EXPANDED_POWER).contains(&n)
                            && matches!(b.node(), Node::Add(_)) =>
                    {
                        expand_product(std::iter::repeat_n(b, n as usize))
                    }
                    _ => b.pow(&e),
                }
            }
            Node::Call(..) => self.map_children(&Expr::expand),
        }
    }

    /// Splits `self = Σᵢ cᵢ varsᵢ + rest`; an error names the first variable found in a non-linear position.
    pub fn linear_form(&self, vars: &[Symbol]) -> Result<LinearForm, SymbolicError> {
        let form = match linearize(self, vars) {
            Ok(form) => form,
            Err(first_error) => linearize(&self.expand(), vars).map_err(|_| first_error)?,
        };
        Ok(LinearForm {
            coefficients: form
                .coefficients
                .into_iter()
                .map(|c| {
                    if c.expand().is_zero() {
                        Expr::zero()
                    } else {
                        c
                    }
                })
                .collect(),
            rest: form.rest,
        })
    }
}

fn expand_product(factors: impl Iterator<Item = Expr>) -> Expr {
    let mut terms: Vec<Expr> = vec![Expr::one()];
    let mut held_back: Vec<Expr> = Vec::new();
    for f in factors {
        match f.node() {
            Node::Add(ts) if terms.len() * ts.len() <= MAX_EXPANDED_TERMS => {
                terms = terms
                    .iter()
                    .flat_map(|t| ts.iter().map(move |s| t * s))
                    .collect();
            }
            Node::Add(_) => held_back.push(f),
            _ => terms.iter_mut().for_each(|t| *t = &*t * &f),
        }
    }
    Expr::product(std::iter::once(Expr::sum(terms)).chain(held_back))
}

fn linearize(e: &Expr, vars: &[Symbol]) -> Result<LinearForm, SymbolicError> {
    let zeros = || vec![Expr::zero(); vars.len()];
    if !e.depends_on_any(vars) {
        return Ok(LinearForm {
            coefficients: zeros(),
            rest: e.clone(),
        });
    }
    match e.node() {
        Node::Sym(s) => {
            let mut coefficients = zeros();
            if let Some(slot) = vars
                .iter()
                .position(|v| v == s)
                .and_then(|i| coefficients.get_mut(i))
            {
                *slot = Expr::one();
            }
            Ok(LinearForm {
                coefficients,
                rest: Expr::zero(),
            })
        }
        Node::Add(terms) => {
            let mut coefficients: Vec<Vec<Expr>> = vec![Vec::new(); vars.len()];
            let mut rest = Vec::new();
            for t in terms {
                let f = linearize(t, vars)?;
                for (acc, c) in coefficients.iter_mut().zip(f.coefficients) {
                    acc.push(c);
                }
                rest.push(f.rest);
            }
            Ok(LinearForm {
                coefficients: coefficients.into_iter().map(Expr::sum).collect(),
                rest: Expr::sum(rest),
            })
        }
        Node::Mul(factors) => {
            let mut dependent = factors.iter().filter(|f| f.depends_on_any(vars));
            let (Some(linear_factor), None) = (dependent.next(), dependent.next()) else {
                return Err(not_linear(e, vars));
            };
            let others = Expr::product(factors.iter().filter(|f| !f.depends_on_any(vars)).cloned());
            let f = linearize(linear_factor, vars)?;
            Ok(LinearForm {
                coefficients: f.coefficients.iter().map(|c| c * &others).collect(),
                rest: f.rest * others,
            })
        }
        Node::Const(_) | Node::Pow(..) | Node::Call(..) => Err(not_linear(e, vars)),
    }
}

fn not_linear(e: &Expr, vars: &[Symbol]) -> SymbolicError {
    let symbol = vars
        .iter()
        .find(|v| e.depends_on(v))
        .map(|v| v.name().to_string())
        .unwrap_or_default();
    SymbolicError::NotLinear {
        symbol,
        term: e.to_string(),
    }
}
