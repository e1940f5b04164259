//! Block-diagram algebra on state-space models: series, parallel, feedback, append, and the loop transfer
//! broken at the plant input or output of an observer-based controller.
//!
//! Conventions follow python-control: `series(g1, g2)` feeds `g1` into `g2` (the product `g2·g1`), the state
//! of the result is `[x1; x2]`, and `feedback(g1, g2, sign)` closes `u1 = u + sign · g2(y1)` (negative
//! feedback for `sign = −1`). All models must share the same time base.

use nalgebra::DMatrix;

use super::error::AnalysisError;
use crate::statespace::StateSpace;

/// Sign of a feedback connection.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedbackSign {
    /// `u1 = u − g2(y1)`.
    Negative,
    /// `u1 = u + g2(y1)`.
    Positive,
}

impl FeedbackSign {
    fn value(self) -> f64 {
        match self {
            FeedbackSign::Negative => -1.0,
            FeedbackSign::Positive => 1.0,
        }
    }
}

/// `g1` followed by `g2`: `y = g2(g1(u))`.
pub fn series(g1: &StateSpace, g2: &StateSpace) -> Result<StateSpace, AnalysisError> {
    same_timebase("series", g1, g2)?;
    sizes_match(
        "series",
        "outputs of the first model vs inputs of the second",
        g1.n_outputs(),
        g2.n_inputs(),
    )?;
    let (n1, n2) = (g1.n_states(), g2.n_states());
    let mut a = DMatrix::zeros(n1 + n2, n1 + n2);
    a.view_mut((0, 0), (n1, n1)).copy_from(g1.a());
    a.view_mut((n1, 0), (n2, n1)).copy_from(&(g2.b() * g1.c()));
    a.view_mut((n1, n1), (n2, n2)).copy_from(g2.a());
    let b = stack_rows(g1.b(), &(g2.b() * g1.d()));
    let c = stack_cols(&(g2.d() * g1.c()), g2.c());
    let d = g2.d() * g1.d();
    build(a, b, c, d, g1.dt())
}

/// `g1` and `g2` driven by the same input, outputs added: `y = g1(u) + g2(u)`.
pub fn parallel(g1: &StateSpace, g2: &StateSpace) -> Result<StateSpace, AnalysisError> {
    same_timebase("parallel", g1, g2)?;
    sizes_match(
        "parallel",
        "numbers of inputs",
        g1.n_inputs(),
        g2.n_inputs(),
    )?;
    sizes_match(
        "parallel",
        "numbers of outputs",
        g1.n_outputs(),
        g2.n_outputs(),
    )?;
    let a = block_diag(g1.a(), g2.a());
    let b = stack_rows(g1.b(), g2.b());
    let c = stack_cols(g1.c(), g2.c());
    let d = g1.d() + g2.d();
    build(a, b, c, d, g1.dt())
}

/// `g1` with `g2` in its feedback path: `y = g1(u1)`, `u1 = u + sign · g2(y)`.
///
/// The algebraic loop through the feedthroughs is solved exactly; if `I − sign · D2 D1` is singular the
/// interconnection is ill-posed and refused.
pub fn feedback(
    g1: &StateSpace,
    g2: &StateSpace,
    sign: FeedbackSign,
) -> Result<StateSpace, AnalysisError> {
    same_timebase("feedback", g1, g2)?;
    sizes_match(
        "feedback",
        "outputs of the forward model vs inputs of the feedback model",
        g1.n_outputs(),
        g2.n_inputs(),
    )?;
    sizes_match(
        "feedback",
        "inputs of the forward model vs outputs of the feedback model",
        g1.n_inputs(),
        g2.n_outputs(),
    )?;
    let s = sign.value();
    let m1 = g1.n_inputs();
    let loop_matrix = DMatrix::identity(m1, m1) - (g2.d() * g1.d()) * s;
    let e = loop_matrix
        .try_inverse()
        .ok_or(AnalysisError::IllPosedFeedback)?;
    if e.iter().any(|v| !v.is_finite()) {
        return Err(AnalysisError::IllPosedFeedback);
    }
    // u1 = E (u + s D2 C1 x1 + s C2 x2)
    let u_x1 = &e * g2.d() * g1.c() * s;
    let u_x2 = &e * g2.c() * s;
    let (n1, n2) = (g1.n_states(), g2.n_states());
    let mut a = DMatrix::zeros(n1 + n2, n1 + n2);
    a.view_mut((0, 0), (n1, n1))
        .copy_from(&(g1.a() + g1.b() * &u_x1));
    a.view_mut((0, n1), (n1, n2)).copy_from(&(g1.b() * &u_x2));
    // y1 = C1 x1 + D1 u1 drives the feedback model.
    let y_x1 = g1.c() + g1.d() * &u_x1;
    let y_x2 = g1.d() * &u_x2;
    a.view_mut((n1, 0), (n2, n1)).copy_from(&(g2.b() * &y_x1));
    a.view_mut((n1, n1), (n2, n2))
        .copy_from(&(g2.a() + g2.b() * &y_x2));
    let b = stack_rows(&(g1.b() * &e), &(g2.b() * g1.d() * &e));
    let c = stack_cols(&y_x1, &y_x2);
    let d = g1.d() * &e;
    build(a, b, c, d, g1.dt())
}

