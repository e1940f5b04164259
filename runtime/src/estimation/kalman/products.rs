//! The matrix products of a Kalman step, written for the shapes and symmetries of the filter.
//!
//! Every product is built column by column as a sum of columns scaled by scalars (`y[:, j] += x[:, k] s`):
//! the innermost loop runs down a contiguous column of the fixed length `NX`, which compiles to straight
//! vector code without branches, and each column is written once, in place. A symmetric result is computed
//! in full columns and then made exactly symmetric by copying its upper triangle onto the lower one: the
//! product of the lower triangle is work thrown away, but rows cut at the diagonal compile to a loop of
//! varying length per column, which costs more than the arithmetic it saves at these sizes. The matrices
//! are read through nalgebra's column-major arrays (`data.0[column][row]`), whose bounds are the const sizes.

use nalgebra::{ArrayStorage, SMatrix, SVector};

/// `A P Aᵀ + Q` for symmetric `P` and `Q`, from `A` and `Aᵀ` (kept with the filter): `T = P Aᵀ` (written into
/// `t`, the filter's work matrix: an `NX × NX` local would not fit the stack of a large filter), then
/// `A T + Q`, its upper triangle mirrored (`4 NX³` flops).
pub(super) fn congruence_plus<const NX: usize>(
    a: &SMatrix<f64, NX, NX>,
    at: &SMatrix<f64, NX, NX>,
    p: &SMatrix<f64, NX, NX>,
    q: &SMatrix<f64, NX, NX>,
    out: &mut SMatrix<f64, NX, NX>,
    t: &mut SMatrix<f64, NX, NX>,
) {
    let (a, at, p) = (&a.data.0, &at.data.0, &p.data.0);
    let t = &mut t.data.0;
    // Column i of T = P Aᵀ is P times column i of Aᵀ (row i of A).
    for i in 0..NX {
        let mut col = [0.0_f64; NX];
        for k in 0..NX {
            let s = at[i][k];
            for r in 0..NX {
                col[r] += p[k][r] * s;
            }
        }
        t[i] = col;
    }
    // Column j of A T + Q is Q[:, j] plus the columns of A weighted by column j of T.
    let out = &mut out.data.0;
    for j in 0..NX {
        let mut col = q.data.0[j];
        for k in 0..NX {
            let s = t[j][k];
            for i in 0..NX {
                col[i] += a[k][i] * s;
            }
        }
        out[j] = col;
    }
    mirror_upper(out);
}

/// `P Cᵀ` for symmetric `P`, the transpose of `C P`: column `a` is `P` times row `a` of `C` (`2 NX² NY` flops).
pub(super) fn covariance_times_ct<const NX: usize, const NY: usize>(
    p: &SMatrix<f64, NX, NX>,
    ct: &SMatrix<f64, NX, NY>,
) -> SMatrix<f64, NX, NY> {
    let (p, ct) = (&p.data.0, &ct.data.0);
    let mut out = [[0.0_f64; NX]; NY];
    for a in 0..NY {
        for k in 0..NX {
            let s = ct[a][k];
            for i in 0..NX {
                out[a][i] += p[k][i] * s;
            }
        }
    }
    SMatrix::from_data(ArrayStorage(out))
}

/// The innovation covariance `S = C P Cᵀ + R` from `P Cᵀ`: the upper triangle of `(P Cᵀ)ᵀ Cᵀ + R`, mirrored
/// (`NY (NY + 1) NX` flops).
pub(super) fn innovation_covariance<const NX: usize, const NY: usize>(
    pct: &SMatrix<f64, NX, NY>,
    ct: &SMatrix<f64, NX, NY>,
    r: &SMatrix<f64, NY, NY>,
) -> SMatrix<f64, NY, NY> {
    let mut s = *r;
    for b in 0..NY {
        for a in 0..b + 1 {
            let mut v = r[(a, b)];
            for k in 0..NX {
                v += pct.data.0[a][k] * ct.data.0[b][k];
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
    pub(super) fn gain<const NX: usize>(&self, pct: &SMatrix<f64, NX, NY>) -> SMatrix<f64, NX, NY> {
        let l = &self.l;
        let mut z = pct.data.0;
        for a in 0..NY {
            for b in 0..a {
                let (done, rest) = z.split_at_mut(a);
                axpy(&mut rest[0], &done[b], -l[(a, b)]);
            }
            scale(&mut z[a], self.inv_diag[a]);
        }
        for a in (0..NY).rev() {
            for b in (a + 1)..NY {
                let (head, done) = z.split_at_mut(b);
                axpy(&mut head[a], &done[0], -l[(b, a)]);
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
pub(super) fn joseph<const NX: usize, const NY: usize>(
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
            let s_ba = s[(b, a)];
            for i in 0..NX {
                w[a][i] -= kd[b][i] * s_ba;
            }
        }
    }
    // Column j: P[:, j] − Σₐ (K[:, a] (P Cᵀ)[j, a] + W[:, a] K[j, a]).
    let out = &mut out.data.0;
    for j in 0..NX {
        let mut col = p.data.0[j];
        for a in 0..NY {
            let (m_ja, k_ja) = (md[a][j], kd[a][j]);
            for i in 0..NX {
                col[i] -= kd[a][i] * m_ja + w[a][i] * k_ja;
            }
        }
        out[j] = col;
    }
    mirror_upper(out);
    SMatrix::from_data(ArrayStorage(w))
}

/// Makes `m` exactly symmetric by copying its upper triangle onto the lower one.
#[inline]
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
fn axpy<const N: usize>(y: &mut [f64; N], x: &[f64; N], s: f64) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += xi * s;
    }
}

/// `y ← y s` on one column.
#[inline]
fn scale<const N: usize>(y: &mut [f64; N], s: f64) {
    for yi in y.iter_mut() {
        *yi *= s;
    }
}
