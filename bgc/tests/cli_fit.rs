//! `bgc fit`, run as a user would: the estimate on a fixed record against SciPy's `least_squares` on the same
//! objective, an unidentifiable parameter, and records that must be refused with the row or column named.

use crate::cli_support;

use cli_support::{bgc, repo};
use serde_json::Value;

/// Writes `text` to a file of the tests' scratch directory and returns its path.
fn temp_file(name: &str, text: &str) -> String {
    let path = crate::scratch::path(&format!("fit-{name}"));
    std::fs::write(&path, text).expect("temporary file written");
    path.display().to_string()
}

fn fit_json(args: &[&str]) -> Value {
    let mut all = vec!["fit"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    let (code, out, err) = bgc(&all);
    assert_eq!(code, 0, "stderr: {err}\nstdout: {out}");
    serde_json::from_str(&out).expect("valid JSON")
}

fn estimate<'a>(v: &'a Value, name: &str) -> &'a Value {
    v["estimates"]
        .as_array()
        .and_then(|a| a.iter().find(|e| e["name"] == name))
        .unwrap_or_else(|| panic!("no estimate of {name} in {v}"))
}

/// The pendulum rig's `theta_pend` and `omega_pend` for 1.2 s from rest at J_p = 0.012 kg m², d_s = 0.2 N m s/rad,
/// with Gaussian noise σ = 2e-3 rad and 2e-2 rad/s (seed 7), made by the script below.
const PENDULUM_RECORD: &str = "\
t,theta_pend,omega_pend
0,2.4603067149651487e-06,-0.0092661515307683028
0.02,0.0092169379978120115,0.97720225250264336
0.040000000000000001,0.039336970352460601,2.0682157372014123
0.059999999999999998,0.085946330108458757,2.5371807061384737
0.080000000000000002,0.13550779300675911,2.2092904256794337
0.10000000000000001,0.17187807445205955,1.5397934955387047
0.12,0.19876323197678805,1.0451841392857344
0.14000000000000001,0.22052186995016229,0.94566574679028981
0.16,0.23876189311266191,1.232230006716704
0.17999999999999999,0.26659979983852972,1.5513435730156295
0.20000000000000001,0.30073164657642598,1.5671945018089601
0.22,0.33116867913960574,1.4222935142582096
0.23999999999999999,0.35656150402692882,1.1551725593469393
0.26000000000000001,0.37535749966280996,0.97595735975670705
0.28000000000000003,0.39527593699234809,0.89672357665962654
0.29999999999999999,0.41455463309253904,0.90095194409587132
0.32000000000000001,0.42890254669653405,0.91936194065292742
0.34000000000000002,0.44880839857406413,0.86699972942974335
0.35999999999999999,0.46215455690824031,0.77238232460436573
0.38,0.4766367712578673,0.57566906879682933
0.40000000000000002,0.48580638081054084,0.44382072705084913
0.41999999999999998,0.49703335021242423,0.36511225151911408
0.44,0.50145612265433059,0.29014404426474522
0.46000000000000002,0.50971960989383513,0.21920749065254802
0.47999999999999998,0.51306833328526635,0.10789719318287626
0.5,0.51385910655700495,0.014796435116890824
0.52000000000000002,0.50827976861891155,-0.11541268974342361
0.54000000000000004,0.50895835373187415,-0.19551393667558636
0.56000000000000005,0.50456291933635655,-0.30344504765314384
0.57999999999999996,0.49766469504104655,-0.40539523924906362
0.59999999999999998,0.48540304158131498,-0.4798216956113795
0.62,0.47671811047478768,-0.59355474418443577
0.64000000000000001,0.46300733897559648,-0.66343136625170351
0.66000000000000003,0.44868488752824759,-0.78113262304330111
0.68000000000000005,0.4358868800819663,-0.85978006902265303
0.69999999999999996,0.41388192096840704,-0.97995583233817252
0.71999999999999997,0.39557530851519046,-1.023809303835733
0.73999999999999999,0.37605865581824244,-1.1376720744382887
0.76000000000000001,0.35033012715191658,-1.215710622885261
0.78000000000000003,0.3270842066913881,-1.2494633234355088
0.80000000000000004,0.30201384405577253,-1.3251714471517331
0.81999999999999995,0.27518978080872886,-1.3615036297574026
0.83999999999999997,0.2447963545396869,-1.3707965297738955
0.85999999999999999,0.21862840194514899,-1.4770059469686145
0.88,0.19158571346732359,-1.5120448670240487
0.90000000000000002,0.15543347541942226,-1.5294874322181049
0.92000000000000004,0.12927931437100365,-1.5523081062285251
0.93999999999999995,0.096320224074554026,-1.5882013766622802
0.95999999999999996,0.062934494347214293,-1.6047379776872999
0.97999999999999998,0.036102183626357032,-1.5958360431805632
1,0.0013898122182396269,-1.6022650266070801
1.02,-0.034762333326394654,-1.6298964212743232
1.04,-0.06431412941843688,-1.6012906564430835
1.0600000000000001,-0.095157973560469081,-1.5833802821572502
1.0800000000000001,-0.12816277207696669,-1.5833479157979076
1.1000000000000001,-0.15739419672474722,-1.5289888480298042
1.1200000000000001,-0.18924464461856919,-1.5171225361126328
1.1399999999999999,-0.21738441113685783,-1.4403537743540165
1.1599999999999999,-0.24458831238555839,-1.410062205629296
1.1799999999999999,-0.27659024896983758,-1.3607515482791126
1.2,-0.30152504807992503,-1.3176477075645041
";

