//! The generated parameter Jacobians (`jac_p_into`, `output_jac_p_into` and `Model`'s `ParamJacobians`) against
//! central differences of the generated `rhs` and `outputs`, against the compiler's own symbolic evaluation
//! (`Equations::param_jacobian_at`, which solves loops and mass matrices on its own path), and against a hand
//! derivation; and `Generated::exact`, the fit's adapter that uses them.

use crate::support::{Rng, equations_of, perturbed};

use bgc_models::corpus;
use bgc_runtime::fit::generated::ParamJacobians;
use bgc_runtime::fit::{FitModel, Generated};
use bgc_runtime::model::{ContinuousModel, Parametric};
use nalgebra::SVector;

/// `(∂f/∂p_k, ∂h/∂p_k)` by central differences of the generated functions, the parameter set through
/// `set_param`: Richardson's extrapolation `(4 D(h/2) − D(h))/3` of the quotients at `h = 1e-3 |p_k|` and `h/2`
/// (truncation of order `h⁴`); also the bound of its rounding error, `100 ε max(|f|, |h|)/h`.
fn differences<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    (t, x, u): (f64, &SVector<f64, NX>, &SVector<f64, NU>),
    k: usize,
) -> (Vec<f64>, f64)
where
    M: ContinuousModel<NX, NU, NY> + Parametric + Clone,
{
    let v = model.param(k).expect("parameter");
    let at = |value: f64| {
        let mut m = model.clone();
        m.set_param(k, value)
            .unwrap_or_else(|e| panic!("{}: {e}", model.param_names()[k]));
        let (mut f, mut y) = (SVector::<f64, NX>::zeros(), SVector::<f64, NY>::zeros());
        m.rhs(t, x, u, &mut f);
        m.outputs(t, x, u, &mut y);
        f.iter().chain(y.iter()).copied().collect::<Vec<f64>>()
    };
    let quotient = |h: f64| -> Vec<f64> {
        let (plus, minus) = (at(v + h), at(v - h));
        plus.iter()
            .zip(&minus)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect()
    };
    let h = 1e-3 * if v == 0.0 { 1.0 } else { v.abs() };
    let (coarse, fine) = (quotient(h), quotient(h / 2.0));
    let largest = at(v).iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let rounding = 100.0 * f64::EPSILON * largest / (h / 2.0);
    let d = coarse
        .iter()
        .zip(&fine)
        .map(|(a, b)| (4.0 * b - a) / 3.0)
        .collect();
    (d, rounding)
}

/// The generated columns of every free parameter at `points` random points (states in `±x_range`, inputs in
/// `±1`, parameters scaled by factors in [0.5, 1.5], those at zero set to 0.05): each agrees with the differences to `1e-6` of the column's
/// largest entry (plus their rounding bound), and with the compiler's symbolic Jacobian to `1e-9`.
fn check<M, const NX: usize, const NU: usize, const NY: usize>(path: &str, model: M, x_range: f64)
where
    M: ContinuousModel<NX, NU, NY> + Parametric + ParamJacobians<NX, NU, NY> + Clone,
{
    let eqs = equations_of(path);
    let mut rng = Rng::new(7);
    let free: Vec<usize> = model
        .param_names()
        .iter()
        .map(|n| {
            eqs.params
                .iter()
                .position(|p| p.0 == *n)
                .expect("parameter of the file")
        })
        .collect();
    for point in 0..5 {
        let mut model = model.clone();
        perturbed(&mut model, &mut rng);
        // A parameter at zero (a friction left out) moves to 0.05, so that the differences can step either side
        // without leaving the physical range.
        for k in 0..free.len() {
            if model.param(k) == Some(0.0) {
                model.set_param(k, 0.05).expect("a small positive value");
            }
        }
        let x = SVector::<f64, NX>::from_fn(|_, _| rng.uniform(-x_range, x_range));
        let u = SVector::<f64, NU>::from_fn(|_, _| rng.uniform(-1.0, 1.0));
        let t = rng.uniform(0.0, 1.0);
        let mut given = vec![None; eqs.params.len()];
        for (c, &k) in free.iter().enumerate() {
            given[k] = model.param(c);
        }
        let compiler = eqs
            .param_jacobian_at(&given, x.as_slice(), u.as_slice(), t, &free)
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        let all: Vec<usize> = (0..free.len()).collect();
        let (mut fp, mut hp) = (vec![0.0; NX * all.len()], vec![0.0; NY * all.len()]);
        assert!(model.jac_p_columns(t, &x, &u, &all, &mut fp));
        assert!(model.output_jac_p_columns(t, &x, &u, &all, &mut hp));
        for (c, name) in model.param_names().iter().enumerate() {
            let (fc, hc) = (&fp[c * NX..(c + 1) * NX], &hp[c * NY..(c + 1) * NY]);
            let got: Vec<f64> = fc.iter().chain(hc).copied().collect();
            let (want, rounding) = differences(&model, (t, &x, &u), c);
            let symbolic: Vec<f64> = compiler
                .fp
                .iter()
                .chain(&compiler.hp)
                .map(|row| row[c])
                .collect();
            let scale = want.iter().fold(1e-300f64, |m, v| m.max(v.abs()));
            for (i, ((g, w), s)) in got.iter().zip(&want).zip(&symbolic).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-6 * scale + rounding,
                    "{path} point {point}: row {i} of ∂/∂{name}: generated {g}, differences {w}"
                );
                assert!(
                    (g - s).abs() <= 1e-9 * scale.max(s.abs()),
                    "{path} point {point}: row {i} of ∂/∂{name}: generated {g}, compiler {s}"
                );
            }
        }
        // A subset in any order: the same columns.
        let some: Vec<usize> = all.iter().rev().step_by(2).copied().collect();
        let mut part = vec![0.0; NX * some.len()];
        assert!(model.jac_p_columns(t, &x, &u, &some, &mut part));
        for (c, &k) in some.iter().enumerate() {
            assert_eq!(part[c * NX..(c + 1) * NX], fp[k * NX..(k + 1) * NX]);
        }
        // No column beyond the parameters, and no columns into a buffer of the wrong length.
        let mut col = vec![0.0; NX];
        assert!(!model.jac_p_columns(t, &x, &u, &[free.len()], &mut col));
        assert!(!model.output_jac_p_columns(t, &x, &u, &[0], &mut vec![0.0; NY + 1]));
    }
}

