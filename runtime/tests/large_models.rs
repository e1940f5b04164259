//! The linear plant, its zero-order-hold loop, the Kalman filter and the continuous observer at a size whose
//! `NX × NX` matrices do not fit a thread's stack: 520 states, so that one such matrix takes
//! 520² · 8 B = 2.16 MB, more than the 2 MiB of a spawned thread's default stack (`std::thread` and the test
//! harness); the UKF and the dual UKF at 362 states, whose `362 × 725` sigma-point matrix takes 2.10 MB, more
//! than 2 MiB too (and whose step costs `O(NX³)` in the test build's light optimisation). Each test runs on a
//! thread of exactly that size; a stack overflow would abort the test binary. The models are diagonal or nearly
//! so, so that every result has a hand derivation.

use bgc_runtime::estimation::dual_ukf::DualUkf;
use bgc_runtime::estimation::observer::ContinuousObserver;
use bgc_runtime::estimation::srukf::SquareRootUkf;
use bgc_runtime::estimation::ukf_augmented::AugmentedUkf;
use bgc_runtime::estimation::{
    KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter, UpdateOutcome,
};
use bgc_runtime::matrix::{boxed_identity, zeroed_box};
use bgc_runtime::sim::{LinearPlant, SampledLoopConfig, simulate_sampled_linear_loop};
use bgc_runtime::statespace::StateSpace;
use nalgebra::{DMatrix, SVector, Vector1};

const N: usize = 520;

/// Runs `test` on a thread with a 2 MiB stack and passes a failed assertion on with its message.
fn on_a_2_mib_thread(test: impl FnOnce() + Send + 'static) {
    // `spawn` without `stack_size` takes `RUST_MIN_STACK` if set; the size is given so that the test does not
    // depend on the environment: 2 MiB, the default.
    let thread = std::thread::Builder::new().stack_size(2 << 20).spawn(test);
    if let Err(panic) = thread.expect("a thread").join() {
        std::panic::resume_unwind(panic);
    }
}

/// `e_k` as a column of `rows` entries.
fn unit_column(rows: usize, k: usize) -> DMatrix<f64> {
    DMatrix::from_fn(rows, 1, |i, _| if i == k { 1.0 } else { 0.0 })
}

/// `N` decoupled first-order lags `ẋᵢ = −λ xᵢ`, the input on the first, the first measured, under a constant
/// input of 1 from `x = (0, 1, 1, …)`. By hand, with `φ = e^{−λT}` and `γ = (1 − φ)/λ`: `x₀[k] = γ (1 − φᵏ)/(1 − φ)`
/// and `xᵢ[k] = φᵏ` for `i > 0`; the measurement is `x₀`.
#[test]
fn a_linear_plant_of_520_states_runs_its_sampled_loop_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (lambda, t, samples) = (2.0, 0.05, 4);
        let ss = StateSpace::new(
            DMatrix::identity(N, N) * -lambda,
            unit_column(N, 0),
            unit_column(N, 0).transpose(),
            DMatrix::zeros(1, 1),
        )
        .expect("a state-space model");
        let plant = LinearPlant::<N, 1, 1>::from_state_space(&ss).expect("the plant's sizes");
        let x0 = SVector::<f64, N>::from_fn(|i, _| if i == 0 { 0.0 } else { 1.0 });
        let cfg = SampledLoopConfig::new(t, samples, x0);
        let mut constant = |_k: usize, _t: f64, _y: &Vector1<f64>| Vector1::new(1.0);
        let traj = simulate_sampled_linear_loop(&plant, &mut constant, &cfg).expect("a run");
        let (phi, gamma) = ((-lambda * t).exp(), (1.0 - (-lambda * t).exp()) / lambda);
        for k in 0..=samples {
            let driven = gamma * (1.0 - phi.powi(k as i32)) / (1.0 - phi);
            let x = &traj.states[k];
            assert!((x[0] - driven).abs() < 1e-13, "x₀[{k}] = {}", x[0]);
            assert!((traj.measurements[k][0] - driven).abs() < 1e-13, "y[{k}]");
            let decayed = phi.powi(k as i32);
            let worst = (1..N).map(|i| (x[i] - decayed).abs()).fold(0.0, f64::max);
            assert!(
                worst < 1e-13,
                "largest error of the free states at {k}: {worst:e}"
            );
        }
        // The plant as a model: its Jacobian is A, written into a matrix on the heap.
        let mut jac = zeroed_box::<N, N>();
        bgc_runtime::model::ContinuousModel::jac_x(&plant, 0.0, &x0, &Vector1::new(0.0), &mut jac);
        assert_eq!(
            (jac[(0, 0)], jac[(N - 1, N - 1)], jac[(0, 1)]),
            (-lambda, -lambda, 0.0)
        );
    });
}

