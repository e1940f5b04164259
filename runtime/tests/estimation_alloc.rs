//! The step functions of the Kalman filter, the UKFs and the dual UKF allocate nothing: a counting global
//! allocator records every allocation made on this test's thread while the steps run.

use bgc_runtime::estimation::angle::AngleKalmanFilter;
use bgc_runtime::estimation::dual_ukf::DualUkf;
use bgc_runtime::estimation::fusion::WeightedFusion;
use bgc_runtime::estimation::health::FilterHealth;
use bgc_runtime::estimation::srukf::SquareRootUkf;
use bgc_runtime::estimation::ukf_augmented::AugmentedUkf;
use bgc_runtime::estimation::{
    FaultPolicy, KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter,
};
use nalgebra::{SMatrix, SVector};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct CountingAllocator;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // `try_with` so that allocations during thread teardown are not counted (and cannot fail).
        let _ = COUNTING.try_with(|on| {
            if on.get() {
                let _ = COUNT.try_with(|c| c.set(c.get() + 1));
            }
        });
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = COUNTING.try_with(|on| {
            if on.get() {
                let _ = COUNT.try_with(|c| c.set(c.get() + 1));
            }
        });
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Runs `f` and returns how many allocations it made on this thread.
fn allocations_in(f: impl FnOnce()) -> usize {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|on| on.set(true));
    f();
    COUNTING.with(|on| on.set(false));
    COUNT.with(|c| c.get())
}

fn pendulum6(x: &SVector<f64, 6>, u: &SVector<f64, 3>, w: &SVector<f64, 3>) -> SVector<f64, 6> {
    let dt = 0.01;
    let mut next = *x;
    for j in 0..3 {
        let acc = (u[j] - w[j] * 9.81 * x[j].sin() - 0.1 * x[3 + j]) / w[j].max(1e-3);
        next[3 + j] = x[3 + j] + dt * acc;
        next[j] = x[j] + dt * next[3 + j];
    }
    next
}

