//! What the FMU tests share: FMPy in a virtual environment of its own, FMUs built with `bgc fmu` into one cargo
//! target directory, and `bgc simulate` runs to compare with.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, Once, OnceLock};

pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

/// Under the workspace's target directory: the FMUs' shared cargo target, the FMUs, the virtual environment.
pub fn scratch() -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target"));
    base.join("fmu-tests")
}

fn run(cmd: &mut Command) -> Output {
    cmd.output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"))
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The Python of a virtual environment with FMPy and libcosimpy from the package registry, made once. A failure
/// to make it fails the test: they are the importers the FMUs are checked against.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = scratch().join("venv");
        let python = venv.join("bin").join("python");
        let ready = |p: &Path| {
            Command::new(p)
                .args(["-c", "import fmpy, numpy, libcosimpy"])
                .output()
                .is_ok_and(|o| o.status.success())
        };
        if !ready(&python) {
            make_venv(&venv, &python);
            assert!(
                ready(&python),
                "fmpy or libcosimpy does not import after pip install"
            );
        }
        python
    })
}

/// Starts making the virtual environment in the background (once), so that it overlaps the FMUs' builds.
fn prepare_python() {
    static STARTED: Once = Once::new();
    STARTED.call_once(|| {
        std::thread::spawn(|| {
            // A failure here is reported by the test that calls `python()` next, which tries again.
            let _ = std::panic::catch_unwind(python);
        });
    });
}

/// A virtual environment at `venv` with FMPy and libcosimpy. The host's pip installs into an environment made
/// without a pip of its own when it can (`pip --python`, pip 22.3 and later), which saves bootstrapping a second
/// pip; otherwise the environment's own pip does.
fn make_venv(venv: &Path, python: &Path) {
    let install = ["install", "--quiet", "--disable-pip-version-check"];
    let packages = ["fmpy", "libcosimpy"];
    let bare = run(Command::new("python3")
        .args(["-m", "venv", "--clear", "--without-pip"])
        .arg(venv));
    if bare.status.success() {
        let host = run(Command::new("python3")
            .args(["-m", "pip", "--python"])
            .arg(python)
            .args(install)
            .args(packages));
        if host.status.success() {
            return;
        }
    }
    let made = run(Command::new("python3")
        .args(["-m", "venv", "--clear"])
        .arg(venv));
    assert!(
        made.status.success(),
        "python3 -m venv {} failed:\n{}",
        venv.display(),
        text(&made.stderr)
    );
    let pip = run(Command::new(python)
        .args(["-m", "pip"])
        .args(install)
        .args(packages));
    assert!(
        pip.status.success(),
        "pip install fmpy libcosimpy failed:\n{}{}",
        text(&pip.stdout),
        text(&pip.stderr)
    );
}

/// The FMU of `model` (a path relative to the workspace) for FMI `version`, built once per test run.
pub fn fmu(model: &str, version: u8) -> PathBuf {
    prepare_python();
    static BUILT: Mutex<Option<HashMap<(String, u8), PathBuf>>> = Mutex::new(None);
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    let map = built.get_or_insert_with(HashMap::new);
    if let Some(p) = map.get(&(model.to_string(), version)) {
        return p.clone();
    }
    let stem = Path::new(model)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let out = scratch().join(format!("{stem}-fmi{version}.fmu"));
    std::fs::create_dir_all(scratch()).unwrap_or_else(|e| panic!("{}: {e}", scratch().display()));
    // The FMU's library at opt-level 1 instead of its release profile's 2: the same code (Rust's floating point
    // does not change with the level), and nalgebra compiles in less time for a test.
    let o = run(Command::new(env!("CARGO_BIN_EXE_bgc"))
        .env("CARGO_PROFILE_RELEASE_OPT_LEVEL", "1")
        .current_dir(workspace())
        .args(["fmu", model, "--fmi", &version.to_string(), "-o"])
        .arg(&out)
        .arg("--target-dir")
        .arg(scratch().join("cargo")));
    assert!(
        o.status.success(),
        "bgc fmu {model} failed:\n{}",
        text(&o.stderr)
    );
    map.insert((model.to_string(), version), out.clone());
    out
}