// The reference: SciPy 1.x `least_squares` on the residuals ((θ − θ_meas)/σ_θ, (ω − ω_meas)/σ_ω) over ln J_p and
// ln d_s, from J_p = 1.3 · 0.012 and d_s = 0.7 · 0.2, simulating the rig's equations by DOP853 at rtol 1e-12.
// It printed J_p 0.01210337751724493, d_s 0.20583616074856637, standard errors 5.4650899772506793e-05 and
// 0.002700788139459535, residual variance 0.729217313791864, correlation 0.35688489140589963. The script:
//
//     # Reference for bgc/tests/cli_fit.rs: a noisy record of the pendulum rig (models/pendulum_rig.bg) and the
//     # weighted least-squares estimate of J_p and d_s by SciPy's least_squares on the same objective.
//     import numpy as np
//     from scipy.integrate import solve_ivp
//     from scipy.optimize import least_squares
//
//     A = np.deg2rad(30.0); T = 2.0; k = 25.0; b = 0.002; m = 0.35; l = 0.18; g = 9.81
//     J_TRUE, D_TRUE = 0.012, 0.2
//     S_TH, S_OM = 2e-3, 2e-2
//     times = np.round(np.arange(0, 61) * 0.02, 10)
//
//     def rhs(t, x, J, d):
//         q, p, th, thm = x
//         fs = A * 2 * np.pi / T * np.cos(2 * np.pi * t / T)
//         fp = p / J
//         return [fs - fp, -m * g * l * np.sin(th) - b * fp + k * q + d * (fs - fp), fp, fs]
//
//     def outputs(J, d):
//         s = solve_ivp(rhs, (0, times[-1]), [0, 0, 0, 0], t_eval=times, args=(J, d), rtol=1e-12, atol=1e-14,
//                       method="DOP853")
//         return s.y[2], s.y[1] / J
//
//     th, om = outputs(J_TRUE, D_TRUE)
//     rng = np.random.default_rng(7)
//     th_m = th + S_TH * rng.standard_normal(len(times))
//     om_m = om + S_OM * rng.standard_normal(len(times))
//     # Cells written with 17 significant digits: the record the test reads is the one fitted here.
//     th_m = np.array([float(f"{v:.17g}") for v in th_m]); om_m = np.array([float(f"{v:.17g}") for v in om_m])
//     print("t,theta_pend,omega_pend")
//     for t, a, c in zip(times, th_m, om_m):
//         print(f"{t:.17g},{a:.17g},{c:.17g}")
//
//     def residuals(z):
//         J, d = np.exp(z)
//         a, c = outputs(J, d)
//         return np.concatenate([(a - th_m) / S_TH, (c - om_m) / S_OM])
//
//     r = least_squares(residuals, np.log([0.012 * 1.3, 0.2 * 0.7]), xtol=1e-15, ftol=1e-15, gtol=1e-15,
//                       diff_step=1e-7)
//     J, d = np.exp(r.x)
//     jac = r.jac / np.array([J, d])  # d r / d theta
//     s2 = 2 * r.cost / (len(r.fun) - 2)
//     cov = s2 * np.linalg.inv(jac.T @ jac)
//     print("# J_p", repr(J), "d_s", repr(d))
//     print("# se", repr(np.sqrt(cov[0, 0])), repr(np.sqrt(cov[1, 1])), "s2", repr(s2), "corr", repr(cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])))

