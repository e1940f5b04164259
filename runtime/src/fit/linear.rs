//! The outputs and their sensitivities for a linear time-invariant model with held inputs, exactly and without an
//! ODE solver.
//!
//! For `ẋ = A x + B u + c` (the model declares itself linear: [`FitModel::is_linear`]) the forward sensitivities
//! `S_k = ∂x/∂θ_k` obey `Ṡ_k = A S_k + A_k x + B_k u + c_k` with `A_k = ∂A/∂θ_k` (and likewise `B_k`, `c_k`): the
//! states and the sensitivities together are again linear, with the block lower-triangular matrix
//! `[[A, 0], [A_k, A]]`. With the input held between samples (zero-order hold) the augmented system is
//! discretised exactly by one matrix exponential per sample interval, `[Φ Γ; 0 I] = exp([A_aug B_aug; 0 0] Δt)`,
//! and stepped by `X[k+1] = Φ X[k] + Γ [u_k; 1]`: exact sensitivities at a cost of milliseconds, where an ODE
//! solver would have to resolve every lightly damped mode at its tolerance. The outputs and their sensitivities
//! at the samples are then taken as on the ODE path.
//!
//! `A`, `B`, `c` and their parameter derivatives are read from the model's rates and Jacobians at unit states and
//! inputs (exact for an affine model); a probe at another point and time checks the declaration, and a model that
//! is not affine there is refused instead of being simulated wrongly.

use nalgebra::{DMatrix, DVector};

use super::record::Record;
use super::sensitivity::{FitModel, Fitted, SensitivityError, Simulated, sample_outputs};
use crate::fit::Interp;
use crate::linalg::{DiscretizeError, zoh_blocks};

/// The augmented continuous system `Ẋ = A_aug X + B_aug [u; 1]` of the states and the scaled sensitivities.
struct Augmented {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
}

/// Relative agreement the probe of the linearity declaration demands (well above the rounding of a finite
/// difference of a parameter Jacobian, far below any real nonlinearity).
const LINEARITY_TOLERANCE: f64 = 1e-6;

/// The same for the rates themselves (no differences involved: rounding only).
const RATE_TOLERANCE: f64 = 1e-10;

/// Intervals whose lengths differ by less than this fraction share one discretisation: a logger's times
/// `k·Δt` differ in their last bits, and a state advanced for `Δt (1 ± 10⁻¹²)` differs from the exact one far
/// below any solver's tolerance.
const SAME_INTERVAL: f64 = 1e-12;

/// States and sensitivities at the record's samples by exact zero-order-hold discretisation, then the outputs
/// and `∂y/∂θ` as [`super::sensitivity::simulate`] gives them.
pub fn simulate(
    model: &dyn FitModel,
    record: &Record,
    x0: &[f64],
    fitted: &Fitted<'_>,
) -> Result<Simulated, SensitivityError> {
    let sys = augmented(model, record, fitted)?;
    let nx = model.state_count();
    let m = fitted.params.len() + fitted.x0.len();
    let mut y = DVector::zeros(nx * (1 + m));
    y.rows_mut(0, nx).copy_from_slice(x0);
    for (k, &i) in fitted.x0.iter().enumerate() {
        let j = fitted.params.len() + k;
        y[nx * (1 + j) + i] = fitted.scale[j];
    }
    let mut states = Vec::with_capacity(record.times.len());
    states.push(y.as_slice().to_vec());
    let mut cache: Vec<(f64, DMatrix<f64>, DMatrix<f64>)> = Vec::new();
    let mut input = DVector::zeros(model.input_count() + 1);
    for k in 0..record.times.len() - 1 {
        let dt = record.times[k + 1] - record.times[k];
        let at = match cache
            .iter()
            .position(|(d, _, _)| (d - dt).abs() <= SAME_INTERVAL * dt)
        {
            Some(i) => i,
            None => {
                let (phi, gamma) =
                    discretise(&sys, dt).map_err(|message| SensitivityError::Model {
                        time: record.times[k],
                        message,
                    })?;
                cache.push((dt, phi, gamma));
                cache.len() - 1
            }
        };
        let (_, phi, gamma) = &cache[at];
        input
            .rows_mut(0, model.input_count())
            .copy_from_slice(&record.inputs[k]);
        input[model.input_count()] = 1.0;
        y = phi * &y + gamma * &input;
        if y.iter().any(|v| !v.is_finite()) {
            return Err(SensitivityError::NonFinite {
                time: record.times[k + 1],
            });
        }
        states.push(y.as_slice().to_vec());
    }
    sample_outputs(model, record, Interp::Zoh, fitted, &states)
}

/// `(Φ, Γ)` of the augmented system over `dt`.
fn discretise(sys: &Augmented, dt: f64) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
    zoh_blocks(&sys.a, &sys.b, dt).map_err(|e| match e {
        DiscretizeError::Overflow { .. } => format!(
            "the sample interval of {dt:?} s is too long for the exact discretisation: A dt or B dt overflows"
        ),
        other => format!("the exact discretisation over the sample interval of {dt:?} s failed: {other}"),
    })
}

/// The rate `f`, `∂f/∂x` and the free columns of `∂f/∂p` at a point.
type RatesAt = (DVector<f64>, DMatrix<f64>, DMatrix<f64>);

/// The rate `f`, `∂f/∂x` and the free columns of `∂f/∂p` at `(t, x, u)`.
fn rates_at(
    model: &dyn FitModel,
    t: f64,
    x: &[f64],
    u: &[f64],
    free: &[usize],
) -> Result<RatesAt, SensitivityError> {
    let fail = |message| SensitivityError::Model { time: t, message };
    let mut f = vec![0.0; model.state_count()];
    model.rhs(t, x, u, &mut f).map_err(fail)?;
    let (fx, fp) = model.rate_jacobians(t, x, u, free).map_err(fail)?;
    Ok((DVector::from_vec(f), fx, fp))
}