/// A Kalman filter of `N` random walks `x[k+1] = α x[k] + B u` with `Q = diag(0, q, q, …)` (singular, so no
/// certificate holds and every step runs the definiteness test in the filter's work matrix), the state
/// `m = N/2` measured with variance `r`, from `P₀ = p₀ I`. By hand, after one step:
/// `P⁻ = diag(α² p₀ + qᵢ)`; `S = P⁻ₘₘ + r`, `K = (P⁻ₘₘ / S) eₘ`, `Pₘₘ = P⁻ₘₘ r / S`, the other entries of `P⁻`
/// unchanged; `x⁻ = α x + B u` and `xₘ = x⁻ₘ + K (y − x⁻ₘ)`.
#[test]
fn a_kalman_filter_of_520_states_steps_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (alpha, q, r, p0, u, y) = (0.9, 0.01, 0.04, 2.0, 0.5, 1.5);
        let m = N / 2;
        let ss = StateSpace::new_discrete(
            DMatrix::identity(N, N) * alpha,
            unit_column(N, 0),
            unit_column(N, m).transpose(),
            DMatrix::zeros(1, 1),
            0.1,
        )
        .expect("a state-space model");
        let model = LinearDiscreteModel::<N, 1, 1>::boxed_from_state_space(&ss).expect("sizes");
        let mut q_matrix = boxed_identity::<N>(q);
        q_matrix[(0, 0)] = 0.0;
        let x0 = SVector::<f64, N>::from_fn(|i, _| 0.001 * i as f64);
        let r_matrix = Vector1::new(r);
        let mut kf =
            KalmanFilter::from_refs(&model, &q_matrix, &r_matrix, &x0, &boxed_identity(p0))
                .expect("a filter");
        // A clone, made on the heap too.
        let mut twin = kf.clone();
        kf.predict(&Vector1::new(u)).expect("a prediction");
        let outcome = kf
            .update(&Vector1::new(y), &Vector1::new(u))
            .expect("an update");
        assert!(matches!(
            outcome,
            UpdateOutcome::Accepted { repair: None, .. }
        ));

        let predicted = |i: usize| alpha * alpha * p0 + if i == 0 { 0.0 } else { q };
        let s = predicted(m) + r;
        let (p, x) = (kf.covariance(), kf.state());
        assert!((kf.innovation_covariance()[(0, 0)] - s).abs() < 1e-14);
        assert!((kf.gain()[(m, 0)] - predicted(m) / s).abs() < 1e-15);
        for i in 0..N {
            let expected = if i == m {
                predicted(m) * r / s
            } else {
                predicted(i)
            };
            assert!(
                (p[(i, i)] - expected).abs() < 1e-14,
                "P[{i}, {i}] = {}",
                p[(i, i)]
            );
            let prior = alpha * x0[i] + if i == 0 { u } else { 0.0 };
            let corrected = if i == m {
                prior + predicted(m) / s * (y - prior)
            } else {
                prior
            };
            assert!((x[i] - corrected).abs() < 1e-14, "x[{i}] = {}", x[i]);
        }
        let off_diagonal =
            (0..N).flat_map(|j| (0..N).filter(move |&i| i != j).map(move |i| (i, j)));
        assert!(off_diagonal.clone().all(|(i, j)| p[(i, j)] == 0.0));

        // The clone kept the initial estimate, and `set_state_from` takes a covariance held on the heap.
        assert_eq!((twin.covariance()[(m, m)], twin.state()[1]), (p0, x0[1]));
        twin.set_state_from(&x0, &boxed_identity(2.0 * p0))
            .expect("a new estimate");
        assert_eq!(twin.covariance()[(m, m)], 2.0 * p0);
    });
}