/// `fmpy validate FMU`: passes only with "No problems found".
pub fn validate(fmu: &Path) {
    let fmpy = python().with_file_name("fmpy");
    let o = run(Command::new(&fmpy).arg("validate").arg(fmu));
    let out = text(&o.stdout);
    assert!(
        o.status.success() && out.contains("No problems found"),
        "fmpy validate {}:\n{out}{}",
        fmu.display(),
        text(&o.stderr)
    );
}

/// A run: the inputs as `bgc simulate` expressions and as FMPy's table, the initial states.
pub struct Scenario {
    pub model: &'static str,
    pub t_end: f64,
    pub dt: f64,
    /// `(name, bgc expression)`.
    pub inputs: &'static [(&'static str, &'static str)],
    /// FMPy's input table: `[t, value of each input]`; a step is two rows at its time.
    pub rows: &'static [&'static [f64]],
    pub x0: &'static [(&'static str, f64)],
    /// The times of the steps (rows there are not compared: the outputs may jump).
    pub jumps: &'static [f64],
}

/// Named columns of a CSV text (header names without their `[unit]`).
pub struct Table {
    pub names: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    pub fn parse(csv: &str) -> Table {
        let mut lines = csv.lines();
        let names = lines
            .next()
            .unwrap_or_default()
            .split(',')
            .map(|h| h.split(" [").next().unwrap_or(h).trim().to_string())
            .collect();
        let rows = lines
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                l.split(',')
                    .map(|v| v.trim().parse().unwrap_or_else(|e| panic!("`{v}`: {e}")))
                    .collect()
            })
            .collect();
        Table { names, rows }
    }

    pub fn column(&self, name: &str) -> Vec<f64> {
        let k = self
            .names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no column `{name}` in {:?}", self.names));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// `bgc simulate` of the scenario with tight tolerances.
pub fn bgc_simulate(s: &Scenario) -> Table {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_bgc"));
    cmd.current_dir(workspace()).args([
        "simulate",
        s.model,
        "--t-end",
        &s.t_end.to_string(),
        "--dt-out",
        &s.dt.to_string(),
        "--rtol",
        "1e-11",
        "--atol",
        "1e-14",
    ]);
    for (name, expr) in s.inputs {
        cmd.arg("--input").arg(format!("{name}={expr}"));
    }
    for (name, v) in s.x0 {
        cmd.arg("--x0").arg(format!("{name}={v}"));
    }
    let o = run(&mut cmd);
    assert!(o.status.success(), "bgc simulate: {}", text(&o.stderr));
    Table::parse(&text(&o.stdout))
}

fn scenario_file(s: &Scenario) -> PathBuf {
    let names: Vec<String> = s.inputs.iter().map(|(n, _)| format!("\"{n}\"")).collect();
    let rows: Vec<String> = s
        .rows
        .iter()
        .map(|r| {
            format!(
                "[{}]",
                r.iter()
                    .map(|v| format!("{v:?}"))
                    .collect::<Vec<_>>()
                    .join(",")
            )
        })
        .collect();
    let start: Vec<String> =
        s.x0.iter()
            .map(|(n, v)| format!("\"{n}\": {v:?}"))
            .collect();
    let json = format!(
        "{{\"inputs\": [{}], \"rows\": [{}], \"start\": {{{}}}}}",
        names.join(","),
        rows.join(","),
        start.join(",")
    );
    let stem = Path::new(s.model)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    static N: AtomicUsize = AtomicUsize::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let path = scratch().join(format!("{stem}-scenario-{}-{n}.json", std::process::id()));
    std::fs::create_dir_all(scratch()).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&path, json).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

fn driver() -> PathBuf {
    workspace().join("bgc/tests/fmu_support/fmpy_driver.py")
}

/// FMPy's simulation of the FMU (`ModelExchange` or `CoSimulation`).
pub fn fmpy_simulate(fmu: &Path, kind: &str, s: &Scenario, rtol: f64) -> Table {
    let scenario = scenario_file(s);
    let o = run(Command::new(python())
        .arg(driver())
        .arg("simulate")
        .arg(fmu)
        .args([
            kind,
            &s.t_end.to_string(),
            &s.dt.to_string(),
            &rtol.to_string(),
        ])
        .arg(&scenario));
    // Written for this run only.
    let _ = std::fs::remove_file(&scenario);
    assert!(o.status.success(), "FMPy {kind}: {}", text(&o.stderr));
    Table::parse(&text(&o.stdout))
}

/// libcosim's Co-Simulation of an FMI 2.0 FMU, the inputs held over each communication step of `s.dt`.
pub fn libcosim_simulate(fmu: &Path, s: &Scenario) -> Table {
    let scenario = scenario_file(s);
    let o = run(Command::new(python())
        .arg(driver())
        .arg("libcosim")
        .arg(fmu)
        .args([&s.t_end.to_string(), &s.dt.to_string()])
        .arg(&scenario));
    // Written for this run only.
    let _ = std::fs::remove_file(&scenario);
    assert!(o.status.success(), "libcosim: {}", text(&o.stderr));
    Table::parse(&text(&o.stdout))
}

/// The largest difference of each output from `bgc simulate`, relative to the output's range in `bgc simulate`,
/// over the rows at common times away from the jumps.
pub fn compare(reference: &Table, fmu: &Table, s: &Scenario) -> Vec<(String, f64)> {
    let t_ref = reference.column("t");
    let t_fmu = fmu.column("time");
    let mut out = Vec::new();
    for name in fmu.names.iter().filter(|n| *n != "time") {
        let r = reference.column(name);
        let f = fmu.column(name);
        let range = r.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v))
            - r.iter().fold(f64::INFINITY, |m, v| m.min(*v));
        let mut worst = 0.0f64;
        let mut compared = 0;
        for (k, t) in t_ref.iter().enumerate() {
            if s.jumps.iter().any(|j| (t - j).abs() < 1e-9) {
                continue;
            }
            // The last row at that time (after an event, FMPy repeats the time).
            let Some(j) = t_fmu.iter().rposition(|tf| (tf - t).abs() < 1e-9) else {
                continue;
            };
            worst = worst.max((f[j] - r[k]).abs() / range.max(1e-300));
            compared += 1;
        }
        assert!(
            compared * 10 >= t_ref.len() * 9,
            "{name}: only {compared} of {} rows at common times",
            t_ref.len()
        );
        out.push((name.clone(), worst));
    }
    out
}

