//! The matrix sign function of a Hamiltonian matrix by the scaled Newton iteration.
//!
//! `Z₀ = H`, `Z_{k+1} = (c_k Z_k + (c_k Z_k)⁻¹)/2` with the determinant scaling `c_k = |det Z_k|^{−1/N}` (Byers
//! 1987), which brings the eigenvalues towards ±1 quickly when they are spread over many orders of magnitude.
//! The scaling is dropped once the relative change falls below `10⁻²` (near convergence it would slow the
//! quadratic phase). The iterates of a Hamiltonian `H` are Hamiltonian, i.e. `J Z` is symmetric with
//! `J = [0 I; −I 0]`; the symmetric part of `J Z` is restored after each step to keep that structure.
//!
//! The iteration fails (returns `None`) when an iterate is singular or it has not converged after
//! [`MAX_SIGN_ITERATIONS`] steps, which happens when `H` has eigenvalues on or very near the imaginary axis.

use nalgebra::DMatrix;

/// Iteration limit of [`hamiltonian_sign`].
pub const MAX_SIGN_ITERATIONS: usize = 100;

/// `sign(H)` of a `2n x 2n` Hamiltonian matrix and the number of iterations, or `None` (see the module docs).
pub fn hamiltonian_sign(h: &DMatrix<f64>) -> Option<(DMatrix<f64>, usize)> {
    let big_n = h.nrows();
    if big_n == 0 || !big_n.is_multiple_of(2) || h.ncols() != big_n {
        return None;
    }
    let n = big_n / 2;
    let mut z = h.clone();
    let mut scaling = true;
    for iteration in 1..=MAX_SIGN_ITERATIONS {
        let lu = z.clone().lu();
        let z_inv = lu.try_inverse()?;
        let c = if scaling {
            let u = lu.u();
            let log_det: f64 = (0..big_n).map(|i| u[(i, i)].abs().ln()).sum();
            let c = (-log_det / big_n as f64).exp();
            if c.is_finite() && c > 0.0 { c } else { 1.0 }
        } else {
            1.0
        };
        let mut next = (&z * c + z_inv / c) * 0.5;
        restore_hamiltonian(&mut next, n);
        if !next.iter().all(|v| v.is_finite()) {
            return None;
        }
        let change = (&next - &z).norm() / next.norm();
        z = next;
        if change < 1e-2 {
            scaling = false;
        }
        if change <= 1e-13 * (big_n as f64) {
            return Some((z, iteration));
        }
    }
    None
}

/// Replaces `Z` by the Hamiltonian matrix nearest in the sense that `J Z` becomes the symmetric part of `J Z`.
fn restore_hamiltonian(z: &mut DMatrix<f64>, n: usize) {
    // Z = [Z11 Z12; Z21 Z22]; J Z = [Z21 Z22; −Z11 −Z12]. Symmetry of J Z means Z21 and Z12 are symmetric and
    // Z22 = −Z11ᵀ.
    let z11 = z.view((0, 0), (n, n)).clone_owned();
    let z22 = z.view((n, n), (n, n)).clone_owned();
    let new11 = (&z11 - z22.transpose()) * 0.5;
    let z12 = z.view((0, n), (n, n)).clone_owned();
    let z21 = z.view((n, 0), (n, n)).clone_owned();
    z.view_mut((0, 0), (n, n)).copy_from(&new11);
    z.view_mut((n, n), (n, n)).copy_from(&(-new11.transpose()));
    z.view_mut((0, n), (n, n))
        .copy_from(&((&z12 + z12.transpose()) * 0.5));
    z.view_mut((n, 0), (n, n))
        .copy_from(&((&z21 + z21.transpose()) * 0.5));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For the scalar Riccati problem, H = [a, −g; −q, −a] satisfies H² = (a² + gq) I, so by hand
    /// sign(H) = H / √(a² + gq).
    #[test]
    fn scalar_hamiltonian_sign_is_h_over_its_modulus() {
        let (a, g, q) = (-3.0, 0.5, 200.0);
        let h = DMatrix::from_row_slice(2, 2, &[a, -g, -q, -a]);
        let (w, iterations) = hamiltonian_sign(&h).unwrap();
        let expected = &h / (a * a + g * q).sqrt();
        assert!((w - expected).amax() < 1e-14);
        assert!(iterations < 10);
    }

    /// Eigenvalues on the imaginary axis (H = [0, 1; −1, 0], λ = ±i) have no sign: the iteration must fail
    /// rather than return a matrix.
    #[test]
    fn imaginary_axis_eigenvalues_fail() {
        let h = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, 0.0]);
        assert!(hamiltonian_sign(&h).is_none());
        assert!(hamiltonian_sign(&DMatrix::zeros(3, 3)).is_none());
    }
}
