//! Nonlinear algebraic loops, kept implicit and solved numerically.
//!
//! Where the resolver tears a loop at a bond variable `v` and the loop is not affine in it (a diode's exponential
//! in series with a resistor), `v` becomes an unknown of the equations, the tear variable `z = Tear(v)` (printed
//! `loop_<v>`), defined by its residual equation
//!
//! ```text
//! 0 = r(z, x, u, p, t) = E(z, x, u, p, t) − z
//! ```
//!
//! where `E` is what the loop computes for `v` from the torn value. Rates, outputs and energy terms hold `z`
//! symbolically; whoever evaluates them solves the residuals first. Residuals that hold each other's tears are
//! grouped into blocks (strongly connected components of "refers to"), ordered so that a block refers only to its
//! own tears and those of earlier blocks: the blocks are solved in turn, each by Newton's method
//! ([`super::newton`]) with the analytic Jacobian `∂r/∂z` of the residuals.
//!
//! Linearisation at an operating point uses the implicit function theorem: with `r(z(x, u), x, u) = 0`,
//! `dz/dx = −(∂r/∂z)⁻¹ ∂r/∂x` and `dz/du = −(∂r/∂z)⁻¹ ∂r/∂u`, so `A = ∂f/∂x + ∂f/∂z dz/dx`,
//! `B = ∂f/∂u + ∂f/∂z dz/du`, and the same for `C`, `D` ([`super::linearise`]).

use super::Equations;
use super::newton::{self, Failure, Problem, Settings};
use super::symbols::{self, Sym, SymExt};
use crate::symbolic::Expr;
use petgraph::graph::DiGraph;
use std::collections::HashMap;

/// One block of nonlinear algebraic equations solved together: `0 = r(z, x, u, p, t)` for its tear variables `z`.
#[derive(Clone, Debug, PartialEq)]
pub struct TearBlock {
    /// The unknowns, `Sym::Tear(v)` for the torn bond variable `v`. Rates, outputs and energy terms hold these
    /// symbols: their values are the block's solution.
    pub tears: Vec<Sym>,
    /// The tears' printable names (`loop_<variable>`, as [`Equations::sym_name`] gives them).
    pub names: Vec<String>,
    /// One residual per tear, in states, inputs, parameters, `t`, this block's tears and earlier blocks' tears.
    pub residuals: Vec<Expr>,
}

/// The blocks of the implicit loops `(v, r)` (tear variable `v`, residual `r`), in solving order.
pub(crate) fn blocks(implicit: &[(usize, Expr)], name: &dyn Fn(Sym) -> String) -> Vec<TearBlock> {
    // Edge i -> j: residual i refers to the tear of loop j. Tarjan's algorithm lists the strongly connected
    // components in reverse topological order of the edges, that is each block after the blocks it refers to.
    let mut graph = DiGraph::<usize, ()>::new();
    let nodes: Vec<_> = (0..implicit.len()).map(|k| graph.add_node(k)).collect();
    let loop_of: HashMap<Sym, usize> = implicit
        .iter()
        .enumerate()
        .map(|(j, (w, _))| (Sym::Tear(*w), j))
        .collect();
    // Each residual's tears in one walk (not one walk per loop: a ladder has hundreds).
    for (i, (_, r)) in implicit.iter().enumerate() {
        for j in r
            .syms()
            .into_iter()
            .filter_map(|s| loop_of.get(&s).copied())
        {
            if let (Some(&a), Some(&b)) = (nodes.get(i), nodes.get(j)) {
                graph.add_edge(a, b, ());
            }
        }
    }
    petgraph::algo::tarjan_scc(&graph)
        .into_iter()
        .map(|component| {
            let mut members: Vec<usize> = component
                .into_iter()
                .filter_map(|n| graph.node_weight(n).copied())
                .collect();
            members.sort_unstable();
            let chosen: Vec<&(usize, Expr)> =
                members.iter().filter_map(|&k| implicit.get(k)).collect();
            let tears: Vec<Sym> = chosen.iter().map(|(v, _)| Sym::Tear(*v)).collect();
            TearBlock {
                names: tears.iter().map(|&s| name(s)).collect(),
                residuals: chosen.iter().map(|(_, r)| r.clone()).collect(),
                tears,
            }
        })
        .collect()
}

/// The scale of residual `r` for the convergence test of [`super::newton`]: its magnitude ([`Expr::magnitude`]: the
/// magnitudes of its terms, and inside a product those of the product's terms, `|a| + |c|·(|d| + |e|) + |z|` for
/// `r = a + c·(d + e) − z`), plus the magnitude of its own tear `z`. A residual cannot be computed more accurately
/// than about `ε` times this, however much its terms cancel.
pub fn residual_scale(r: &Expr, own: Sym) -> Expr {
    symbols::add(vec![
        r.magnitude(),
        symbols::call(crate::ir::Func::Abs, vec![symbols::leaf(own)]),
    ])
}

