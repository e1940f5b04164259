//! `A, B, C, D` in the declared coordinates as expressions of the parameters (the numeric counterpart and the
//! mathematics are in [`super::coords`]).
//!
//! Symbolically the invariants are found by Gaussian elimination on the rows of `[A B]`, integrated flows first:
//! an energy-state row that reduces to zero is a combination `ẋ_i = Σ α_r ẋ_r` of earlier rows, so on the
//! invariant subspace `x_i = Σ α_r x_r` and `x_i` is eliminated. On the remaining states `r`:
//! `A_r = A_rr + A_re S`, `C_r = C_r + C_e S` (`x_e = S r`), `z = T_r r`, and
//! `A_z = T_r A_r T_r⁻¹`, `B_z = T_r B_r`, `C_z = C_r T_r⁻¹`, `D_z = D`. When there are as many coordinates as
//! states in play, nothing is eliminated: `T` is square and the map the plain similarity. A zero that the canonical
//! form does not recognise would hide an invariant; the result is then refused (a dimension error), never silently
//! wrong.

use super::Equations;
use super::coords::CoordsError;
use super::linear::{Jacobians, StateSelection, linear_state_space};
use super::solve::gauss;
use super::symbols::{self, Sym, SymExt, add, mul};
use crate::symbolic::Expr;

fn is_zero(e: &Expr) -> bool {
    e.is_zero() || symbols::expand(e).is_zero()
}

