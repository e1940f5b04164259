//! Linear time-invariant state-space models, continuous or discrete.

use nalgebra::DMatrix;

/// `ẋ = A x + B u`, `y = C x + D u` (or `x[k+1] = A x[k] + B u[k]` when `dt` is `Some`).
///
/// The matrices are private and only [`StateSpace::new`] and [`StateSpace::new_discrete`] build a model, so
/// every `StateSpace` has consistent sizes (`A` n×n, `B` n×m, `C` p×n, `D` p×m), finite entries and, when
/// discrete, a positive finite sample time. Functions that take a `StateSpace` rely on that and need not
/// check it again.
///
/// ```compile_fail
/// // A model cannot be assembled from its fields (here a 2x2 `A` with a 1x1 `B`).
/// use nalgebra::DMatrix;
/// let _ = bgc_runtime::statespace::StateSpace {
///     a: DMatrix::zeros(2, 2),
///     b: DMatrix::zeros(1, 1),
///     c: DMatrix::zeros(1, 2),
///     d: DMatrix::zeros(1, 1),
///     dt: None,
/// };
/// ```
///
/// ```
/// use bgc_runtime::statespace::{StateSpace, StateSpaceError};
/// use nalgebra::{DMatrix, dmatrix};
/// let bad = StateSpace::new(DMatrix::zeros(2, 2), DMatrix::zeros(1, 1), DMatrix::zeros(1, 2), dmatrix![0.0]);
/// assert!(matches!(bad, Err(StateSpaceError::Shape { name: "B", .. })));
/// let nan = StateSpace::new(dmatrix![f64::NAN], dmatrix![1.0], dmatrix![1.0], dmatrix![0.0]);
/// assert!(matches!(nan, Err(StateSpaceError::NonFinite { name: "A", .. })));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    /// The sample time of a discrete-time model; `None` for continuous time.
    dt: Option<f64>,
}

/// Why a state-space model could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StateSpaceError {
    #[error("matrix {name} is {rows}x{cols}, expected {expected_rows}x{expected_cols}")]
    Shape {
        name: &'static str,
        rows: usize,
        cols: usize,
        expected_rows: usize,
        expected_cols: usize,
    },
    #[error("matrix {name} has a non-finite entry at ({row}, {col})")]
    NonFinite {
        name: &'static str,
        row: usize,
        col: usize,
    },
    #[error("sample time {dt:?} is not a positive finite number")]
    BadSampleTime { dt: f64 },
}

impl StateSpace {
    /// A continuous-time model; checks shapes and finiteness.
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
    ) -> Result<Self, StateSpaceError> {
        let n = a.nrows();
        let m = b.ncols();
        let p = c.nrows();
        check_shape("A", &a, n, n)?;
        check_shape("B", &b, n, m)?;
        check_shape("C", &c, p, n)?;
        check_shape("D", &d, p, m)?;
        for (name, mat) in [("A", &a), ("B", &b), ("C", &c), ("D", &d)] {
            check_finite(name, mat)?;
        }
        Ok(StateSpace {
            a,
            b,
            c,
            d,
            dt: None,
        })
    }

    /// A discrete-time model with sample time `dt`.
    pub fn new_discrete(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        dt: f64,
    ) -> Result<Self, StateSpaceError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(StateSpaceError::BadSampleTime { dt });
        }
        let mut ss = Self::new(a, b, c, d)?;
        ss.dt = Some(dt);
        Ok(ss)
    }

    /// The state matrix `A` (n×n).
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// The input matrix `B` (n×m).
    pub fn b(&self) -> &DMatrix<f64> {
        &self.b
    }

    /// The output matrix `C` (p×n).
    pub fn c(&self) -> &DMatrix<f64> {
        &self.c
    }

    /// The feedthrough matrix `D` (p×m).
    pub fn d(&self) -> &DMatrix<f64> {
        &self.d
    }

    /// The sample time of a discrete-time model; `None` for continuous time.
    pub fn dt(&self) -> Option<f64> {
        self.dt
    }

    /// The matrices `(A, B, C, D)` and the sample time, moved out of the model.
    #[allow(clippy::type_complexity)]
    pub fn into_parts(
        self,
    ) -> (
        DMatrix<f64>,
        DMatrix<f64>,
        DMatrix<f64>,
        DMatrix<f64>,
        Option<f64>,
    ) {
        (self.a, self.b, self.c, self.d, self.dt)
    }

    /// The same model with its output negated (`−C`, `−D`); sizes and finiteness are unchanged.
    pub fn with_negated_output(&self) -> StateSpace {
        StateSpace {
            a: self.a.clone(),
            b: self.b.clone(),
            c: -&self.c,
            d: -&self.d,
            dt: self.dt,
        }
    }

    pub fn n_states(&self) -> usize {
        self.a.nrows()
    }

    pub fn n_inputs(&self) -> usize {
        self.b.ncols()
    }

    pub fn n_outputs(&self) -> usize {
        self.c.nrows()
    }
}

fn check_shape(
    name: &'static str,
    m: &DMatrix<f64>,
    expected_rows: usize,
    expected_cols: usize,
) -> Result<(), StateSpaceError> {
    if m.nrows() != expected_rows || m.ncols() != expected_cols {
        return Err(StateSpaceError::Shape {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            expected_rows,
            expected_cols,
        });
    }
    Ok(())
}

fn check_finite(name: &'static str, m: &DMatrix<f64>) -> Result<(), StateSpaceError> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(StateSpaceError::NonFinite {
                    name,
                    row: i,
                    col: j,
                });
            }
        }
    }
    Ok(())
}
