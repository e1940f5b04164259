//! Resolution of derivative causality: the state rates `ẋ = F(x, u, ẋ)` where storages in derivative causality
//! contribute terms linear in `ẋ`. Writing `F = F0 + G ẋ` (`G = ∂F/∂ẋ`, which must not depend on `ẋ`), the rates
//! are the solution of `(I - G) ẋ = F0`, found by symbolic Gaussian elimination on the rates that appear in `G`
//! (the coupled block), then substituted into the others.
//!
//! Two inertias on one 1-junction give `(1 + J_2/J_1) ṗ_1 = F0`, that is the merged inertia `J_1 + J_2`; an inertia
//! behind a transformer of ratio `n` is reflected as `J/n²`.

// Index loops read like the textbook elimination they implement.
#![allow(clippy::needless_range_loop)]

use super::symbols::{self, Sym, SymExt, div, mul};
use crate::symbolic::{Expr, Node};
use petgraph::unionfind::UnionFind;
use std::collections::BTreeSet;

/// Why the rates could not be solved.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum SolveError {
    /// A rate appears nonlinearly (state index of the rate whose equation is nonlinear).
    Nonlinear(usize),
    /// `I - G` is singular on the coupled block.
    Singular,
    /// A derivative that cannot be taken symbolically.
    NotDifferentiable(usize),
}

/// Solves `ẋ = F(x, u, ẋ)` for `ẋ`; returns the explicit rates.
pub(crate) fn solve_rates(f: &[Expr]) -> Result<Vec<Expr>, SolveError> {
    solve_rates_with(f, None)
}

/// As [`solve_rates`], with the right-hand sides `F0` of the coupled rows given (in another form of the same
/// values, such as intermediates) instead of computed from `f`.
pub(crate) fn solve_rates_with(
    f: &[Expr],
    f0_given: Option<&[Expr]>,
) -> Result<Vec<Expr>, SolveError> {
    let n = f.len();
    let coupled = rates_appearing(f);
    if coupled.is_empty() {
        return Ok(f.to_vec());
    }
    let is_rate = |s: Sym| matches!(s, Sym::StateDot(_));
    // Row i of G: (k, ∂F_i/∂ẋ_{coupled[k]}) for the rates F_i reads, k increasing (the others are zero);
    // f0 = F with ẋ = 0.
    let mut g: Vec<Vec<(usize, Expr)>> = Vec::with_capacity(n);
    let mut f0 = Vec::with_capacity(n);
    for (i, fi) in f.iter().enumerate() {
        g.push(rate_derivatives(fi, i, &|j| {
            coupled.binary_search(&j).ok()
        })?);
        f0.push(symbols::subst(fi, &mut |s| is_rate(s).then(Expr::zero)));
    }
    // The coupled block: (I - G_cc) ẋ_c = F0_c, by rows of its entries that are not zero.
    let a: Vec<SparseRow> = coupled
        .iter()
        .enumerate()
        .map(|(r, &j)| {
            let mut row = SparseRow::new();
            row.insert(r, Expr::one());
            for (c, d) in g.get(j).into_iter().flatten() {
                let identity = row.remove(c).unwrap_or_else(Expr::zero);
                let entry = symbols::sub(identity, d.clone());
                if !entry.is_zero() {
                    row.insert(*c, entry);
                }
            }
            row
        })
        .collect();
    let f0 = match f0_given {
        Some(given) if given.len() == n => given.to_vec(),
        _ => f0,
    };
    let rhs: Vec<Expr> = coupled.iter().map(|&j| f0[j].clone()).collect();
    let xc = gauss_sparse(a, rhs).ok_or(SolveError::Singular)?;
    let mut out = Vec::with_capacity(n);
    for (i, row) in g.iter().enumerate() {
        if let Ok(k) = coupled.binary_search(&i) {
            out.push(xc[k].clone());
        } else {
            let mut terms = vec![f0[i].clone()];
            for (k, d) in row {
                terms.push(mul(vec![d.clone(), xc[*k].clone()]));
            }
            out.push(symbols::add(terms));
        }
    }
    Ok(out)
}

/// One block of `M`: its rows (states) and its matrix.
pub(crate) type MassRows = (Vec<usize>, Vec<Vec<Expr>>);

/// The rates (generalised forces in the block rows) and the blocks of `M`.
pub(crate) type MassForm = (Vec<Expr>, Vec<MassRows>);

