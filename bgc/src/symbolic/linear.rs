//! Expansion of products over sums, and extraction of linear coefficients.
//!
//! [`Expr::linear_form`] splits `e = Σᵢ cᵢ xᵢ + rest` where no `cᵢ` and not `rest` depends on any `xⱼ`. It walks the
//! expression: a sum is linear when its terms are, a product when at most one factor depends on the `xⱼ` and that
//! factor is linear; any other occurrence of an `xⱼ` (in a power, a function argument, a product of two of them)
//! makes `e` non-linear. When the direct walk fails, it retries on [`Expr::expand`]`(e)`, so `x*(x + 1) - x^2` is
//! recognised as linear. Coefficients that expand to 0 are reported as exactly 0.

use super::SymbolicError;
use super::dag::{Dag, Memo};
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
    /// [`MAX_EXPANDED_POWER`]), recursively, also inside function arguments and exponents. Each distinct node is
    /// expanded once.
    pub fn expand(&self) -> Expr {
        let dag = Dag::new([self]);
        let mut memo: Memo<Expr> = Memo::new(&dag);
        for (i, e) in dag.order.iter().enumerate() {
            let x = |c: &Expr| memo.get(c).cloned().unwrap_or_else(|| c.clone());
            let expanded = match e.node() {
                Node::Const(_) | Node::Sym(_) => (*e).clone(),
                Node::Add(xs) => Expr::sum(xs.iter().map(x)),
                Node::Mul(xs) => expand_product(xs.iter().map(x)),
                Node::Pow(b, ex) => {
                    let b = x(b);
                    let ex = x(ex);
                    match ex.as_const().and_then(super::eval::as_i32) {
                        Some(n)
                            if (2..=MAX_EXPANDED_POWER).contains(&n)
                                && matches!(b.node(), Node::Add(_)) =>
                        {
                            expand_product(std::iter::repeat_n(b, n as usize))
                        }
                        _ => b.pow(&ex),
                    }
                }
                Node::Call(..) => e.map_children(&x),
            };
            memo.set(i, expanded);
        }
        memo.get(self).cloned().unwrap_or_else(|| self.clone())
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

/// The linear form of `e`, computed node by node from the bottom up. Only sums and products are descended into
/// (anything else that depends on a variable is not linear); the error is that of the first non-linear node met
/// from the top, as a walk from the top would find it: the first failing term of a sum, the one dependent factor of
/// a product.
fn linearize(e: &Expr, vars: &[Symbol]) -> Result<LinearForm, SymbolicError> {
    let full = Dag::new([e]);
    let mut depends = vec![false; full.len()];
    for (i, n) in full.order.iter().enumerate() {
        let mut d = n.as_symbol().is_some_and(|s| vars.contains(s));
        n.node().for_each_child(|c| {
            d |= full
                .index(c)
                .and_then(|k| depends.get(k))
                .copied()
                .unwrap_or(false);
        });
        if let Some(slot) = depends.get_mut(i) {
            *slot = d;
        }
    }
    let dep = |n: &Expr| {
        full.index(n)
            .and_then(|k| depends.get(k))
            .copied()
            .unwrap_or(false)
    };
    let linear_part = Dag::new_pruned([e], |n| {
        dep(n) && matches!(n.node(), Node::Add(_) | Node::Mul(_))
    });
    // A failure is kept as the node that is not linear; its message is made once, at the end.
    let mut memo: Memo<Result<LinearForm, Expr>> = Memo::new(&linear_part);
    for (i, n) in linear_part.order.iter().enumerate() {
        let form = |c: &Expr| memo.get(c).cloned().unwrap_or_else(|| Err(c.clone()));
        memo.set(i, linear_node(n, vars, &dep, &form));
    }
    memo.get(e)
        .cloned()
        .unwrap_or_else(|| Err(e.clone()))
        .map_err(|failed| not_linear(&failed, vars))
}

/// The linear form of one node from those of its children.
fn linear_node(
    e: &Expr,
    vars: &[Symbol],
    dep: &dyn Fn(&Expr) -> bool,
    form: &dyn Fn(&Expr) -> Result<LinearForm, Expr>,
) -> Result<LinearForm, Expr> {
    let zeros = || vec![Expr::zero(); vars.len()];
    if !dep(e) {
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
                let f = form(t)?;
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
            let mut dependent = factors.iter().filter(|f| dep(f));
            let (Some(linear_factor), None) = (dependent.next(), dependent.next()) else {
                return Err(e.clone());
            };
            let others = Expr::product(factors.iter().filter(|f| !dep(f)).cloned());
            let f = form(linear_factor)?;
            Ok(LinearForm {
                coefficients: f.coefficients.iter().map(|c| c * &others).collect(),
                rest: f.rest * others,
            })
        }
        Node::Const(_) | Node::Pow(..) | Node::Call(..) => Err(e.clone()),
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