/// The observer `x̂' = A x̂ + B u + L (y − C x̂)` of `N` lags `ẋᵢ = −xᵢ` with the first state measured and
/// `L = 3 e₀`: by hand `x̂'₀ = −x̂₀ + u + 3 (y − x̂₀)`, `x̂'ᵢ = −x̂ᵢ`, and `A − L C` is `−I` with `−4` at `(0, 0)`.
#[test]
fn a_continuous_observer_of_520_states_runs_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let a = boxed_identity::<N>(-1.0);
        let mut b = zeroed_box::<N, 1>();
        b[0] = 1.0;
        let mut c = zeroed_box::<1, N>();
        c[0] = 1.0;
        let mut l = zeroed_box::<N, 1>();
        l[0] = 3.0;
        let observer =
            ContinuousObserver::from_refs(&a, &b, &c, &zeroed_box(), &l).expect("finite");
        let x_hat = SVector::<f64, N>::from_fn(|i, _| 1.0 + i as f64);
        let (u, y) = (Vector1::new(0.5), Vector1::new(2.0));
        let dx = observer.rhs(&x_hat, &u, &y);
        assert!((dx[0] - (-1.0 + 0.5 + 3.0 * (2.0 - 1.0))).abs() < 1e-15);
        assert!((1..N).all(|i| dx[i] == -x_hat[i]));
        let error_dynamics = observer.error_dynamics();
        assert_eq!(
            (error_dynamics[(0, 0)], error_dynamics[(N - 1, N - 1)]),
            (-4.0, -1.0)
        );
        assert_eq!(error_dynamics.sum(), -4.0 - (N - 1) as f64);
    });
}

/// States of the unscented filters' tests, and their sigma points (`2 NU_STATES + 1`).
const NU_STATES: usize = 362;
const NU_POINTS: usize = 725;

/// The UKF of `NU_STATES` scaled random walks `x[k+1] = α x[k]` with `Q = q I`, the state `m` measured with
/// variance `r`, from `P₀ = p₀ I`, with `α = 1`, `κ = 0` sigma points (`W₀⁽ᵐ⁾ = 0`). For a linear model the
/// unscented transform is exact, so the hand derivation of the Kalman filter's test holds to rounding:
/// `P⁻ = (α² p₀ + q) I`, `S = P⁻ₘₘ + r`, `Pₘₘ = P⁻ₘₘ r / S`, `xₘ = α x₀ₘ + (P⁻ₘₘ / S) (y − α x₀ₘ)`.
#[test]
fn a_ukf_of_362_states_steps_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (alpha, q, r, p0, y) = WALK;
        let m = NU_STATES / 2;
        let x0 = SVector::<f64, NU_STATES>::from_fn(|i, _| 0.001 * i as f64);
        let points = SigmaPoints::new(1.0, 2.0, 0.0).expect("weights");
        let mut ukf = UnscentedKalmanFilter::<NU_STATES, 1, 1, NU_POINTS>::from_refs(
            points,
            &boxed_identity(q),
            &Vector1::new(r),
            &x0,
            &boxed_identity(p0),
        )
        .expect("a filter");
        let u = Vector1::new(0.0);
        ukf.predict(&u, |x, _u| x * alpha).expect("a prediction");
        let outcome = ukf
            .update(&Vector1::new(y), &u, |x, _u| Vector1::new(x[m]))
            .expect("an update");
        assert!(matches!(outcome, UpdateOutcome::Accepted { .. }));
        assert_walk_step(ukf.covariance(), ukf.state(), &x0);
    });
}

