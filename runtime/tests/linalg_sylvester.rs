//! The Bartels–Stewart Lyapunov, Sylvester and Stein solvers at up to 200 states against scipy (and, for the
//! Stein equation, a dense Kronecker solve in numpy).
//!
//! The references were computed once with scipy 1.17.1 / numpy 2.4.6:
//!
//! ```python
//! import numpy as np, scipy.linalg as sl
//! def chain(n, k=1.0, c=0.1):          # the damped mass-spring chain of `chain` below
//!     masses = n // 2
//!     a = np.zeros((n, n))
//!     for i in range(masses):
//!         q, v = 2 * i, 2 * i + 1
//!         a[q, v] = 1.0
//!         nb = 2.0 if i + 1 < masses else 1.0
//!         a[v, q] = -k * nb; a[v, v] = -c * nb
//!         if i > 0: a[v, q - 2] = k; a[v, v - 2] = c
//!         if i + 1 < masses: a[v, q + 2] = k; a[v, v + 2] = c
//!     return a
//! def cmat(m, n):
//!     return np.array([[np.sin(i + 2 * j + 1.0) for j in range(n)] for i in range(m)])
//! def summary(name, x):                # the entries and sums that `Summary` holds
//!     m, n = x.shape
//!     print(name, x[0,0], x[m-1,n-1], x[0,n-1], x[m//2, n//3], np.trace(x[:min(m,n),:min(m,n)]), np.linalg.norm(x))
//! a = chain(200, c=1.0)
//! summary("lyap200", sl.solve_continuous_lyapunov(a, -np.eye(200)))
//! summary("dlyap200", sl.solve_discrete_lyapunov(0.9 * (np.eye(200) + 0.05 * a), np.eye(200)))
//! a1 = chain(150, c=1.0); b1 = chain(200, c=1.0).T - 0.5 * np.eye(200); c1 = cmat(150, 200)
//! summary("sylv150x200", sl.solve_sylvester(a1, b1, -c1))
//! a2 = np.eye(40) + 0.05 * chain(40); b2 = (np.eye(30) + 0.05 * chain(30)).T; c2 = cmat(40, 30)
//! k = np.kron(b2.T, a2) - np.eye(1200)  # A X B − X + C = 0 ⇔ (Bᵀ ⊗ A − I) vec X = −vec C
//! x2 = np.linalg.solve(k, -c2.flatten(order="F")).reshape((40, 30), order="F")
//! summary("stein40x30", x2)
//! ```

use bgc_runtime::linalg::{LyapunovError, dlyap, lyap, stein, sylvester};
use nalgebra::DMatrix;

/// `n/2` unit masses, springs `k = 1`, dampers `c`, the first tied to a wall; states `[q₁, v₁, q₂, v₂, …]`.
fn chain(n: usize, c: f64) -> DMatrix<f64> {
    let masses = n / 2;
    let mut a = DMatrix::<f64>::zeros(n, n);
    for i in 0..masses {
        let (q, v) = (2 * i, 2 * i + 1);
        a[(q, v)] = 1.0;
        let neighbours = if i + 1 < masses { 2.0 } else { 1.0 };
        a[(v, q)] = -neighbours;
        a[(v, v)] = -c * neighbours;
        if i > 0 {
            a[(v, q - 2)] = 1.0;
            a[(v, v - 2)] = c;
        }
        if i + 1 < masses {
            a[(v, q + 2)] = 1.0;
            a[(v, v + 2)] = c;
        }
    }
    a
}

fn cmat(m: usize, n: usize) -> DMatrix<f64> {
    DMatrix::from_fn(m, n, |i, j| (i as f64 + 2.0 * j as f64 + 1.0).sin())
}

/// `X[0,0]`, `X[m−1,n−1]`, `X[0,n−1]`, `X[m/2,n/3]`, the trace of the leading square block, `‖X‖_F`.
struct Summary([f64; 6]);

impl Summary {
    fn assert_matches(&self, x: &DMatrix<f64>, what: &str) {
        let (m, n) = x.shape();
        let k = m.min(n);
        let got = [
            x[(0, 0)],
            x[(m - 1, n - 1)],
            x[(0, n - 1)],
            x[(m / 2, n / 3)],
            x.view((0, 0), (k, k)).trace(),
            x.norm(),
        ];
        // Entries to 1e-11 of the solution's size (scipy's own error is about 1e-15 of it), sums likewise.
        let scale = self.0[5];
        for (i, (g, r)) in got.iter().zip(self.0).enumerate() {
            assert!(
                (g - r).abs() <= 1e-11 * scale,
                "{what}: quantity {i} is {g}, scipy {r}"
            );
        }
    }
}

