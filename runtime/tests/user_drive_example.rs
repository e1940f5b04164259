//! The example crate `examples/user_drive` built as a user's own crate (outside the workspace, its own target
//! directory, `RUSTFLAGS=-D warnings`) and run: the generated `state_space` of a linear model with a `var` output,
//! LQI and Kalman designs against scipy, and the sampled closed loop against the same loop computed by scipy.
//!
//! Reference values (scipy 1.17), from the hand-derived model (states `p_L, p_m, q_s, p_J, θ_L`; `i = p_L/L_a`,
//! `ω_m = p_m/J_m`, `ω_L = p_J/J_L`, shaft torque `k_s q_s + d_s (ω_m/n − ω_L)`):
//!
//! ```python
//! import numpy as np, scipy.linalg as sl
//! R_a, L_a, k_t, J_m, n, k_s, d_s, J_L = 1.2, 2e-3, 0.05, 2e-5, 50.0, 300.0, 0.5, 0.01
//! A = np.array([[-R_a/L_a, -k_t/J_m, 0, 0, 0],
//!               [k_t/L_a, -d_s/(J_m*n*n), -k_s/n, d_s/(n*J_L), 0],
//!               [0, 1/(J_m*n), 0, -1/J_L, 0],
//!               [0, d_s/(n*J_m), k_s, -d_s/J_L, 0],
//!               [0, 0, 0, 1/J_L, 0]])
//! B = np.array([[1.0], [0], [0], [0], [0]]); C = np.array([[0, 0, 0, 0, 1.0], [1/L_a, 0, 0, 0, 0]])
//! Aa = np.block([[A, np.zeros((5, 1))], [-C[:1], np.zeros((1, 1))]]); Ba = np.vstack([B, [[0]]])
//! Q = np.diag([0, 0, 0, 0, 1e3, 1e5]); Rw = np.array([[1.0]])
//! K = np.linalg.solve(Rw, Ba.T @ sl.solve_continuous_are(Aa, Ba, Q, Rw))
//! T = 1e-3; E = sl.expm(np.block([[A, B], [np.zeros((1, 6))]]) * T); Ad, Bd = E[:5, :5], E[:5, 5:]
//! Qd = np.zeros((5, 5)); Qd[0, 0] = (0.1*T)**2; Qd[3, 3] = (0.05*T)**2; Qd[4, 4] = 1e-14
//! Rd = np.diag([1e-4**2, 1e-2**2])
//! P = sl.solve_discrete_are(Ad.T, C.T, Qd, Rd); M = P @ C.T @ np.linalg.inv(C @ P @ C.T + Rd)
//! # the loop of src/main.rs without noise: update, control, integrator, predict; plant exact under ZOH
//! x = np.zeros(5); xh = np.zeros(5); z = 0.0; us = []; th = []
//! for k in range(1500):
//!     y = C @ x; xh = xh + M @ (y - C @ xh); u = -(K[:, :5] @ xh) - K[:, 5:] @ [z]
//!     z += T * (1.0 - y[0]); xh = Ad @ xh + Bd @ u; x = Ad @ x + Bd @ u; us.append(u[0]); th.append(x[4])
//! # final angle 0.99999941, peak angle 1.00141, peak voltage 11.128
//! ```

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `A` and `B` of the hand derivation above.
const A: [[f64; 5]; 5] = [
    [-600.0, -2500.0, 0.0, 0.0, 0.0],
    [25.0, -10.0, -6.0, 1.0, 0.0],
    [0.0, 1000.0, 0.0, -100.0, 0.0],
    [0.0, 500.0, 300.0, -50.0, 0.0],
    [0.0, 0.0, 0.0, 100.0, 0.0],
];
const B: [f64; 5] = [1.0, 0.0, 0.0, 0.0, 0.0];
/// scipy's LQI gain `[K_x, K_z]`.
const K: [f64; 6] = [
    20.08956174769823,
    490.2212917690491,
    54.152896241077826,
    10.703136024228492,
    54.395538179803815,
    -316.22776601683745,
];
/// scipy's innovation gain `M = P Cᵀ (C P Cᵀ + R)⁻¹`, row after row.
const M: [f64; 10] = [
    -0.0003004963477480297,
    0.0019239809853629135,
    0.0045245039846963245,
    -9.288256571960479e-07,
    -0.1449927276598046,
    1.1045233852484849e-05,
    0.19536829058589827,
    3.245041260530265e-06,
    0.18906034208314862,
    -1.5024817387397285e-05,
];
/// scipy's noise-free loop.
const PEAK_ANGLE: f64 = 1.0014105111068503;
const PEAK_VOLTAGE: f64 = 11.128246871541645;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

/// The example's own target directory, under the workspace's.
fn target_dir() -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target"));
    base.join("user_drive")
}

/// `cargo build` of the crate at `dir` as a user's crate: its own target directory, warnings denied. Without
/// debug information or an incremental cache, which the test reads neither of.
fn cargo_build(dir: &Path) -> Output {
    Command::new(env!("CARGO"))
        .args(["build", "--offline", "--quiet"])
        .current_dir(dir)
        .env("CARGO_TARGET_DIR", target_dir())
        .env("RUSTFLAGS", "-D warnings")
        .env("CARGO_PROFILE_DEV_DEBUG", "false")
        .env("CARGO_INCREMENTAL", "0")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTDOCFLAGS")
        .output()
        .unwrap_or_else(|e| panic!("cannot run cargo: {e}"))
}

