//! The back-support exoskeleton of Shojaei Barjuei, Caldwell & Ortiz (Designs 2020, 4, 53) end to end: model
//! check (Sec. 5.1), LQR with single and double integral action (Eqs. 10–17), observer (Eqs. 4–9), lifting
//! scenario at 1 kHz with noise (Sec. 5.2), margins and disturbance rejection, beside the paper's figures, and the
//! bench identification of the unprinted J_g, k_g, k_s, J_sint (at the paper's sensor bounds and with a realistic
//! encoder; `bench_identification` in the JSON).
//!
//! ```text
//! cargo run --release --example back_support -- [--json PATH] [--out DIR]
//! ```
//!
//! Prints a summary table (each row with its status against the paper and the reason); `--json PATH` writes
//! the figures, the observer retuned by loop transfer recovery included (`recovery`); SVG plots (analogs of
//! Figs. 10–11 and 14–20, and the margins against the recovery weight) go to `--out DIR` (default
//! `target/exo/back_support/`). The computations live in `bgc_workspace::back_support`.

mod bench;
mod charts;
mod figures;
mod plots;
mod table;

use std::path::PathBuf;
use std::process::ExitCode;

use bgc_workspace::back_support::identification::BenchConfig;
use bgc_workspace::back_support::{scenario::ScenarioConfig, study};

struct Args {
    json: Option<PathBuf>,
    out: PathBuf,
}

const USAGE: &str = "usage: back_support [--json PATH] [--out DIR]";

fn parse_args() -> Result<Option<Args>, String> {
    let mut args = Args {
        json: None,
        out: PathBuf::from("target/exo/back_support"),
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--json" => {
                args.json = Some(PathBuf::from(it.next().ok_or("--json needs a path")?));
            }
            "--out" => args.out = PathBuf::from(it.next().ok_or("--out needs a directory")?),
            "-h" | "--help" => return Ok(None),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(Some(args))
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(Some(a)) => a,
        Ok(None) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("error: {e}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let cfg = ScenarioConfig::paper();
    let s = match study(&cfg) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    table::print_table(&s);
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("error: cannot create {}: {e}", args.out.display());
        return ExitCode::FAILURE;
    }
    let bench = serde_json::json!([
        bench::run(
            "paper's sensor bounds",
            &BenchConfig::paper(),
            &args.out.join("bench_paper.csv")
        ),
        bench::run(
            "realistic 17-bit encoder",
            &BenchConfig::realistic(),
            &args.out.join("bench_realistic.csv")
        ),
    ]);
    if let Some(path) = &args.json {
        let mut figures = figures::json(&s);
        if let Some(map) = figures.as_object_mut() {
            map.insert("bench_identification".into(), bench);
        }
        let text = match serde_json::to_string_pretty(&figures) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: cannot serialise the figures: {e}");
                return ExitCode::FAILURE;
            }
        };
        if let Err(e) = std::fs::write(path, text + "\n") {
            eprintln!("error: cannot write {}: {e}", path.display());
            return ExitCode::FAILURE;
        }
        println!("figures written to {}", path.display());
    }
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("error: cannot create {}: {e}", args.out.display());
        return ExitCode::FAILURE;
    }
    match charts::plots(&s, &args.out) {
        Ok(files) => println!("{} plots written to {}", files, args.out.display()),
        Err(e) => {
            eprintln!("error: plotting failed: {e}");
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}