#[test]
fn lyapunov_of_a_200_state_chain_matches_scipy() {
    let a = chain(200, 1.0);
    let q = DMatrix::<f64>::identity(200, 200);
    let x = lyap(&a, &q).unwrap();
    Summary([
        50.99999999989213,
        50.499999999947825,
        -2.7878421300380824e-12,
        61769.49999986247,
        8506824.999983463,
        8381319.537188527,
    ])
    .assert_matches(&x, "lyap");
    let ad = (DMatrix::<f64>::identity(200, 200) + &a * 0.05) * 0.9;
    let xd = dlyap(&ad, &q).unwrap();
    Summary([
        4.943412260610336,
        4.212071991997918,
        1.3624804132403181e-16,
        1.3790799145114426e-09,
        883.5188631571182,
        65.68738875265113,
    ])
    .assert_matches(&xd, "dlyap");
}

#[test]
fn sylvester_150_by_200_matches_scipy() {
    let a = chain(150, 1.0);
    let b = chain(200, 1.0).transpose() - DMatrix::<f64>::identity(200, 200) * 0.5;
    let x = sylvester(&a, &b, &cmat(150, 200)).unwrap();
    Summary([
        0.5985986797637097,
        0.09452214510456439,
        -0.49823964505798185,
        0.13458055041888792,
        1.0346298793463085,
        50.50197157767475,
    ])
    .assert_matches(&x, "sylvester");
}

#[test]
fn stein_40_by_30_matches_a_kronecker_solve() {
    let a = DMatrix::<f64>::identity(40, 40) + chain(40, 0.1) * 0.05;
    let b = (DMatrix::<f64>::identity(30, 30) + chain(30, 0.1) * 0.05).transpose();
    let x = stein(&a, &b, &cmat(40, 30)).unwrap();
    Summary([
        -3.7096665292077415,
        34.3253750293623,
        -4.302685124753875,
        -17.124963233903372,
        -601.8398968859826,
        1404.0586527212042,
    ])
    .assert_matches(&x, "stein");
}

/// Sylvester with 2x2 blocks in both factors and in the off-diagonal coupling, checked by its definition:
/// `A = [[−1, 2], [−3, −1]] ⊕ −2` and `B = [[−0.5, 1], [−4, −0.5]]` (complex pairs −1 ± 2.45i, −0.5 ± 2i),
/// rotated to full matrices; `A X + X B + C` must vanish to rounding.
#[test]
fn sylvester_with_complex_pairs_satisfies_the_equation() {
    let a = DMatrix::from_row_slice(3, 3, &[-1.0, 2.0, 0.3, -3.0, -1.0, 0.7, 0.0, 0.0, -2.0]);
    let b = DMatrix::from_row_slice(2, 2, &[-0.5, 1.0, -4.0, -0.5]);
    let v = nalgebra::dvector![1.0, 2.0, -1.0];
    let h = DMatrix::identity(3, 3) - &v * v.transpose() * (2.0 / v.norm_squared());
    let a = &h * a * &h;
    let c = cmat(3, 2);
    let x = sylvester(&a, &b, &c).unwrap();
    assert!((&a * &x + &x * &b + &c).amax() < 1e-14);
    let y = stein(&(&a * 0.3), &(&b * 0.2), &c).unwrap();
    assert!((&a * 0.3 * &y * &b * 0.2 - &y + &c).amax() < 1e-14);
}

#[test]
fn sylvester_refuses_a_shared_eigenvalue_pair_and_bad_shapes() {
    // λ(A) = 1, μ(B) = −1: λ + μ = 0.
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -3.0]);
    let b = DMatrix::from_row_slice(1, 1, &[-1.0]);
    assert!(matches!(
        sylvester(&a, &b, &DMatrix::from_element(2, 1, 1.0)),
        Err(LyapunovError::NoUniqueSolution { .. })
    ));
    // λ(A) = 2, μ(B) = 0.5: λ μ = 1.
    let a = DMatrix::from_row_slice(1, 1, &[2.0]);
    let b = DMatrix::from_row_slice(1, 1, &[0.5]);
    assert!(matches!(
        stein(&a, &b, &DMatrix::from_element(1, 1, 1.0)),
        Err(LyapunovError::NoUniqueSolution { .. })
    ));
    assert!(matches!(
        sylvester(&a, &b, &DMatrix::from_element(2, 1, 1.0)),
        Err(LyapunovError::Input(_))
    ));
}
