//! The generated rhs, outputs and Jacobians allocate nothing: a counting global allocator sees no allocation while
//! they run (for the models and every corpus model).
//!
//! The count is per thread: the other tests of this binary run on other threads at the same time, and their
//! allocations must not be counted here.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// Allocations made so far on this thread.
fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Counts one allocation on this thread; `try_with` so that allocations during thread teardown cannot fail.
fn count_one() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

macro_rules! exercise {
    ($($module:path),* $(,)?) => {{
        let mut calls = 0usize;
        $(
            {
                use $module as m;
                let p = m::Params::default();
                let x = m::State::from_fn(|i, _| 0.1 * (i as f64 + 1.0));
                let u = m::Inputs::from_fn(|i, _| 0.2 * (i as f64 + 1.0));
                let mut dx = m::State::zeros();
                let mut y = m::Outputs::zeros();
                let mut jx = m::JacX::zeros();
                let mut ju = m::JacU::zeros();
                let mut cx = m::OutJacX::zeros();
                let mut du = m::OutJacU::zeros();
                let before = allocations();
                m::rhs_into(&p, 0.3, &x, &u, &mut dx);
                let dx2 = m::rhs(&p, 0.3, &x, &u);
                m::outputs_into(&p, 0.3, &x, &u, &mut y);
                m::jac_x_into(&p, 0.3, &x, &u, &mut jx);
                m::jac_u_into(&p, 0.3, &x, &u, &mut ju);
                m::output_jac_x_into(&p, 0.3, &x, &u, &mut cx);
                m::output_jac_u_into(&p, 0.3, &x, &u, &mut du);
                let after = allocations();
                assert_eq!(after - before, 0, "{} allocated", stringify!($module));
                // The results are used (and finite at this point), so nothing above was optimised away.
                assert!(dx.iter().chain(dx2.iter()).chain(jx.iter()).all(|v| v.is_finite()));
                assert!(y.iter().chain(ju.iter()).chain(cx.iter()).chain(du.iter()).all(|v| v.is_finite()));
                calls += 1;
            }
        )*
        calls
    }};
}

#[test]
fn generated_functions_do_not_allocate() {
    // Prove the counter works.
    let before = allocations();
    let v = vec![1.0_f64; 16];
    assert!(allocations() > before);
    drop(v);
    let n = exercise!(
        bgc_models::back_support,
        bgc_models::pendulum_rig,
        bgc_models::rehab_leg,
        bgc_models::walking_leg,
        bgc_models::corpus::dc_motor_load,
        bgc_models::corpus::diode_rc,
        bgc_models::corpus::gear_train,
        bgc_models::corpus::hydraulic_cylinder,
        bgc_models::corpus::msd_chain,
        bgc_models::corpus::oscillator,
        bgc_models::corpus::parallel_rlc,
        bgc_models::corpus::pendulum,
        bgc_models::corpus::quarter_car,
        bgc_models::corpus::resistive_network,
        bgc_models::corpus::series_rlc,
        bgc_models::corpus::two_tank,
    );
    assert_eq!(n, 16);
}
