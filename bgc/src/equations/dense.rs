//! Small dense real linear algebra for coordinate changes: products, solves with partial pivoting, null spaces by
//! reduced row echelon form on a row- and column-equilibrated copy (so that states of very different scales, such
//! as a motor angle and a spring torque, do not decide the rank by their units).

// Index loops read like the textbook algorithms they implement.
#![allow(clippy::needless_range_loop)]

pub(crate) type Mat = Vec<Vec<f64>>;

pub(crate) fn zeros(r: usize, c: usize) -> Mat {
    vec![vec![0.0; c]; r]
}

pub(crate) fn cols(m: &Mat) -> usize {
    m.first().map_or(0, Vec::len)
}

pub(crate) fn mul(a: &Mat, b: &Mat) -> Mat {
    let (n, k, p) = (a.len(), cols(a), cols(b));
    let mut out = zeros(n, p);
    for i in 0..n {
        for l in 0..k {
            let x = a[i][l];
            if x == 0.0 {
                continue;
            }
            for j in 0..p {
                out[i][j] += x * b[l][j];
            }
        }
    }
    out
}

pub(crate) fn transpose(a: &Mat) -> Mat {
    let mut out = zeros(cols(a), a.len());
    for (i, row) in a.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            out[j][i] = *v;
        }
    }
    out
}

/// Solves `a x = b` (square `a`, several right-hand sides) by Gaussian elimination with partial pivoting. `None`
/// when a pivot is below `1e-12` times the largest entry of `a` (numerically singular).
pub(crate) fn solve(a: &Mat, b: &Mat) -> Option<Mat> {
    let n = a.len();
    if cols(a) != n || b.len() != n {
        return None;
    }
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return if n == 0 { Some(b.clone()) } else { None };
    }
    let mut a = a.clone();
    let mut x = b.clone();
    let p = cols(b);
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(col, pivot);
        x.swap(col, pivot);
        for r in col + 1..n {
            let f = a[r][col] / a[col][col];
            if f == 0.0 {
                continue;
            }
            for c in col..n {
                a[r][c] -= f * a[col][c];
            }
            for c in 0..p {
                x[r][c] -= f * x[col][c];
            }
        }
    }
    for r in (0..n).rev() {
        for c in 0..p {
            let mut acc = x[r][c];
            for k in r + 1..n {
                acc -= a[r][k] * x[k][c];
            }
            x[r][c] = acc / a[r][r];
        }
    }
    Some(x)
}

/// A basis of the null space of `m` (`rows × n`), as the columns of an `n × k` matrix.
pub(crate) fn null_space(m: &Mat, n: usize) -> Mat {
    // Equilibrate columns (this changes the basis, undone below) and rows (this does not).
    let col_scale: Vec<f64> = (0..n)
        .map(|j| {
            let s = m.iter().fold(0.0f64, |acc, r| {
                acc.max(r.get(j).copied().unwrap_or(0.0).abs())
            });
            if s > 0.0 { 1.0 / s } else { 1.0 }
        })
        .collect();
    let mut a: Mat = m
        .iter()
        .map(|r| {
            (0..n)
                .map(|j| r.get(j).copied().unwrap_or(0.0) * col_scale[j])
                .collect::<Vec<f64>>()
        })
        .map(|r: Vec<f64>| {
            let s = r.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
            if s > 0.0 {
                r.iter().map(|v| v / s).collect()
            } else {
                r
            }
        })
        .collect();
    let tol = 1e-9;
    let mut pivots = Vec::new();
    let mut row = 0;
    for col in 0..n {
        if row >= a.len() {
            break;
        }
        let Some(p) = (row..a.len()).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
        else {
            break;
        };
        if a[p][col].abs() <= tol {
            continue;
        }
        a.swap(row, p);
        let pv = a[row][col];
        for v in a[row].iter_mut() {
            *v /= pv;
        }
        for r in 0..a.len() {
            if r != row {
                let f = a[r][col];
                if f != 0.0 {
                    for c in 0..n {
                        a[r][c] -= f * a[row][c];
                    }
                }
            }
        }
        pivots.push(col);
        row += 1;
    }
    let free: Vec<usize> = (0..n).filter(|c| !pivots.contains(c)).collect();
    let mut basis = zeros(n, free.len());
    for (k, &fcol) in free.iter().enumerate() {
        basis[fcol][k] = 1.0;
        for (r, &pc) in pivots.iter().enumerate() {
            basis[pc][k] = -a[r][fcol];
        }
    }
    // Undo the column scaling: null(M S) = S^-1 null(M), so x = S x'.
    for (j, s) in col_scale.iter().enumerate() {
        for v in basis[j].iter_mut() {
            *v *= s;
        }
    }
    basis
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_and_null_space() {
        let a = vec![vec![2.0, 1.0], vec![1.0, 3.0]];
        let x = solve(&a, &vec![vec![3.0], vec![5.0]]).unwrap_or_default();
        // 2x + y = 3, x + 3y = 5  =>  x = 4/5, y = 7/5
        assert!((x[0][0] - 0.8).abs() < 1e-14 && (x[1][0] - 1.4).abs() < 1e-14);
        // The null space of [1 2 3; 2 4 6] is two-dimensional and each basis vector is annihilated.
        let m = vec![vec![1.0, 2.0, 3.0], vec![2.0, 4.0, 6.0]];
        let n = null_space(&m, 3);
        assert_eq!(cols(&n), 2);
        let prod = mul(&m, &n);
        assert!(prod.iter().flatten().all(|v| v.abs() < 1e-12), "{prod:?}");
        assert!(
            solve(
                &vec![vec![1.0, 2.0], vec![2.0, 4.0]],
                &vec![vec![1.0], vec![1.0]]
            )
            .is_none()
        );
    }
}
