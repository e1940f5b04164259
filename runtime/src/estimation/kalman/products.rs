//! The matrix products of a Kalman step, written for the shapes and symmetries of the filter.
//!
//! Every product is built column by column as a sum of columns scaled by scalars (`y[:, j] += x[:, k] s`,
//! [`combine`]): the innermost loop runs down a contiguous column of the fixed length `NX`, which compiles to
//! straight vector code without branches, and each column is written once, in place. A symmetric result is
//! computed down to the diagonal in blocks of four rows ([`upper_combination`]) and then made exactly symmetric
//! by copying its upper triangle onto the lower one. The matrices are read through nalgebra's column-major
//! arrays (`data.0[column][row]`), whose bounds are the const sizes.
//!
//! Each product forms its `a b + c` through `M` (`isa`) and is inlined into the step, so that it is compiled
//! with the instruction set the step runs on.

use super::isa::MulAdd;
use nalgebra::{ArrayStorage, SMatrix, SVector};

/// `A P Aᵀ + Q` for symmetric `P` and `Q`, from `A` and `Aᵀ` (kept with the filter): `T = P Aᵀ` (written into
/// `t`, the filter's work matrix: an `NX × NX` local would not fit the stack of a large filter), then
/// `A T + Q` down to the diagonal, its upper triangle mirrored (about `3 NX³` flops).
#[inline(always)]
pub(super) fn congruence_plus<M: MulAdd, const NX: usize>(
    a: &SMatrix<f64, NX, NX>,
    at: &SMatrix<f64, NX, NX>,
    p: &SMatrix<f64, NX, NX>,
    q: &SMatrix<f64, NX, NX>,
    out: &mut SMatrix<f64, NX, NX>,
    t: &mut SMatrix<f64, NX, NX>,
) {
    let (a, at, p, q) = (&a.data.0, &at.data.0, &p.data.0, &q.data.0);
    let t = &mut t.data.0;
    // Column i of T = P Aᵀ is P times column i of Aᵀ (row i of A).
    for i in 0..NX {
        combine::<M, NX, NX>(p, &at[i], [0.0; NX], &mut t[i]);
    }
    // Column j of A T + Q is Q[:, j] plus the columns of A weighted by column j of T; its rows to the
    // diagonal are enough.
    let out = &mut out.data.0;
    for j in 0..NX {
        upper_combination::<M, NX, NX, 1>([(a, &t[j])], &q[j], &mut out[j], j);
    }
    mirror_upper(out);
}

/// `P Cᵀ` for symmetric `P`, the transpose of `C P`: column `a` is `P` times row `a` of `C` (`2 NX² NY` flops).
#[inline(always)]
pub(super) fn covariance_times_ct<M: MulAdd, const NX: usize, const NY: usize>(
    p: &SMatrix<f64, NX, NX>,
    ct: &SMatrix<f64, NX, NY>,
) -> SMatrix<f64, NX, NY> {
    let (p, ct) = (&p.data.0, &ct.data.0);
    let mut out = [[0.0_f64; NX]; NY];
    for (column, row_of_c) in out.iter_mut().zip(ct) {
        combine::<M, NX, NX>(p, row_of_c, [0.0; NX], column);
    }
    SMatrix::from_data(ArrayStorage(out))
}

/// The innovation covariance `S = C P Cᵀ + R` from `P Cᵀ`: the upper triangle of `(P Cᵀ)ᵀ Cᵀ + R`, mirrored
/// (`NY (NY + 1) NX` flops).
#[inline(always)]
pub(super) fn innovation_covariance<M: MulAdd, const NX: usize, const NY: usize>(
    pct: &SMatrix<f64, NX, NY>,
    ct: &SMatrix<f64, NX, NY>,
    r: &SMatrix<f64, NY, NY>,
) -> SMatrix<f64, NY, NY> {
    let mut s = *r;
    for b in 0..NY {
        for a in 0..b + 1 {
            let mut v = r[(a, b)];
            for k in 0..NX {
                v = M::mul_add(pct.data.0[a][k], ct.data.0[b][k], v);
            }
            s[(a, b)] = v;
            s[(b, a)] = v;
        }
    }
    s
}

/// The lower Cholesky factor `L` of the innovation covariance with the reciprocals of its diagonal, which the
/// solves below multiply by instead of dividing.
pub(super) struct InnovationFactor<const NY: usize> {
    l: SMatrix<f64, NY, NY>,
    inv_diag: [f64; NY],
}

