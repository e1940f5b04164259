//! The report of `bgc fit`: estimates with standard errors in their declared units, the combinations the record
//! does not determine, correlations, residual RMS per output, iterations and the reason the fit stopped.

use super::ReportFormat;
use super::fit::{Units, estimates_in_units};
use super::io::stdout;
use bgc::ir::Model;
use bgc_runtime::fit::{FitReport, Record};
use serde_json::json;
use std::fmt::Write as _;

/// Prints the report on standard output.
pub fn print(
    model: &Model,
    record: &Record,
    report: &FitReport,
    units: &Units,
    format: ReportFormat,
) {
    let outputs: Vec<(String, String)> = record
        .outputs
        .iter()
        .map(|&o| {
            let d = &model.outputs[o];
            (d.name.clone(), d.unit_text.clone())
        })
        .collect();
    match format {
        ReportFormat::Text => stdout(&text(model, record, report, units, &outputs)),
        ReportFormat::Json => stdout(&format!(
            "{:#}\n",
            value(model, record, report, units, &outputs)
        )),
    }
}

fn text(
    model: &Model,
    record: &Record,
    report: &FitReport,
    units: &Units,
    outputs: &[(String, String)],
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "fit of `{}` to {} samples ({} measured values of {} outputs)",
        model.name,
        record.times.len(),
        record.sample_count(),
        outputs.len()
    );
    let _ = writeln!(
        s,
        "\n{:<16} {:>13} {:>12} {:>9} {:>13}  unit",
        "quantity", "estimate", "std. error", "rel.", "start"
    );
    for (name, value, se, start, unit, determined) in estimates_in_units(report, units) {
        if determined || se.is_finite() {
            let mark = if determined { "" } else { "  not determined" };
            let _ = writeln!(
                s,
                "{name:<16} {value:>13.6e} {se:>12.3e} {:>8.2} % {start:>13.6e}  {unit}{mark}",
                100.0 * se / value.abs()
            );
        } else {
            let _ = writeln!(
                s,
                "{name:<16} {:>13} {:>12} {:>10} {start:>13.6e}  {unit}",
                "not determined", "-", "-"
            );
        }
    }
    for u in &report.undetermined {
        let what = match &u.held {
            Some(h) => format!("`{h}` is held at its start"),
            None => "nothing is held; its leading quantity is reported as not determined".into(),
        };
        let _ = writeln!(
            s,
            "\nnot identifiable: the record does not determine {} (relative standard error {}); {what}",
            combination(&u.combination),
            percent(u.relative_std_error),
        );
    }
    if report.correlated.len() > 1 {
        let _ = writeln!(s, "\ncorrelation");
        let _ = write!(s, "{:<16}", "");
        for n in &report.correlated {
            let _ = write!(s, " {n:>9.9}");
        }
        s.push('\n');
        for (i, n) in report.correlated.iter().enumerate() {
            let _ = write!(s, "{n:<16}");
            for j in 0..report.correlated.len() {
                let _ = write!(s, " {:>9.4}", report.correlation[(i, j)]);
            }
            s.push('\n');
        }
    }
    let _ = writeln!(s, "\nresidual RMS");
    for ((name, unit), rms) in outputs.iter().zip(&report.rms) {
        let _ = writeln!(s, "{name:<16} {rms:>13.6e}  {unit}");
    }
    let _ = writeln!(
        s,
        "\nweighted residual variance {:.4} ({} degrees of freedom)",
        report.residual_variance, report.degrees_of_freedom
    );
    let _ = writeln!(
        s,
        "stopped after {} iterations: {}; {} (Gauss–Newton step {:.2e} standard errors)",
        report.iterations,
        report.stop.describe(),
        report.convergence.describe(),
        report.optimality
    );
    s
}

/// `J_sint^1.00 · J_g^-0.12`.
fn combination(c: &[(String, f64)]) -> String {
    c.iter()
        .map(|(n, e)| format!("{n}^{e:.2}"))
        .collect::<Vec<_>>()
        .join(" · ")
}

fn percent(x: f64) -> String {
    if x.is_finite() {
        format!("{:.0} %", 100.0 * x)
    } else {
        "unbounded: the record does not depend on it".into()
    }
}

fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() {
        json!(x)
    } else {
        serde_json::Value::Null
    }
}

fn value(
    model: &Model,
    record: &Record,
    report: &FitReport,
    units: &Units,
    outputs: &[(String, String)],
) -> serde_json::Value {
    let estimates: Vec<_> = estimates_in_units(report, units)
        .into_iter()
        .map(|(name, value, se, start, unit, determined)| {
            json!({
                "name": name,
                "value": value,
                "std_error": finite_or_null(se),
                "start": start,
                "unit": unit,
                "determined": determined,
            })
        })
        .collect();
    let undetermined: Vec<_> = report
        .undetermined
        .iter()
        .map(|u| {
            json!({
                "combination": u.combination.iter().map(|(n, e)| json!({"name": n, "exponent": e})).collect::<Vec<_>>(),
                "relative_std_error": finite_or_null(u.relative_std_error),
                "held": u.held,
            })
        })
        .collect();
    let n = report.correlated.len();
    let correlation: Vec<Vec<serde_json::Value>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| finite_or_null(report.correlation[(i, j)]))
                .collect()
        })
        .collect();
    let rms: Vec<_> = outputs
        .iter()
        .zip(&report.rms)
        .map(|((name, unit), r)| json!({"output": name, "rms": finite_or_null(*r), "unit": unit}))
        .collect();
    json!({
        "model": model.name,
        "samples": record.times.len(),
        "measured_values": record.sample_count(),
        "estimates": estimates,
        "undetermined": undetermined,
        "correlation": {"names": report.correlated, "matrix": correlation},
        "residual_rms": rms,
        "residual_variance": finite_or_null(report.residual_variance),
        "degrees_of_freedom": report.degrees_of_freedom,
        "iterations": report.iterations,
        "stop": report.stop,
        "status": report.convergence,
        "converged": report.convergence.converged(),
        "optimality": finite_or_null(report.optimality),
    })
}
