//! The measurement system of a rehabilitation exoskeleton (Yang et al., Sensors 2018, 18, 2588), simulated:
//! the pendulum rig run that measures the sensor variances and sets the fusion weights (Sec. 2.3.3), then the
//! exoskeleton test without load with those weights (Sec. 3.1). Prints E (Eq. 28) of vision, IMU and fusion
//! beside the paper's values and draws the analogs of Figs. 10–12.
//!
//! ```text
//! cargo run --release --example rehab_fusion -- [--seed N] [--json PATH] [--out DIR] [--smoothing-q Q]
//! ```
//!
//! `--smoothing-q Q` adds the scalar estimator of Eqs. 19–21 after the weighted fusion with process variance
//! `Q` [deg²] per sample (left out by default: as a random walk it only adds lag, see the pipeline's docs).

mod plots;

use bgc_workspace::rehab::RehabError;
use bgc_workspace::rehab::experiment::{
    DEG2_PER_RAD2, Figures, SegmentRun, Setup, run_leg, run_rig,
};
use bgc_workspace::rehab::generated::{pendulum_rig_model, rehab_leg_model};
use bgc_workspace::rehab::pipeline::ImuFilterTuning;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// The paper's orderings of E (Eqs. 30, 33 and 35).
const PAPER_ORDER: [&str; 3] = [
    "vision > IMU > fusion",
    "vision > IMU > fusion",
    "IMU > vision > fusion",
];

/// The paper's E values (Eqs. 32 and 34), vision / IMU / fusion [deg²].
const PAPER_THIGH: [f64; 3] = [100.59, 91.33, 27.06];
const PAPER_CALF: [f64; 3] = [185.01, 218.10, 53.38];

struct Args {
    seed: u64,
    json: Option<PathBuf>,
    out: PathBuf,
    smoothing_q_deg2: Option<f64>,
}

const USAGE: &str = "usage: rehab_fusion [--seed N] [--json PATH] [--out DIR] [--smoothing-q DEG2]";

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        seed: 1,
        json: None,
        out: PathBuf::from("target/exo/rehab_fusion"),
        smoothing_q_deg2: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value\n{USAGE}"));
        match flag.as_str() {
            "--seed" => {
                let v = value("--seed")?;
                args.seed = v
                    .parse()
                    .map_err(|_| format!("--seed: `{v}` is not a whole number"))?;
            }
            "--json" => args.json = Some(PathBuf::from(value("--json")?)),
            "--out" => args.out = PathBuf::from(value("--out")?),
            "--smoothing-q" => {
                let v = value("--smoothing-q")?;
                let q: f64 = v
                    .parse()
                    .map_err(|_| format!("--smoothing-q: `{v}` is not a number"))?;
                if !(q.is_finite() && q > 0.0) {
                    return Err(format!(
                        "--smoothing-q must be positive and finite, got {v}"
                    ));
                }
                args.smoothing_q_deg2 = Some(q);
            }
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument `{other}`\n{USAGE}")),
        }
    }
    Ok(args)
}

#[derive(Serialize)]
struct SegmentReport {
    name: &'static str,
    figures_deg2: Figures,
    paper_deg2: Option<[f64; 3]>,
    fusion_beats_both: bool,
    /// The sources by decreasing E, and the paper's order.
    order: String,
    paper_order: &'static str,
    frames_delivered: usize,
    frames_captured: usize,
    samples_in_window: usize,
}

#[derive(Serialize)]
struct Report {
    seed: u64,
    rig_setup: Setup,
    leg_setup: Setup,
    /// Rig-measured variances (Eq. 28) of the IMU and the vision [deg²].
    rig_variances_deg2: [f64; 2],
    /// Rig-measured accelerometer-angle variance, the IMU filter's R [deg²].
    rig_accel_variance_deg2: f64,
    /// The IMU filter as calibrated on the rig (its R is the measured accelerometer-angle variance) [rad²].
    imu_filter: ImuFilterTuning,
    /// Weights of Eq. 27 for the IMU and the vision.
    weights: [f64; 2],
    /// Fused variance of Eq. 25 [deg²].
    fused_variance_deg2: f64,
    segments: Vec<SegmentReport>,
}

