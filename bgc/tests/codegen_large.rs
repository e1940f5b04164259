//! A large model's generated module: its long bodies split into parts of bounded size, its state space as
//! entries rather than `N²` matrices on the stack, and `validate` checking each distinct element value once. The
//! module of a 600-state chain is compiled and run on a thread with the default 2 MiB stack, on which its
//! `state_space` (an `A` of 600² · 8 bytes = 2.9 MB) used to overflow.

use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch};
use crate::equations_support::families::{self, benchmark_chain};
use crate::loops_globalised::LIBM_STD;
use bgc::codegen::rust::Options;

const MASSES: usize = 300;
const STATES: usize = 2 * MASSES;
/// The parameters and the point the program evaluates at.
const M: f64 = 2.0;
const B: f64 = 0.3;
const K: f64 = 5.0;
const U: f64 = 1.5;

/// The state of the program: `x_i = 0.01 (i + 1) (-1)^i`.
fn state(i: usize) -> f64 {
    let sign = if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    0.01 * (i + 1) as f64 * sign
}

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("chain.module");
}

fn state(i: usize) -> f64 {
    let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
    0.01 * (i + 1) as f64 * sign
}

fn run() {
    let p = model::Params { m: 2.0, b: 0.3, k: 5.0 };
    let mut x = model::State::zeros();
    for i in 0..model::N_STATES {
        x[i] = state(i);
    }
    let mut u = model::Inputs::zeros();
    u[0] = 1.5;
    let dx = model::rhs(&p, 0.0, &x, &u);
    // A x + B u from the entries, and how many each matrix has.
    let mut ax = vec![0.0; model::N_STATES];
    let mut counts = [0usize; 4];
    model::state_space_entries(&p, &mut |m, r, c, v| {
        let k = (m as u8 - b'A') as usize;
        counts[k] += 1;
        match m {
            'A' => ax[r] += v * x[c],
            'B' => ax[r] += v * u[c],
            _ => {}
        }
    });
    // ∂f/∂x x from the triplets.
    let mut values: Box<[f64; model::JAC_X_NNZ]> =
        vec![0.0; model::JAC_X_NNZ].into_boxed_slice().try_into().unwrap();
    model::jac_x_sparse_into(&p, 0.0, &x, &u, &mut values);
    let mut jx = vec![0.0; model::N_STATES];
    for k in 0..model::JAC_X_NNZ {
        jx[model::JAC_X_ROWS[k]] += values[k] * x[model::JAC_X_COLS[k]];
    }
    for i in 0..model::N_STATES {
        println!("{:e} {:e} {:e}", dx[i], ax[i], jx[i]);
    }
    println!("counts {} {} {} {}", counts[0], counts[1], counts[2], counts[3]);
    println!("energy {:e} {:e}", model::stored_energy(&p, 0.0, &x, &u), model::dissipated_power(&p, 0.0, &x, &u));
    let bad = model::Params { m: -1.0, ..p };
    match bad.validate() {
        Err(e) => println!("error {e}"),
        Ok(()) => println!("error none"),
    }
}

fn main() {
    // A spawned thread's default stack, whatever `RUST_MIN_STACK` says.
    let worker = std::thread::Builder::new().stack_size(2 << 20).spawn(run).unwrap();
    worker.join().unwrap();
}
"#;

/// `f(x, u)` of [`shared_chain`] by hand: `v_i = p_i/m`; `q̇_wall = v_1`, `q̇_spring_i = v_i − v_{i+1}`;
/// `ṗ_i = (u − k q_wall for i = 1, else k q_spring_{i−1}) − b v_i − (k q_spring_i for i < n)`.
fn hand_rates(x: &[f64]) -> Vec<f64> {
    let p = |i: usize| x[2 * i - 1];
    let q_spring = |i: usize| x[2 * i];
    let v = |i: usize| p(i) / M;
    let mut f = vec![0.0; STATES];
    f[0] = v(1);
    for i in 1..=MASSES {
        let incoming = if i == 1 {
            U - K * x[0]
        } else {
            K * q_spring(i - 1)
        };
        let outgoing = if i < MASSES { K * q_spring(i) } else { 0.0 };
        f[2 * i - 1] = incoming - B * v(i) - outgoing;
        if i < MASSES {
            f[2 * i] = v(i) - v(i + 1);
        }
    }
    f
}

