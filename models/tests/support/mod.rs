//! Checks of a generated model against the compiler's own evaluation of the derived equations
//! (`bgc::equations`, evaluated by `bgc::equations::symbols::eval`, a path that shares no code with the generated Rust)
//! and against finite differences and the power balance.
#![allow(dead_code)]

use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{
    Equations, StateSelection, declared_state_space, jacobians, linearise, numeric_state_space,
};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use bgc::symbolic::Expr;
use bgc_runtime::model::{ContinuousModel, Parametric};
use nalgebra::{SMatrix, SVector};

/// The equations of the single model of a file of the workspace (path relative to the workspace root).
pub fn equations_of(path: &str) -> Equations {
    let full = format!("{}/../{path}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{full}: {e}"));
    let mut sources = SourceMap::new();
    let root = sources.add(path, text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(!bgc::diagnostic::has_errors(&diags), "{path}: {diags:?}");
    assert_eq!(models.len(), 1, "{path}");
    let (causality, _) = bgc::causality::analyse(&models[0]);
    let (eqs, diags) = bgc::equations::derive(&models[0], &causality);
    assert!(!bgc::diagnostic::has_errors(&diags), "{path}: {diags:?}");
    eqs
}

/// A small deterministic generator (xorshift64*), uniform in `[lo, hi)`.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.max(1))
    }

    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        lo + (hi - lo) * ((r >> 11) as f64 / (1u64 << 53) as f64)
    }
}

pub fn eval(e: &Expr, params: &[f64], x: &[f64], u: &[f64], t: f64) -> f64 {
    sym::eval(e, &|s| match s {
        Sym::Param(i) => params.get(i).copied(),
        Sym::State(i) => x.get(i).copied(),
        Sym::Input(i) => u.get(i).copied(),
        Sym::Time => Some(t),
        _ => None,
    })
    .unwrap_or_else(|e| panic!("cannot evaluate: {e:?}"))
}

/// `|a - b| <= rel * max(|a|, |b|)` (exact equality for zeros).
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a - b).abs() <= rel * a.abs().max(b.abs())
}

fn matrix_close<const R: usize, const C: usize>(
    what: &str,
    got: &SMatrix<f64, R, C>,
    want: &[Vec<f64>],
    rel: f64,
) {
    matrix_close_abs(what, got, want, rel, 0.0);
}

/// As `close` per entry, or within `abs` times the largest entry of `want` (rounding residue of a numeric
/// inverse where the exact entry is zero).
fn matrix_close_abs<const R: usize, const C: usize>(
    what: &str,
    got: &SMatrix<f64, R, C>,
    want: &[Vec<f64>],
    rel: f64,
    abs: f64,
) {
    let largest = want.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert_eq!(want.len(), R, "{what}: rows");
    for (r, row) in want.iter().enumerate() {
        assert_eq!(row.len(), C, "{what}: columns");
        for (c, &w) in row.iter().enumerate() {
            let g = got[(r, c)];
            assert!(
                close(g, w, rel) || (g - w).abs() <= abs * largest,
                "{what}[{r}][{c}]: generated {g}, compiler {w}"
            );
        }
    }
}

/// Parameters: the defaults, each scaled by a random factor in [0.5, 1.5] (keeps signs, so stays physical).
pub fn perturbed<M: Parametric>(model: &mut M, rng: &mut Rng) -> Vec<f64> {
    let n = model.param_names().len();
    for i in 0..n {
        let v = model.param(i).unwrap_or(f64::NAN);
        let scaled = v * rng.uniform(0.5, 1.5);
        model
            .set_param(i, scaled)
            .unwrap_or_else(|e| panic!("perturbed parameter refused: {e}"));
    }
    (0..n).map(|i| model.param(i).unwrap_or(f64::NAN)).collect()
}

/// The generated rhs, outputs and Jacobians agree with the compiler's evaluation to `1e-12` relative at 100 random
/// points, and the Jacobians agree with central differences of the generated rhs and outputs.
pub fn check_agreement<M, const NX: usize, const NU: usize, const NY: usize>(path: &str, model: M)
where
    M: ContinuousModel<NX, NU, NY> + Parametric,
{
    check_agreement_in(path, model, 1.0);
}

