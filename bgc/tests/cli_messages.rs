//! Messages that point at the cause: power directions, forgotten domains, datasheet units, follow-on findings,
//! symbolic entries in the user's parameters, `fmt --check` diffs and the language reference's own examples.

use crate::cli_support;

use cli_support::{bgc, ok_json, temp_model};

#[test]
fn a_reversed_storage_bond_says_it_points_out_and_how_to_turn_it() {
    let path = temp_model(
        "reversed",
        "model m {
    domain translational;
    input F [N];
    Se push = F;
    I mass1 = 1;
    1 v1;
    0 j;
    Sf v2 = 0;
    C spring = 1;
    bond push -> v1;
    bond mass1 -> v1;
    bond v1 -> j -> spring;
    bond j -> v2;
}
",
    );
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("the bond of `mass1` (an `I`) points out of it"),
        "{err}"
    );
    assert!(err.contains("write `bond v1 -> mass1;`"), "{err}");
    assert!(
        err.contains("the bond of source `v2` points into it"),
        "{err}"
    );
    assert!(err.contains("write `bond v2 -> j;`"), "{err}");
    // The old text described the usual convention as if it were the problem.
    assert!(!err.contains("element's bond points into it"), "{err}");
}

/// A DC motor on a voltage source, written without `domain electrical;`: the winding, the inductance and the
/// source take the model's rotational domain.
const MOTOR_WITHOUT_DOMAIN: &str = "model motor {
    domain rotational;
    param R_a = 1 [Ohm];
    param L_a = 1 [mH];
    param k_t = 0.05 [N m/A];
    param J = 1e-5 [kg m^2];
    input u [V];
    Se supply = u;
    1 current;
    R winding = R_a;
    I inductance = L_a;
    GY emf = k_t;
    1 speed;
    I rotor = J;
    bond supply -> current -> winding, inductance;
    bond current -> emf -> speed -> rotor;
}
";

#[test]
fn a_unit_of_another_domain_names_that_domain_and_where_to_declare_it() {
    let path = temp_model("motor_no_domain", MOTOR_WITHOUT_DOMAIN);
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 1);
    assert!(err.contains("in the electrical domain"), "{err}");
    assert!(err.contains("`domain electrical;`"), "{err}");
    // The gyrator: k_t fits electrical to rotational, and reads in both datasheet forms.
    assert!(err.contains("from the electrical to rotational"), "{err}");
    assert!(err.contains("V s (= N m/A)"), "{err}");
    let err = err.replace(&path, "motor.bg");
    insta::assert_snapshot!("motor_without_domain", err);
}

#[test]
fn a_misspelled_name_is_reported_once() {
    let path = temp_model(
        "misspelled",
        "model m {
    domain translational;
    param k_spring = 800 [N/m];
    I mass = 1;
    C spring = 1/k_sprng;
    1 v;
    bond v -> mass;
    bond v -> sprng;
}
",
    );
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown name `k_sprng`"), "{err}");
    assert!(
        err.contains("bond to `sprng`, which does not exist"),
        "{err}"
    );
    // Neither the parameter the name meant nor the element the bond meant is reported again.
    assert!(!err.contains("BG0402"), "{err}");
    assert!(!err.contains("BG0306"), "{err}");
    assert!(err.contains("2 errors, 0 warnings"), "{err}");
}

#[test]
fn symbolic_entries_show_the_parameter_the_user_overrode() {
    let path = temp_model(
        "motor_std",
        "import \"std.bg\";
model drive {
    domain electrical;
    param Rw = 2 [Ohm];
    param kt = 0.1 [N m/A];
    input u [V];
    Se supply = u;
    dc_motor mot(R_a = Rw, k_t = kt);
    bond supply -> mot.v;
}
",
    );
    let v = ok_json(&["statespace", &path, "--symbolic"]);
    let a = v["A"].to_string();
    assert!(a.contains("Rw"), "{a}");
    assert!(!a.contains("mot.R_a"), "{a}");
    assert!(!a.contains("mot.k_t"), "{a}");
    assert!(a.contains("kt"), "{a}");
}