/// A block's residuals evaluated by the tree evaluator, the other symbols' values given.
struct TreeBlock<'a> {
    block: &'a TearBlock,
    scales: Vec<Expr>,
    jacobian: Vec<Expr>,
    value: &'a dyn Fn(Sym) -> Option<f64>,
}

impl TreeBlock<'_> {
    fn at(&self, z: &[f64], e: &Expr) -> f64 {
        let tears = &self.block.tears;
        symbols::eval(e, &|s| match tears.iter().position(|&t| t == s) {
            Some(k) => z.get(k).copied(),
            None => (self.value)(s),
        })
        .unwrap_or(f64::NAN)
    }
}

impl Problem for TreeBlock<'_> {
    fn size(&self) -> usize {
        self.block.tears.len()
    }

    fn residual(&mut self, z: &[f64], r: &mut [f64], scale: &mut [f64]) {
        for (out, e) in r.iter_mut().zip(&self.block.residuals) {
            *out = self.at(z, e);
        }
        for (out, e) in scale.iter_mut().zip(&self.scales) {
            *out = self.at(z, e);
        }
    }

    fn jacobian(&mut self, z: &[f64], jac: &mut [f64]) {
        for (out, e) in jac.iter_mut().zip(&self.jacobian) {
            *out = self.at(z, e);
        }
    }
}

/// `∂r_i/∂z_j` of a block, row-major; `None` when a residual uses a function without a derivative.
pub(crate) fn block_jacobian(block: &TearBlock) -> Option<Vec<Expr>> {
    let m = block.tears.len();
    let column: HashMap<Sym, usize> = block
        .tears
        .iter()
        .enumerate()
        .map(|(j, &z)| (z, j))
        .collect();
    let mut out = vec![Expr::zero(); m * m];
    for (i, r) in block.residuals.iter().enumerate() {
        // Only the tears the residual reads, all in one walk of it when they are many (a block of linear loops
        // whose residuals each read every tear).
        let read: Vec<(usize, Sym)> = r
            .syms()
            .into_iter()
            .filter_map(|s| column.get(&s).map(|&j| (j, s)))
            .collect();
        let wrt: Vec<Sym> = read.iter().map(|&(_, s)| s).collect();
        for ((j, _), d) in read.iter().zip(symbols::gradient(r, &wrt).ok()?) {
            out[i * m + j] = d;
        }
    }
    Some(out)
}

/// A block that could not be solved.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopFailure {
    /// The block's tear names.
    pub tears: Vec<String>,
    /// The tear whose residual is largest.
    pub worst: String,
    pub failure: Failure,
}

impl LoopFailure {
    /// Its tears for a message ([`tear_names`]).
    pub fn tear_list(&self) -> String {
        tear_names(&self.tears)
    }
}

/// The most tear names a message lists; a longer list gives the first few, the last and the count.
const LISTED_TEARS: usize = 8;