/// The fit of the SciPy reference below: `J_p` and `d_s` from the record at `data`, weighted by its noise.
fn pendulum_fit(data: &str) -> Value {
    fit_json(&[
        &repo("models/pendulum_rig.bg"),
        "--data",
        data,
        "--free",
        "J_p,d_s",
        "--param",
        "J_p=0.0156",
        "--param",
        "d_s=0.14",
        "--weight",
        "theta_pend=250000",
        "--weight",
        "omega_pend=2500",
    ])
}

#[test]
fn pendulum_estimate_agrees_with_scipy_least_squares() {
    let data = temp_file("pendulum.csv", PENDULUM_RECORD);
    let v = pendulum_fit(&data);
    let close = |got: f64, want: f64, rel: f64| {
        assert!(
            (got - want).abs() <= rel * want.abs(),
            "got {got}, want {want}"
        );
    };
    let j = estimate(&v, "J_p");
    let d = estimate(&v, "d_s");
    close(j["value"].as_f64().unwrap(), 0.01210337751724493, 1e-6);
    close(d["value"].as_f64().unwrap(), 0.20583616074856637, 1e-5);
    close(
        j["std_error"].as_f64().unwrap(),
        5.4650899772506793e-05,
        1e-3,
    );
    close(d["std_error"].as_f64().unwrap(), 0.002700788139459535, 1e-3);
    close(
        v["residual_variance"].as_f64().unwrap(),
        0.729217313791864,
        1e-5,
    );
    close(
        v["correlation"]["matrix"][0][1].as_f64().unwrap(),
        0.35688489140589963,
        1e-3,
    );
    assert_eq!(v["converged"], true);
}

/// The pendulum record as spreadsheets and data tools export it: every cell in quotes (`csv.QUOTE_ALL`, MATLAB's
/// `writetable` of text), and with `;` between cells and decimal commas (a spreadsheet where the decimal separator
/// is a comma). Both said "the record's header: `\"t\"`: write the unit once, in brackets at the end"; both now
/// give the estimates of the plain record.
#[test]
fn a_record_in_quotes_or_with_decimal_commas_is_read_as_the_plain_one() {
    let quoted: String = PENDULUM_RECORD
        .lines()
        .map(|l| {
            let cells: Vec<String> = l.split(',').map(|c| format!("\"{c}\"")).collect();
            cells.join(",") + "\n"
        })
        .collect();
    let semicolons: String = PENDULUM_RECORD
        .lines()
        .map(|l| l.replace(',', ";").replace('.', ",") + "\n")
        .collect();
    for (name, text) in [("quoted", quoted), ("semicolons", semicolons)] {
        let data = temp_file(&format!("pendulum_{name}.csv"), &text);
        let v = pendulum_fit(&data);
        let j = estimate(&v, "J_p")["value"].as_f64().unwrap_or(f64::NAN);
        let d = estimate(&v, "d_s")["value"].as_f64().unwrap_or(f64::NAN);
        assert!(
            (j - 0.01210337751724493).abs() <= 1e-6 * 0.0121,
            "{name}: {v}"
        );
        assert!(
            (d - 0.20583616074856637).abs() <= 1e-5 * 0.206,
            "{name}: {v}"
        );
    }
}