/// The `name: value` lines of the example's output.
fn values(stdout: &str, name: &str) -> Vec<f64> {
    let prefix = format!("{name}: ");
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("no `{name}` in\n{stdout}"));
    line.split_whitespace()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|e| panic!("`{v}` of `{name}`: {e}"))
        })
        .collect()
}

fn assert_close(what: &str, got: &[f64], expected: &[f64], rel: f64) {
    assert_eq!(got.len(), expected.len(), "{what}: {got:?}");
    let scale = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (g, e)) in got.iter().zip(expected).enumerate() {
        assert!(
            (g - e).abs() <= rel * scale,
            "{what}[{k}] = {g}, expected {e} (within {rel} of {scale})"
        );
    }
}

#[test]
fn the_user_drive_builds_without_warnings_and_tracks_its_reference() {
    let dir = workspace().join("examples/user_drive");
    let build = cargo_build(&dir);
    assert!(
        build.status.success(),
        "the example does not build with -D warnings:\n{}",
        String::from_utf8_lossy(&build.stderr)
    );
    let exe = target_dir()
        .join("debug")
        .join(format!("user-drive{}", std::env::consts::EXE_SUFFIX));
    let run = Command::new(&exe)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", exe.display()));
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );

    // The generated `state_space` has the five states of `bgc statespace`, the integrated flow last.
    assert!(stdout.contains("states: p_inductance p_rotor q_shaft_spring p_load theta_L"));
    let a: Vec<f64> = A.iter().flatten().copied().collect();
    assert_close("A", &values(&stdout, "A"), &a, 1e-12);
    assert_close("B", &values(&stdout, "B"), &B, 1e-12);
    // The symbolic Jacobians at rest are the same matrices.
    assert!(values(&stdout, "state_space minus linearisation")[0] <= 1e-12);

    // The designs agree with scipy's.
    assert_close("K", &values(&stdout, "K"), &K, 1e-6);
    assert_close("M", &values(&stdout, "M"), &M, 1e-5);
    assert!(values(&stdout, "slowest closed-loop pole (real part)")[0] < -10.0);

    // The loop on the generated model (BDF between samples, measurement noise of 1e-4 rad and 0.01 A) ends at
    // the reference and follows scipy's exact sampled loop.
    let final_angle = values(&stdout, "final angle")[0];
    assert!((final_angle - 1.0).abs() < 1e-3, "{stdout}");
    assert!(values(&stdout, "final current")[0].abs() < 0.05, "{stdout}");
    let peak = values(&stdout, "peak angle")[0];
    assert!((peak - PEAK_ANGLE).abs() < 2e-3, "{stdout}");
    let voltage = values(&stdout, "peak voltage")[0];
    assert!(
        (voltage - PEAK_VOLTAGE).abs() < 0.05 * PEAK_VOLTAGE,
        "{stdout}"
    );
    assert!(values(&stdout, "2% settling time")[0] < 0.6, "{stdout}");
    assert!(values(&stdout, "largest angle estimate error (second half)")[0] < 1e-3);
}

#[test]
fn a_build_script_error_is_printed_once() {
    // A copy of the example with a misspelt name in its model, in the example's target directory.
    let dir = target_dir().join("broken_crate");
    std::fs::create_dir_all(dir.join("src")).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let example = workspace().join("examples/user_drive");
    let manifest = std::fs::read_to_string(example.join("Cargo.toml"))
        .unwrap_or_else(|e| panic!("Cargo.toml: {e}"))
        .replace("name = \"user-drive\"", "name = \"broken-drive\"")
        .replace("../../", &format!("{}/", workspace().display()))
        // It lies under the workspace's target directory: a workspace of its own, not a member of this one.
        + "\n[workspace]\n";
    let model = std::fs::read_to_string(example.join("drive.bg"))
        .unwrap_or_else(|e| panic!("drive.bg: {e}"))
        .replace("= int(f(load))", "= int(f(lod))");
    let files = [
        ("Cargo.toml", manifest),
        ("drive.bg", model),
        (
            "build.rs",
            "fn main() -> Result<(), Box<dyn std::error::Error>> {\n    \
             bgc::build::compile(&[\"drive.bg\"])?;\n    Ok(())\n}\n"
                .to_string(),
        ),
        ("src/main.rs", "fn main() {}\n".to_string()),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    std::fs::copy(example.join("Cargo.lock"), dir.join("Cargo.lock"))
        .unwrap_or_else(|e| panic!("Cargo.lock: {e}"));
    let build = cargo_build(&dir);
    let stderr = String::from_utf8_lossy(&build.stderr);
    assert!(!build.status.success(), "{stderr}");
    assert_eq!(stderr.matches("error[BG0201]").count(), 1, "{stderr}");
    assert_eq!(stderr.matches("drive.bg:33:").count(), 1, "{stderr}");
    assert!(!stderr.contains("rendered"), "{stderr}");
    assert!(
        stderr.contains("Error: drive.bg: bgc found errors (shown above)"),
        "{stderr}"
    );
}
