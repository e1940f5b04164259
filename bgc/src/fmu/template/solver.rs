//! The Co-Simulation integrator: extrapolated linearly implicit Euler (the stiff extrapolation method of
//! Deuflhard, as in Hairer & Wanner's SEULEX), with the generated Jacobian.
//!
//! One step of size `h` takes `n = 1, 2, ..., K` substeps of the linearly implicit Euler method
//! `(I − (h/n)·J)·Δ = (h/n)·f(t, y)`, `y ← y + Δ`, with `J = ∂f/∂x` at the start of the step, and extrapolates the
//! results to `h/n → 0` (Aitken–Neville in `h`). Every entry of the table has the stability function 0 at
//! infinity (products of `1/(1 − z/n)`), so the method damps the stiff modes of the plants (thousands of rad/s)
//! instead of resolving them, which an explicit method would have to. The difference of the two last entries of
//! the table's diagonal estimates the local error; the step size follows it.

use crate::model as m;
use crate::plant::{self, NX, Params};

/// Substep counts 1..=K: order K.
const K: usize = 4;
/// The smallest step, relative to the time scale of the run, before the integrator gives up.
const MIN_STEP: f64 = 1e-14;

/// Why an integration failed.
#[derive(Debug)]
pub struct Failure(pub String);

pub struct Integrator {
    /// The step size to try next (kept from step to step).
    pub h: f64,
    pub rtol: f64,
    pub atol: f64,
    /// Work space kept between steps, so that a step allocates nothing.
    work: Work,
}

/// The buffers of one extrapolated step.
struct Work {
    /// `∂f/∂x` at the start of the step (on the heap: a large model's does not fit a thread's stack).
    jac: Box<m::JacX>,
    /// `I − (h/n)·J`, row-major, decomposed in place.
    matrix: Vec<f64>,
    /// The row interchanges of the decomposition.
    pivots: Vec<usize>,
    f0: Vec<f64>,
    f: Vec<f64>,
    y: Vec<f64>,
    /// The extrapolation table: row `j` holds `j + 1` states.
    table: Vec<Vec<f64>>,
}

impl Work {
    fn new() -> Work {
        Work {
            jac: plant::zeroed_matrix(),
            matrix: vec![0.0; NX * NX],
            pivots: vec![0; NX],
            f0: vec![0.0; NX],
            f: vec![0.0; NX],
            y: vec![0.0; NX],
            table: (0..K).map(|j| vec![0.0; (j + 1) * NX]).collect(),
        }
    }

    /// The last step's most extrapolated state: the end of the table's last row.
    fn best(&self) -> &[f64] {
        &self.table[K - 1][(K - 1) * NX..K * NX]
    }
}

impl Integrator {
    pub fn new(rtol: f64) -> Integrator {
        Integrator {
            h: 0.0,
            rtol,
            atol: rtol * 1e-3,
            work: Work::new(),
        }
    }

    /// Integrates `x` from `t0` to `t1` with the inputs `u` held.
    pub fn advance(
        &mut self,
        p: &Params,
        t0: f64,
        t1: f64,
        x: &mut [f64],
        u: &[f64],
    ) -> Result<(), Failure> {
        let span = t1 - t0;
        // A model without states (outputs that are functions of the inputs) has nothing to integrate; its 0×0
        // Jacobian has no LU decomposition to take.
        if span <= 0.0 || NX == 0 {
            return Ok(());
        }
        let mut t = t0;
        if self.h <= 0.0 || !self.h.is_finite() {
            self.h = span.min(1e-4);
        }
        let min = MIN_STEP * t1.abs().max(span).max(1.0);
        while t < t1 {
            let last = t1 - t <= self.h * 1.000_001;
            let h = if last { t1 - t } else { self.h };
            match self.try_step(p, t, h, x, u) {
                Some(err) if err <= 1.0 => {
                    x.copy_from_slice(self.work.best());
                    t = if last { t1 } else { t + h };
                    let grow = (0.9 * err.max(1e-10).powf(-1.0 / K as f64)).clamp(0.2, 4.0);
                    // The shortened last step says nothing about the step the dynamics allow.
                    if !last || grow < 1.0 {
                        self.h = h * grow;
                    }
                }
                Some(err) => {
                    self.h = h * (0.9 * err.powf(-1.0 / K as f64)).clamp(0.1, 0.9);
                }
                None => self.h = h * 0.25,
            }
            if self.h < min {
                return Err(Failure(format!(
                    "the step size fell below {min:e} s at t = {t} (the states are not finite or the \
                     Jacobian is singular there)"
                )));
            }
        }
        Ok(())
    }

