//! `bgc simulate` on a large model: from 200 states on, the implicit methods work with the equations' sparse
//! Jacobian and a sparse LU. Checked against an explicit method at tight tolerances and the energy balance, on a
//! chain of masses with dampers joined by springs (`equations_sparse::chain`).

use crate::cli_support;
use crate::equations_sparse::chain;

use cli_support::{Csv, simulate, temp_model};

fn run(path: &str, solver: &str, tolerances: &[&str]) -> Csv {
    let mut args = vec![
        path,
        "--input",
        "u=sin(3*t)",
        "--t-end",
        "5",
        "--dt-out",
        "0.25",
        "--solver",
        solver,
    ];
    args.extend_from_slice(tolerances);
    simulate(&args)
}

/// The largest difference between two runs over every column but time.
fn largest_difference(a: &Csv, b: &Csv) -> f64 {
    assert_eq!(a.header, b.header);
    let columns = a.header.iter().filter(|h| h.as_str() != "t");
    columns
        .map(|name| {
            let (x, y) = (a.col(name), b.col(name));
            x.iter()
                .zip(&y)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_chain_of_600_states_follows_the_explicit_reference_on_every_implicit_method() {
    let path = temp_model("chain300", &chain(300));
    let reference = run(&path, "tsit45", &["--rtol", "1e-10", "--atol", "1e-12"]);
    assert_eq!(reference.header.len(), 1 + 600 + 3);
    for solver in ["bdf", "esdirk34", "tr_bdf2"] {
        let csv = run(&path, solver, &["--rtol", "1e-8", "--atol", "1e-10"]);
        let worst = largest_difference(&csv, &reference);
        assert!(worst < 1e-5, "{solver}: largest difference {worst:e}");
    }
}

/// BDF at these tolerances keeps `stored + dissipated - supplied` within 1.5e-6 of the energy supplied (the
/// explicit reference at 1e-10 within 8e-8); 1e-5 leaves room for rounding on other platforms.
#[test]
fn a_chain_of_600_states_keeps_its_energy_balance() {
    let path = temp_model("chain300_energy", &chain(300));
    let csv = run(&path, "bdf", &["--rtol", "1e-8", "--atol", "1e-10"]);
    let (stored, dissipated, supplied) = (
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    let scale = supplied.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    assert!(scale > 0.1, "the drive supplies energy: {scale}");
    for k in 0..stored.len() {
        let balance = stored[k] + dissipated[k] - supplied[k];
        assert!(balance.abs() < 1e-5 * scale, "row {k}: balance {balance:e}");
    }
}