fn unit(n: usize, i: usize) -> Vec<f64> {
    let mut v = vec![0.0; n];
    v[i] = 1.0;
    v
}

/// Reads `A`, `B`, `c` and their parameter derivatives from the model, checks them at a probe point, and builds
/// the augmented system.
fn augmented(
    model: &dyn FitModel,
    record: &Record,
    fitted: &Fitted<'_>,
) -> Result<Augmented, SensitivityError> {
    let (nx, nu) = (model.state_count(), model.input_count());
    let np = fitted.params.len();
    let m = np + fitted.x0.len();
    let t0 = record.times[0];
    let (zx, zu) = (vec![0.0; nx], vec![0.0; nu]);
    let (c, a, cp) = rates_at(model, t0, &zx, &zu, fitted.params)?;
    let mut b = DMatrix::zeros(nx, nu);
    let mut ap = vec![DMatrix::zeros(nx, nx); np];
    let mut bp = vec![DMatrix::zeros(nx, nu); np];
    for j in 0..nu {
        let (f, _, fp) = rates_at(model, t0, &zx, &unit(nu, j), fitted.params)?;
        b.set_column(j, &(f - &c));
        for (k, bk) in bp.iter_mut().enumerate() {
            bk.set_column(j, &(fp.column(k) - cp.column(k)));
        }
    }
    for i in 0..nx {
        let (_, _, fp) = rates_at(model, t0, &unit(nx, i), &zu, fitted.params)?;
        for (k, ak) in ap.iter_mut().enumerate() {
            ak.set_column(i, &(fp.column(k) - cp.column(k)));
        }
    }
    probe(model, record, fitted, (&a, &b, &c), (&ap, &bp, &cp))?;
    let n = nx * (1 + m);
    let mut big_a = DMatrix::zeros(n, n);
    let mut big_b = DMatrix::zeros(n, nu + 1);
    for blk in 0..=m {
        big_a.view_mut((blk * nx, blk * nx), (nx, nx)).copy_from(&a);
    }
    big_b.view_mut((0, 0), (nx, nu)).copy_from(&b);
    big_b.view_mut((0, nu), (nx, 1)).copy_from(&c);
    for k in 0..np {
        let s = fitted.scale[k];
        let row = nx * (1 + k);
        big_a.view_mut((row, 0), (nx, nx)).copy_from(&(&ap[k] * s));
        big_b.view_mut((row, 0), (nx, nu)).copy_from(&(&bp[k] * s));
        big_b
            .view_mut((row, nu), (nx, 1))
            .copy_from(&(cp.column(k) * s));
    }
    Ok(Augmented { a: big_a, b: big_b })
}

type Affine<'a> = (&'a DMatrix<f64>, &'a DMatrix<f64>, &'a DVector<f64>);
type AffineDerivatives<'a> = (&'a [DMatrix<f64>], &'a [DMatrix<f64>], &'a DMatrix<f64>);

/// Checks the model against the affine form read at the record's start: at another state, input and the
/// record's last time, the rates, `∂f/∂x` and `∂f/∂p` must be those of the affine form.
fn probe(
    model: &dyn FitModel,
    record: &Record,
    fitted: &Fitted<'_>,
    (a, b, c): Affine<'_>,
    (ap, bp, cp): AffineDerivatives<'_>,
) -> Result<(), SensitivityError> {
    let (nx, nu) = (model.state_count(), model.input_count());
    let t1 = *record.times.last().unwrap_or(&record.times[0]);
    // An irregular point: no symmetry of the model can hide a nonlinearity there.
    let x: Vec<f64> = (0..nx).map(|i| 0.37 + 0.61 * (i as f64).sin()).collect();
    let u: Vec<f64> = (0..nu).map(|j| -0.29 + 0.83 * (j as f64).cos()).collect();
    let (f, fx, fp) = rates_at(model, t1, &x, &u, fitted.params)?;
    let (xv, uv) = (
        DVector::from_column_slice(&x),
        DVector::from_column_slice(&u),
    );
    let predicted = a * &xv + b * &uv + c;
    // The rates are compared strictly, the (possibly differenced) Jacobians at the tolerance of a difference.
    let mut worst = relative_gap(&f, &predicted) * (LINEARITY_TOLERANCE / RATE_TOLERANCE);
    worst = worst.max(relative_gap(&fx, a));
    for k in 0..ap.len() {
        let want = &ap[k] * &xv + &bp[k] * &uv + cp.column(k);
        worst = worst.max(relative_gap(&fp.column(k).clone_owned(), &want));
    }
    if worst > LINEARITY_TOLERANCE {
        return Err(SensitivityError::Model {
            time: t1,
            message: format!(
                "the model is declared linear, but its rates or Jacobians at another state, input and time \
                 differ from the affine form read at the start by {worst:.1e} (relative); fit it without the \
                 declaration"
            ),
        });
    }
    Ok(())
}

/// `‖x − y‖∞ / max(‖y‖∞, ‖x‖∞, tiny)`.
fn relative_gap<R: nalgebra::Dim, C: nalgebra::Dim>(
    x: &nalgebra::OMatrix<f64, R, C>,
    y: &nalgebra::OMatrix<f64, R, C>,
) -> f64
where
    nalgebra::DefaultAllocator: nalgebra::allocator::Allocator<R, C>,
{
    let size = x.amax().max(y.amax()).max(f64::MIN_POSITIVE);
    (x - y).amax() / size
}
