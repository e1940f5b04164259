//! Symbolic derivatives with respect to chosen parameters, through the derived parameters.
//!
//! A derived parameter (`param J = m*r^2;`, [`Equations::derived`]) moves with the parameters it is defined from,
//! so the derivative of an expression `e` with respect to a chosen parameter `p_c` is the total one
//!
//! ```text
//! de/dp_c = Σ_j ∂e/∂p_j · dp_j/dp_c,     dp_j/dp_c = Σ_i ∂g_j/∂p_i · dp_i/dp_c   (p_j = g_j(p_0 … p_j−1))
//! ```
//!
//! [`ParamChain`] holds `dp_j/dp_c` for every parameter `j` as an expression of the parameters (built in parameter
//! order: a derived parameter refers to earlier ones only), and [`ParamChain::jacobian`] applies it to the partial
//! derivatives of the stage's expressions (those of the shared engine [`crate::symbolic`]). The
//! derivatives are partial in everything else: states, inputs, time and the tears of nonlinear loops stay fixed;
//! the callers add the loops' and the mass matrices' contributions by the implicit function theorem.

use super::Equations;
use super::linear::LinearError;
use super::symbols::Sym;
use crate::symbolic::{Expr, Symbol};

/// `dp_j/dp_c` for every parameter `j` and chosen parameter `c`.
#[derive(Clone, Debug)]
pub struct ParamChain {
    /// The chosen parameters (indices into [`Equations::params`]), in column order.
    pub columns: Vec<usize>,
    /// Every parameter's symbol, in parameter order.
    pub symbols: Vec<Symbol>,
    /// `links[j][c] = dp_j/dp_columns[c]`.
    pub links: Vec<Vec<Expr>>,
}

impl ParamChain {
    /// The chain for the parameters `columns`. A chosen parameter moves alone (a derived one is then set directly,
    /// its definition overridden); a parameter in `pinned` (a derived one held at a given value) does not move;
    /// every other derived parameter follows its definition. An error names a derived parameter whose definition
    /// cannot be converted, or a column that is no parameter.
    pub fn new(
        eqs: &Equations,
        columns: &[usize],
        pinned: &[usize],
    ) -> Result<ParamChain, LinearError> {
        let n = eqs.params.len();
        if let Some(&bad) = columns.iter().find(|&&c| c >= n) {
            return Err(LinearError::Dimension {
                what: "parameter",
                expected: n,
                got: bad + 1,
            });
        }
        let symbols: Vec<Symbol> = (0..eqs.params.len())
            .map(|j| Sym::Param(j).symbol())
            .collect();
        let zeros = || vec![Expr::zero(); columns.len()];
        let mut links: Vec<Vec<Expr>> = Vec::with_capacity(n);
        for j in 0..n {
            let row = if columns.contains(&j) {
                columns
                    .iter()
                    .map(|&c| if c == j { Expr::one() } else { Expr::zero() })
                    .collect()
            } else if pinned.contains(&j) {
                zeros()
            } else {
                match eqs.derived.get(j).and_then(Option::as_ref) {
                    None => zeros(),
                    Some(def) => {
                        let g = def.clone();
                        // A definition refers to earlier parameters only, whose links are known.
                        combine(
                            &Expr::sparse_jacobian(&[g], &symbols[..j]),
                            &links,
                            columns.len(),
                        )
                        .pop()
                        .unwrap_or_else(zeros)
                    }
                }
            };
            links.push(row);
        }
        Ok(ParamChain {
            columns: columns.to_vec(),
            symbols,
            links,
        })
    }

    /// `de_i/dp_c` for each of `exprs` and each chosen parameter, row by row (zeros where `e_i` reads no parameter
    /// that moves with `p_c`).
    pub fn jacobian(&self, exprs: &[Expr]) -> Vec<Vec<Expr>> {
        let mut out = combine(
            &Expr::sparse_jacobian(exprs, &self.symbols),
            &self.links,
            self.columns.len(),
        );
        out.resize_with(exprs.len(), || vec![Expr::zero(); self.columns.len()]);
        out
    }
}

/// `Σ_j partial[i][j] · links[j][c]` from the sparse partials `(i, j, ∂e_i/∂p_j)` (sorted by row), as rows
/// `0..=max i`.
fn combine(
    partial: &[(usize, usize, Expr)],
    links: &[Vec<Expr>],
    columns: usize,
) -> Vec<Vec<Expr>> {
    let rows = partial.iter().map(|(i, _, _)| i + 1).max().unwrap_or(0);
    let mut terms: Vec<Vec<Vec<Expr>>> = vec![vec![Vec::new(); columns]; rows];
    for (i, j, d) in partial {
        let Some(link_row) = links.get(*j) else {
            continue;
        };
        for (c, link) in link_row.iter().enumerate() {
            if link.is_zero() {
                continue;
            }
            let term = if link.is_one() { d.clone() } else { d * link };
            if let Some(slot) = terms.get_mut(*i).and_then(|r| r.get_mut(c)) {
                slot.push(term);
            }
        }
    }
    terms
        .into_iter()
        .map(|row| row.into_iter().map(Expr::sum).collect())
        .collect()
}