impl<const NY: usize> InnovationFactor<NY> {
    pub(super) fn new(l: SMatrix<f64, NY, NY>) -> Self {
        let inv_diag = std::array::from_fn(|a| 1.0 / l[(a, a)]);
        InnovationFactor { l, inv_diag }
    }

    /// `L⁻¹ e`; the normalised innovation squared `eᵀ S⁻¹ e` is its squared length.
    pub(super) fn whiten(&self, e: &SVector<f64, NY>) -> SVector<f64, NY> {
        let mut z = *e;
        for a in 0..NY {
            let mut v = z[a];
            for b in 0..a {
                v -= self.l[(a, b)] * z[b];
            }
            z[a] = v * self.inv_diag[a];
        }
        z
    }

    /// The gain `K = P Cᵀ S⁻¹` from `P Cᵀ`: `Z = P Cᵀ L⁻ᵀ` by a forward sweep over the columns, then
    /// `K = Z L⁻¹` by a backward sweep (`2 NX NY²` flops).
    #[inline(always)]
    pub(super) fn gain<M: MulAdd, const NX: usize>(
        &self,
        pct: &SMatrix<f64, NX, NY>,
    ) -> SMatrix<f64, NX, NY> {
        let l = &self.l;
        let mut z = pct.data.0;
        for a in 0..NY {
            for b in 0..a {
                let (done, rest) = z.split_at_mut(a);
                axpy::<M, NX>(&mut rest[0], &done[b], -l[(a, b)]);
            }
            scale(&mut z[a], self.inv_diag[a]);
        }
        for a in (0..NY).rev() {
            for b in (a + 1)..NY {
                let (head, done) = z.split_at_mut(b);
                axpy::<M, NX>(&mut head[a], &done[0], -l[(b, a)]);
            }
            scale(&mut z[a], self.inv_diag[a]);
        }
        SMatrix::from_data(ArrayStorage(z))
    }
}

/// The Joseph form `(I − K C) P (I − K C)ᵀ + K R Kᵀ` for any gain `K` and symmetric `P`, from `P Cᵀ` and
/// `S = C P Cᵀ + R` (computed for the innovation anyway), without forming `I − K C`: with `G = I − K C`,
/// `G P = P − K C P` and `G P Cᵀ = P Cᵀ − K (S − R)`, so `G P Gᵀ + K R Kᵀ = P − K (P Cᵀ)ᵀ − W Kᵀ` with
/// `W = P Cᵀ − K S`. `W` costs `2 NX NY²` flops and the result `4 NX² NY` (its upper triangle mirrored),
/// against about `4 NX³` for the products as written. Writes the result to `out` and returns `W` (for the rounding bound).
#[inline(always)]
pub(super) fn joseph<M: MulAdd, const NX: usize, const NY: usize>(
    p: &SMatrix<f64, NX, NX>,
    k: &SMatrix<f64, NX, NY>,
    pct: &SMatrix<f64, NX, NY>,
    s: &SMatrix<f64, NY, NY>,
    out: &mut SMatrix<f64, NX, NX>,
) -> SMatrix<f64, NX, NY> {
    let (kd, md) = (&k.data.0, pct.data.0);
    let mut w = md;
    for a in 0..NY {
        for b in 0..NY {
            let s_ba = -s[(b, a)];
            for i in 0..NX {
                w[a][i] = M::mul_add(kd[b][i], s_ba, w[a][i]);
            }
        }
    }
    // Column j: P[:, j] − Σₐ (K[:, a] (P Cᵀ)[j, a] + W[:, a] K[j, a]), to the diagonal.
    let out = &mut out.data.0;
    for j in 0..NX {
        let m_row: [f64; NY] = std::array::from_fn(|a| -md[a][j]);
        let k_row: [f64; NY] = std::array::from_fn(|a| -kd[a][j]);
        upper_combination::<M, NX, NY, 2>(
            [(kd, &m_row), (&w, &k_row)],
            &p.data.0[j],
            &mut out[j],
            j,
        );
    }
    mirror_upper(out);
    SMatrix::from_data(ArrayStorage(w))
}