/// The tear variables `names` of a loop for a message, each in backticks: `` `loop_a`, `loop_b` ``, or for a block
/// of more than eight the first four, the last and how many there are (a ladder's block of a thousand tears would
/// otherwise make a message of sixteen thousand characters).
pub fn tear_names(names: &[String]) -> String {
    let quoted = |ns: &[String]| {
        ns.iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match names {
        [first @ .., last] if names.len() > LISTED_TEARS => format!(
            "{}, …, `{last}` ({} tear variables)",
            quoted(first.get(..LISTED_TEARS / 2).unwrap_or(first)),
            names.len()
        ),
        _ => quoted(names),
    }
}

/// `the algebraic loop for` its tears `names` ([`tear_names`]), as the loop errors name a block.
pub fn loop_named(names: &[String]) -> String {
    loop_for(&tear_names(names))
}

/// `the algebraic loop for` the tears `tears`, already listed for a message ([`tear_names`]).
pub fn loop_for(tears: &str) -> String {
    format!("the algebraic loop for {tears}")
}

/// Solves every block at the values `value` of the other symbols (parameters, states, inputs, `t`), from `z = 0`.
/// Returns each tear with its value.
pub fn solve_all(
    eqs: &Equations,
    value: &dyn Fn(Sym) -> Option<f64>,
) -> Result<Vec<(Sym, f64)>, LoopFailure> {
    let mut solved: Vec<(Sym, f64)> = Vec::new();
    for block in &eqs.tear_blocks {
        let known = |s: Sym| match solved.iter().find(|(t, _)| *t == s) {
            Some((_, v)) => Some(*v),
            None => value(s),
        };
        let failure = |failure: Failure| LoopFailure {
            tears: block.names.clone(),
            worst: block.names.get(failure.index).cloned().unwrap_or_default(),
            failure,
        };
        let no_derivative = Failure {
            kind: newton::FailureKind::NonFinite,
            iterations: 0,
            residual: f64::NAN,
            index: 0,
        };
        let jacobian = block_jacobian(block).ok_or_else(|| failure(no_derivative))?;
        let mut problem = TreeBlock {
            block,
            scales: block
                .residuals
                .iter()
                .zip(&block.tears)
                .map(|(r, &z)| residual_scale(r, z))
                .collect(),
            jacobian,
            value: &known,
        };
        let mut z = vec![0.0; block.tears.len()];
        newton::solve(&mut problem, &mut z, Settings::default()).map_err(failure)?;
        solved.extend(block.tears.iter().copied().zip(z));
    }
    Ok(solved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::equations::symbols::{add, mul, pow, sub};

    fn z(v: usize) -> Expr {
        symbols::leaf(Sym::Tear(v))
    }

    #[test]
    fn coupled_loops_form_one_block_after_the_blocks_they_use() {
        // Loop 7 refers to loop 3 only; loops 3 and 5 refer to each other.
        let implicit = vec![
            (7, sub(mul(vec![symbols::num(2.0), z(3)]), z(7))),
            (3, sub(pow(z(5), symbols::num(2.0)), z(3))),
            (5, sub(add(vec![z(3), symbols::leaf(Sym::State(0))]), z(5))),
        ];
        let b = blocks(&implicit, &|s| format!("{s:?}"));
        assert_eq!(b.len(), 2);
        assert_eq!(b[0].tears, [Sym::Tear(3), Sym::Tear(5)]);
        assert_eq!(b[1].tears, [Sym::Tear(7)]);
        assert_eq!(b[1].names, ["Tear(7)"]);
        assert_eq!(b[1].residuals[0], implicit[0].1);
    }

    #[test]
    fn a_block_of_two_tears_is_solved_jointly() {
        // z3 = z5^2, z5 = z3 + x - 1 with x = 0.75, so z5^2 - z5 - 0.25 = 0: from z = 0 Newton finds
        // z5 = (1 - sqrt 2)/2, z3 = z5^2 (the root nearer the start).
        let block = TearBlock {
            tears: vec![Sym::Tear(3), Sym::Tear(5)],
            names: vec!["a".into(), "b".into()],
            residuals: vec![
                sub(pow(z(5), symbols::num(2.0)), z(3)),
                sub(
                    add(vec![z(3), symbols::leaf(Sym::State(0)), symbols::num(-1.0)]),
                    z(5),
                ),
            ],
        };
        let value = |s: Sym| (s == Sym::State(0)).then_some(0.75);
        let mut problem = TreeBlock {
            block: &block,
            scales: block
                .residuals
                .iter()
                .zip(&block.tears)
                .map(|(r, &t)| residual_scale(r, t))
                .collect(),
            jacobian: block_jacobian(&block).unwrap_or_default(),
            value: &value,
        };
        let mut zs = [0.0, 0.0];
        let k = newton::solve(&mut problem, &mut zs, Settings::default());
        assert!(k.is_ok(), "{k:?}");
        let b = (1.0 - 2f64.sqrt()) / 2.0;
        assert!((zs[1] - b).abs() < 1e-14, "{zs:?}");
        assert!((zs[0] - b * b).abs() < 1e-14, "{zs:?}");
    }

    #[test]
    fn the_scale_sums_the_magnitudes_of_the_terms() {
        // r = 3 - 5 x - z at x = 1, z = -2: |3| + |-5| + |2| + |z| = 12.
        let r = sub(
            add(vec![
                symbols::num(3.0),
                mul(vec![symbols::num(-5.0), symbols::leaf(Sym::State(0))]),
            ]),
            z(1),
        );
        let s = residual_scale(&r, Sym::Tear(1));
        let v = symbols::eval(&s, &|s| match s {
            Sym::State(0) => Some(1.0),
            Sym::Tear(1) => Some(-2.0),
            _ => None,
        });
        assert_eq!(v, Ok(12.0));
    }

    #[test]
    fn a_message_lists_a_long_block_by_its_ends_and_count() {
        let names = |n: usize| (1..=n).map(|k| format!("loop_e_n{k}")).collect::<Vec<_>>();
        assert_eq!(tear_names(&names(1)), "`loop_e_n1`");
        assert_eq!(
            tear_names(&names(8)),
            "`loop_e_n1`, `loop_e_n2`, `loop_e_n3`, `loop_e_n4`, `loop_e_n5`, `loop_e_n6`, `loop_e_n7`, `loop_e_n8`"
        );
        assert_eq!(
            tear_names(&names(1000)),
            "`loop_e_n1`, `loop_e_n2`, `loop_e_n3`, `loop_e_n4`, …, `loop_e_n1000` (1000 tear variables)"
        );
    }
}