/// As [`check_agreement`], with the states drawn from `[-x_range, x_range)` (inputs from `[-1, 1)`). A model with
/// nonlinear algebraic loops is compared with the compiler's Newton solution of its loops (`rates_at`,
/// `outputs_at`, `linearise`) to `1e-10` relative: the two solves stop at residuals of `1e-12` of the terms, not at
/// the same bits.
pub fn check_agreement_in<M, const NX: usize, const NU: usize, const NY: usize>(
    path: &str,
    mut model: M,
    x_range: f64,
) where
    M: ContinuousModel<NX, NU, NY> + Parametric,
{
    let eqs = equations_of(path);
    assert_eq!(eqs.states.len(), NX, "{path}: states");
    assert_eq!(eqs.inputs.len(), NU, "{path}: inputs");
    assert_eq!(eqs.outputs.len(), NY, "{path}: outputs");
    let f: Vec<Expr> = eqs.f.iter().map(|e| e.clone().expect("rate")).collect();
    // The generated `Params` has the free parameters as fields (in `Parametric` order); derived ones follow them.
    let free: Vec<usize> = (0..eqs.params.len())
        .filter(|&k| eqs.derived.get(k).is_none_or(Option::is_none))
        .collect();
    let free_names: Vec<&str> = free.iter().map(|&k| eqs.params[k].0.as_str()).collect();
    assert_eq!(
        model.param_names(),
        free_names.as_slice(),
        "{path}: parameters"
    );
    let h: Vec<Expr> = eqs
        .outputs
        .iter()
        .map(|o| o.explicit.clone().expect("output"))
        .collect();
    // The Jacobians from the equations stage's own differentiation (None when it cannot differentiate, e.g. min).
    let symbolic_jac = jacobians(&eqs, StateSelection::All).ok();
    let uses_min_max =
        format!("{f:?}{h:?}").contains("Min") || format!("{f:?}{h:?}").contains("Max");
    let loops = !eqs.tear_blocks.is_empty();
    let rel = if loops { 1e-10 } else { 1e-12 };
    assert!(
        symbolic_jac.is_some() || uses_min_max || loops,
        "{path}: the compiler's Jacobians are missing"
    );
    let mut rng = Rng::new(0x5eed ^ path.len() as u64);
    for point in 0..100 {
        // New parameters every 10 points.
        if point % 10 == 0 {
            perturbed(&mut model, &mut rng);
        }
        let mut given = vec![None; eqs.params.len()];
        for (i, &k) in free.iter().enumerate() {
            given[k] = model.param(i);
        }
        let params = eqs.param_values(&given);
        let x = SVector::<f64, NX>::from_fn(|_, _| rng.uniform(-x_range, x_range));
        let u = SVector::<f64, NU>::from_fn(|_, _| rng.uniform(-1.0, 1.0));
        let t = rng.uniform(0.0, 2.0);
        let mut dx = SVector::<f64, NX>::zeros();
        model.rhs(t, &x, &u, &mut dx);
        // The compiler's rates: `f` itself, or for the rows of an I-field `M ẋ = F` solved numerically.
        let rates = eqs
            .rates_at(&params, x.as_slice(), u.as_slice(), t)
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        for (i, fi) in f.iter().enumerate() {
            let want = if eqs.has_mass() || loops {
                rates[i]
            } else {
                eval(fi, &params, x.as_slice(), u.as_slice(), t)
            };
            assert!(
                close(dx[i], want, rel),
                "{path}: rate {i} at point {point}: generated {}, compiler {want}",
                dx[i]
            );
        }
        let mut y = SVector::<f64, NY>::zeros();
        model.outputs(t, &x, &u, &mut y);
        let solved_outputs = eqs
            .outputs_at(&params, x.as_slice(), u.as_slice(), t)
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        for (k, hk) in h.iter().enumerate() {
            let want = if loops {
                solved_outputs[k]
            } else {
                eval(hk, &params, x.as_slice(), u.as_slice(), t)
            };
            assert!(
                close(y[k], want, rel),
                "{path}: output {k} at point {point}: generated {}, compiler {want}",
                y[k]
            );
        }
        let mut ax = SMatrix::<f64, NX, NX>::zeros();
        let mut bu = SMatrix::<f64, NX, NU>::zeros();
        let mut cx = SMatrix::<f64, NY, NX>::zeros();
        let mut du = SMatrix::<f64, NY, NU>::zeros();
        model.jac_x(t, &x, &u, &mut ax);
        model.jac_u(t, &x, &u, &mut bu);
        model.output_jac_x(t, &x, &u, &mut cx);
        model.output_jac_u(t, &x, &u, &mut du);
        if symbolic_jac.is_some() || loops {
            // The compiler's linearisation (for I-fields: the Jacobians of the solved rates).
            let num = linearise(
                &eqs,
                StateSelection::All,
                &params,
                x.as_slice(),
                u.as_slice(),
                t,
            )
            .unwrap_or_else(|e| panic!("{path}: {e}"));
            // Through a mass matrix both sides solve a linear system (Cholesky here, LU in the compiler), and
            // through loops the compiler solves one system of all tears where the generated code solves one per
            // block: their rounding differs by a few ulps of the largest entry, which a small entry sees as a
            // relative error (an entry that is exactly zero between separate loops is 1e-15 in the compiler's).
            let abs = if eqs.has_mass() || loops { 1e-12 } else { 0.0 };
            matrix_close_abs(&format!("{path}: df/dx"), &ax, &num.a, rel, abs);
            matrix_close_abs(&format!("{path}: df/du"), &bu, &num.b, rel, abs);
            matrix_close(&format!("{path}: dh/dx"), &cx, &num.c, rel);
            matrix_close(&format!("{path}: dh/du"), &du, &num.d, rel);
        }
        finite_differences(path, &model, (t, x_range), &x, &u, (&ax, &bu, &cx, &du));
    }
}