#[test]
fn a_large_chain_runs_on_a_default_thread_stack_with_the_hand_derived_rates() {
    let code = generate_text(
        "chain.bg",
        &benchmark_chain(MASSES),
        Options { runtime: false },
    );
    assert!(code.contains(&format!("pub const N_STATES: usize = {STATES};")));
    // No `N²` matrix is declared: the state space comes as entries.
    assert!(!code.contains("pub fn state_space("), "a dense state space");
    assert!(code.contains("pub fn state_space_entries("));
    // Bodies are split: the Jacobian calls its parts, and no function is longer than a few hundred statements.
    assert!(code.contains("fn jac_x_part_1("), "jac_x_into is not split");
    let longest = longest_function(&code);
    assert!(longest.1 < 1500, "`{}` has {} lines", longest.0, longest.1);

    let dir = scratch("large-chain");
    let printed = build_and_run(&dir, "chain", &code, MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let lines: Vec<&str> = printed.lines().collect();
    assert_eq!(
        lines.len(),
        STATES + 3,
        "the program stopped early:\n{printed}"
    );
    let x: Vec<f64> = (0..STATES).map(state).collect();
    let expected = hand_rates(&x);
    for (i, (line, e)) in lines.iter().zip(&expected).enumerate() {
        let values: Vec<f64> = line
            .split_whitespace()
            .map(|v| v.parse().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(values.len(), 3, "{line}");
        // rhs, A x + B u, and ∂f/∂x x (the model is linear and `u` enters only ṗ_1).
        let jx_expected = if i == 1 { e - U } else { *e };
        for (v, want) in values.iter().zip([*e, *e, jx_expected]) {
            assert!(
                (v - want).abs() <= 1e-13 * want.abs().max(1.0),
                "state {i}: {v} vs {want} in {line}"
            );
        }
    }
    // A: 1 entry in the row of q_wall, 2 per spring, 3 per mass but the last (2): 5n − 2. B: u in ṗ_1 alone.
    // No outputs: C and D are empty.
    assert_eq!(
        lines[STATES],
        format!("counts {} 1 0 0", 5 * MASSES - 2),
        "{printed}"
    );
    let energy: Vec<f64> = lines[STATES + 1]
        .split_whitespace()
        .skip(1)
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    let stored: f64 = x[0] * x[0] * K / 2.0
        + (1..=MASSES)
            .map(|i| x[2 * i - 1].powi(2) / (2.0 * M))
            .sum::<f64>()
        + (1..MASSES).map(|i| K * x[2 * i].powi(2) / 2.0).sum::<f64>();
    let dissipated: f64 = (1..=MASSES).map(|i| B * (x[2 * i - 1] / M).powi(2)).sum();
    assert_eq!(energy.len(), 2, "{}", lines[STATES + 1]);
    assert!(
        (energy[0] - stored).abs() <= 1e-12 * stored,
        "{energy:?} vs {stored}"
    );
    assert!(
        (energy[1] - dissipated).abs() <= 1e-12 * dissipated,
        "{energy:?} vs {dissipated}"
    );
    // `validate` checks `m` once and names the first mass and how many share it.
    assert_eq!(
        lines[STATES + 2],
        format!(
            "error parameter `m` = -1.0 is not physical: the inertia of `mass1` (m) and of {} other \
             elements with the same value must be positive and finite",
            MASSES - 1
        )
    );
}

#[test]
fn validate_checks_each_distinct_value_once_and_names_its_first_element() {
    let code = generate_text("chain.bg", &benchmark_chain(40), Options { runtime: false });
    let start = code.find("pub fn validate").unwrap_or_default();
    let end = code[start..]
        .find("\n    }\n")
        .map_or(code.len(), |e| start + e);
    let validate = &code[start..end];
    // Three checks: the wall's and the springs' `1/k`, the masses' `m`, the dampers' `b`.
    assert_eq!(validate.matches("let v = ").count(), 3, "{validate}");
    for comment in [
        "        // wall and 39 other elements: 1/k\n",
        "        // mass1 and 39 other elements: m\n",
        "        // damp1 and 39 other elements: b\n",
    ] {
        assert!(validate.contains(comment), "{comment}\n{validate}");
    }
    // A value alone keeps its element's message.
    let one = generate_text("chain.bg", &benchmark_chain(1), Options { runtime: false });
    assert!(
        one.contains("reason: \"the inertia of `mass1` (m) must be positive and finite\","),
        "{one}"
    );
}

/// The benchmark chain of `n` masses whose last quarter has parameters of its own (`m2`, `b2`).
fn chain_in_two_halves(n: usize) -> String {
    let later = |line: &str, prefix: &str| {
        line.strip_prefix(prefix)
            .and_then(|rest| rest.split(' ').next())
            .and_then(|k| k.parse::<usize>().ok())
            .is_some_and(|k| 4 * k > 3 * n)
    };
    families::chain_with(n, 1.0, 1.0)
        .lines()
        .map(|line| {
            if line == "    input u [N];" {
                format!("    param m2 = 2 [kg];\n    param b2 = 0.25 [N s/m];\n{line}\n")
            } else if later(line, "    I mass") {
                format!("{}m2;\n", line.trim_end_matches("m;"))
            } else if later(line, "    R damp") {
                format!("{}b2;\n", line.trim_end_matches("b;"))
            } else {
                format!("{line}\n")
            }
        })
        .collect()
}

#[test]
fn parts_drafted_on_two_threads_read_the_parameter_terms_the_module_declares_in_order() {
    // 1,800 rates: eight parts of `rhs`, the later four drafted on a second thread; the terms of `m2` and `b2` are
    // first met in the sixth.
    let code = generate_text(
        "chain.bg",
        &chain_in_two_halves(900),
        Options { runtime: false },
    );
    assert!(
        code.contains("fn rhs_part_8("),
        "rhs is not split into eight parts"
    );
    let start = code.find("pub struct ParamTerms {").unwrap_or_default();
    let end = code[start..].find("\n}\n").map_or(start, |e| start + e);
    let declared: Vec<&str> = code[start..end]
        .lines()
        .filter_map(|l| l.trim().trim_start_matches("pub ").strip_suffix(": f64,"))
        .collect();
    // Each field read is declared, and read in some part.
    let mut read: Vec<&str> = code
        .match_indices("c.")
        .filter(|(at, _)| !code[..*at].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
        .map(|(at, _)| {
            let rest = &code[at + 2..];
            let len = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            &rest[..len]
        })
        .collect();
    read.sort_unstable();
    read.dedup();
    let mut sorted = declared.clone();
    sorted.sort_unstable();
    assert_eq!(read, sorted, "read vs declared {declared:?}");
    // In the order the statements meet them: the first half's terms before the second half's.
    let half = |f: &&str| f.contains("m2") || f.contains("b2");
    let first_later = declared.iter().position(half).unwrap_or(declared.len());
    assert!(
        first_later > 0 && first_later < declared.len() && declared[first_later..].iter().all(half),
        "{declared:?}"
    );
}

/// The function of `code` with the most lines, and that number.
fn longest_function(code: &str) -> (String, usize) {
    let mut longest = (String::new(), 0);
    let mut current: Option<(String, usize)> = None;
    for line in code.lines() {
        if line.starts_with("pub fn ") || line.starts_with("fn ") {
            current = Some((line.to_string(), 0));
        }
        if let Some((name, count)) = current.as_mut() {
            *count += 1;
            if line == "}" {
                if *count > longest.1 {
                    longest = (name.clone(), *count);
                }
                current = None;
            }
        }
    }
    longest
}

const LEVERS_MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("levers.module");
}

fn run() {
    let p = model::Params::default();
    let mut x = model::State::zeros();
    for i in 0..model::N_STATES {
        x[i] = 0.37 * ((5 * i + 3) % 11) as f64 - 1.6;
    }
    let mut u = model::Inputs::zeros();
    u[0] = 0.8;
    let mut values: Box<[f64; model::JAC_X_NNZ]> =
        vec![0.0; model::JAC_X_NNZ].into_boxed_slice().try_into().unwrap();
    model::jac_x_sparse_into(&p, 0.0, &x, &u, &mut values);
    let mut jac = vec![vec![0.0; model::N_STATES]; model::N_STATES];
    for k in 0..model::JAC_X_NNZ {
        jac[model::JAC_X_ROWS[k]][model::JAC_X_COLS[k]] = values[k];
    }
    // Central differences of the generated rates, which solve each block's M at the point.
    let h = 1e-6;
    let mut worst = 0.0f64;
    for c in 0..model::N_STATES {
        let (mut up, mut down) = (x, x);
        up[c] += h;
        down[c] -= h;
        let (fu, fd) = (model::rhs(&p, 0.0, &up, &u), model::rhs(&p, 0.0, &down, &u));
        for r in 0..model::N_STATES {
            let want = (fu[r] - fd[r]) / (2.0 * h);
            worst = worst.max((jac[r][c] - want).abs() / (1.0 + want.abs()));
        }
    }
    // The dense Jacobian on a thread of 256 KiB (its matrix made here, on the heap): it solves one mass block's
    // rows at a time, in a frame of their own, and equals the triplets.
    let dense = Box::new(model::JacX::zeros());
    let dense = std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(move || {
            let mut dense = dense;
            model::jac_x_into(&p, 0.0, &x, &u, &mut dense);
            dense
        })
        .unwrap()
        .join()
        .unwrap();
    let mut apart = 0.0f64;
    for r in 0..model::N_STATES {
        for c in 0..model::N_STATES {
            apart = apart.max((dense[(r, c)] - jac[r][c]).abs() / (1.0 + jac[r][c].abs()));
        }
    }
    println!("{} {:e} {:e}", model::JAC_X_NNZ, worst, apart);
}

fn main() {
    let worker = std::thread::Builder::new().stack_size(2 << 20).spawn(run).unwrap();
    worker.join().unwrap();
}
"#;

/// A large model of mass blocks (100 levers, each an inertia behind an MTF whose modulus varies with its angle:
/// 100 blocks of 1 x 1, 200 states) gets `jac_x_sparse_into` too: its block rows are solved with each block's `M`,
/// 4 entries per lever, and every entry equals central differences of the generated rates (to 1e-6), on a thread
/// with a 2 MiB stack. The dense `jac_x_into` equals them on a thread of 256 KiB (it held every block's rows and a
/// copy of the rates per block at once, and needed more than 512 KiB in a debug build).
#[test]
fn a_large_model_of_mass_blocks_gets_the_sparse_jacobian_of_its_rates() {
    let code = generate_text(
        "levers.bg",
        &crate::equations_kinematic::levers(100),
        Options { runtime: false },
    );
    assert!(code.contains("pub const N_STATES: usize = 200;"));
    assert!(
        code.contains("fn jac_x_sparse_mass_1("),
        "no mass rows in the triplets"
    );
    let dir = scratch("large-levers");
    let printed = build_and_run(&dir, "levers", &code, LEVERS_MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let fields: Vec<&str> = printed.split_whitespace().collect();
    assert_eq!(fields.first(), Some(&"400"), "{printed}");
    let worst: f64 = fields
        .get(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN);
    assert!(worst < 1e-6, "{printed}");
    let apart: f64 = fields
        .get(2)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN);
    assert!(apart < 1e-12, "{printed}");
}

/// 50 pairs of coupled coils (constant 2 x 2 inductance matrices, 200 states): their mass blocks need no rates in
/// `jac_x_sparse_into`, and the module compiles with `-D warnings` (it declared an unused `dx` argument before).
#[test]
fn a_large_model_of_constant_mass_blocks_compiles_without_warnings() {
    let mut text = String::from(
        "model coils {\n    domain electrical;\n    param L1 = 2 [H];\n    param L2 = 3 [H];\n    param Mu = 1 [H];\n    \
         param R1 = 5 [Ohm];\n    input u [V];\n",
    );
    for k in 0..50 {
        text += &format!(
            "    Se s{k} = u;\n    1 a{k};\n    1 b{k};\n    \
             IF c{k}(2) {{ mass[1, 1] = L1; mass[1, 2] = Mu; mass[2, 2] = L2; }}\n    R r{k} = R1;\n    \
             R q{k} = R1;\n    bond s{k} -> a{k};\n    bond a{k} -> c{k}[1];\n    bond a{k} -> r{k};\n    \
             bond b{k} -> c{k}[2];\n    bond b{k} -> q{k};\n"
        );
    }
    text += "}\n";
    let code = generate_text("coils.bg", &text, Options { runtime: false });
    assert!(code.contains("pub const N_STATES: usize = 200;"));
    assert!(
        code.contains("fn jac_x_sparse_mass_1(p: &Params, x: &State, values"),
        "{code}"
    );
    let dir = scratch("large-coils");
    crate::codegen_support::rustc::stand_ins(&dir);
    let compiled = crate::codegen_support::rustc::compile_no_std_with(
        &dir,
        "coils",
        &code,
        &["-D", "warnings"],
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert!(compiled.is_ok(), "{compiled:?}");
}

/// The code generation of `text` (named `name`), or its diagnostics.
fn compile(
    name: &str,
    text: &str,
) -> Result<bgc::codegen::CompiledFile, Vec<bgc::diagnostic::Diagnostic>> {
    let mut sources = bgc::span::SourceMap::new();
    let id = sources.add(name, text);
    bgc::codegen::compile(&mut sources, id, &mut bgc::lower::MemoryLoader::new())
}

/// The warnings of code `code` in `compiled`: each message, then its help.
fn warnings_of(compiled: &bgc::codegen::CompiledFile, code: &str) -> Vec<String> {
    compiled
        .warnings
        .iter()
        .filter(|d| d.code.0 == code)
        .map(|d| format!("{} / {}", d.message, d.help.clone().unwrap_or_default()))
        .collect()
}

/// The BG0702 warnings of `compiled`.
fn no_state_space_warnings(compiled: &bgc::codegen::CompiledFile) -> Vec<String> {
    warnings_of(compiled, "BG0702")
}

/// Loops with more tears than generated code keeps on its stack are refused with the reason and the way out, not
/// generated into matrices that overflow it (a ladder of 190 rungs with a resistance per resistor has 197, 11 of
/// them the currents along it that would otherwise sum every rung beyond); a
/// smaller linear block is generated, and its module's `state_space` evaluates the Jacobians unless `A` is too
/// large for that, which a warning says; the loops' correction of the Jacobians holds only the states it reaches.
#[test]
fn generated_loops_are_bounded_and_a_linear_block_has_its_state_space() {
    let text = crate::equations_support::families::ladder_distinct(190);
    let Err(diags) = compile("ladder.bg", &text) else {
        panic!("generated")
    };
    let errors: Vec<String> = diags
        .iter()
        .filter(|d| d.is_error())
        .map(|d| d.message.clone())
        .collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    for part in ["197 tear variables", "at most 181 tears", "bgc simulate"] {
        assert!(errors[0].contains(part), "{part}: {}", errors[0]);
    }
    assert!(!errors[0].contains("  "), "{}", errors[0]);
    // The bound is a block's: 200 separate loops of one tear each are generated, each block solved and correcting
    // the Jacobians with matrices of its own tear (1 × 1), none of all 200 tears.
    let separate =
        compile("star.bg", &families::loops_in_series(200, 1)).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(warnings_of(&separate, "BG0703").is_empty());
    let module = bgc::codegen::rust::generate(&separate, "star.bg");
    assert!(module.contains("pub const N_TEARS: usize = 200;"));
    for shape in [
        "    rz_199 = SMatrix::<f64, 1, 1>::zeros();",
        "    dz_199 = bgc_solve(rz_199, rv_199);",
    ] {
        assert!(module.contains(shape), "no `{}`", shape.trim());
    }
    assert!(!module.contains("SMatrix::<f64, N_TEARS, N_TEARS>"));
    // Below the bound the loops are generated; the model is linear but has no symbolic state space, so its
    // `state_space` evaluates its Jacobians at the origin (models/tests/loops.rs checks the numbers).
    let small = crate::equations_support::families::ladder_distinct(40);
    let compiled = compile("small.bg", &small).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(no_state_space_warnings(&compiled).is_empty());
    let module = bgc::codegen::rust::generate(&compiled, "small.bg");
    assert!(module.contains("pub fn state_space(p: &Params) -> EnergyStateSpace {\n"));
    assert!(module.contains("    jac_x_into(p, 0.0, &x, &u, &mut jx);\n"));
    // With 182 more states (a resistor and a capacitor each) `A` would pass 256 KiB: no `state_space`, and a
    // warning that says so and where `A, B, C, D` are.
    let branches: String = (1..=182)
        .map(|k| format!("    0 j{k};\n    C c{k} = c;\n    R r{k} = ra1;\n    bond j{k} -> c{k};\n    bond j{k} -> r{k};\n"))
        .collect();
    let Some(body) = small.strip_suffix("}\n") else {
        panic!("the ladder's text ends with its model's brace")
    };
    let large = format!("{body}{branches}}}\n");
    let compiled = compile("large.bg", &large).unwrap_or_else(|d| panic!("{d:?}"));
    let notes = no_state_space_warnings(&compiled);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("more than 181 states"), "{}", notes[0]);
    assert!(notes[0].contains("no `state_space`"), "{}", notes[0]);
    let module = bgc::codegen::rust::generate(&compiled, "large.bg");
    assert!(
        !module.contains("pub fn state_space("),
        "a state_space of 183 states"
    );
    // The loops' correction of `∂f/∂x` is taken where it can be, at the capacitor the ladder drives: its
    // matrices are the block's tears by that one state, not by all 183 (`rows × cols × tears` multiplications
    // per call).
    let tears = module
        .lines()
        .find_map(|l| l.strip_prefix("pub const N_TEARS: usize = "))
        .and_then(|n| n.trim_end_matches(';').parse::<usize>().ok());
    let Some(tears) = tears else {
        panic!("no N_TEARS")
    };
    assert!(
        tears > 30,
        "{tears} tears: the ladder's rungs are one block"
    );
    for shape in [
        "    const LOOP_ROWS_0: [usize; 1] = [0];\n".to_string(),
        "    const LOOP_COLS_0: [usize; 1] = [0];\n".to_string(),
        format!("    let mut rv_0 = SMatrix::<f64, {tears}, 1>::zeros();\n"),
        format!("    let mut gz_0 = SMatrix::<f64, 1, {tears}>::zeros();\n"),
    ] {
        assert!(module.contains(&shape), "no `{}`", shape.trim());
    }
    assert!(!module.contains(", 183>"), "tears by all states");
    // A ladder of four rungs keeps its loops in closed form and has its state space.
    let closed = crate::equations_support::families::ladder_distinct(4);
    let compiled = compile("closed.bg", &closed).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(no_state_space_warnings(&compiled).is_empty());
    let module = bgc::codegen::rust::generate(&compiled, "closed.bg");
    assert!(module.contains("pub fn state_space("), "no state_space");
    // Its closed forms nest: the entries of `A, B, C, D` and the resistors' powers are written over `let`s of their
    // shared subexpressions (the module had 5,776 lines when they were printed as trees; the models crate checks
    // their values against the compiler's state space and the power balance).
    for shared in ["    let ss_1 = ", "    let dissipated_1 = "] {
        assert!(module.contains(shared), "no `{}`", shared.trim());
    }
    let lines = module.lines().count();
    assert!(lines < 3_500, "{lines} lines");
}

/// A block of loops whose tears reach many states: the generated Jacobians keep its `rv`, `gz` and `dz`, tears by
/// those states, on the stack, and above 256 KiB a warning says so and what to do (one block of 31 tears, the 30
/// diode currents and the shared resistor's, by 1,080 states: 261 KiB); 31 tears by 1,050 states (254 KiB) compile
/// without it, and so do 30 separate loops of one tear each by 37 states, whose matrices are per block.
#[test]
fn jacobian_matrices_above_256_kib_on_the_stack_are_a_warning() {
    let warnings = |text: &str| {
        let compiled = compile("loops.bg", text).unwrap_or_else(|d| panic!("{d:?}"));
        warnings_of(&compiled, "BG0703")
    };
    let large = warnings(&families::loops_sharing_a_resistor(30, 36));
    assert_eq!(large.len(), 1, "{large:?}");
    for part in [
        "the generated Jacobian functions of `hub` keep a matrix of the algebraic loops' tear variables",
        "(261 KiB) on the stack",
        "std::thread::Builder::stack_size",
        "`bgc fmu` refuses",
    ] {
        assert!(large[0].contains(part), "{part}: {}", large[0]);
    }
    assert!(warnings(&families::loops_sharing_a_resistor(30, 35)).is_empty());
    assert!(warnings(&families::loops_in_series(30, 37)).is_empty());
}