/// The state space in the declared coordinates with symbolic entries.
pub fn declared_state_space_symbolic(eqs: &Equations) -> Result<Jacobians, CoordsError> {
    let coords = eqs.coords.as_ref().ok_or(CoordsError::NoCoords)?;
    if coords.is_empty() {
        return Err(CoordsError::Underived);
    }
    let full = linear_state_space(eqs, StateSelection::All)?;
    let n_all = full.states.len();
    let m_in = full.inputs.len();
    // The states in play, as in the numeric version: energy states, and the integrated flows that coordinates,
    // outputs or other used states refer to.
    let mut used = vec![false; n_all];
    used[..eqs.energy_states.min(n_all)]
        .iter_mut()
        .for_each(|u| *u = true);
    let mark = |e: &Expr, used: &mut Vec<bool>| {
        e.for_each_sym(&mut |s| {
            if let Sym::State(j) = s
                && let Some(u) = used.get_mut(j)
            {
                *u = true;
            }
        })
    };
    for (_, e) in coords {
        mark(e, &mut used);
    }
    for row in &full.dhdx {
        for (j, e) in row.iter().enumerate() {
            if !e.is_zero() {
                used[j] = true;
            }
        }
    }
    loop {
        let mut changed = false;
        for i in 0..n_all {
            if !used[i] {
                continue;
            }
            for (j, e) in full.dfdx[i].iter().enumerate() {
                if !e.is_zero() && !used[j] {
                    used[j] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    // Row order for the elimination: integrated flows first, then energy states.
    let mut order: Vec<usize> = (eqs.energy_states..n_all).filter(|&j| used[j]).collect();
    order.extend((0..eqs.energy_states.min(n_all)).filter(|&j| used[j]));
    let n = order.len();
    let row_of = |i: usize| -> Vec<Expr> {
        order
            .iter()
            .map(|&j| full.dfdx[i][j].clone())
            .chain(full.dfdu[i].iter().cloned())
            .collect()
    };
    // Reduced rows with their combination of original rows (indexed by position in `order`).
    // (pivot column, reduced row, combination of original rows)
    let mut pivots: Vec<(usize, Vec<Expr>, Vec<Expr>)> = Vec::new();
    // (position, coefficients of x_pos = Σ coef x_other)
    let mut eliminated: Vec<(usize, Vec<Expr>)> = Vec::new();
    // As many coordinates as states in play: `T` is square over them, and the map is the plain similarity
    // `A_z = T A T⁻¹` (when `T` is invertible), invariants or not, as in the numeric version: no row is reduced.
    let reduced: &[usize] = if coords.len() == n { &[] } else { &order };
    for (pos, &i) in reduced.iter().enumerate() {
        let mut row = row_of(i);
        let mut comb: Vec<Expr> = (0..n)
            .map(|k| if k == pos { Expr::one() } else { Expr::zero() })
            .collect();
        for (col, prow, pcomb) in &pivots {
            if is_zero(&row[*col]) {
                continue;
            }
            let factor = symbols::div(row[*col].clone(), prow[*col].clone());
            for (r, p) in row.iter_mut().zip(prow) {
                *r = symbols::sub(r.clone(), mul(vec![factor.clone(), p.clone()]));
            }
            for (c, p) in comb.iter_mut().zip(pcomb) {
                *c = symbols::sub(c.clone(), mul(vec![factor.clone(), p.clone()]));
            }
        }
        match row.iter().position(|e| !is_zero(e)) {
            Some(col) => pivots.push((col, row, comb)),
            None => {
                // comb · x is invariant (zero along trajectories from rest): x_pos = -Σ_{k≠pos} comb_k x_k / comb_pos.
                // The combination involves only pivot rows, never another eliminated state.
                let lead = comb[pos].clone();
                let expr: Vec<Expr> = comb
                    .iter()
                    .enumerate()
                    .map(|(k, c)| {
                        if k == pos {
                            Expr::zero()
                        } else {
                            symbols::neg(symbols::div(c.clone(), lead.clone()))
                        }
                    })
                    .collect();
                eliminated.push((pos, expr));
            }
        }
    }
    let elim_pos: Vec<usize> = eliminated.iter().map(|e| e.0).collect();
    let kept: Vec<usize> = (0..n).filter(|p| !elim_pos.contains(p)).collect();
    let k = kept.len();
    if k != coords.len() {
        return Err(CoordsError::NotInvertible {
            coords: coords.len(),
            subspace: k,
            invariants: eliminated.len(),
        });
    }
    // x (in `order` positions) = M_r r: identity on kept positions, S on eliminated ones.
    let mut m_r: Vec<Vec<Expr>> = vec![vec![Expr::zero(); k]; n];
    for (c, &p) in kept.iter().enumerate() {
        m_r[p][c] = Expr::one();
    }
    for (p, expr) in &eliminated {
        for (c, &q) in kept.iter().enumerate() {
            m_r[*p][c] = expr[q].clone();
        }
    }
    let a_pos = |r: usize, c: usize| full.dfdx[order[r]][order[c]].clone();
    let matmul = |left: &dyn Fn(usize, usize) -> Expr,
                  rows: usize,
                  inner: usize,
                  right: &[Vec<Expr>],
                  cols: usize| {
        (0..rows)
            .map(|r| {
                (0..cols)
                    .map(|c| {
                        add((0..inner)
                            .map(|t| mul(vec![left(r, t), right[t][c].clone()]))
                            .collect())
                    })
                    .collect()
            })
            .collect::<Vec<Vec<Expr>>>()
    };
    // T (coords × n in `order` positions).
    let t_full: Vec<Vec<Expr>> = coords
        .iter()
        .map(|(_, e)| {
            order
                .iter()
                .map(|&j| symbols::diff(e, Sym::State(j)).unwrap_or_else(|_| Expr::zero()))
                .collect()
        })
        .collect();
    let t_r = matmul(&|r, c| t_full[r][c].clone(), k, n, &m_r, k);
    let a_x_m = matmul(&a_pos, n, n, &m_r, k); // A M_r, n × k
    let inv = inverse(&t_r).ok_or(CoordsError::Singular)?;
    // The elimination gives M_r with T_r invertible: A_z = T A M_r T_r⁻¹, B_z = T B, C_z = C M_r T_r⁻¹.
    let t_a_m = matmul(&|r, c| t_full[r][c].clone(), k, n, &a_x_m, k);
    let a_z = matmul(&|r, c| t_a_m[r][c].clone(), k, k, &inv, k);
    let b_order: Vec<Vec<Expr>> = order.iter().map(|&j| full.dfdu[j].clone()).collect();
    let b_z = matmul(&|r, c| t_full[r][c].clone(), k, n, &b_order, m_in);
    let c_order = |r: usize, c: usize| full.dhdx[r][order[c]].clone();
    let c_m = matmul(&c_order, full.outputs.len(), n, &m_r, k);
    let c_z = matmul(&|r, c| c_m[r][c].clone(), full.outputs.len(), k, &inv, k);
    Ok(Jacobians {
        states: coords.iter().map(|(name, _)| name.clone()).collect(),
        inputs: full.inputs,
        outputs: full.outputs,
        dfdx: a_z,
        dfdu: b_z,
        dhdx: c_z,
        dhdu: full.dhdu,
    })
}

/// The inverse of a square symbolic matrix, column by column.
fn inverse(a: &[Vec<Expr>]) -> Option<Vec<Vec<Expr>>> {
    let n = a.len();
    let mut cols = Vec::with_capacity(n);
    for c in 0..n {
        let mut m: Vec<Vec<Expr>> = a.to_vec();
        let mut e: Vec<Expr> = (0..n)
            .map(|r| if r == c { Expr::one() } else { Expr::zero() })
            .collect();
        cols.push(gauss(&mut m, &mut e)?);
    }
    Some(
        (0..n)
            .map(|r| (0..n).map(|c| cols[c][r].clone()).collect())
            .collect(),
    )
}