#[test]
fn fmt_check_prints_a_unified_diff() {
    let path = temp_model(
        "unformatted",
        "model m { domain rotational; I rotor = 1; Se s = 1; bond s -> rotor; }\n",
    );
    let before = std::fs::read_to_string(&path).expect("read");
    let (code, out, err) = bgc(&["fmt", "--check", &path]);
    assert_eq!(code, 1);
    assert!(
        out.starts_with(&format!("--- {path}\n+++ {path} (canonical layout)\n@@ ")),
        "{out}"
    );
    assert!(out.contains("\n-model m { domain rotational;"), "{out}");
    assert!(
        out.contains("\n+model m {\n+    domain rotational;\n"),
        "{out}"
    );
    assert!(err.contains("not in the canonical layout"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&path).expect("read"),
        before,
        "--check changed the file"
    );
}

#[test]
fn a_finding_inside_the_standard_library_names_its_path_and_the_users_instance() {
    let path = temp_model(
        "std_gearbox",
        "import \"std.bg\";
model drive {
    domain rotational;
    input omega [rad/s];
    Sf motor = omega;
    gearbox gb(ratio = 50);
    1 w_load;
    I load = 0.1;
    bond motor -> gb.in;
    bond gb.out -> w_load -> load;
}
",
    );
    let (code, _, err) = bgc(&["check", &path]);
    let err = err.replace(&path, "drive.bg");
    // The flow source imposes the speed of the gearbox's input inertia: derivative causality there.
    assert!(err.contains("┌─ bgc/std/std.bg:67:5"), "{err}");
    assert!(err.contains("67 │     I inertia = J_in;"), "{err}");
    assert!(
        err.contains("in instance `gb` (the element `gb.inertia`), declared here"),
        "{err}"
    );
    assert!(err.contains(" 6 │     gearbox gb(ratio = 50);"), "{err}");
    assert!(code == 0 || code == 1, "{err}");
}

/// `bgc check --format json` gives the certain fix of a diagnostic (the ASCII form of a pasted character) in
/// `fix`, for tools that apply it; other diagnostics have none.
#[test]
fn json_diagnostics_carry_their_certain_fix() {
    let path = temp_model(
        "pasted_units",
        "model a { domain rotational; param J = 2 [kg·m²]; param b = 1 [N m s/rad]; Se s = 1; I i = J; \
         R r = bb; 1 j; bond s -> j -> i, r; }\n",
    );
    let (code, out, err) = bgc(&["check", "--format", "json", &path]);
    assert_eq!(code, 1, "{err}");
    let diags: serde_json::Value = serde_json::from_str(&out).unwrap_or_default();
    let fixes: Vec<(&str, Option<&str>)> = diags
        .as_array()
        .map(|a| {
            a.iter()
                .map(|d| (d["code"].as_str().unwrap_or(""), d["fix"].as_str()))
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(
        fixes,
        vec![
            ("BG0104", Some(" ")),
            ("BG0104", Some("^2")),
            ("BG0201", None)
        ]
    );
}

/// A file without a model passed `bgc check` without a word, so an empty or truncated file looked checked. Each file
/// now gets its summary line: what it holds, or that it declares nothing.
#[test]
fn a_file_without_a_model_says_what_it_holds() {
    let dir = crate::scratch::path("no_model_summary");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let files = [
        ("empty.bg", ""),
        ("comments.bg", "// a model will come here\n"),
        (
            "lib.bg",
            "component Spring {\n    domain translational;\n    param k = 1 [N/m];\n    C c = 1/k;\n    0 a;\n    \
             port p = a;\n    bond a -> c;\n}\n",
        ),
        ("uses.bg", "import \"lib.bg\";\n"),
    ];
    let mut args = vec!["check".to_string()];
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
        args.push(path.display().to_string());
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, out, err) = crate::cli_support::bgc(&refs);
    assert_eq!((code, err.as_str()), (0, ""));
    let lines: Vec<&str> = out
        .lines()
        .map(|l| l.rsplit('/').next().unwrap_or(l))
        .collect();
    assert_eq!(
        lines,
        [
            "empty.bg: no model: the file declares nothing",
            "comments.bg: no model: the file declares nothing",
            "lib.bg: no model; 1 component",
            "uses.bg: no model; 1 import",
        ]
    );
}