/// The square-root UKF of the UKF's test, against the same hand derivation.
#[test]
fn a_square_root_ukf_of_362_states_steps_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (alpha, q, r, p0, y) = WALK;
        let m = NU_STATES / 2;
        let x0 = SVector::<f64, NU_STATES>::from_fn(|i, _| 0.001 * i as f64);
        let points = SigmaPoints::new(1.0, 2.0, 0.0).expect("weights");
        let mut ukf = SquareRootUkf::<NU_STATES, 1, 1, NU_POINTS>::from_refs(
            points,
            &boxed_identity(q),
            &Vector1::new(r),
            &x0,
            &boxed_identity(p0),
        )
        .expect("a filter");
        let u = Vector1::new(0.0);
        ukf.predict(&u, |x, _u| x * alpha).expect("a prediction");
        let outcome = ukf
            .update(&Vector1::new(y), &u, |x, _u| Vector1::new(x[m]))
            .expect("an update");
        assert!(matches!(outcome, UpdateOutcome::Accepted { .. }));
        assert_walk_step(&ukf.covariance(), ukf.state(), &x0);
    });
}

/// `(α, q, r, p₀, y)` of the unscented filters' tests.
const WALK: (f64, f64, f64, f64, f64) = (0.9, 0.01, 0.04, 2.0, 1.5);

/// The hand derivation of one step of the UKF's test: `P = diag(α² p₀ + q)` but `Pₘₘ = P⁻ₘₘ r / S`, and
/// `x = α x₀` but `xₘ = α x₀ₘ + (P⁻ₘₘ / S) (y − α x₀ₘ)`, to rounding.
fn assert_walk_step(
    p: &nalgebra::SMatrix<f64, NU_STATES, NU_STATES>,
    x: &SVector<f64, NU_STATES>,
    x0: &SVector<f64, NU_STATES>,
) {
    let (alpha, q, r, p0, y) = WALK;
    let m = NU_STATES / 2;
    let predicted = alpha * alpha * p0 + q;
    let s = predicted + r;
    for i in 0..NU_STATES {
        let expected = if i == m { predicted * r / s } else { predicted };
        assert!(
            (p[(i, i)] - expected).abs() < 1e-12,
            "P[{i}, {i}] = {}",
            p[(i, i)]
        );
        let prior = alpha * x0[i];
        let corrected = if i == m {
            prior + predicted / s * (y - prior)
        } else {
            prior
        };
        assert!((x[i] - corrected).abs() < 1e-12, "x[{i}] = {}", x[i]);
    }
    let largest_off_diagonal = (0..NU_STATES)
        .flat_map(|j| (0..NU_STATES).filter(move |&i| i != j).map(move |i| (i, j)))
        .map(|(i, j)| p[(i, j)].abs())
        .fold(0.0, f64::max);
    assert!(
        largest_off_diagonal < 1e-12,
        "largest off-diagonal entry {largest_off_diagonal:e}"
    );
}