/// The rates of a system with implicit rows (`0 = F_i(x, u, ẋ)` for the velocity states of
/// [`super::kinematic`]) in the mass-matrix form: rows whose rate is explicit and free of `ẋ` are substituted
/// into the others; the remaining rows `U` (the implicit ones and those coupled through `ẋ`) give
/// `M ẋ_U = F` with `M_ab = δ_ab − ∂F_a/∂ẋ_b` for an explicit row, `−∂F_a/∂ẋ_b` for an implicit one, and
/// `F = F(ẋ = 0)`. No symbolic division: the consumers solve `M` numerically, so a pivot that vanishes at some
/// configuration is never divided by. Returns the rates (the generalised forces in the rows `U`) and `M` split
/// into the blocks that no entry couples (each block's rows in increasing order, the blocks by their first row):
/// a thousand separate levers are a thousand 1×1 blocks, not one square of a million entries.
pub(crate) fn mass_form(f: &[Expr], implicit_rows: &[bool]) -> Result<MassForm, SolveError> {
    let n = f.len();
    let is_rate = |s: Sym| matches!(s, Sym::StateDot(_));
    let implicit = |i: usize| implicit_rows.get(i).copied().unwrap_or(false);
    let mut f = f.to_vec();
    // Explicit rows free of ẋ, substituted until none is left to substitute (each round frees more rows).
    let mut known = vec![false; n];
    loop {
        let fresh: Vec<usize> = (0..n)
            .filter(|&i| !known[i] && !implicit(i) && !f[i].any_sym(&is_rate))
            .collect();
        if fresh.is_empty() {
            break;
        }
        fresh.iter().for_each(|&i| known[i] = true);
        // Indexed, not searched: `fresh` may hold nearly every state of a large model.
        let mut values: Vec<Option<Expr>> = vec![None; n];
        for &i in &fresh {
            values[i] = Some(f[i].clone());
        }
        for fi in f.iter_mut().filter(|fi| fi.any_sym(&is_rate)) {
            *fi = symbols::subst(fi, &mut |s| match s {
                Sym::StateDot(j) => values.get(j).cloned().flatten(),
                _ => None,
            });
        }
    }
    let mut in_rows: Vec<bool> = (0..n)
        .map(|i| implicit(i) || (!known[i] && f[i].any_sym(&is_rate)))
        .collect();
    for fi in &f {
        fi.for_each_sym(&mut |s| {
            if let Sym::StateDot(j) = s
                && let Some(row) = in_rows.get_mut(j)
            {
                *row = true;
            }
        });
    }
    let rows: Vec<usize> = (0..n).filter(|&i| in_rows[i]).collect();
    let mut place: Vec<Option<usize>> = vec![None; n];
    for (k, &i) in rows.iter().enumerate() {
        place[i] = Some(k);
    }
    // Per row, its entries that are not zero, by place: `δ − ∂F_i/∂ẋ_j` for the rates it reads, and its
    // identity entry; ∂F_i/∂ẋ_j of a rate it does not read is zero.
    let mut entries: Vec<Vec<(usize, Expr)>> = Vec::with_capacity(rows.len());
    for (k, &i) in rows.iter().enumerate() {
        let identity = |c: usize| {
            if c == k && !implicit(i) {
                Expr::one()
            } else {
                Expr::zero()
            }
        };
        let mut row: Vec<(usize, Expr)> = Vec::new();
        for (c, d) in rate_derivatives(&f[i], i, &|j| place.get(j).copied().flatten())? {
            // −d term by term, so that `M + m` prints as such rather than `-(-M - m)`.
            let minus_d = match d.node() {
                Node::Add(terms) => symbols::add(terms.iter().cloned().map(symbols::neg).collect()),
                _ => symbols::neg(d),
            };
            row.push((c, symbols::add(vec![identity(c), minus_d])));
        }
        if !row.iter().any(|(c, _)| *c == k) && !identity(k).is_zero() {
            row.push((k, Expr::one()));
            row.sort_by_key(|(c, _)| *c);
        }
        row.retain(|(_, e)| !e.is_zero());
        entries.push(row);
    }
    for &i in &rows {
        f[i] = symbols::subst(&f[i], &mut |s| is_rate(s).then(Expr::zero));
    }
    let blocks = coupled_blocks(&entries)
        .into_iter()
        .map(|places| {
            let matrix = places
                .iter()
                .map(|&a| {
                    places
                        .iter()
                        .map(|b| {
                            entries[a]
                                .binary_search_by_key(b, |(c, _)| *c)
                                .map_or_else(|_| Expr::zero(), |at| entries[a][at].1.clone())
                        })
                        .collect()
                })
                .collect();
            (places.iter().map(|&k| rows[k]).collect(), matrix)
        })
        .collect();
    Ok((f, blocks))
}