#[test]
fn back_support_parameter_jacobians_agree() {
    use bgc_models::back_support as m;
    check::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "models/back_support.bg",
        m::Model::default(),
        1.0,
    );
}

/// The I-field's mass-matrix rows, with inertias and gravity moments derived from the masses and the height.
#[test]
fn walking_leg_parameter_jacobians_agree() {
    use bgc_models::walking_leg as m;
    check::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "models/walking_leg.bg",
        m::Model::default(),
        1.0,
    );
}

#[test]
fn pendulum_rig_parameter_jacobians_agree() {
    use bgc_models::pendulum_rig as m;
    check::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "models/pendulum_rig.bg",
        m::Model::default(),
        1.0,
    );
}

/// The diode's nonlinear loop, through the implicit function theorem (charges of ±1 mC, see `agreement.rs`).
#[test]
fn diode_rc_parameter_jacobians_agree() {
    use corpus::diode_rc as m;
    check::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "bgc/tests/corpus/diode_rc.bg",
        m::Model::default(),
        1e-3,
    );
}

/// Loops solved block after block, a block reading an earlier one's tear: `∂z/∂p` block by block, through
/// `r_m` of the second loops' sources and `I_s`, `V_t` of every diode (charges of ±1 mC).
#[test]
fn chained_loops_parameter_jacobians_agree() {
    use corpus::chained_loops as m;
    check::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "models/tests/models/chained_loops.bg",
        m::Model::default(),
        1e-3,
    );
}

/// The oscillator of corpus/oscillator.bg: ṗ = F − d p/m − k q, q̇ = p/m, so ∂ṗ/∂m = d p/m², ∂ṗ/∂k = −q,
/// ∂ṗ/∂d = −p/m, ∂q̇/∂m = −p/m², and nothing else.
#[test]
fn oscillator_parameter_jacobian_is_the_hand_derivation() {
    use corpus::oscillator as m;
    assert_eq!(m::PARAM_NAMES, ["m", "k", "d"]);
    assert_eq!(m::STATE_NAMES, ["p_mass", "q_spring"]);
    let params = m::Params::default();
    let (mass, d) = (params.m, params.d);
    let (p, q) = (0.7, -0.02);
    let mut jac = m::JacP::zeros();
    m::jac_p_into(
        &params,
        0.0,
        &m::State::new(p, q),
        &m::Inputs::new(3.0),
        &mut jac,
    );
    let want = [
        [d * p / (mass * mass), -q, -p / mass],
        [-p / (mass * mass), 0.0, 0.0],
    ];
    for (r, row) in want.iter().enumerate() {
        for (c, w) in row.iter().enumerate() {
            let g = jac[(r, c)];
            assert!(
                (g - w).abs() <= 1e-15 * w.abs(),
                "[{r}][{c}]: {g} against {w}"
            );
        }
    }
}

/// `Generated::exact` takes the parameter columns from the generated derivatives, `Generated::new` from central
/// differences through `set_param`: the fit sees the same Jacobians (to the differences' accuracy).
#[test]
fn the_fit_adapter_takes_the_generated_columns() {
    use bgc_models::back_support as m;
    let exact = Generated::exact(m::Model::default());
    let differences = Generated::new(m::Model::default());
    let x: Vec<f64> = (0..m::N_STATES).map(|i| 0.1 * (i as f64 - 4.0)).collect();
    let u = [0.8, -1.5];
    let free: Vec<usize> = (0..m::N_PARAMS).collect();
    let (fx_e, fp_e) = exact.rate_jacobians(0.2, &x, &u, &free).unwrap();
    let (fx_d, fp_d) = differences.rate_jacobians(0.2, &x, &u, &free).unwrap();
    assert_eq!(fx_e, fx_d);
    let (_, hp_e) = exact.output_jacobians(0.2, &x, &u, &free).unwrap();
    let (_, hp_d) = differences.output_jacobians(0.2, &x, &u, &free).unwrap();
    for (e, d) in [(&fp_e, &fp_d), (&hp_e, &hp_d)] {
        for c in 0..free.len() {
            let scale = d.column(c).amax().max(1e-300);
            let diff = (e.column(c) - d.column(c)).amax();
            assert!(diff <= 1e-6 * scale, "column {c}: {e} against {d}");
        }
    }
    // The exact adapter names a parameter it does not have.
    assert!(exact.rate_jacobians(0.2, &x, &u, &[m::N_PARAMS]).is_err());
}
