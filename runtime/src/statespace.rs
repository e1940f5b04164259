//! Linear time-invariant state-space models, continuous or discrete.

use nalgebra::DMatrix;

/// `ẋ = A x + B u`, `y = C x + D u` (or `x[k+1] = A x[k] + B u[k]` when `dt` is `Some`).
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
    /// The sample time of a discrete-time model; `None` for continuous time.
    pub dt: Option<f64>,
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
    #[error("sample time {dt} is not a positive finite number")]
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