    /// One extrapolated step: leaves the new state at the end of the table (`Work::best`) and returns its error
    /// norm, or `None` when a matrix is singular or a value is not finite.
    fn try_step(&mut self, p: &Params, t: f64, h: f64, x: &[f64], u: &[f64]) -> Option<f64> {
        let w = &mut self.work;
        plant::jac_x_into(p, t, x, u, &mut w.jac);
        plant::rhs(p, t, x, u, &mut w.f0);
        for j in 0..K {
            let n = j + 1;
            let hs = h / n as f64;
            for r in 0..NX {
                for c in 0..NX {
                    w.matrix[r * NX + c] = f64::from(u8::from(r == c)) - w.jac[(r, c)] * hs;
                }
            }
            decompose(&mut w.matrix, &mut w.pivots)?;
            w.y.copy_from_slice(x);
            for i in 0..n {
                if i == 0 {
                    w.f.copy_from_slice(&w.f0);
                } else {
                    plant::rhs(p, t + i as f64 * hs, &w.y, u, &mut w.f);
                }
                w.f.iter_mut().for_each(|v| *v *= hs);
                solve(&w.matrix, &w.pivots, &mut w.f);
                for (yk, d) in w.y.iter_mut().zip(&w.f) {
                    *yk += d;
                }
            }
            // Aitken–Neville: row j of the table from row j − 1.
            let (done, rest) = w.table.split_at_mut(j);
            let row = &mut rest[0];
            row[..NX].copy_from_slice(&w.y);
            for k in 1..=j {
                let ratio = n as f64 / (n - k) as f64 - 1.0;
                let previous = &done[j - 1][(k - 1) * NX..k * NX];
                for i in 0..NX {
                    let a = row[(k - 1) * NX + i];
                    row[k * NX + i] = a + (a - previous[i]) / ratio;
                }
            }
        }
        let last = &w.table[K - 1];
        let best = &last[(K - 1) * NX..K * NX];
        let second = &last[(K - 2) * NX..(K - 1) * NX];
        let mut sum = 0.0;
        for i in 0..NX {
            let scale = self.atol + self.rtol * x[i].abs().max(best[i].abs());
            let e = (best[i] - second[i]) / scale;
            sum += e * e;
        }
        let err = (sum / NX.max(1) as f64).sqrt();
        (err.is_finite() && best.iter().all(|v| v.is_finite())).then_some(err)
    }
}

/// LU decomposition with partial pivoting of the row-major `NX x NX` matrix `a`, in place (`L` below the diagonal
/// with a unit diagonal, `U` on and above). `None` when a pivot is zero or not finite.
fn decompose(a: &mut [f64], pivots: &mut [usize]) -> Option<()> {
    for k in 0..NX {
        let (mut best, mut size) = (k, a[k * NX + k].abs());
        for r in k + 1..NX {
            if a[r * NX + k].abs() > size {
                (best, size) = (r, a[r * NX + k].abs());
            }
        }
        if size == 0.0 || !size.is_finite() {
            return None;
        }
        pivots[k] = best;
        if best != k {
            for c in 0..NX {
                a.swap(k * NX + c, best * NX + c);
            }
        }
        let pivot = a[k * NX + k];
        for r in k + 1..NX {
            let factor = a[r * NX + k] / pivot;
            a[r * NX + k] = factor;
            if factor != 0.0 {
                for c in k + 1..NX {
                    a[r * NX + c] -= factor * a[k * NX + c];
                }
            }
        }
    }
    Some(())
}

/// Solves `A z = b` in place in `b`, with `A` decomposed by `decompose`.
fn solve(a: &[f64], pivots: &[usize], b: &mut [f64]) {
    for k in 0..NX {
        b.swap(k, pivots[k]);
    }
    for r in 1..NX {
        let sum: f64 = (0..r).map(|c| a[r * NX + c] * b[c]).sum();
        b[r] -= sum;
    }
    for r in (0..NX).rev() {
        let sum: f64 = (r + 1..NX).map(|c| a[r * NX + c] * b[c]).sum();
        b[r] = (b[r] - sum) / a[r * NX + r];
    }
}