/// `(column, ∂f/∂ẋ_j)` for each state rate `ẋ_j` that `f` (row `i`) reads and `column` places, by column; the
/// rates it does not read give zero. Errors when `f` cannot be differentiated or is not linear in the rates.
fn rate_derivatives(
    f: &Expr,
    i: usize,
    column: &dyn Fn(usize) -> Option<usize>,
) -> Result<Vec<(usize, Expr)>, SolveError> {
    let mut read: Vec<(usize, usize)> = f
        .syms()
        .into_iter()
        .filter_map(|s| match s {
            Sym::StateDot(j) => column(j).map(|c| (c, j)),
            _ => None,
        })
        .collect();
    read.sort_unstable();
    let wrt: Vec<Sym> = read.iter().map(|&(_, j)| Sym::StateDot(j)).collect();
    let slopes = symbols::gradient(f, &wrt).map_err(|_| SolveError::NotDifferentiable(i))?;
    let mut row = Vec::with_capacity(read.len());
    for ((c, _), d) in read.into_iter().zip(slopes) {
        if d.any_sym(&|s| matches!(s, Sym::StateDot(_))) {
            return Err(SolveError::Nonlinear(i));
        }
        row.push((c, d));
    }
    Ok(row)
}

/// The places of the rows that the entries couple, directly or through other rows: each group in increasing
/// order, the groups by their first place.
fn coupled_blocks(entries: &[Vec<(usize, Expr)>]) -> Vec<Vec<usize>> {
    let n = entries.len();
    let mut sets = UnionFind::<usize>::new(n);
    for (a, row) in entries.iter().enumerate() {
        for &(b, _) in row.iter().filter(|(b, _)| *b < n) {
            sets.union(a, b);
        }
    }
    let mut group_of: Vec<Option<usize>> = vec![None; n];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for v in 0..n {
        let g = *group_of[sets.find_mut(v)].get_or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(v);
    }
    groups
}

/// The states whose rate `ẋ_j` appears in some of `f`, in increasing order (one walk over each expression).
pub(crate) fn rates_appearing(f: &[Expr]) -> Vec<usize> {
    let mut seen = std::collections::BTreeSet::new();
    for fi in f {
        fi.for_each_sym(&mut |s| {
            if let Sym::StateDot(j) = s {
                seen.insert(j);
            }
        });
    }
    seen.into_iter().collect()
}

/// A row of a sparse matrix: its entries that are not zero, by column.
pub(crate) type SparseRow = std::collections::BTreeMap<usize, Expr>;

/// Symbolic Gaussian elimination of `a x = b`; pivots on numeric entries first, then on any structurally non-zero
/// entry. `None` when a column has no non-zero pivot.
pub(crate) fn gauss(a: &mut [Vec<Expr>], b: &mut [Expr]) -> Option<Vec<Expr>> {
    let rows = super::sparse_linear::SparseMatrix::from_dense(a, b.len())
        .entries
        .into_iter()
        .map(|row| row.into_iter().collect())
        .collect();
    gauss_sparse(rows, b.to_vec())
}

