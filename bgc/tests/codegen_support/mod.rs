//! The models the generated-code tests run on: every `.bg` file of `models/` and of the compiler's corpus that
//! compiles, a file with two models and long names (the layout inside `pub mod`s) and a chain of 130 masses (the
//! forms large models take).
#![allow(dead_code)]

pub mod rustc;

use bgc::codegen::{self, rust};
use bgc::lower::MemoryLoader;
use bgc::span::SourceMap;
use std::path::{Path, PathBuf};

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Two models in one file, with names, documentation and expressions long enough to wrap.
pub const TWO_MODELS: &str = r#"
/// A mass on a spring, pushed by a force: the simplest mechanical oscillator there is, with a
/// documentation comment long enough to be wrapped by the generator.
/// - a first point of a list that goes on long enough to need a second line in the generated code
/// - a second point
model first_model_with_a_rather_long_name {
    domain translational;
    param mass_of_the_moving_carriage_in_kilograms = 2 [kg] "the mass of the carriage on the rail, which the force pushes along the rail";
    param type = 800 [N/m] "a parameter whose name is a Rust keyword";
    param Gain_Of_The_Force = 3.14159 [1] "a parameter that looks like pi";
    param reference_force_of_the_actuator = 10 [N] "scales the force inside the sine";
    param damping_time_constant = 0.05 [s] "time constant of the damper";
    input F [N] "force";
    Se push = Gain_Of_The_Force * F * sin(F / reference_force_of_the_actuator) * cos(F / reference_force_of_the_actuator);
    I mass = mass_of_the_moving_carriage_in_kilograms;
    C spring = 1/(type * (1 + Gain_Of_The_Force * 0.5));
    R damper = type * damping_time_constant + 0.1 * mass_of_the_moving_carriage_in_kilograms / damping_time_constant;
    1 v;
    bond push -> v -> mass, spring, damper;
    output x [m] = q(spring) "position";
    output power_into_the_carriage_from_the_force [W] = e(push) * f(v) "power";
}

model second {
    domain electrical;
    param R_s = 10 [Ohm] "resistance";
    param C_s = 1e-3 [F] "capacitance";
    input V [V] "supply";
    Se supply = V;
    R r = R_s;
    C cap = C_s;
    1 loop;
    bond supply -> loop -> r, cap;
}
"#;

/// A chain of `n` masses joined by springs and dampers, pushed at one end: `2n - 1` storages, so that for
/// `n > 128` the stored energy has more terms than one function gets `let`s.
pub fn chain(n: usize) -> String {
    let mut text = String::from(
        "model chain {\n    domain translational;\n    input F [N];\n    Se push = F;\n",
    );
    for i in 0..n {
        text.push_str(&format!(
            "    param m{i} = {} [kg];\n    I mass{i} = m{i};\n    1 v{i};\n",
            1.0 + 0.01 * i as f64
        ));
        if i + 1 < n {
            text.push_str(&format!(
                "    param k{i} = {} [N/m];\n    C spring{i} = 1/k{i};\n    R damper{i} = 0.5;\n    0 j{i};\n    1 rel{i};\n",
                100 + i
            ));
        }
    }
    text.push_str("    bond push -> v0;\n");
    for i in 0..n {
        text.push_str(&format!("    bond v{i} -> mass{i};\n"));
        if i + 1 < n {
            text.push_str(&format!(
                "    bond v{i} -> j{i};\n    bond j{i} -> v{};\n    bond j{i} -> rel{i} -> spring{i}, damper{i};\n",
                i + 1
            ));
        }
    }
    text.push_str("    output x0 [m/s] = f(v0);\n}\n");
    text
}

/// The files the models crate generates (which must compile).
pub const MODELS_CRATE: [&str; 14] = [
    "models/back_support.bg",
    "models/pendulum_rig.bg",
    "models/rehab_leg.bg",
    "bgc/tests/corpus/dc_motor_load.bg",
    "bgc/tests/corpus/gear_train.bg",
    "bgc/tests/corpus/hydraulic_cylinder.bg",
    "bgc/tests/corpus/msd_chain.bg",
    "bgc/tests/corpus/oscillator.bg",
    "bgc/tests/corpus/parallel_rlc.bg",
    "bgc/tests/corpus/pendulum.bg",
    "bgc/tests/corpus/quarter_car.bg",
    "bgc/tests/corpus/resistive_network.bg",
    "bgc/tests/corpus/series_rlc.bg",
    "bgc/tests/corpus/two_tank.bg",
];

/// The generated module of every model file that compiles (the files of [`MODELS_CRATE`] at least), with the
/// runtime's impls or without, named by path relative to the workspace root; the two-model text as
/// `two_models.bg`.
pub fn generated_modules(runtime: bool) -> Vec<(String, String)> {
    let root = workspace();
    let options = rust::Options { runtime };
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in ["models", "models/tests/models", "bgc/tests/corpus"] {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "bg"))
            .collect();
        entries.sort();
        files.extend(entries);
    }
    let mut out = Vec::new();
    for path in files {
        let name = path
            .strip_prefix(&root)
            .unwrap_or(&path)
            .display()
            .to_string();
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut sources = SourceMap::new();
        let id = sources.add(name.as_str(), text);
        if let Ok(compiled) = codegen::compile(&mut sources, id, &mut MemoryLoader::new()) {
            out.push((name.clone(), rust::generate_with(&compiled, &name, options)));
        }
    }
    for must in MODELS_CRATE {
        assert!(
            out.iter().any(|(name, _)| name == must),
            "{must} does not compile"
        );
    }
    for (name, text) in [
        ("two_models.bg", TWO_MODELS.to_string()),
        ("chain.bg", chain(130)),
    ] {
        out.push((name.to_string(), generate_text(name, &text, options)));
    }
    out
}

/// The module generated from `text` (named `name`); panics with the diagnostics if it does not compile.
pub fn generate_text(name: &str, text: &str, options: rust::Options) -> String {
    let mut sources = SourceMap::new();
    let id = sources.add(name, text);
    match codegen::compile(&mut sources, id, &mut MemoryLoader::new()) {
        Ok(compiled) => rust::generate_with(&compiled, name, options),
        Err(diags) => panic!(
            "{}",
            bgc::diagnostic::render::to_text(&sources, &diags, false)
        ),
    }
}

/// A fresh directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = crate::scratch::path(&format!("codegen-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}