/// `bgc simulate` writes its header with units (`t [s],x [m]`); a record with such a header said "the record
/// has no `t` column". A header cell may now carry a unit in brackets, and the column is converted to the model's
/// unit: the pendulum record in milliseconds and degrees gives the estimate of the record in seconds and radians.
#[test]
fn a_record_with_units_in_its_header_is_converted_to_the_model_units() {
    let mut converted = String::from("t [ms],theta_pend [deg],omega_pend [rad/s]\n");
    for line in PENDULUM_RECORD.lines().skip(1) {
        let v: Vec<f64> = line.split(',').filter_map(|c| c.parse().ok()).collect();
        if let [t, theta, omega] = v[..] {
            let deg = theta.to_degrees();
            converted.push_str(&format!("{},{deg},{omega}\n", t * 1e3));
        }
    }
    let data = temp_file("pendulum_units.csv", &converted);
    let v = pendulum_fit(&data);
    let j = estimate(&v, "J_p")["value"].as_f64().unwrap_or(f64::NAN);
    let d = estimate(&v, "d_s")["value"].as_f64().unwrap_or(f64::NAN);
    assert!((j - 0.01210337751724493).abs() <= 1e-6 * 0.0121, "{v}");
    assert!((d - 0.20583616074856637).abs() <= 1e-5 * 0.206, "{v}");
    // A unit of another dimension, and a column `bgc simulate` writes that a fit does not read.
    let model = repo("models/pendulum_rig.bg");
    let wrong = "t [s],theta_pend [s]\n0,0\n1,0\n";
    let (code, err) = refused(&model, wrong, "J_p");
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("the record's column `theta_pend` is in [rad]")
            && err.contains("but [s] is in"),
        "{err}"
    );
    let simulated = "t [s],theta_pend [rad],energy [J]\n0,0,0\n1,0,0\n";
    let (code, err) = refused(&model, simulated, "J_p");
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("`energy` is a column of `bgc simulate`"),
        "{err}"
    );
}

#[test]
fn a_product_the_record_cannot_split_is_named_and_held() {
    // Gravity enters only as m_p g l_p: the record determines m_p l_p, not m_p / l_p.
    let data = temp_file("pendulum-product.csv", PENDULUM_RECORD);
    let v = fit_json(&[
        &repo("models/pendulum_rig.bg"),
        "--data",
        &data,
        "--free",
        "m_p,l_p,J_p",
    ]);
    let undetermined = v["undetermined"].as_array().expect("a list");
    assert_eq!(undetermined.len(), 1, "{v}");
    let combo = undetermined[0]["combination"].as_array().unwrap();
    let names: Vec<&str> = combo.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert!(
        names.contains(&"m_p") && names.contains(&"l_p"),
        "{combo:?}"
    );
    // m_p / l_p: exponents of opposite sign and equal size.
    let exps: Vec<f64> = combo
        .iter()
        .map(|c| c["exponent"].as_f64().unwrap())
        .collect();
    assert!((exps[0] + exps[1]).abs() < 1e-3, "{exps:?}");
    let held = undetermined[0]["held"].as_str().unwrap();
    assert_eq!(estimate(&v, held)["determined"], false);
    assert!(estimate(&v, held)["std_error"].is_null());
    assert_eq!(estimate(&v, "J_p")["determined"], true);
}

/// Runs `bgc fit` on `model` with a record and returns the exit code and standard error.
fn refused(model: &str, record: &str, free: &str) -> (i32, String) {
    // One file per call: tests run in parallel, and two records of one length (the name this had) overwrote each
    // other between writing and reading.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let data = temp_file(&format!("bad-{call}.csv"), record);
    let (code, _, err) = bgc(&["fit", model, "--data", &data, "--free", free]);
    (code, err)
}