/// [`gauss`] on the rows' entries that are not zero: the work is that of the entries and their fill-in, not of
/// the whole square (a chain of storages in derivative causality couples each rate to its neighbours only). The
/// result is the dense elimination's: a zero entry changes no value it would have been combined with, and the
/// pivots are chosen as there, in the order the dense elimination's row swaps give the rows.
pub(crate) fn gauss_sparse(mut a: Vec<SparseRow>, mut b: Vec<Expr>) -> Option<Vec<Expr>> {
    let m = b.len();
    if a.len() != m || a.iter().any(|row| row.range(m..).next().is_some()) {
        return None;
    }
    // The rows stay where they are: `at[p]` is the row at position `p` of the dense elimination, `pos[r]` the
    // position of row `r`.
    let mut at: Vec<usize> = (0..m).collect();
    let mut pos: Vec<usize> = (0..m).collect();
    // Per column, the rows not yet pivoted that hold an entry there.
    let mut holders: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); m];
    for (r, row) in a.iter().enumerate() {
        for &c in row.keys() {
            holders[c].insert(r);
        }
    }
    for col in 0..m {
        let mut candidates: Vec<usize> = holders[col].iter().copied().collect();
        candidates.sort_unstable_by_key(|&r| pos[r]);
        let entry = |r: usize| a[r].get(&col);
        let pivot = candidates
            .iter()
            .copied()
            .find(|&r| entry(r).is_some_and(|e| e.num().is_some()))
            .or_else(|| {
                candidates
                    .iter()
                    .copied()
                    .min_by_key(|&r| entry(r).map_or(usize::MAX, Expr::node_count))
            })?;
        let displaced = at[col];
        at.swap(col, pos[pivot]);
        pos[displaced] = pos[pivot];
        pos[pivot] = col;
        let pivot_row = std::mem::take(&mut a[pivot]);
        for &c in pivot_row.keys() {
            holders[c].remove(&pivot);
        }
        let p = pivot_row.get(&col)?.clone();
        let b_pivot = b[pivot].clone();
        for r in candidates.into_iter().filter(|&r| r != pivot) {
            let row = &mut a[r];
            // The entry in the pivot's column is eliminated and never read again.
            let Some(x) = row.remove(&col) else {
                continue;
            };
            holders[col].remove(&r);
            let factor = div(x, p.clone());
            for (&c, v) in pivot_row.range(col + 1..) {
                let old = row.remove(&c);
                let held = old.is_some();
                let new = symbols::sub(
                    old.unwrap_or_else(Expr::zero),
                    mul(vec![factor.clone(), v.clone()]),
                );
                match (new.is_zero(), held) {
                    (true, true) => {
                        holders[c].remove(&r);
                    }
                    (false, held) => {
                        row.insert(c, new);
                        if !held {
                            holders[c].insert(r);
                        }
                    }
                    (true, false) => {}
                }
            }
            b[r] = symbols::sub(b[r].clone(), mul(vec![factor, b_pivot.clone()]));
        }
        a[pivot] = pivot_row;
    }
    // The unknowns are the columns: the row at position `p` gives unknown `p`.
    let mut x = vec![Expr::zero(); m];
    for p in (0..m).rev() {
        let row = &a[at[p]];
        let mut acc = vec![b[at[p]].clone()];
        for (&c, v) in row.range(p + 1..) {
            acc.push(symbols::neg(mul(vec![v.clone(), x[c].clone()])));
        }
        let pivot = row.get(&p)?.clone();
        x[p] = over_common_denominator(symbols::add(acc), pivot);
    }
    Some(x)
}