/// The Jacobians `∂f/∂x, ∂f/∂u, ∂h/∂x, ∂h/∂u` of a generated model.
type Jacobians<'a, const NX: usize, const NU: usize, const NY: usize> = (
    &'a SMatrix<f64, NX, NX>,
    &'a SMatrix<f64, NX, NU>,
    &'a SMatrix<f64, NY, NX>,
    &'a SMatrix<f64, NY, NU>,
);

/// Central differences of the generated functions against the generated Jacobians; the state steps are relative
/// to `max(|x_j|, x_range)`.
fn finite_differences<M, const NX: usize, const NU: usize, const NY: usize>(
    path: &str,
    model: &M,
    (t, x_range): (f64, f64),
    x: &SVector<f64, NX>,
    u: &SVector<f64, NU>,
    (ax, bu, cx, du): Jacobians<NX, NU, NY>,
) where
    M: ContinuousModel<NX, NU, NY>,
{
    // Each column: perturb one variable, difference f and h. The tolerance allows the truncation error (relative
    // 1e-6 of the entry) and the rounding error of f/h of magnitude |f| at step h (about eps |f| / h).
    let check =
        |name: &str, col: usize, fp: &[f64], fm: &[f64], step: f64, jac: &dyn Fn(usize) -> f64| {
            for r in 0..fp.len() {
                let fd = (fp[r] - fm[r]) / (2.0 * step);
                let exact = jac(r);
                let scale = fp[r].abs().max(fm[r].abs());
                let tol = 1e-6 * exact.abs() + 1e-4 * f64::EPSILON.sqrt() * scale / step + 1e-9;
                assert!(
                    (fd - exact).abs() <= tol,
                    "{path}: {name}[{r}][{col}]: symbolic {exact}, finite difference {fd}"
                );
            }
        };
    let eval_f = |x: &SVector<f64, NX>, u: &SVector<f64, NU>| {
        let mut dx = SVector::<f64, NX>::zeros();
        let mut y = SVector::<f64, NY>::zeros();
        model.rhs(t, x, u, &mut dx);
        model.outputs(t, x, u, &mut y);
        (dx, y)
    };
    for j in 0..NX {
        let step = 1e-6 * x[j].abs().max(x_range);
        let (mut xp, mut xm) = (*x, *x);
        xp[j] += step;
        xm[j] -= step;
        let ((fp, yp), (fm, ym)) = (eval_f(&xp, u), eval_f(&xm, u));
        check("df/dx", j, fp.as_slice(), fm.as_slice(), step, &|r| {
            ax[(r, j)]
        });
        check("dh/dx", j, yp.as_slice(), ym.as_slice(), step, &|r| {
            cx[(r, j)]
        });
    }
    for j in 0..NU {
        let step = 1e-6 * u[j].abs().max(1.0);
        let (mut up, mut um) = (*u, *u);
        up[j] += step;
        um[j] -= step;
        let ((fp, yp), (fm, ym)) = (eval_f(x, &up), eval_f(x, &um));
        check("df/du", j, fp.as_slice(), fm.as_slice(), step, &|r| {
            bu[(r, j)]
        });
        check("dh/du", j, yp.as_slice(), ym.as_slice(), step, &|r| {
            du[(r, j)]
        });
    }
}

/// The generated energy-state `A, B, C, D` agree with the compiler's numeric state space.
pub fn check_state_space<const NE: usize, const NU: usize, const NY: usize>(
    path: &str,
    params: &[f64],
    ss: &(
        SMatrix<f64, NE, NE>,
        SMatrix<f64, NE, NU>,
        SMatrix<f64, NY, NE>,
        SMatrix<f64, NY, NU>,
    ),
    declared: bool,
) {
    let eqs = equations_of(path);
    let num = if declared {
        declared_state_space(&eqs, params).unwrap_or_else(|e| panic!("{path}: {e}"))
    } else {
        numeric_state_space(&eqs, StateSelection::Energy, params)
            .unwrap_or_else(|e| panic!("{path}: {e}"))
    };
    // The declared-coordinate matrices go through a symbolic inverse in the generated code and a numeric one in
    // the compiler: agreement to rounding, not to the last bit.
    let (rel, abs) = if declared {
        (1e-9, 1e-12)
    } else {
        (1e-12, 0.0)
    };
    matrix_close_abs(&format!("{path}: A"), &ss.0, &num.a, rel, abs);
    matrix_close_abs(&format!("{path}: B"), &ss.1, &num.b, rel, abs);
    matrix_close_abs(&format!("{path}: C"), &ss.2, &num.c, rel, abs);
    matrix_close_abs(&format!("{path}: D"), &ss.3, &num.d, rel, abs);
}