#[test]
fn bad_records_are_refused_with_the_row_or_column_named() {
    let pend = repo("models/pendulum_rig.bg");
    let (code, err) = refused(&pend, "t,theta_pend\n0,0\n0.1,NaN\n0.2,0.1\n", "J_p");
    assert_eq!(code, 1);
    assert!(
        err.contains("line 3") && err.contains("theta_pend") && err.contains("NaN"),
        "{err}"
    );
    let (code, err) = refused(&pend, "t,theta_pend\n0,0\n0.2,0.1\n0.1,0.2\n", "J_p");
    assert_eq!(code, 1);
    assert!(
        err.contains("line 4") && err.contains("strictly increasing"),
        "{err}"
    );
    let (code, err) = refused(&pend, "t,theta_pend,speed\n0,0,1\n0.1,0,1\n", "J_p");
    assert_eq!(code, 1);
    assert!(
        err.contains("column 3 `speed`") && err.contains("no input or output"),
        "{err}"
    );
    let (code, err) = refused(&pend, "secs,theta_pend\n0,0\n0.1,0\n", "J_p");
    assert_eq!(code, 1);
    assert!(err.contains("no `t` (or `time`) column"), "{err}");
    // back_support has inputs tau_m and omega_h: both must be in the record.
    let back = repo("models/back_support.bg");
    let (code, err) = refused(&back, "t,tau_m,omega_m\n0,0,0\n0.1,0,0\n", "J_g");
    assert_eq!(code, 1);
    assert!(err.contains("model input `omega_h`"), "{err}");
    let (code, err) = refused(&pend, "t,theta_pend\n0,0\n0.1,\n", "J_p");
    assert_eq!(code, 1);
    assert!(err.contains("measured values"), "{err}");
    let (code, err) = refused(&pend, "t,theta_pend\n0,0\n0.1,0\n0.2,0\n", "J_q");
    assert_eq!(code, 1);
    assert!(
        err.contains("--free: unknown parameter `J_q` (did you mean `J_p`?)"),
        "{err}"
    );
    // A state, an output or a repeated name in --free says what it is.
    let record = "t,theta_pend\n0,0\n0.1,0\n0.2,0\n";
    for (free, said) in [
        (
            "theta",
            "`theta` is a state, not a parameter; its initial value is fitted with --free-x0",
        ),
        (
            "theta_pend",
            "`theta_pend` is an output of the model, not a parameter",
        ),
        (
            "J_p,d_s,J_p",
            "--free names parameter `J_p` twice (at places 1 and 3)",
        ),
    ] {
        let (code, err) = refused(&pend, record, free);
        assert_eq!(code, 1, "{free}");
        assert!(err.contains(said), "{free}: {err}");
    }
}

#[test]
fn a_fit_that_stalls_is_reported_and_exits_with_3() {
    // A record of zeros: the rig, driven by its stepper, cannot stay at rest for any positive J_p and d_s; the
    // iteration drives J_p towards zero and stops moving far from any minimum.
    let mut zeros = String::from("t,theta_pend,omega_pend\n");
    for k in 0..61 {
        zeros.push_str(&format!("{},0,0\n", 0.02 * k as f64));
    }
    let data = temp_file("zeros.csv", &zeros);
    let (code, out, err) = bgc(&[
        "fit",
        &repo("models/pendulum_rig.bg"),
        "--data",
        &data,
        "--free",
        "J_p,d_s",
        "--format",
        "json",
    ]);
    assert_eq!(code, 3, "stderr: {err}\nstdout: {out}");
    assert!(err.contains("stalled"), "{err}");
    let v: Value = serde_json::from_str(&out).expect("the report is printed");
    assert_eq!(v["status"], "stalled");
    assert_eq!(v["converged"], false);
    assert!(v["optimality"].as_f64().unwrap() > 0.01, "{v}");
    // The statistics of a point that is no minimum hold nothing, but the quantities they cannot vouch for are
    // flagged.
    let undetermined = v["undetermined"].as_array().expect("a list");
    assert!(!undetermined.is_empty(), "{v}");
    assert!(undetermined.iter().all(|u| u["held"].is_null()), "{v}");
    assert_eq!(estimate(&v, "J_p")["determined"], false);
}