/// Block-diagonal stacking: the inputs and outputs of all models side by side, no coupling.
pub fn append(models: &[&StateSpace]) -> Result<StateSpace, AnalysisError> {
    let Some(first) = models.first() else {
        return build(
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 0),
            None,
        );
    };
    let mut acc = (*first).clone();
    for g in &models[1..] {
        same_timebase("append", &acc, g)?;
        acc = build(
            block_diag(acc.a(), g.a()),
            block_diag(acc.b(), g.b()),
            block_diag(acc.c(), g.c()),
            block_diag(acc.d(), g.d()),
            acc.dt(),
        )?;
    }
    Ok(acc)
}

/// `−g`: the same model with its output negated.
pub fn negate(g: &StateSpace) -> StateSpace {
    g.with_negated_output()
}

/// A static gain `y = K u` as a model without states, on the given time base.
pub fn static_gain(k: DMatrix<f64>, dt: Option<f64>) -> Result<StateSpace, AnalysisError> {
    let (p, m) = k.shape();
    build(
        DMatrix::zeros(0, 0),
        DMatrix::zeros(0, m),
        DMatrix::zeros(p, 0),
        k,
        dt,
    )
}

/// The observer-based state-feedback controller as a model from the plant output `y` to the plant input `u`:
/// `x̂' = A x̂ + B u + L (y − C x̂ − D u)`, `u = −K x̂`, that is
/// `x̂' = (A − B K − L C + L D K) x̂ + L y`, `u = −K x̂`.
///
/// `gain` is `K` (inputs × states) and `observer_gain` is `L` (states × outputs). For a discrete plant this
/// is the predictor form of the observer.
pub fn observer_controller(
    plant: &StateSpace,
    gain: &DMatrix<f64>,
    observer_gain: &DMatrix<f64>,
) -> Result<StateSpace, AnalysisError> {
    let (n, m, p) = (plant.n_states(), plant.n_inputs(), plant.n_outputs());
    sizes_match(
        "observer_controller",
        "rows of K vs plant inputs",
        gain.nrows(),
        m,
    )?;
    sizes_match(
        "observer_controller",
        "columns of K vs plant states",
        gain.ncols(),
        n,
    )?;
    sizes_match(
        "observer_controller",
        "rows of L vs plant states",
        observer_gain.nrows(),
        n,
    )?;
    sizes_match(
        "observer_controller",
        "columns of L vs plant outputs",
        observer_gain.ncols(),
        p,
    )?;
    let a =
        plant.a() - plant.b() * gain - observer_gain * plant.c() + observer_gain * plant.d() * gain;
    build(
        a,
        observer_gain.clone(),
        -gain,
        DMatrix::zeros(m, p),
        plant.dt(),
    )
}

/// The loop transfer broken at the plant input, `L_in = −C·P`, for a controller `u = C(y)` that already
/// contains its feedback sign (as [`observer_controller`] does). Its margins are the input margins of the
/// loop under the negative-feedback convention of [`super::margins::stability_margins`].
pub fn loop_at_plant_input(
    plant: &StateSpace,
    controller: &StateSpace,
) -> Result<StateSpace, AnalysisError> {
    Ok(negate(&series(plant, controller)?))
}

/// The loop transfer broken at the plant output, `L_out = −P·C` (same conventions as
/// [`loop_at_plant_input`]).
pub fn loop_at_plant_output(
    plant: &StateSpace,
    controller: &StateSpace,
) -> Result<StateSpace, AnalysisError> {
    Ok(negate(&series(controller, plant)?))
}

fn build(
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    dt: Option<f64>,
) -> Result<StateSpace, AnalysisError> {
    Ok(match dt {
        None => StateSpace::new(a, b, c, d)?,
        Some(dt) => StateSpace::new_discrete(a, b, c, d, dt)?,
    })
}

fn same_timebase(
    operation: &'static str,
    g1: &StateSpace,
    g2: &StateSpace,
) -> Result<(), AnalysisError> {
    let same = match (g1.dt(), g2.dt()) {
        (None, None) => true,
        (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * a.abs().max(b.abs()),
        _ => false,
    };
    if same {
        Ok(())
    } else {
        Err(AnalysisError::TimebaseMismatch {
            operation,
            left: g1.dt(),
            right: g2.dt(),
        })
    }
}

fn sizes_match(
    operation: &'static str,
    detail: &'static str,
    left: usize,
    right: usize,
) -> Result<(), AnalysisError> {
    if left == right {
        Ok(())
    } else {
        Err(AnalysisError::SizeMismatch {
            operation,
            detail,
            left,
            right,
        })
    }
}

fn block_diag(x: &DMatrix<f64>, y: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(x.nrows() + y.nrows(), x.ncols() + y.ncols());
    out.view_mut((0, 0), x.shape()).copy_from(x);
    out.view_mut(x.shape(), y.shape()).copy_from(y);
    out
}

fn stack_rows(top: &DMatrix<f64>, bottom: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(top.nrows() + bottom.nrows(), top.ncols());
    out.view_mut((0, 0), top.shape()).copy_from(top);
    out.view_mut((top.nrows(), 0), bottom.shape())
        .copy_from(bottom);
    out
}

fn stack_cols(left: &DMatrix<f64>, right: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(left.nrows(), left.ncols() + right.ncols());
    out.view_mut((0, 0), left.shape()).copy_from(left);
    out.view_mut((0, left.ncols()), right.shape())
        .copy_from(right);
    out
}
