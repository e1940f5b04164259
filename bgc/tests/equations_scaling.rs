//! The scaling families of `benches/equations_scaling.rs` at small sizes, against hand-derived values: a resistor
//! ladder with chained algebraic loops, outputs defined through earlier outputs, and a chain of modulated
//! transformers whose inertias are all rigidly coupled (one in integral causality, the rest dependent).

use bgc::causality::analyse;
use bgc::codegen::explicit_outputs;
use bgc::diagnostic::Diagnostic;
use bgc::equations::symbols::{Sym, SymExt};
use bgc::equations::{
    Equations, LinearError, StateSelection, derive, expr_text, linear_through_loops, linearise,
    time_in_loops, to_text,
};
use bgc::lower::{MemoryLoader, lower};
use bgc::simulate::System;
use bgc::simulate::input::Signal;
use bgc::span::SourceMap;
use bgc::symbolic::{Expr, Node};

use crate::equations_support::families::{
    gear_train, gyrator_chain, ladder, ladder_distinct, ladder_distinct_resistances,
    loops_sharing_a_resistor, mtf_chain, mtf_chain_with_phases, output_chain, parallel_pairs,
};

/// Lowers, analyses and derives one model from source text; any error fails the test.
pub fn equations(text: &str) -> Equations {
    let mut sources = SourceMap::new();
    let root = sources.add("scaling.bg".to_string(), text.to_string());
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{diags:?}");
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    let errors: Vec<&Diagnostic> = diags.iter().filter(|d| d.is_error()).collect();
    assert!(errors.is_empty(), "{errors:?}");
    eqs
}

fn state(eqs: &Equations, name: &str) -> usize {
    eqs.states
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no state {name} in {:?}", eqs.states))
}