fn segment_report(
    run: &SegmentRun,
    window: (f64, f64),
    paper: Option<[f64; 3]>,
    paper_order: &'static str,
) -> SegmentReport {
    let f = run.figures;
    let mut by_e = [
        ("vision", f.e_vision),
        ("IMU", f.e_imu),
        ("fusion", f.e_fusion),
    ];
    by_e.sort_by(|a, b| b.1.total_cmp(&a.1));
    let order = by_e.map(|(name, _)| name).join(" > ");
    SegmentReport {
        order,
        paper_order,
        name: run.name,
        figures_deg2: f,
        paper_deg2: paper,
        fusion_beats_both: f.e_fusion < f.e_imu.min(f.e_vision),
        frames_delivered: run.frames_delivered,
        frames_captured: run.frames_captured,
        samples_in_window: run
            .estimates
            .times
            .iter()
            .filter(|t| **t >= window.0 && **t <= window.1)
            .count(),
    }
}

fn print_report(r: &Report) {
    let rs = &r.rig_setup;
    println!(
        "Rehabilitation-exoskeleton measurement system (Yang et al. 2018), seed {}",
        r.seed
    );
    println!(
        "Rig: stepper-driven pendulum, 30 deg at 0.5 Hz; IMU every {:.2} ms, camera {} frame/s, latency {} ms, \
         {:.0} % frames lost",
        rs.imu.dt * 1e3,
        rs.camera.frame_rate,
        rs.camera.latency * 1e3,
        rs.camera.lost_probability * 100.0
    );
    println!(
        "  measured on the rig (Eq. 28): accelerometer angle {:.2} deg^2 (the IMU filter's R), IMU {:.2} deg^2, \
         vision {:.2} deg^2",
        r.rig_accel_variance_deg2, r.rig_variances_deg2[0], r.rig_variances_deg2[1]
    );
    println!(
        "  weights (Eq. 27): W_IMU = {:.4}, W_vision = {:.4}; fused variance (Eq. 25) {:.2} deg^2",
        r.weights[0], r.weights[1], r.fused_variance_deg2
    );
    println!();
    println!(
        "{:<9} {:>14} {:>8} {:>8} {:>13} | {:>13} {:>8} {:>8}",
        "E [deg^2]", "vision", "IMU", "fusion", "accel(Eq.2)", "paper: vision", "IMU", "fusion"
    );
    for s in &r.segments {
        let f = s.figures_deg2;
        let paper = match s.paper_deg2 {
            Some(p) => format!("{:>13.2} {:>8.2} {:>8.2}", p[0], p[1], p[2]),
            None => "    (Eq. 29 not in the text)".to_string(),
        };
        println!(
            "{:<9} {:>14.2} {:>8.2} {:>8.2} {:>13.2} | {}",
            s.name, f.e_vision, f.e_imu, f.e_fusion, f.e_accel, paper
        );
    }
    println!();
    for s in &r.segments {
        let f = s.figures_deg2;
        println!(
            "{:<8} E_fusion < min(E_IMU, E_vision): {} ({:.2} < {:.2}, ratio {:.2}); order {} (paper: {})",
            s.name,
            if s.fusion_beats_both { "yes" } else { "NO" },
            f.e_fusion,
            f.e_imu.min(f.e_vision),
            f.e_fusion / f.e_imu.min(f.e_vision),
            s.order,
            s.paper_order,
        );
        println!(
            "{:<8} {} of {} frames delivered, {} IMU samples in the window",
            "", s.frames_delivered, s.frames_captured, s.samples_in_window
        );
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let q = args.smoothing_q_deg2.map(|q| q / DEG2_PER_RAD2);
    let rig_setup = Setup {
        smoothing_q: q,
        ..Setup::rig()
    };
    let leg_setup = Setup {
        smoothing_q: q,
        ..Setup::leg()
    };
    let rig = run_rig(&pendulum_rig_model(), &rig_setup, args.seed)?;
    let leg = run_leg(
        &rehab_leg_model(),
        &leg_setup,
        &rig.calibration,
        args.seed.wrapping_add(1),
    )?;
    let [thigh, calf] = &leg;
    let report = Report {
        seed: args.seed,
        rig_setup,
        leg_setup,
        rig_variances_deg2: rig.variances.map(|v| v * DEG2_PER_RAD2),
        rig_accel_variance_deg2: rig.accel_variance * DEG2_PER_RAD2,
        imu_filter: rig.calibration.filter,
        weights: rig.weights,
        fused_variance_deg2: rig.fused_variance * DEG2_PER_RAD2,
        segments: vec![
            segment_report(&rig.segment, rig_setup.window, None, PAPER_ORDER[0]),
            segment_report(thigh, leg_setup.window, Some(PAPER_THIGH), PAPER_ORDER[1]),
            segment_report(calf, leg_setup.window, Some(PAPER_CALF), PAPER_ORDER[2]),
        ],
    };
    print_report(&report);

    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let out = |name: &str| args.out.join(name);
    let full = (0.0, rig_setup.t_end);
    let rig_note = format!(
        "Pendulum rig run (Sec. 2.3.3) that measures the sensor variances and sets the fusion weights; seed {}.",
        args.seed
    );
    let leg_note = format!(
        "Exoskeleton test without load (Sec. 3.1), thigh and calf, fusion weights from the rig run; seed {}.",
        args.seed
    );
    plots::draw(
        &out("fig10_rig_sources.svg"),
        &plots::source_panels(&rig.segment, full),
        (4, 1),
        full,
        "pendulum angle (°)",
        &rig_note,
    )?;
    let zoom = (4.0, 5.0);
    plots::draw(
        &out("fig11_rig_zoom.svg"),
        &[(
            "Fig. 11 analog: rig, 4th to 5th second".to_string(),
            plots::angle_curves(&rig.segment, zoom),
        )],
        (1, 1),
        zoom,
        "pendulum angle (°)",
        &rig_note,
    )?;
    let cycles = (9.0, 15.0);
    plots::draw(
        &out("fig12_leg.svg"),
        &[
            (
                "Fig. 12 analog: thigh".to_string(),
                plots::angle_curves(thigh, cycles),
            ),
            (
                "Fig. 12 analog: calf".to_string(),
                plots::angle_curves(calf, cycles),
            ),
        ],
        (1, 2),
        cycles,
        "segment angle from vertical (°)",
        &leg_note,
    )?;
    let rig_errors = (2.0, 8.0);
    plots::draw(
        &out("errors_rig.svg"),
        &[(
            "Rig: error of each source".to_string(),
            plots::error_curves(&rig.segment, rig_errors),
        )],
        (1, 1),
        rig_errors,
        "estimate − standard (°)",
        &rig_note,
    )?;
    plots::draw(
        &out("errors_leg.svg"),
        &[
            (
                "Thigh: error of each source".to_string(),
                plots::error_curves(thigh, cycles),
            ),
            (
                "Calf: error of each source".to_string(),
                plots::error_curves(calf, cycles),
            ),
        ],
        (2, 1),
        cycles,
        "estimate − standard (°)",
        &leg_note,
    )?;
    println!("\nplots in {}", args.out.display());
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        println!("figures in {}", path.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(msg) => {
            eprintln!("{msg}");
            return ExitCode::from(2);
        }
    };
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let kind = if e.downcast_ref::<RehabError>().is_some() {
                "simulation"
            } else {
                "output"
            };
            eprintln!("rehab_fusion: {kind} error: {e}");
            ExitCode::FAILURE
        }
    }
}
