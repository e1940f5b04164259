//! The canonical total order of expressions, by which sums sort their terms and products their factors.
//!
//! Terms of sums and factors of products are sorted by [`Ord for Expr`](Expr#impl-Ord-for-Expr):
//! - constants come first, ordered by [`f64::total_cmp`];
//! - any other expression is seen as `coefficient × Π baseᵢ^expᵢ` (a product's own factors; `x^e` is one factor;
//!   anything else is one factor with exponent 1). Two expressions compare their factor lists lexicographically,
//!   each factor by base then exponent, then the shorter list first, then the coefficient.
//! - bases compare by kind (constant < symbol < call < sum < product < power), then structurally: symbols by
//!   [`Symbol`](super::Symbol)'s order (kind, then name), calls by function then arguments, sums by their terms.
//!
//! So `x` < `x^2` < `x*y` < `y`, and `2*x` sits next to `x`: like terms are adjacent, which is what collection needs.
//!
//! The comparison is a sequence of steps of which the first that is not `Equal` decides. It runs on an explicit
//! work list of such steps rather than by recursion, so comparing deep expressions cannot overflow the stack, and it
//! stops at identical nodes (equal by hash-consing), so it descends only where two expressions differ.

use super::expr::{Expr, Node};
use std::cmp::Ordering;

impl PartialOrd for Expr {
    fn partial_cmp(&self, other: &Expr) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Expr {
    fn cmp(&self, other: &Expr) -> Ordering {
        if self.same_node(other) {
            return Ordering::Equal;
        }
        // Most comparisons are decided by the bases of the first factors, which needs no work list.
        if let Some(order) = by_first_bases(self, other) {
            return order;
        }
        // The first step runs before anything is pushed: no allocation when it decides.
        let mut steps = Vec::new();
        match Step::Expr(self, other).run(&mut steps) {
            Ordering::Equal => run(steps),
            decided => decided,
        }
    }
}

/// Runs the steps of a comparison until one decides it.
fn run(mut steps: Vec<Step<'_>>) -> Ordering {
    while let Some(step) = steps.pop() {
        let order = step.run(&mut steps);
        if order.is_ne() {
            return order;
        }
    }
    Ordering::Equal
}

/// The order of two expressions when the bases of their first factors decide it: constants against anything else,
/// or first bases of different kinds or different symbols (the first step of the full comparison, which compares
/// factors before their number and coefficients). `None` when the full comparison must go on.
fn by_first_bases(x: &Expr, y: &Expr) -> Option<Ordering> {
    match (x.node(), y.node()) {
        (Node::Const(a), Node::Const(b)) => return Some(a.total_cmp(b)),
        (Node::Const(_), _) => return Some(Ordering::Less),
        (_, Node::Const(_)) => return Some(Ordering::Greater),
        _ => {}
    }
    let (bx, _) = x.coeff_and_factors().1.first()?.base_exp();
    let (by, _) = y.coeff_and_factors().1.first()?.base_exp();
    by_bases(bx, by)
}

/// The order of two bases when their kinds or (for symbols) their symbols decide it.
fn by_bases(bx: &Expr, by: &Expr) -> Option<Ordering> {
    if bx.same_node(by) {
        return None;
    }
    let by_rank = rank(bx).cmp(&rank(by));
    if by_rank.is_ne() {
        return Some(by_rank);
    }
    match (bx.node(), by.node()) {
        (Node::Sym(a), Node::Sym(b)) => Some(a.cmp(b)).filter(|o| o.is_ne()),
        _ => None,
    }
}

/// One step of a comparison: either decided at once, or expanded into further steps (pushed in reverse, so that
/// they run in order).
enum Step<'a> {
    Decided(Ordering),
    /// Whole expressions.
    Expr(&'a Expr, &'a Expr),
    /// Factors: base, then exponent.
    Factor(&'a Expr, &'a Expr),
    /// Exponents of two factors with equal bases; `None` is exponent 1.
    Exponent(Option<&'a Expr>, Option<&'a Expr>),
    /// Bases: kind, then structure.
    Base(&'a Expr, &'a Expr),
}