#[test]
fn filter_steps_do_not_allocate() {
    // The counter itself must work: a Vec allocates.
    assert!(allocations_in(|| drop(std::hint::black_box(vec![1u8; 16]))) >= 1);

    // Kalman filter, 7 states, 2 measurements, with a NIS gate, plus a rejected NaN measurement.
    let mut a = SMatrix::<f64, 7, 7>::identity();
    for i in 0..6 {
        a[(i, i + 1)] = 0.01;
    }
    let model = LinearDiscreteModel {
        a,
        b: SMatrix::<f64, 7, 1>::repeat(0.01),
        c: SMatrix::<f64, 2, 7>::from_fn(|i, j| if j == 3 * i { 1.0 } else { 0.0 }),
        d: SMatrix::<f64, 2, 1>::zeros(),
    };
    let mut kf = KalmanFilter::new(
        model,
        SMatrix::<f64, 7, 7>::identity() * 1e-4,
        SMatrix::<f64, 2, 2>::identity() * 1e-2,
        SVector::<f64, 7>::zeros(),
        SMatrix::<f64, 7, 7>::identity(),
    )
    .unwrap();
    kf.set_fault_policy(FaultPolicy {
        nis_gate: Some(20.0),
        ..FaultPolicy::default()
    })
    .unwrap();
    let mut health = FilterHealth::<7, 2, 5>::new();
    let n = allocations_in(|| {
        for k in 0..50 {
            let u = SVector::<f64, 1>::new((k as f64).sin());
            kf.predict(&u).unwrap();
            let y = if k == 10 {
                SVector::<f64, 2>::new(f64::NAN, 0.0)
            } else if k == 20 {
                SVector::<f64, 2>::new(1e6, 0.0) // gated out
            } else {
                SVector::<f64, 2>::new(0.01 * k as f64, 0.0)
            };
            kf.update(&y, &u).unwrap();
            health
                .record_innovation(kf.innovation(), kf.innovation_covariance())
                .unwrap();
            health
                .record_state_error(&SVector::<f64, 7>::zeros(), kf.covariance())
                .unwrap();
        }
        std::hint::black_box(health.report());
    });
    assert_eq!(n, 0, "Kalman filter and health monitor allocated");

    // UKF and square-root UKF, 6 states, 3 measurements.
    let w = SVector::<f64, 3>::new(1.0, 2.0, 3.0);
    let pts6 = SigmaPoints::<6, 13>::new(0.5, 2.0, 0.0).unwrap();
    let q6 = SMatrix::<f64, 6, 6>::identity() * 1e-5;
    let r3 = SMatrix::<f64, 3, 3>::identity() * 1e-3;
    let x0 = SVector::<f64, 6>::repeat(0.1);
    let p0 = SMatrix::<f64, 6, 6>::identity() * 0.1;
    let mut ukf = UnscentedKalmanFilter::<6, 3, 3, 13>::new(pts6, q6, r3, x0, p0).unwrap();
    let mut sr = SquareRootUkf::<6, 3, 3, 13>::new(pts6, q6, r3, x0, p0).unwrap();
    let h = |x: &SVector<f64, 6>, _u: &SVector<f64, 3>| x.fixed_rows::<3>(0).into_owned();
    let n = allocations_in(|| {
        for k in 0..50 {
            let u = SVector::<f64, 3>::repeat((k as f64 * 0.1).sin());
            let y = SVector::<f64, 3>::repeat(0.1);
            ukf.predict(&u, |x, u| pendulum6(x, u, &w)).unwrap();
            ukf.update(&y, &u, h).unwrap();
            sr.predict(&u, |x, u| pendulum6(x, u, &w)).unwrap();
            sr.update(&y, &u, h).unwrap();
        }
    });
    assert_eq!(n, 0, "UKF or square-root UKF allocated");

    // Augmented UKF: 2 states, 1 process-noise and 1 measurement-noise entry.
    let mut aug = AugmentedUkf::<2, 1, 1, 1, 1, 4, 9>::new(
        SigmaPoints::new(0.7, 2.0, 0.0).unwrap(),
        SMatrix::<f64, 1, 1>::new(0.01),
        SMatrix::<f64, 1, 1>::new(0.01),
        SVector::<f64, 2>::new(0.1, 0.0),
        SMatrix::<f64, 2, 2>::identity(),
    )
    .unwrap();
    let n = allocations_in(|| {
        for _ in 0..50 {
            let u = SVector::<f64, 1>::new(0.3);
            aug.predict(&u, |x, u, v| {
                SVector::<f64, 2>::new(x[0] + 0.1 * x[1], x[1] + 0.1 * (u[0] + v[0]))
            })
            .unwrap();
            aug.update(&SVector::<f64, 1>::new(0.2), &u, |x, _u, n| {
                SVector::<f64, 1>::new(x[0] + n[0])
            })
            .unwrap();
        }
    });
    assert_eq!(n, 0, "augmented UKF allocated");

    // Dual UKF: 6 states, 3 parameters.
    let state = UnscentedKalmanFilter::<6, 3, 3, 13>::new(pts6, q6, r3, x0, p0).unwrap();
    let mut dual = DualUkf::new(
        state,
        SigmaPoints::<3, 7>::new(0.5, 2.0, 0.0).unwrap(),
        SVector::<f64, 3>::new(1.2, 1.8, 3.3),
        SMatrix::<f64, 3, 3>::identity() * 0.01,
        0.995,
    )
    .unwrap();
    let n = allocations_in(|| {
        for k in 0..50 {
            let u = SVector::<f64, 3>::repeat((k as f64 * 0.1).sin());
            let y = SVector::<f64, 3>::repeat(0.1);
            dual.step_with(&u, &y, pendulum6, |x, _u, _w| {
                x.fixed_rows::<3>(0).into_owned()
            })
            .unwrap();
        }
    });
    assert_eq!(n, 0, "dual UKF allocated");

    // Angle filter and fusion.
    let mut angle = AngleKalmanFilter::new(
        0.01,
        1e-6,
        1e-8,
        1e-3,
        0.0,
        0.0,
        SMatrix::<f64, 2, 2>::identity(),
    )
    .unwrap();
    let fusion = WeightedFusion::new(SVector::<f64, 2>::new(0.01, 0.04)).unwrap();
    let n = allocations_in(|| {
        for k in 0..50 {
            angle.step(0.1, 0.001 * k as f64).unwrap();
            std::hint::black_box(
                fusion
                    .fuse(&SVector::<f64, 2>::new(angle.angle(), 0.0))
                    .unwrap(),
            );
        }
    });
    assert_eq!(n, 0, "angle filter or fusion allocated");

    // The covariance repair path (eigen-decomposition) of the fault tests: f(x) = x² with β = −1.
    let mut bad = UnscentedKalmanFilter::<1, 0, 1, 3>::new(
        SigmaPoints::new(1.0, -1.0, 0.0).unwrap(),
        SMatrix::<f64, 1, 1>::new(0.5),
        SMatrix::<f64, 1, 1>::new(0.1),
        SVector::<f64, 1>::zeros(),
        SMatrix::<f64, 1, 1>::identity(),
    )
    .unwrap();
    let u0 = SVector::<f64, 0>::zeros();
    let mut repaired = None;
    let n = allocations_in(|| {
        repaired = bad
            .predict(&u0, |x, _| SVector::<f64, 1>::new(x[0] * x[0]))
            .unwrap();
    });
    assert!(repaired.is_some());
    assert_eq!(n, 0, "covariance repair allocated");
}