/// Writes the column `init + X w` (`X` of `K` columns of length `N`) to `out`. The sum stays in registers
/// until it is stored. Its chain of multiply-adds waits on itself; the processor overlaps the chains of
/// consecutive columns. (Two columns in one loop, sharing the loads of `X`, compile to shuffles that cost
/// more than the loads they save.)
#[inline(always)]
fn combine<M: MulAdd, const N: usize, const K: usize>(
    x: &[[f64; N]; K],
    w: &[f64; K],
    init: [f64; N],
    out: &mut [f64; N],
) {
    let mut sum = init;
    for k in 0..K {
        let s = w[k];
        for r in 0..N {
            sum[r] = M::mul_add(x[k][r], s, sum[r]);
        }
    }
    *out = sum;
}

/// Rows `0..=j` of the column `init + Σₜ Xₜ wₜ` (each `Xₜ` of `K` columns of length `N`), written to `out`,
/// for a symmetric result whose lower triangle is then mirrored from the upper one. The rows go in blocks of
/// four, one vector register with AVX2 (the block that holds row `j` is computed whole: the rows of it below
/// the diagonal are overwritten by the mirror), and the fewer than four rows after the last whole block only
/// for the columns that reach them. For `N = 7` that is 91 multiply-adds per product instead of 147 for
/// whole columns. Each block's sum stays in registers and is stored whole.
#[inline(always)]
fn upper_combination<M: MulAdd, const N: usize, const K: usize, const T: usize>(
    terms: [(&[[f64; N]; K], &[f64; K]); T],
    init: &[f64; N],
    out: &mut [f64; N],
    j: usize,
) {
    let (init_blocks, init_tail) = init.as_chunks::<4>();
    let (out_blocks, out_tail) = out.as_chunks_mut::<4>();
    for (b, (sum_out, start)) in out_blocks
        .iter_mut()
        .zip(init_blocks)
        .enumerate()
        .take(j / 4 + 1)
    {
        let mut sum = *start;
        for (x, w) in terms {
            for (column, s) in x.iter().zip(w) {
                let block = &column.as_chunks::<4>().0[b];
                for r in 0..4 {
                    sum[r] = M::mul_add(block[r], *s, sum[r]);
                }
            }
        }
        *sum_out = sum;
    }
    if j >= N - init_tail.len() {
        let mut sum = [0.0; 4];
        let tail = &mut sum[..init_tail.len()];
        tail.copy_from_slice(init_tail);
        for (x, w) in terms {
            for (column, s) in x.iter().zip(w) {
                for (v, xv) in tail.iter_mut().zip(column.as_chunks::<4>().1) {
                    *v = M::mul_add(*xv, *s, *v);
                }
            }
        }
        out_tail.copy_from_slice(tail);
    }
}

/// `y + M v`, column by column.
#[inline(always)]
pub(super) fn plus_product<M: MulAdd, const R: usize, const C: usize>(
    y: &SVector<f64, R>,
    m: &SMatrix<f64, R, C>,
    v: &SVector<f64, C>,
) -> SVector<f64, R> {
    let mut sum = [0.0; R];
    combine::<M, R, C>(&m.data.0, &v.data.0[0], y.data.0[0], &mut sum);
    SVector::from_data(ArrayStorage([sum]))
}

/// The Frobenius norm `‖m‖_F`, unscaled like nalgebra's `norm` (the certificates refuse an infinite one),
/// inlined into the step.
#[inline(always)]
pub(super) fn frobenius<M: MulAdd, const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> f64 {
    let mut squares = [0.0_f64; R];
    for column in &m.data.0 {
        for (sum, v) in squares.iter_mut().zip(column) {
            *sum = M::mul_add(*v, *v, *sum);
        }
    }
    squares.iter().sum::<f64>().sqrt()
}

/// Makes `m` exactly symmetric by copying its upper triangle onto the lower one.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // a transpose: the same array read at (i, j) and written at (j, i)
fn mirror_upper<const N: usize>(m: &mut [[f64; N]; N]) {
    for j in 0..N {
        for i in (j + 1)..N {
            // Row i of column j (below the diagonal) takes row j of column i (above it).
            m[j][i] = m[i][j];
        }
    }
}

/// `y ← y + x s` on one column.
#[inline(always)]
fn axpy<M: MulAdd, const N: usize>(y: &mut [f64; N], x: &[f64; N], s: f64) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi = M::mul_add(*xi, s, *yi);
    }
}

/// `y ← y s` on one column.
#[inline(always)]
fn scale<const N: usize>(y: &mut [f64; N], s: f64) {
    for yi in y.iter_mut() {
        *yi *= s;
    }
}
