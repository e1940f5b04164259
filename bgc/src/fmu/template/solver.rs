//! The Co-Simulation integrator: extrapolated linearly implicit Euler (the stiff extrapolation method of
//! Deuflhard, as in Hairer & Wanner's SEULEX), with the generated Jacobian.
//!
//! One step of size `h` takes `n = 1, 2, ..., K` substeps of the linearly implicit Euler method
//! `(I − (h/n)·J)·Δ = (h/n)·f(t, y)`, `y ← y + Δ`, with `J = ∂f/∂x` at the start of the step, and extrapolates the
//! results to `h/n → 0` (Aitken–Neville in `h`). Every entry of the table has the stability function 0 at
//! infinity (products of `1/(1 − z/n)`), so the method damps the stiff modes of the plants (thousands of rad/s)
//! instead of resolving them, which an explicit method would have to. The difference of the two last entries of
//! the table's diagonal estimates the local error; the step size follows it.

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
}

impl Integrator {
    pub fn new(rtol: f64) -> Integrator {
        Integrator {
            h: 0.0,
            rtol,
            atol: rtol * 1e-3,
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
                Some((x_new, err)) if err <= 1.0 => {
                    x.copy_from_slice(&x_new);
                    t = if last { t1 } else { t + h };
                    let grow = (0.9 * err.max(1e-10).powf(-1.0 / K as f64)).clamp(0.2, 4.0);
                    // The shortened last step says nothing about the step the dynamics allow.
                    if !last || grow < 1.0 {
                        self.h = h * grow;
                    }
                }
                Some((_, err)) => {
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

    /// One extrapolated step: the new state and its error norm, or `None` when a matrix is singular or a value
    /// is not finite.
    fn try_step(
        &self,
        p: &Params,
        t: f64,
        h: f64,
        x: &[f64],
        u: &[f64],
    ) -> Option<(Vec<f64>, f64)> {
        let jac = plant::jac_x(p, t, x, u);
        let mut f0 = vec![0.0; NX];
        plant::rhs(p, t, x, u, &mut f0);
        let mut table: Vec<Vec<f64>> = Vec::with_capacity(K);
        let mut f = vec![0.0; NX];
        for j in 0..K {
            let n = j + 1;
            let hs = h / n as f64;
            // A matrix of dynamic size: nalgebra decomposes fixed sizes only up to 127.
            let lu = nalgebra::DMatrix::from_fn(NX, NX, |r, c| {
                f64::from(u8::from(r == c)) - jac[(r, c)] * hs
            })
            .lu();
            let mut y = x.to_vec();
            for i in 0..n {
                if i == 0 {
                    f.copy_from_slice(&f0);
                } else {
                    plant::rhs(p, t + i as f64 * hs, &y, u, &mut f);
                }
                let rhs = nalgebra::DVector::from_iterator(NX, f.iter().map(|v| v * hs));
                let delta = lu.solve(&rhs)?;
                for (yk, d) in y.iter_mut().zip(delta.iter()) {
                    *yk += d;
                }
            }
            // Aitken–Neville: row j of the table from row j − 1, in place.
            let mut row = y;
            for k in 1..=j {
                let ratio = n as f64 / (n - k) as f64 - 1.0;
                let next: Vec<f64> = (0..NX)
                    .map(|i| {
                        let a = row[(k - 1) * NX + i];
                        a + (a - table[j - 1][(k - 1) * NX + i]) / ratio
                    })
                    .collect();
                row.extend(next);
            }
            table.push(row);
        }
        let last = &table[K - 1];
        let best = &last[(K - 1) * NX..K * NX];
        let second = &last[(K - 2) * NX..(K - 1) * NX];
        let mut sum = 0.0;
        for i in 0..NX {
            let scale = self.atol + self.rtol * x[i].abs().max(best[i].abs());
            let e = (best[i] - second[i]) / scale;
            sum += e * e;
        }
        let err = (sum / NX.max(1) as f64).sqrt();
        (err.is_finite() && best.iter().all(|v| v.is_finite())).then(|| (best.to_vec(), err))
    }
}