impl<'a> Step<'a> {
    /// Decides the step, or pushes its parts and returns `Equal`.
    fn run(self, steps: &mut Vec<Step<'a>>) -> Ordering {
        match self {
            Step::Decided(o) => o,
            Step::Expr(x, y) => compare_exprs(x, y, steps),
            Step::Factor(x, y) => {
                let (bx, ex) = x.base_exp();
                let (by, ey) = y.base_exp();
                steps.push(Step::Exponent(ex, ey));
                steps.push(Step::Base(bx, by));
                Ordering::Equal
            }
            Step::Exponent(ex, ey) => match (ex, ey) {
                (None, None) => Ordering::Equal,
                (None, Some(e)) => cmp_with_one(e).reverse(),
                (Some(e), None) => cmp_with_one(e),
                (Some(a), Some(b)) => {
                    steps.push(Step::Expr(a, b));
                    Ordering::Equal
                }
            },
            Step::Base(x, y) => compare_bases(x, y, steps),
        }
    }
}

fn compare_exprs<'a>(x: &'a Expr, y: &'a Expr, steps: &mut Vec<Step<'a>>) -> Ordering {
    if x.same_node(y) {
        return Ordering::Equal;
    }
    match (x.node(), y.node()) {
        (Node::Const(a), Node::Const(b)) => a.total_cmp(b),
        (Node::Const(_), _) => Ordering::Less,
        (_, Node::Const(_)) => Ordering::Greater,
        _ => {
            let (ca, fa) = x.coeff_and_factors();
            let (cb, fb) = y.coeff_and_factors();
            steps.push(Step::Decided(ca.total_cmp(&cb)));
            push_factor_lists(fa, fb, steps);
            Ordering::Equal
        }
    }
}

/// Factor lists compared factor by factor, then the shorter first.
fn push_factor_lists<'a>(fa: &'a [Expr], fb: &'a [Expr], steps: &mut Vec<Step<'a>>) {
    steps.push(Step::Decided(fa.len().cmp(&fb.len())));
    for (f, g) in fa.iter().zip(fb).rev() {
        steps.push(Step::Factor(f, g));
    }
}

/// The order of two coefficient-free terms given by their factors (`coeff_and_factors().1`): the order of the
/// products of those factors, without building them.
pub(super) fn cmp_factors(fa: &[Expr], fb: &[Expr]) -> Ordering {
    if Expr::same_nodes(fa, fb) {
        return Ordering::Equal;
    }
    if let (Some(f), Some(g)) = (fa.first(), fb.first())
        && let Some(order) = by_bases(f.base_exp().0, g.base_exp().0)
    {
        return order;
    }
    let mut steps = Vec::new();
    push_factor_lists(fa, fb, &mut steps);
    run(steps)
}

fn compare_bases<'a>(x: &'a Expr, y: &'a Expr, steps: &mut Vec<Step<'a>>) -> Ordering {
    if x.same_node(y) {
        return Ordering::Equal;
    }
    let by_rank = rank(x).cmp(&rank(y));
    if by_rank.is_ne() {
        return by_rank;
    }
    match (x.node(), y.node()) {
        (Node::Const(a), Node::Const(b)) => a.total_cmp(b),
        (Node::Sym(a), Node::Sym(b)) => a.cmp(b),
        (Node::Call(f, xs), Node::Call(g, ys)) => {
            let by_func = f.cmp(g);
            if by_func.is_eq() {
                push_lists(xs, ys, steps);
            }
            by_func
        }
        (Node::Add(xs), Node::Add(ys)) => {
            push_lists(xs, ys, steps);
            Ordering::Equal
        }
        (Node::Mul(_), Node::Mul(_)) => {
            steps.push(Step::Expr(x, y));
            Ordering::Equal
        }
        (Node::Pow(b1, e1), Node::Pow(b2, e2)) => {
            steps.push(Step::Expr(e1, e2));
            steps.push(Step::Expr(b1, b2));
            Ordering::Equal
        }
        _ => Ordering::Equal,
    }
}

/// Lexicographic comparison of two lists, then the shorter first.
fn push_lists<'a>(xs: &'a [Expr], ys: &'a [Expr], steps: &mut Vec<Step<'a>>) {
    steps.push(Step::Decided(xs.len().cmp(&ys.len())));
    for (x, y) in xs.iter().zip(ys).rev() {
        steps.push(Step::Expr(x, y));
    }
}

/// `e` compared with the constant 1.
fn cmp_with_one(e: &Expr) -> Ordering {
    match e.as_const() {
        Some(c) => c.total_cmp(&1.0),
        None => Ordering::Greater,
    }
}

fn rank(e: &Expr) -> u8 {
    match e.node() {
        Node::Const(_) => 0,
        Node::Sym(_) => 1,
        Node::Call(..) => 2,
        Node::Add(_) => 3,
        Node::Mul(_) => 4,
        Node::Pow(..) => 5,
    }
}
