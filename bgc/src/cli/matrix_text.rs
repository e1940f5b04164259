//! Matrices as `bgc statespace --format text` prints them: one format per matrix, chosen as numpy's printing
//! chooses it, so that a row reads at a glance.
//!
//! - Exact zeros print as `0` (a negative zero too).
//! - When every non-zero magnitude lies in [1e-4, 1e8) and the largest is at most 1000 times the smallest, the
//!   numbers are fixed-point with the fewest decimals (at most 8) that show every entry to 8 significant digits;
//!   otherwise all are in scientific notation with the fewest mantissa digits (at most 8) that do.
//! - Columns are right-aligned.
//!
//! JSON keeps full precision; this form is for reading.

/// The most digits after the point (fixed) or in the mantissa (scientific).
const PRECISION: usize = 8;

/// The cells of a numeric matrix, formatted alike.
pub fn format_matrix(rows: &[Vec<f64>]) -> Vec<Vec<String>> {
    let nonzero: Vec<f64> = rows
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite() && *v != 0.0)
        .map(f64::abs)
        .collect();
    let max = nonzero.iter().copied().fold(0.0, f64::max);
    let min = nonzero.iter().copied().fold(f64::INFINITY, f64::min);
    let fixed = nonzero.is_empty() || (max < 1e8 && min >= 1e-4 && max / min <= 1e3);
    let digits = rows
        .iter()
        .flatten()
        .filter(|v| v.is_finite() && **v != 0.0)
        .map(|v| needed_digits(*v, fixed))
        .max()
        .unwrap_or(0);
    rows.iter()
        .map(|r| r.iter().map(|v| cell(*v, fixed, digits)).collect())
        .collect()
}

/// The fewest digits (after the point, or of the mantissa) that show `v` as it prints with [`PRECISION`] of them.
fn needed_digits(v: f64, fixed: bool) -> usize {
    let full = if fixed {
        format!("{:.*}", PRECISION, v)
    } else {
        format!("{:.*e}", PRECISION, v)
    };
    let mantissa = full.split('e').next().unwrap_or("");
    let decimals = mantissa.split('.').nth(1).unwrap_or("");
    decimals.trim_end_matches('0').len()
}

fn cell(v: f64, fixed: bool, digits: usize) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return v.to_string();
    }
    if fixed {
        format!("{v:.digits$}")
    } else {
        format!("{v:.digits$e}")
    }
}

/// The rows of cells right-aligned to the widest cell, two spaces of indent and two between columns.
pub fn layout(cells: &[Vec<String>]) -> String {
    let width = cells
        .iter()
        .flatten()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(0);
    let mut out = String::new();
    for row in cells {
        let line: Vec<String> = row.iter().map(|c| format!("{c:>width$}")).collect();
        out.push_str(&format!("  {}\n", line.join("  ")));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeros_are_zero_and_fixed_point_has_the_fewest_decimals() {
        // numpy: np.array([[0., -0., 1.5], [-2.25, 100., 0.125]]) prints 0., -0., 1.5, -2.25, 100., 0.125 with
        // three decimals; zeros here print as 0.
        let cells = format_matrix(&[vec![0.0, -0.0, 1.5], vec![-2.25, 100.0, 0.125]]);
        assert_eq!(
            cells,
            vec![vec!["0", "0", "1.500"], vec!["-2.250", "100.000", "0.125"]]
        );
    }

    #[test]
    fn wide_ranges_are_scientific_with_the_fewest_mantissa_digits() {
        // The ratio 4e4 > 1e3 makes numpy choose scientific notation: 2.e+00, -8.e+04.
        let cells = format_matrix(&[vec![2.0, -80000.0, 0.0]]);
        assert_eq!(cells, vec![vec!["2e0", "-8e4", "0"]]);
        let cells = format_matrix(&[vec![1.0 / 3.0, 1e-9]]);
        assert_eq!(cells, vec![vec!["3.33333333e-1", "1.00000000e-9"]]);
    }

    #[test]
    fn columns_are_aligned() {
        let text = layout(&format_matrix(&[vec![1.0, -10.0], vec![0.0, 2.5]]));
        assert_eq!(text, "    1.0  -10.0\n      0    2.5\n");
    }
}