/// `num / den`, with the reciprocals in the terms of `den` cleared first: `u / (1 + J_2/J_1)` becomes
/// `J_1 u / (J_1 + J_2)`, which shows the merged inertia. A denominator that is a product with one sum in it is
/// handled through that sum.
fn over_common_denominator(num: Expr, den: Expr) -> Expr {
    let den = symbols::expand(&den);
    let (num, terms) = match den.node() {
        Node::Add(terms) => (num, terms.clone()),
        Node::Mul(fs)
            if fs
                .iter()
                .filter(|f| matches!(f.node(), Node::Add(_)))
                .count()
                == 1 =>
        {
            let mut others = Vec::new();
            let mut sum = Vec::new();
            for f in fs {
                match f.node() {
                    Node::Add(ts) => sum = ts.clone(),
                    _ => others.push(f.clone()),
                }
            }
            (div(num, mul(others)), sum)
        }
        _ => return div(num, den),
    };
    // Each base with the largest power it is divided by in any term.
    let mut clear: Vec<(Expr, f64)> = Vec::new();
    for t in &terms {
        let factors: Vec<&Expr> = match t.node() {
            Node::Mul(fs) => fs.iter().collect(),
            _ => vec![t],
        };
        for f in factors {
            if let Node::Pow(b, x) = f.node()
                && let Some(v) = x.num().filter(|v| *v < 0.0)
            {
                match clear.iter_mut().find(|(c, _)| c == b) {
                    Some(entry) => entry.1 = entry.1.max(-v),
                    None => clear.push((b.clone(), -v)),
                }
            }
        }
    }
    if clear.is_empty() {
        return div(num, symbols::add(terms));
    }
    let l = mul(clear
        .into_iter()
        .map(|(b, k)| symbols::pow(b, symbols::num(k)))
        .collect());
    let den = symbols::add(
        terms
            .iter()
            .map(|t| mul(vec![t.clone(), l.clone()]))
            .collect(),
    );
    div(mul(vec![num, l]), den)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(i: usize) -> Expr {
        symbols::leaf(Sym::Param(i))
    }

    #[test]
    fn merged_inertia() {
        // ṗ = u - (J2/J1) ṗ  =>  ṗ = u / (1 + J2/J1)
        let f = vec![symbols::sub(
            symbols::leaf(Sym::Input(0)),
            mul(vec![div(p(1), p(0)), symbols::leaf(Sym::StateDot(0))]),
        )];
        let x = solve_rates(&f).unwrap_or_default();
        let v = symbols::eval(&x[0], &|s| match s {
            Sym::Param(0) => Some(2.0),
            Sym::Param(1) => Some(3.0),
            Sym::Input(0) => Some(10.0),
            _ => None,
        });
        // J1 = 2, J2 = 3: ṗ_1 = 10 · 2/5 = 4.
        assert_eq!(v, Ok(4.0));
    }

    #[test]
    fn two_by_two() {
        // ẋ0 = 1 + ẋ1 / 2, ẋ1 = 2 + ẋ0 / 4  =>  ẋ0 = (1 + 1)/(1 - 1/8) = 16/7, ẋ1 = 2 + 4/7 = 18/7
        let f = vec![
            symbols::add(vec![
                Expr::one(),
                mul(vec![symbols::num(0.5), symbols::leaf(Sym::StateDot(1))]),
            ]),
            symbols::add(vec![
                symbols::num(2.0),
                mul(vec![symbols::num(0.25), symbols::leaf(Sym::StateDot(0))]),
            ]),
        ];
        let x = solve_rates(&f).unwrap_or_default();
        let v: Vec<f64> = x.iter().map(|e| e.num().unwrap_or(f64::NAN)).collect();
        assert!(
            (v[0] - 16.0 / 7.0).abs() < 1e-12 && (v[1] - 18.0 / 7.0).abs() < 1e-12,
            "{v:?}"
        );
    }

    /// The dense elimination the sparse one replaced: every entry of the square, zeros included.
    fn gauss_dense(a: &mut [Vec<Expr>], b: &mut [Expr]) -> Option<Vec<Expr>> {
        let m = b.len();
        for col in 0..m {
            let candidates = (col..m).filter(|&r| !a[r][col].is_zero());
            let pivot = candidates
                .clone()
                .find(|&r| a[r][col].num().is_some())
                .or_else(|| candidates.min_by_key(|&r| a[r][col].node_count()))?;
            a.swap(col, pivot);
            b.swap(col, pivot);
            for r in col + 1..m {
                if a[r][col].is_zero() {
                    continue;
                }
                let factor = div(a[r][col].clone(), a[col][col].clone());
                for c in col..m {
                    a[r][c] = symbols::sub(
                        a[r][c].clone(),
                        mul(vec![factor.clone(), a[col][c].clone()]),
                    );
                }
                b[r] = symbols::sub(b[r].clone(), mul(vec![factor, b[col].clone()]));
            }
        }
        let mut x = vec![Expr::zero(); m];
        for r in (0..m).rev() {
            let mut acc = vec![b[r].clone()];
            for c in r + 1..m {
                acc.push(symbols::neg(mul(vec![a[r][c].clone(), x[c].clone()])));
            }
            if a[r][r].is_zero() {
                return None;
            }
            x[r] = over_common_denominator(symbols::add(acc), a[r][r].clone());
        }
        Some(x)
    }

    #[test]
    fn the_sparse_elimination_gives_the_dense_ones_expressions() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move |below: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % below
        };
        let mut solved = 0;
        for _ in 0..300 {
            let m = 1 + next(7) as usize;
            // Entries: zero (most), a number, a parameter, or a parameter times a number; so that pivots are
            // chosen both ways and rows must be swapped.
            let mut entry = |_: usize| match next(6) {
                0 => symbols::num((1 + next(4)) as f64),
                1 => p(next(3) as usize),
                2 => mul(vec![symbols::num(2.0), p(next(3) as usize)]),
                _ => Expr::zero(),
            };
            let a: Vec<Vec<Expr>> = (0..m).map(|_| (0..m).map(&mut entry).collect()).collect();
            let b: Vec<Expr> = (0..m)
                .map(|k| symbols::add(vec![p(3 + k), Expr::one()]))
                .collect();
            let dense = gauss_dense(&mut a.clone(), &mut b.clone());
            let sparse = gauss(&mut a.clone(), &mut b.clone());
            assert_eq!(sparse, dense, "{a:?}");
            let Some(x) = sparse else { continue };
            solved += 1;
            // And it solves the system: A x = b at a point.
            let at = |e: &Expr| {
                symbols::eval(e, &|s| match s {
                    Sym::Param(i) => Some(1.37 + 0.74 * i as f64 + 0.013 * (i * i) as f64),
                    _ => None,
                })
                .unwrap_or(f64::NAN)
            };
            for (row, rhs) in a.iter().zip(&b) {
                let lhs: f64 = row.iter().zip(&x).map(|(aij, xj)| at(aij) * at(xj)).sum();
                assert!(
                    (lhs - at(rhs)).abs() <= 1e-9 * (1.0 + at(rhs).abs()),
                    "{a:?}"
                );
            }
        }
        assert!(solved > 100, "{solved} of 300 systems were regular");
    }
}