/// A dual UKF of the same walks with the factor `w` as its one parameter, `x[k+1] = w x[k]`, started at
/// `w = α`: its state filter's step is the UKF's step at `α`, so after one step its state estimate is that of
/// a plain UKF run alongside (the same arithmetic, hence equal to the last bit).
#[test]
fn a_dual_ukf_of_362_states_steps_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (alpha, q, r, p0, y) = WALK;
        let m = NU_STATES / 2;
        let x0 = SVector::<f64, NU_STATES>::from_fn(|i, _| 0.001 * i as f64);
        let points = SigmaPoints::new(1.0, 2.0, 0.0).expect("weights");
        let filter = || {
            UnscentedKalmanFilter::<NU_STATES, 1, 1, NU_POINTS>::from_refs(
                points,
                &boxed_identity(q),
                &Vector1::new(r),
                &x0,
                &boxed_identity(p0),
            )
            .expect("a filter")
        };
        let mut plain = filter();
        let param_points = SigmaPoints::<1, 3>::new(1.0, 2.0, 0.0).expect("weights");
        let (w0, pw0) = (Vector1::new(alpha), Vector1::new(0.01));
        let mut dual = DualUkf::new(filter(), param_points, w0, pw0, 1.0).expect("a dual UKF");
        let u = Vector1::new(0.0);
        let measure = |x: &SVector<f64, NU_STATES>| Vector1::new(x[m]);
        dual.step_with(
            &u,
            &Vector1::new(y),
            |x, _u, w| x * w[0],
            |x, _u, _w| measure(x),
        )
        .expect("a step");
        plain.predict(&u, |x, _u| x * alpha).expect("a prediction");
        plain
            .update(&Vector1::new(y), &u, |x, _u| measure(x))
            .expect("an update");
        assert_eq!(dual.state(), plain.state());
        assert!(dual.parameters()[0].is_finite());
    });
}

/// The augmented UKF of the same walks with the process noise `v` (variance `q`) entering the first state and
/// the measurement noise `n` (variance `r`) added to `x_m`: `NA = 362 + 1 + 1` augmented states and 729 points.
/// By hand, `P⁻ = α² p₀ I + q e₀e₀ᵀ`, and the update is the Kalman filter's: `Pₘₘ = P⁻ₘₘ r / (P⁻ₘₘ + r)`.
#[test]
fn an_augmented_ukf_of_362_states_steps_on_a_2_mib_thread() {
    on_a_2_mib_thread(|| {
        let (alpha, q, r, p0, y) = WALK;
        let m = NU_STATES / 2;
        let x0 = SVector::<f64, NU_STATES>::from_fn(|i, _| 0.001 * i as f64);
        let points = SigmaPoints::new(1.0, 2.0, 0.0).expect("weights");
        let mut ukf = AugmentedUkf::<NU_STATES, 1, 1, 1, 1, 364, 729>::from_refs(
            points,
            &Vector1::new(q),
            &Vector1::new(r),
            &x0,
            &boxed_identity(p0),
        )
        .expect("a filter");
        let u = Vector1::new(0.0);
        let propagate = |x: &SVector<f64, NU_STATES>, _u: &Vector1<f64>, v: &Vector1<f64>| {
            let mut next = x * alpha;
            next[0] += v[0];
            next
        };
        ukf.predict(&u, propagate).expect("a prediction");
        let measure = |x: &SVector<f64, NU_STATES>, _u: &Vector1<f64>, n: &Vector1<f64>| {
            Vector1::new(x[m] + n[0])
        };
        let outcome = ukf
            .update(&Vector1::new(y), &u, measure)
            .expect("an update");
        assert!(matches!(outcome, UpdateOutcome::Accepted { .. }));
        let predicted = |i: usize| alpha * alpha * p0 + if i == 0 { q } else { 0.0 };
        let s = predicted(m) + r;
        let (p, x) = (ukf.covariance(), ukf.state());
        for i in 0..NU_STATES {
            let expected = if i == m {
                predicted(m) * r / s
            } else {
                predicted(i)
            };
            assert!(
                (p[(i, i)] - expected).abs() < 1e-12,
                "P[{i}, {i}] = {}",
                p[(i, i)]
            );
            let prior = alpha * x0[i];
            let corrected = if i == m {
                prior + predicted(m) / s * (y - prior)
            } else {
                prior
            };
            assert!((x[i] - corrected).abs() < 1e-12, "x[{i}] = {}", x[i]);
        }
    });
}
