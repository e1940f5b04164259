//! Linearisation of a model whose `NX × NX` Jacobian does not fit a thread's stack.

use bgc_runtime::linearize::{boxed_jacobians_at, linearize};
use bgc_runtime::model::ContinuousModel;
use nalgebra::{SVector, Vector1};

/// A line of `N` cells with cubic losses, `ẋᵢ = xᵢ₋₁ − 2 xᵢ + xᵢ₊₁ − xᵢ³` (cold ends), heated by `u` at the first
/// cell and measured at the middle one. Only `rhs` and `outputs` are written: the Jacobians come from the
/// trait's central differences.
struct CubicHeatLine<const N: usize>;

impl<const N: usize> ContinuousModel<N, 1, 1> for CubicHeatLine<N> {
    fn rhs(&self, _t: f64, x: &SVector<f64, N>, u: &Vector1<f64>, dx: &mut SVector<f64, N>) {
        for i in 0..N {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < N { x[i + 1] } else { 0.0 };
            dx[i] = left - 2.0 * x[i] + right - x[i].powi(3);
        }
        dx[0] += u[0];
    }

    fn outputs(&self, _t: f64, x: &SVector<f64, N>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[N / 2];
    }
}

/// 600 states: `A` alone takes 600² · 8 B = 2.9 MB, more than the 2 MiB of a spawned thread's default stack
/// (`std::thread` and the test harness), so the linearisation must never hold it on the stack. Against the hand
/// derivation at `xᵢ = sin(i/50)`: `A` tridiagonal with `1` beside the diagonal and `−2 − 3 xᵢ²` on it,
/// `B = e₀`, `C = e₃₀₀ᵀ`, `D = 0`.
#[test]
fn a_model_of_600_states_is_linearised_on_a_thread_with_the_default_stack() {
    const N: usize = 600;
    let run = || {
        let x0 = SVector::<f64, N>::from_fn(|i, _| (i as f64 / 50.0).sin());
        let ss = linearize(&CubicHeatLine::<N>, &x0, &Vector1::new(0.2)).expect("a linearisation");
        let (a, b, c, d) = (ss.a(), ss.b(), ss.c(), ss.d());
        assert_eq!((a.nrows(), b.ncols(), c.nrows()), (N, 1, 1));
        let mut worst: f64 = 0.0;
        for j in 0..N {
            for i in 0..N {
                let expected = match i.abs_diff(j) {
                    0 => -2.0 - 3.0 * x0[i] * x0[i],
                    1 => 1.0,
                    _ => 0.0,
                };
                worst = worst.max((a[(i, j)] - expected).abs());
            }
            let e = |k: usize| if j == k { 1.0 } else { 0.0 };
            assert!((b[(j, 0)] - e(0)).abs() < 1e-9, "B[{j}]");
            assert!((c[(0, j)] - e(N / 2)).abs() < 1e-9, "C[{j}]");
        }
        assert!(worst < 1e-8, "largest error in A: {worst:e}");
        assert_eq!(d[(0, 0)], 0.0);
        // The same matrices as fixed-size ones, on the heap.
        let j = boxed_jacobians_at(&CubicHeatLine::<N>, 0.0, &x0, &Vector1::new(0.2))
            .expect("the Jacobians");
        assert!(j.a.iter().zip(a.iter()).all(|(x, y)| x == y));
        let entries = (j.b[(0, 0)], j.c[(0, N / 2)], j.d[(0, 0)]);
        assert_eq!(entries, (b[(0, 0)], c[(0, N / 2)], d[(0, 0)]));
    };
    // `spawn` without `stack_size` takes `RUST_MIN_STACK` if set; the size is given so that the test does not
    // depend on the environment: 2 MiB, the default.
    let thread = std::thread::Builder::new().stack_size(2 << 20).spawn(run);
    // A stack overflow aborts the test binary; a failed assertion is passed on with its message.
    if let Err(panic) = thread.expect("a thread").join() {
        std::panic::resume_unwind(panic);
    }
}
