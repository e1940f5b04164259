//! The generated `state_space` of linear models: in the energy states, in all states when an output reads an
//! integrated flow (as `bgc statespace` prints it), in declared coordinates with `coords`, and the
//! `#[allow(dead_code)]` every generated item carries so that a binary that uses some of them builds under
//! `-D warnings` (the build of `examples/user_drive` checks that in a real crate).

use bgc::codegen::{self, rust};
use bgc::lower::MemoryLoader;
use bgc::span::SourceMap;

fn generate(text: &str) -> String {
    let mut sources = SourceMap::new();
    let root = sources.add("test.bg", text);
    match codegen::compile(&mut sources, root, &mut MemoryLoader::new()) {
        Ok(file) => rust::generate(&file, "test.bg"),
        Err(diags) => panic!(
            "{}",
            bgc::diagnostic::render::to_text(&sources, &diags, false)
        ),
    }
}

/// A mass on a spring pushed by a force; `extra` is added to the model.
fn oscillator(extra: &str) -> String {
    format!(
        "model oscillator {{
    domain translational;
    param m = 2 [kg];
    param k = 800 [N/m];
    param d = 4 [N s/m];
    input F [N];
    Se push = F;
    I mass = m;
    C spring = 1/k;
    R damper = d;
    1 v;
    bond push -> v -> mass, spring, damper;
{extra}
}}
"
    )
}

#[test]
fn an_energy_state_model_gets_its_energy_state_space() {
    let code = generate(&oscillator("    output x [m] = q(spring);"));
    assert!(
        code.contains("pub fn state_space(p: &Params) -> EnergyStateSpace {"),
        "{code}"
    );
    assert!(
        code.contains("SMatrix<f64, N_ENERGY_STATES, N_ENERGY_STATES>,"),
        "{code}"
    );
}

#[test]
fn an_output_that_reads_an_integrated_flow_gets_the_state_space_in_all_states() {
    // `pos` integrates the mass's velocity: the energy states (p_mass, q_spring) do not give the output, so the
    // state space is in all three states, as `bgc statespace` prints it.
    let code = generate(&oscillator(
        "    var pos [m] = int(f(mass));\n    output x [m] = pos;",
    ));
    assert!(code.contains("pub const N_STATES: usize = 3;"), "{code}");
    assert!(
        code.contains("pub fn state_space(p: &Params) -> FullStateSpace {"),
        "{code}"
    );
    assert!(code.contains("SMatrix<f64, N_STATES, N_STATES>,"), "{code}");
    assert!(!code.contains("No `state_space`"), "{code}");
    // d/dt pos = f_mass = p_mass/m, and the output is the integrated flow itself.
    assert!(code.contains("    a[(2, 0)] = 1.0 / p.m;\n"), "{code}");
    assert!(code.contains("    c[(0, 2)] = 1.0;\n"), "{code}");
}

#[test]
fn declared_coordinates_give_state_space_declared_as_well() {
    let code = generate(&oscillator(
        "    var pos [m] = int(f(mass));\n    coords [pos, f(mass)];\n    output x [m] = pos;",
    ));
    assert!(
        code.contains("pub fn state_space(p: &Params) -> FullStateSpace {"),
        "{code}"
    );
    assert!(
        code.contains("pub fn state_space_declared(p: &Params) -> DeclaredStateSpace {"),
        "{code}"
    );
    assert!(code.contains("pub const N_COORDS: usize = 2;"), "{code}");
}

#[test]
fn every_item_allows_dead_code() {
    let code = generate(&oscillator(
        "    var pos [m] = int(f(mass));\n    output x [m] = pos;",
    ));
    let lines: Vec<&str> = code.lines().collect();
    let items = [
        "pub const ",
        "pub type ",
        "pub fn ",
        "pub struct ",
        "pub enum ",
        "impl ",
        "fn ",
    ];
    let mut checked = 0;
    for (k, line) in lines.iter().enumerate() {
        if items.iter().any(|i| line.starts_with(i)) {
            let above = lines[..k]
                .iter()
                .rev()
                .take_while(|l| l.starts_with("#[") || l.starts_with("///"))
                .any(|l| l.starts_with("#[allow(") && l.contains("dead_code"));
            assert!(
                above,
                "line {}: `{line}` without #[allow(dead_code)]",
                k + 1
            );
            checked += 1;
        }
    }
    assert!(checked > 20, "{checked} items");
    // One attribute per item: an item that needs another lint too gets both in one `allow`.
    assert!(!code.contains("#[allow(dead_code)]\n#[allow("), "{code}");
}