/// A record that the model reproduces exactly (a divider's current `v/40`, computed as `v * 0.025`, which rounds
/// differently from the model) reached r1 = 10 (r2 = 30) and was reported "stalled (not a minimum)", exit 3: there
/// the residuals are rounding errors, and the Gauss–Newton step in their standard error (3.5) measures nothing.
/// It is an exact fit, converged.
#[test]
fn a_record_the_model_reproduces_exactly_is_a_converged_fit() {
    let mut record = String::from("t,v,i\n");
    for k in 0..50 {
        let v = 1.0 + k as f64 * 0.1;
        record.push_str(&format!("{},{v},{}\n", 0.01 * k as f64, v * 0.025));
    }
    let data = temp_file("divider_exact.csv", &record);
    let model = repo("bgc/tests/fmu_support/no_states.bg");
    for start in ["r1=10", "r1=3"] {
        let v = fit_json(&[&model, "--data", &data, "--free", "r1", "--param", start]);
        assert_eq!(v["status"], "converged", "{start}: {v}");
        assert_eq!(v["optimality"], 0.0, "{start}: {v}");
        let r1 = estimate(&v, "r1")["value"].as_f64().unwrap_or(f64::NAN);
        assert!((r1 - 10.0).abs() <= 1e-12, "{start}: {v}");
    }
}

#[test]
fn a_linear_model_with_held_inputs_is_fitted_on_the_exact_path() {
    // The back-support drive (linear) answering a held torque step, simulated by `bgc simulate` at the defaults
    // (J_g = 4e-5 kg m², k_g = 26400 N m/rad) and measured without noise: the fit from 10 % off must come back
    // to the simulated values (to the simulation's tolerance) and converge.
    let (code, sim, err) = bgc(&[
        "simulate",
        &repo("models/back_support.bg"),
        "--t-end",
        "0.2",
        "--dt-out",
        "0.001",
        "--input",
        "tau_m=0.1*step(0.01)",
        "--input",
        "omega_h=0",
        "--rtol",
        "1e-10",
    ]);
    assert_eq!(code, 0, "{err}");
    let mut lines = sim.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.split(' ').next() == Some(name))
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (t, w, tau) = (col("t"), col("omega_m"), col("tau_s"));
    let mut csv = String::from("t,tau_m,omega_h,omega_m,tau_s\n");
    for line in lines {
        let cells: Vec<f64> = line
            .split(',')
            .map(|c| c.parse().expect("a number"))
            .collect();
        let u = if cells[t] >= 0.01 - 1e-12 { 0.1 } else { 0.0 };
        csv.push_str(&format!("{},{u},0,{},{}\n", cells[t], cells[w], cells[tau]));
    }
    let data = temp_file("back-support-step.csv", &csv);
    let v = fit_json(&[
        &repo("models/back_support.bg"),
        "--data",
        &data,
        "--free",
        "J_g,k_g",
        "--param",
        "J_g=4.4e-5",
        "--param",
        "k_g=23760",
    ]);
    assert_eq!(v["status"], "converged", "{v}");
    let j_g = estimate(&v, "J_g")["value"].as_f64().unwrap();
    let k_g = estimate(&v, "k_g")["value"].as_f64().unwrap();
    assert!((j_g / 4e-5 - 1.0).abs() < 1e-5, "J_g = {j_g}");
    assert!((k_g / 26400.0 - 1.0).abs() < 1e-5, "k_g = {k_g}");
}
