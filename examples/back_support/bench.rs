//! The bench-identification step: the simulated lab test (trunk held, chirp motor torque) at the paper's encoder
//! bound and at a realistic one, the fit of J_g, k_g, k_s and J_sint, a table and its JSON.

use std::fmt::Write as _;
use std::path::Path;

use bgc_models::back_support::{INPUT_NAMES, OUTPUT_NAMES};
use bgc_runtime::fit::Record;
use bgc_workspace::back_support::identification::{
    BenchConfig, BenchIdentification, bench_record, identify,
};
use serde_json::{Value, json};

/// Runs the identification for one test and prints its table; writes the record to `csv` in the form
/// `bgc fit --data` reads. The JSON of the result (or of its error).
pub fn run(label: &str, cfg: &BenchConfig, csv: &Path) -> Value {
    println!(
        "\nbench identification, {label} (encoder |v_v| <= {:.1e} rad/s, torque sensor |v_t| <= 35e-3 N m)",
        cfg.encoder_bound
    );
    let result = bench_record(cfg).and_then(|r| {
        match std::fs::write(csv, record_csv(&r)) {
            Ok(()) => println!("  record written to {}", csv.display()),
            Err(e) => println!("  cannot write {}: {e}", csv.display()),
        }
        identify(cfg, &r)
    });
    match result {
        Ok(id) => {
            print_table(&id);
            value(label, cfg, &id)
        }
        Err(e) => {
            println!("  not identified: {e}");
            json!({"test": label, "encoder_bound": cfg.encoder_bound, "error": e.to_string()})
        }
    }
}

/// The record as CSV: `t`, the inputs and the measured outputs by their model names.
fn record_csv(r: &Record) -> String {
    let mut header = vec!["t"];
    header.extend(INPUT_NAMES);
    header.extend(
        r.outputs
            .iter()
            .map(|&k| OUTPUT_NAMES.get(k).copied().unwrap_or("?")),
    );
    let mut text = header.join(",") + "\n";
    for ((t, u), y) in r.times.iter().zip(&r.inputs).zip(&r.measured) {
        let _ = write!(text, "{t:e}");
        for v in u.iter().chain(y) {
            let _ = write!(text, ",{v:e}");
        }
        text.push('\n');
    }
    text
}

fn print_table(id: &BenchIdentification) {
    println!(
        "  {:<8} {:>12} {:>13} {:>11} {:>9}  determined",
        "param", "truth", "estimate", "std. error", "off (SE)"
    );
    for p in &id.parameters {
        if p.determined {
            println!(
                "  {:<8} {:>12.5e} {:>13.6e} {:>11.3e} {:>9.2}  yes",
                p.name,
                p.truth,
                p.estimate,
                p.std_error,
                (p.estimate - p.truth) / p.std_error
            );
        } else {
            println!(
                "  {:<8} {:>12.5e} {:>13.6e} {:>11.3e} {:>9}  no{}",
                p.name,
                p.truth,
                p.estimate,
                p.std_error,
                "-",
                if p.std_error.is_nan() {
                    " (held at its start)"
                } else {
                    ""
                }
            );
        }
    }
    for u in &id.report.undetermined {
        let combo: Vec<String> = u
            .combination
            .iter()
            .map(|(n, e)| format!("{n}^{e:.2}"))
            .collect();
        println!(
            "  not identifiable: {} (relative standard error {:.0} %)",
            combo.join(" · "),
            100.0 * u.relative_std_error
        );
    }
    println!(
        "  weighted residual variance {:.3}; {} after {} iterations (Gauss–Newton step {:.2} standard errors)",
        id.report.residual_variance,
        id.report.convergence.describe(),
        id.report.iterations,
        id.report.optimality
    );
}

fn finite(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

fn value(label: &str, cfg: &BenchConfig, id: &BenchIdentification) -> Value {
    let rows: Vec<Value> = id
        .parameters
        .iter()
        .map(|p| {
            json!({"name": p.name, "truth": p.truth, "estimate": p.estimate,
                   "std_error": finite(p.std_error), "determined": p.determined})
        })
        .collect();
    let undetermined: Vec<Value> = id
        .report
        .undetermined
        .iter()
        .map(|u| {
            json!({"combination": u.combination.iter().map(|(n, e)| json!({"name": n, "exponent": e})).collect::<Vec<_>>(),
                   "relative_std_error": finite(u.relative_std_error), "held": u.held})
        })
        .collect();
    json!({
        "test": label,
        "encoder_bound": cfg.encoder_bound,
        "parameters": rows,
        "undetermined": undetermined,
        "residual_variance": finite(id.report.residual_variance),
        "status": id.report.convergence,
        "optimality": finite(id.report.optimality),
        "iterations": id.report.iterations,
    })
}