#[test]
fn ladder_of_two_rungs_is_the_hand_derived_divider() {
    // Node voltages v1, v2 = q/c: (u − v1)/r = v1/r + (v1 − v2)/r gives v1 = (u + v2)/3; the capacitor's current
    // is (v1 − v2)/r − v2/(2r) = (u/3 − 7 v2/6)/r, and i1 = (u − v1)/r = (2u/3 − v2/3)/r.
    let eqs = equations(&ladder(2));
    let p = eqs.default_params();
    let (r, c) = (1.0, 1e-3);
    for &(q, u) in &[(0.0, 1.0), (2e-3, -0.5), (-1e-3, 3.0)] {
        let v2 = q / c;
        let rates = eqs
            .rates_at(&p, &[q], &[u], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let want = (u / 3.0 - 7.0 * v2 / 6.0) / r;
        assert!(
            (rates[0] - want).abs() < 1e-12 * (1.0 + want.abs()),
            "{rates:?} vs {want}"
        );
        let y = eqs
            .outputs_at(&p, &[q], &[u], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let want = (2.0 * u / 3.0 - v2 / 3.0) / r;
        assert!(
            (y[0] - want).abs() < 1e-12 * (1.0 + want.abs()),
            "{y:?} vs {want}"
        );
    }
}

#[test]
fn outputs_through_earlier_outputs_are_the_composition() {
    let levels = 6;
    let eqs = equations(&output_chain(levels));
    let p = eqs.default_params();
    let q = 0.7;
    let mut x = vec![0.0; eqs.states.len()];
    x[state(&eqs, "q_spring")] = q;
    let y = eqs
        .outputs_at(&p, &x, &[], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut want = (q * q).sin() + q.cos();
    for (i, got) in y.iter().enumerate() {
        assert!((got - want).abs() < 1e-12, "y{}: {got} vs {want}", i + 1);
        want = (want * want).sin() + want.cos();
    }
}

/// The node voltages `V_0 = u, V_1 … V_N = q/c` of the ladder by nodal analysis: at node `k < N`,
/// `(V_{k−1} − V_k)/r = V_k/(k r) + (V_k − V_{k+1})/r`. Returns the capacitor's current
/// `(V_{N−1} − V_N)/r − V_N/(N r)` and the source's `(u − V_1)/r`.
fn ladder_currents(rungs: usize, r: f64, vc: f64, u: f64) -> (f64, f64) {
    let series = vec![r; rungs];
    let shunt: Vec<f64> = (1..=rungs).map(|k| k as f64 * r).collect();
    nodal_currents(&series, &shunt, vc, u)
}

/// Nodal analysis of a ladder with series resistances `ra` and shunt resistances `rb` (rung `k` at index `k − 1`),
/// `V_0 = u` and `V_N = vc`: at node `k < N`, `(V_{k−1} − V_k)/ra_k = V_k/rb_k + (V_k − V_{k+1})/ra_{k+1}`, a
/// tridiagonal system solved by elimination. Returns the capacitor's current `(V_{N−1} − V_N)/ra_N − V_N/rb_N` and
/// the source's `(u − V_1)/ra_1`.
fn nodal_currents(ra: &[f64], rb: &[f64], vc: f64, u: f64) -> (f64, f64) {
    let n = ra.len();
    // Unknowns V_1 … V_{N−1}: row k: −V_{k−1}/ra_k + (1/ra_k + 1/rb_k + 1/ra_{k+1}) V_k − V_{k+1}/ra_{k+1} = 0,
    // the known ends moved to the right.
    let m = n - 1;
    let mut diag: Vec<f64> = (0..m)
        .map(|i| 1.0 / ra[i] + 1.0 / rb[i] + 1.0 / ra[i + 1])
        .collect();
    let upper: Vec<f64> = (0..m).map(|i| -1.0 / ra[i + 1]).collect();
    let mut rhs = vec![0.0; m];
    rhs[0] += u / ra[0];
    rhs[m - 1] += vc / ra[m];
    for k in 1..m {
        // Row k's sub-diagonal is −1/ra_k, the same conductance as row k − 1's super-diagonal.
        let w = upper[k - 1] / diag[k - 1];
        diag[k] -= w * upper[k - 1];
        rhs[k] -= w * rhs[k - 1];
    }
    let mut v = vec![0.0; m];
    v[m - 1] = rhs[m - 1] / diag[m - 1];
    for k in (0..m - 1).rev() {
        v[k] = (rhs[k] - upper[k] * v[k + 1]) / diag[k];
    }
    let i_cap = (v[m - 1] - vc) / ra[m] - vc / rb[m];
    (i_cap, (u - v[0]) / ra[0])
}

/// The ladder's rate (the capacitor's current) and output (the source's) at three points `(q, u)`, against
/// `currents(q/c, u) = (i_cap, i_src)` of nodal analysis, to 1e-12; `what` names the ladder in a failure.
fn assert_nodal_values(
    eqs: &Equations,
    c: f64,
    what: &str,
    currents: &dyn Fn(f64, f64) -> (f64, f64),
) {
    let p = eqs.default_params();
    for &(q, u) in &[(0.0, 1.0), (2e-3, -0.5), (-1e-3, 3.0)] {
        let (i_cap, i_src) = currents(q / c, u);
        let rates = eqs
            .rates_at(&p, &[q], &[u], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (rates[0] - i_cap).abs() < 1e-12 * (1.0 + i_cap.abs()),
            "{what}: {rates:?} vs {i_cap}"
        );
        let y = eqs
            .outputs_at(&p, &[q], &[u], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (y[0] - i_src).abs() < 1e-12 * (1.0 + i_src.abs()),
            "{what}: {y:?} vs {i_src}"
        );
    }
}

/// A ladder whose rungs form a chain of algebraic loops: every solved loop is multiplied out, so the explicit rate
/// stays a few terms in `q_cap` and `u` (nested, it grows about fivefold per rung), with the values of nodal
/// analysis.
#[test]
fn long_ladder_stays_small_and_matches_nodal_analysis() {
    let rungs = 12;
    let eqs = equations(&ladder(rungs));
    let (r, c) = (1.0, 1e-3);
    let rate = eqs.f[0].as_ref().unwrap_or_else(|| panic!("no rate"));
    let text = expr_text(&eqs, rate);
    assert!(text.len() < 100, "{text}");
    assert_nodal_values(&eqs, c, &format!("{rungs} rungs"), &|vc, u| {
        ladder_currents(rungs, r, vc, u)
    });
    // The nodal analysis itself, on the two-rung ladder derived by hand above.
    let (i_cap, i_src) = ladder_currents(2, 1.0, 0.6, 1.5);
    assert!((i_cap - (1.5 / 3.0 - 7.0 * 0.6 / 6.0)).abs() < 1e-15);
    assert!((i_src - (2.0 * 1.5 / 3.0 - 0.6 / 3.0)).abs() < 1e-15);
}

/// A ladder with a resistance per resistor: solved one inside the other, its loops' closed forms grow geometrically
/// (nothing collects), so past a size the loops are one block of linear equations solved numerically. The
/// equations stay small, their values are those of nodal analysis, and the model is still linear: its state space
/// without an operating point is exact.
#[test]
fn ladder_with_a_resistance_per_resistor_keeps_its_loops_linear_and_small() {
    let size = |rungs: usize| to_text(&equations(&ladder_distinct(rungs))).len();
    let (small, large) = (size(8), size(16));
    assert!(
        large < 3 * small,
        "the equations grow geometrically: {small} bytes at 8 rungs, {large} at 16"
    );
    let c = 1e-3;
    for rungs in [16, 40, 100] {
        let eqs = equations(&ladder_distinct(rungs));
        assert!(!eqs.tear_blocks.is_empty(), "{rungs} rungs in closed form");
        let (ra, rb): (Vec<f64>, Vec<f64>) = (1..=rungs).map(ladder_distinct_resistances).unzip();
        assert_nodal_values(&eqs, c, &format!("{rungs} rungs"), &|vc, u| {
            nodal_currents(&ra, &rb, vc, u)
        });
        let p = eqs.default_params();
        assert!(linear_through_loops(&eqs, StateSelection::Energy));
        let ss = linearise(&eqs, StateSelection::Energy, &p, &[0.0], &[0.0], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        // By superposition: A and C from q = 1 (V_N = 1/c) with u = 0, B and D from u = 1 with q = 0.
        let (a, cc) = nodal_currents(&ra, &rb, 1.0 / c, 0.0);
        let (b, d) = nodal_currents(&ra, &rb, 0.0, 1.0);
        for (got, want, what) in [
            (ss.a[0][0], a, "A"),
            (ss.b[0][0], b, "B"),
            (ss.c[0][0], cc, "C"),
            (ss.d[0][0], d, "D"),
        ] {
            // C is tiny for a long ladder: compare against the scale of the currents it is a difference of.
            let scale = a.abs().max(d.abs());
            assert!(
                (got - want).abs() < 1e-12 * scale,
                "{rungs} rungs: {what} = {got} vs {want}"
            );
        }
    }
}

/// The currents along a ladder with a resistance per resistor each hold every rung beyond them. Multiplied out in
/// the loop's unknowns, the residual of one rung read all rungs beyond it, and the equations grew with the square
/// of the ladder (14 MB of text at 1,000 rungs). A sum of more than 16 unknowns is an unknown of its own, so each
/// residual reads a bounded number of them and the text grows with the ladder. Many diode branches that share a
/// resistor are the same case across: each branch reads its own current and the shared one. Loops solved in closed
/// form nest at most four deep.
#[test]
fn each_residual_of_a_loop_reads_a_bounded_number_of_its_unknowns() {
    // Per residual of every block: the unknowns it reads.
    let read = |eqs: &Equations| -> Vec<usize> {
        eqs.tear_blocks
            .iter()
            .flat_map(|b| b.residuals.iter())
            .map(|r| {
                r.syms()
                    .into_iter()
                    .filter(|s| matches!(s, Sym::Tear(_)))
                    .count()
            })
            .collect()
    };
    let size = |eqs: &Equations| to_text(eqs).len();
    let (medium, long) = (
        equations(&ladder_distinct(100)),
        equations(&ladder_distinct(200)),
    );
    for (rungs, eqs) in [(100, &medium), (200, &long)] {
        let most = read(eqs).into_iter().max().unwrap_or(0);
        assert!(
            most <= 20,
            "{rungs} rungs: a residual reads {most} unknowns"
        );
    }
    let (a, b) = (size(&medium), size(&long));
    assert!(b < 2 * a + a / 4, "{a} bytes at 100 rungs, {b} at 200");
    // Short residuals leave the closed-form budget room for many rungs, and each rung's closed form holds the
    // previous one several times (its parameter derivatives in generated code grew to 13 MB at 100 rungs with
    // eight nested): four nest at most, as on a short ladder.
    for (rungs, eqs) in [(12, &equations(&ladder_distinct(12))), (100, &medium)] {
        assert_eq!(eqs.loops.len(), 4, "{rungs} rungs: {:?}", eqs.loops);
    }
    let hub = equations(&loops_sharing_a_resistor(30, 1));
    let mut counts = read(&hub);
    counts.sort_unstable();
    // The shared current sums the 30 branches; each branch reads its own current and the shared one.
    assert_eq!(counts.len(), 31, "{counts:?}");
    assert_eq!(counts.last(), Some(&31), "{counts:?}");
    assert!(counts[..30].iter().all(|&n| n <= 2), "{counts:?}");
}

/// A signal of time on loops kept as a linear block is refused by name, as it is in a rate: the state space has no
/// column for it (it would vanish from A and B).
#[test]
fn a_signal_of_time_on_a_linear_block_of_loops_is_refused_by_name() {
    let text = ladder_distinct(12).replace(
        "    Se src = u;",
        "    param V0 = 1 [V];\n    param w = 50 [rad/s];\n    Se src = u + V0*sin(w*t);",
    );
    let eqs = equations(&text);
    assert!(!eqs.tear_blocks.is_empty());
    assert!(!linear_through_loops(&eqs, StateSelection::Energy));
    match time_in_loops(&eqs) {
        Some(e @ LinearError::TimeDependent { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("`src`") && msg.contains("algebraic loop"),
                "{msg}"
            );
        }
        other => panic!("expected a refusal naming `src`, got {other:?}"),
    }
    assert!(time_in_loops(&equations(&ladder_distinct(12))).is_none());
}

/// `y_1 … y_levels` at `q_spring = q` by the recurrence itself.
fn output_chain_values(levels: usize, q: f64) -> Vec<f64> {
    let mut y = vec![(q * q).sin() + q.cos()];
    while y.len() < levels {
        let p = y[y.len() - 1];
        y.push((p * p).sin() + p.cos());
    }
    y
}

/// Outputs defined through earlier outputs refer to them instead of copying them: each explicit output is as long
/// as its own definition, however deep the chain (copying doubles it at every level, 2⁴⁰ copies here).
#[test]
fn outputs_through_earlier_outputs_are_shared_not_copied() {
    let levels = 40;
    let eqs = equations(&output_chain(levels));
    for k in 1..levels {
        let e = eqs.outputs[k]
            .explicit
            .as_ref()
            .unwrap_or_else(|| panic!("y{} not derived", k + 1));
        let mut refs = Vec::new();
        e.for_each_sym(&mut |s| refs.push(s));
        refs.sort();
        refs.dedup();
        assert_eq!(refs, vec![Sym::Output(k - 1)], "y{}", k + 1);
        assert_eq!(
            expr_text(&eqs, e),
            format!("sin(y{k}^2) + cos(y{k})"),
            "y{}",
            k + 1
        );
    }
    let q = -0.4;
    let want = output_chain_values(levels, q);
    let mut x = vec![0.0; eqs.states.len()];
    x[state(&eqs, "q_spring")] = q;
    let p = eqs.default_params();
    let y = eqs
        .outputs_at(&p, &x, &[], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    // The generated code's outputs: one shared node per output.
    let generated = explicit_outputs(&eqs).unwrap_or_else(|e| panic!("{e}"));
    // The simulation's output columns at t = 0.
    let (system, _) = System::new(&eqs, p.clone(), Vec::new()).unwrap_or_else(|e| panic!("{e}"));
    let mut y0 = x.clone();
    y0.extend([0.0, 0.0]);
    let row = system
        .row(&y0, 0.0, &mut Vec::new(), &mut Vec::new())
        .unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<(String, f64)> = eqs
        .params
        .iter()
        .cloned()
        .chain([("q_spring".to_string(), q), ("p_mass".to_string(), 0.0)])
        .collect();
    for k in 0..levels {
        assert!(
            (y[k] - want[k]).abs() < 1e-12,
            "y{}: {} vs {}",
            k + 1,
            y[k],
            want[k]
        );
        let column = row[eqs.states.len() + k];
        assert!(
            (column - want[k]).abs() < 1e-12,
            "simulated y{}: {column}",
            k + 1
        );
        let g = generated[k]
            .as_ref()
            .unwrap_or_else(|| panic!("generated y{}", k + 1))
            .eval(|s| names.iter().find(|(n, _)| n == s.name()).map(|(_, v)| *v))
            .unwrap_or_else(|e| panic!("generated y{}: {e}", k + 1));
        assert!((g - want[k]).abs() < 1e-12, "generated y{}: {g}", k + 1);
    }
}

/// Checks the rates derived for an MTF chain of `n_mtf` links (`text`) whose modulus `k` and its `θ`-derivative
/// are `modulus(k, θ)`, at three points, against Lagrange. With `ω = θ̇ = f(j0)`, junction `k` turns at
/// `ω/(n_1⋯n_k)` (a transformer's output flow is its input flow over its modulus), so `T = ½ m(θ) ω²` with
/// `m = J Σ_{k=0..N} Π_{j≤k} n_j^(−2)`, and `m ω̇ + ½ m'(θ) ω² = τ − b ω`. The velocity state is the far end's flow
/// `ω/Π` (`Π = n_1⋯n_N`), whose rate is `ω̇/Π − (ω/Π) (Π'/Π) θ̇` with `Π'/Π = Σ_j n_j'/n_j`.
fn assert_follows_lagrange(text: &str, n_mtf: usize, modulus: impl Fn(usize, f64) -> (f64, f64)) {
    let (j, b) = (1.0, 0.1);
    let eqs = equations(text);
    let p = eqs.default_params();
    let (iw, it) = (state(&eqs, &format!("f_j{n_mtf}")), state(&eqs, "theta"));
    for &(theta, w0, tau) in &[(0.3, 0.5, 1.0), (2.0, -1.2, 0.0), (-1.0, 0.1, -2.0)] {
        // Π_k = n_1⋯n_k and Π_k'/Π_k = Σ_{j≤k} n_j'/n_j, accumulated link by link.
        let (mut m, mut dm, mut prod, mut log_slope) = (j, 0.0, 1.0, 0.0);
        for k in 1..=n_mtf {
            let (n, dn) = modulus(k, theta);
            prod *= n;
            log_slope += dn / n;
            m += j / (prod * prod);
            dm += -2.0 * j * log_slope / (prod * prod);
        }
        let dw0 = (tau - b * w0 - 0.5 * dm * w0 * w0) / m;
        let want = dw0 / prod - w0 / prod * log_slope * w0;
        let mut x = vec![0.0; eqs.states.len()];
        x[it] = theta;
        x[iw] = w0 / prod;
        let rates = eqs
            .rates_at(&p, &x, &[tau], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (rates[it] - w0).abs() < 1e-12 * (1.0 + w0.abs()),
            "θ̇ {rates:?}"
        );
        assert!(
            (rates[iw] - want).abs() < 1e-10 * (1.0 + want.abs()),
            "N = {n_mtf}, θ = {theta}: {} vs {want}",
            rates[iw]
        );
    }
}

/// Every modulus `1 + 0.1 cos θ` (whose powers the engine collects), for 3 and 50 links.
#[test]
fn chain_of_modulated_transformers_follows_lagrange() {
    for n_mtf in [3, 50] {
        let modulus = |_: usize, theta: f64| (1.0 + 0.1 * theta.cos(), -0.1 * theta.sin());
        assert_follows_lagrange(&mtf_chain(n_mtf), n_mtf, modulus);
    }
}

/// Modulus `k` is `1 + 0.1 cos(θ + k/100)`: the flows are products of distinct factors. 3 and 12 links.
#[test]
fn chain_of_modulated_transformers_with_distinct_moduli_follows_lagrange() {
    for n_mtf in [3, 12] {
        let modulus = |k: usize, theta: f64| {
            let phase = theta + k as f64 * 0.01;
            (1.0 + 0.1 * phase.cos(), -0.1 * phase.sin())
        };
        assert_follows_lagrange(&mtf_chain_with_phases(n_mtf), n_mtf, modulus);
    }
}

/// Everything the equations of a model store: rates, mass matrices and energy terms, as distinct nodes.
fn stored_equations(eqs: &Equations) -> usize {
    let mut all: Vec<Expr> = eqs.rates.clone();
    all.extend(
        eqs.mass
            .iter()
            .flat_map(|m| m.matrix.iter().flatten().cloned()),
    );
    all.extend(eqs.energy.iter().filter_map(|t| t.value.clone()));
    Expr::distinct_nodes(&all)
}

/// Along a chain of modulated transformers each flow is the next one times `1 + 0.1 cos θ`. Kept as products the
/// flows share their levels and the equations are stored in a size linear in the chain; multiplied out into
/// polynomials of degree `k` in `cos θ` they shared nothing: 60 and 120 links took 4,172 and 6,921 nodes (850 and
/// 1,684 as products), and `bgc rust` of 200 links wrote 63 MB of code.
#[test]
fn the_flows_along_a_chain_of_modulated_transformers_stay_products() {
    let (n, m) = (60, 120);
    let (small, large) = (
        stored_equations(&equations(&mtf_chain(n))),
        stored_equations(&equations(&mtf_chain(m))),
    );
    assert!(
        large <= 20 * m && large <= 2 * small + 200,
        "{n} links: {small} nodes; {m} links: {large} nodes"
    );
    let text = bgc::equations::to_text(&equations(&mtf_chain(3)));
    let stored_i0 = text
        .lines()
        .find(|l| l.trim_start().starts_with("stored i0 = "))
        .unwrap_or_default();
    assert!(stored_i0.contains("cos(theta) + 1)^4"), "{stored_i0}");
}

/// `n` voltage sources in series on one 1-junction with a load resistor: the junction's flow `(u0 + ... )/r`
/// is in the power of every source.
fn many_sources(n: usize) -> String {
    let mut s = String::from(
        "model many {\n    domain electrical;\n    param r = 2 [Ohm];\n    1 j;\n    R load = r;\n    bond j -> load;\n",
    );
    for k in 0..n {
        s.push_str(&format!(
            "    input u{k} [V];\n    Se s{k} = u{k};\n    bond s{k} -> j;\n"
        ));
    }
    s.push_str("}\n");
    s
}

/// The power of each of 2,000 sources holds the sum of all their voltages: printed term by term that was 4,000
/// copies of the sum (quadratic text, 8 GB at 30,000 sources). The sum is printed once, in a `where` definition,
/// and the terms over it; the terms themselves stay explicit and right (`P_k = u_k (Σ u)/r`, `P_load = (Σ u)²/r`).
#[test]
fn energy_terms_sharing_a_large_sum_print_it_once() {
    let n = 2000;
    let eqs = equations(&many_sources(n));
    let text = bgc::equations::to_text(&eqs);
    // The last input twice: in the sum's definition and in its own source's power.
    assert_eq!(
        text.matches("u1999").count(),
        2,
        "{}",
        &text[..text.len().min(2000)]
    );
    let s7 = text
        .lines()
        .find(|l| l.starts_with("  supplied s7 = "))
        .unwrap_or_default();
    assert!(s7.len() < 40 && s7.contains("u7"), "{s7}");
    assert!(text.len() < 40 * n + 20_000, "{} bytes", text.len());
    // The values: inputs u_k = k/1000 V, r = 2 Ohm.
    let u: Vec<f64> = (0..n).map(|k| k as f64 / 1000.0).collect();
    let flow = u.iter().sum::<f64>() / 2.0;
    let value = |name: &str| {
        let term = eqs
            .energy
            .iter()
            .find(|t| t.element == name)
            .and_then(|t| t.value.clone());
        let term = term.unwrap_or_else(|| panic!("no energy of {name}"));
        bgc::equations::symbols::eval(&term, &|s| match s {
            Sym::Input(k) => u.get(k).copied(),
            Sym::Param(_) => Some(2.0),
            _ => None,
        })
        .unwrap_or(f64::NAN)
    };
    assert!((value("s7") - u[7] * flow).abs() <= 1e-12 * (u[7] * flow).abs());
    assert!((value("load") - 2.0 * flow * flow).abs() <= 1e-12 * 2.0 * flow * flow);
    // A small model prints as before: no definitions.
    let small = bgc::equations::to_text(&equations(&many_sources(3)));
    assert!(!small.contains("where"), "{small}");
    assert!(small.contains("  supplied s0 = "), "{small}");
}

/// The gear train's efforts by hand: junction `k` moves at `v_k = p / 1.001^k`; the effort into transformer `k` is
/// `e_k = (0.1 v_k + q_k + e_{k+1}) / 1.001` (power `e f` is kept across each ratio) with `e_{N+1} = 0`; and
/// `ṗ = u − e_1`.
fn gear_efforts(p: f64, q: &[f64]) -> Vec<f64> {
    let n = q.len();
    let mut e = vec![0.0; n + 1];
    for k in (1..=n).rev() {
        let v = p / 1.001f64.powi(k as i32);
        e[k - 1] = (0.1 * v + q[k - 1] + e[k]) / 1.001;
    }
    e.truncate(n);
    e
}

/// The outputs of a derived model, stored: their distinct nodes.
fn stored_outputs(eqs: &Equations) -> usize {
    let outputs: Vec<Expr> = eqs
        .outputs
        .iter()
        .map(|o| o.explicit.clone().expect("output derived"))
        .collect();
    Expr::distinct_nodes(&outputs)
}

/// Each effort of a gear train holds the next through a numeric ratio: shared, the outputs are stored in a size
/// linear in the train (1,000 more stages add about 20,000 nodes; merged into one flat sum each, the efforts took
/// 505,501 nodes at 1,000 stages and four times that at 2,000), and they and the rate of the input mass are the
/// hand-derived ones.
#[test]
fn the_efforts_along_a_gear_train_are_shared_and_hand_derived() {
    let n = 1000;
    let eqs = equations(&gear_train(n));
    let (stored, doubled) = (
        stored_outputs(&eqs),
        stored_outputs(&equations(&gear_train(2 * n))),
    );
    assert!(
        doubled - stored <= 40 * n,
        "{stored} nodes for {n} stages, {doubled} for {}",
        2 * n
    );
    let params = eqs.default_params();
    let mut x = vec![0.0; eqs.states.len()];
    let p = 0.8;
    x[state(&eqs, "p_m0")] = p;
    let q: Vec<f64> = (1..=n).map(|k| ((k % 7) as f64 - 3.0) * 0.25).collect();
    for (k, qk) in q.iter().enumerate() {
        x[state(&eqs, &format!("q_c{}", k + 1))] = *qk;
    }
    let u = 1.5;
    let want = gear_efforts(p, &q);
    let y = eqs
        .outputs_at(&params, &x, &[u], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    for (k, (got, want)) in y.iter().zip(&want).enumerate() {
        assert!(
            (got - want).abs() < 1e-12 * (1.0 + want.abs()),
            "e{}: {got} vs {want}",
            k + 1
        );
    }
    let rates = eqs
        .rates_at(&params, &x, &[u], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let dp = rates[state(&eqs, "p_m0")];
    assert!(
        (dp - (u - want[0])).abs() < 1e-12 * (1.0 + dp.abs()),
        "{dp} vs {}",
        u - want[0]
    );
}

/// The simulation's Jacobian of a gear train: the rate of the input mass is one long sum held whole that reads
/// every state, differentiated in one walk, and its entries are the hand-derived ones, `∂ṗ/∂q_k = −1.001^−k` and
/// `∂ṗ/∂p = −Σ_k 0.1·1.001^−2k` (from `ṗ = u − e_1` with the efforts of `gear_efforts`).
#[test]
fn the_simulations_jacobian_of_a_gear_train_is_hand_derived() {
    let n = 200;
    let eqs = equations(&gear_train(n));
    let signal = Signal::parse("0").unwrap_or_else(|e| panic!("{e}"));
    let (system, _) =
        System::new(&eqs, eqs.default_params(), vec![signal]).unwrap_or_else(|e| panic!("{e}"));
    let pattern = system.jacobian_pattern().expect("a symbolic Jacobian");
    let mut y = vec![0.5; eqs.states.len()];
    y.extend([0.0, 0.0]);
    let mut values = vec![0.0; pattern.len()];
    system
        .jacobian_values(&y, &[0.0], 0.0, &mut values, &mut Vec::new())
        .expect("a symbolic Jacobian");
    let p = state(&eqs, "p_m0");
    let row: Vec<(usize, f64)> = pattern
        .iter()
        .zip(&values)
        .filter(|((r, _), _)| *r == p)
        .map(|((_, c), v)| (*c, *v))
        .collect();
    assert_eq!(row.len(), n + 1, "the input mass's rate reads every state");
    for (c, got) in row {
        let want = if c == p {
            -(1..=n)
                .map(|k| 0.1 / 1.001f64.powi(2 * k as i32))
                .sum::<f64>()
        } else {
            let k: i32 = eqs.states[c]
                .name
                .trim_start_matches("q_c")
                .parse()
                .expect("a spring");
            -1.001f64.powi(-k)
        };
        assert!(
            (got - want).abs() < 1e-12 * want.abs().max(1.0),
            "{}: {got} vs {want}",
            eqs.states[c].name
        );
    }
}

/// Pairs of resistors in parallel on a mass's junction, each pair an algebraic loop of its own, solved where it
/// closes: the mass feels `Σ_k a_k b_k / (a_k + b_k)` times its velocity (each pair's effort is the velocity times
/// the pair's parallel resistance).
#[test]
fn pairs_of_parallel_resistors_are_each_solved_as_their_own_loop() {
    let n = 500;
    let eqs = equations(&parallel_pairs(n));
    assert_eq!(eqs.loops.len(), n, "one loop per pair");
    let (p, u) = (0.7, 2.0);
    let rates = eqs
        .rates_at(&eqs.default_params(), &[p], &[u], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let resistance: f64 = (0..n)
        .map(|k| {
            let (a, b) = ((1 + k % 3) as f64, (2 + k % 5) as f64);
            a * b / (a + b)
        })
        .sum();
    let want = u - resistance * p;
    assert!(
        (rates[0] - want).abs() < 1e-12 * want.abs().max(1.0),
        "{} vs {want}",
        rates[0]
    );
}

/// The gyrator chain's rates by hand. The gyrator `g_i` (ratio `r`) imposes the effort `r v_{i-1}` on compliance
/// `c_i` (`C = 1/k`), so `q̇_i = r v̇_{i-1}/k` and the gyrator's effort back on `j_{i-1}` is `r (q̇_i + v_i)`.
/// With `v = p/J` and `e_0 = tau`, `e_i = r v_{i-1}`: `(J + r²/k) v̇_i = e_i − b v_i − r v_{i+1}` for `i < n`,
/// and `J v̇_n = e_n − b v_n`; the rates are `ṗ_i = J v̇_i`.
fn gyrator_rates(p: &[f64], tau: f64, (j, b, k, r): (f64, f64, f64, f64)) -> Vec<f64> {
    let n = p.len() - 1;
    let v: Vec<f64> = p.iter().map(|p| p / j).collect();
    (0..=n)
        .map(|i| {
            let e = if i == 0 { tau } else { r * v[i - 1] };
            if i == n {
                e - b * v[i]
            } else {
                j * (e - b * v[i] - r * v[i + 1]) / (j + r * r / k)
            }
        })
        .collect()
}

/// Every compliance of the gyrator chain is in derivative causality and coupled to its neighbours through the
/// rates: the coupled block is solved as a sparse system, and each rate is the hand-derived one.
#[test]
fn a_chain_of_gyrators_with_every_compliance_dependent_follows_the_hand_derivation() {
    let n = 400;
    let eqs = equations(&gyrator_chain(n));
    assert_eq!(eqs.states.len(), n + 1, "only the inertias have states");
    let params = eqs.default_params();
    let p: Vec<f64> = (0..=n)
        .map(|i| ((i % 5) as f64 - 2.0) * 0.3 + 0.01 * i as f64)
        .collect();
    let mut x = vec![0.0; eqs.states.len()];
    for (i, pi) in p.iter().enumerate() {
        x[state(&eqs, &format!("p_i{i}"))] = *pi;
    }
    let tau = 0.7;
    let rates = eqs
        .rates_at(&params, &x, &[tau], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let want = gyrator_rates(&p, tau, (1.0, 0.1, 2.0, 1.5));
    for (i, want) in want.iter().enumerate() {
        let got = rates[state(&eqs, &format!("p_i{i}"))];
        assert!(
            (got - want).abs() < 1e-12 * (1.0 + want.abs()),
            "dp_i{i}/dt: {got} vs {want}"
        );
    }
}

/// The size of the equations' rates as stored: each distinct node and the references to its children (a flat
/// product of `m` factors is one node and `m` references).
fn stored_rates_size(eqs: &Equations) -> usize {
    let mut seen: std::collections::HashSet<Expr> = std::collections::HashSet::new();
    let mut stack: Vec<Expr> = eqs.rates.clone();
    let mut size = 0;
    while let Some(e) = stack.pop() {
        if !seen.insert(e.clone()) {
            continue;
        }
        let children: Vec<Expr> = match e.node() {
            Node::Add(cs) | Node::Mul(cs) | Node::Call(_, cs) => cs.clone(),
            Node::Pow(b, x) => vec![b.clone(), x.clone()],
            Node::Const(_) | Node::Sym(_) => Vec::new(),
        };
        size += 1 + children.len();
        stack.extend(children);
    }
    size
}

/// The chain of modulated transformers with a modulus of its own per link (`1 + 0.1 cos(θ + k/100)`): the flows are
/// flat products of distinct factors, and the time derivative of each dependent inertia's momentum differentiates
/// one. Over shared tails the rates grow with the square of the chain as stored, or less (1,429 at 20 links, 4,179
/// at 40); the flat product rule wrote a product of each flow's length for each of its factors, the cube of the
/// chain in all (4,629 and 28,039).
#[test]
fn the_rates_of_a_chain_of_distinct_moduli_grow_with_its_square() {
    let (n, m) = (20, 40);
    let (small, large) = (
        stored_rates_size(&equations(&mtf_chain_with_phases(n))),
        stored_rates_size(&equations(&mtf_chain_with_phases(m))),
    );
    assert!(
        large <= 5 * small,
        "{n} links: {small}; {m} links: {large}: more than quadratic"
    );
}