/// FMPy's directional derivatives and central differences, one column per state and input, and the dependencies
/// the description lists per row (`None`: all).
pub struct Jacobians {
    pub dd: Vec<Vec<f64>>,
    pub fd: Vec<Vec<f64>>,
    pub deps: Vec<Option<Vec<usize>>>,
}

pub fn fmpy_jacobian(fmu: &Path, s: &Scenario) -> Jacobians {
    let scenario = scenario_file(s);
    let o = run(Command::new(python())
        .arg(driver())
        .arg("jacobian")
        .arg(fmu)
        .arg(&scenario));
    // Written for this run only.
    let _ = std::fs::remove_file(&scenario);
    assert!(o.status.success(), "FMPy jacobian: {}", text(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&text(&o.stdout)).unwrap_or_else(|e| panic!("{e}"));
    let matrix = |key: &str| -> Vec<Vec<f64>> {
        v[key]
            .as_array()
            .into_iter()
            .flatten()
            .map(|c| {
                c.as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|x| x.as_f64())
                    .collect()
            })
            .collect()
    };
    let deps = v["deps"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|d| {
            d.as_array().map(|cols| {
                cols.iter()
                    .filter_map(|c| c.as_u64().map(|c| c as usize))
                    .collect()
            })
        })
        .collect();
    Jacobians {
        dd: matrix("dd"),
        fd: matrix("fd"),
        deps,
    }
}

/// The driver's calls of the C interface against the standard's rules (`interface` for FMI 2.0, `interface3` for
/// FMI 3.0, in the driver).
pub fn fmpy_interface(fmu: &Path, command: &str) -> serde_json::Value {
    let o = run(Command::new(python()).arg(driver()).arg(command).arg(fmu));
    assert!(o.status.success(), "interface: {}", text(&o.stderr));
    serde_json::from_str(&text(&o.stdout)).unwrap_or_else(|e| panic!("{e}"))
}
