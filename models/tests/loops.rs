//! The generated Newton solve of a nonlinear algebraic loop (corpus/diode_rc.bg): its solution satisfies the
//! diode's law written out by hand, and where no solution can be computed the generated functions say so (an
//! `Err` from `solve_loops`, NaN from `rhs`, `outputs` and the Jacobians) instead of returning a wrong number.

use crate::support;

use bgc_models::corpus::diode_rc as m;
use nalgebra::SVector;

/// The loop, by hand: the current `i` through the source, the series resistor, the diode and the capacitor obeys
/// `u = R_s i + v_d + q/C` with the diode `i = I_s (exp(v_d/V_t) − 1)`.
fn diode_residual(p: &m::Params, q: f64, u: f64, i: f64) -> (f64, f64) {
    let v_d = u - q / p.C_v - p.R_s * i;
    let law = p.I_s * ((v_d / p.V_t).exp() - 1.0);
    (law - i, v_d)
}

#[test]
fn the_solved_current_satisfies_the_diode_law() {
    let p = m::Params::default();
    // Forward bias (2 V across the series resistor and the diode), reverse bias and no bias.
    for (q, u) in [(0.0, 2.0), (1e-3, -1.0), (0.0, 0.0)] {
        let x = SVector::from([q]);
        let uu = SVector::from([u]);
        let z = m::solve_loops(&p, 0.0, &x, &uu).unwrap_or_else(|e| panic!("{e}"));
        let i = z[0];
        assert_eq!(m::TEAR_NAMES, ["loop_f_diode"]);
        let (r, v_d) = diode_residual(&p, q, u, i);
        assert!(
            r.abs() <= 1e-12 * (i.abs() + p.I_s),
            "q {q}, u {u}: i {i}, residual {r}"
        );
        // The rate of the charge is that current, the outputs the current and the diode's voltage.
        assert_eq!(m::rhs(&p, 0.0, &x, &uu)[0], i);
        let y = m::outputs(&p, 0.0, &x, &uu);
        assert_eq!(y[0], i);
        assert!(
            (y[1] - v_d).abs() <= 1e-12 * v_d.abs().max(1e-9),
            "{} vs {v_d}",
            y[1]
        );
    }
    // Forward bias: most of the 2 V drop is across R_s = 100 Ω, the diode takes about V_t ln(i/I_s) ≈ 0.5 V.
    let z = m::solve_loops(&p, 0.0, &SVector::from([0.0]), &SVector::from([2.0]));
    let i = z.map(|z| z[0]).unwrap_or(f64::NAN);
    assert!(i > 0.013 && i < 0.016, "{i}");
    // Reverse bias: the saturation current.
    let z = m::solve_loops(&p, 0.0, &SVector::from([1e-3]), &SVector::from([-1.0]));
    let i = z.map(|z| z[0]).unwrap_or(f64::NAN);
    assert!((i + p.I_s).abs() < 1e-12 * p.I_s, "{i}");
}

#[test]
fn a_steep_loop_far_from_the_start_is_solved() {
    // q = −1 C on 1 mF is −1000 V: from zero current the diode sees exp(1000/0.05), which overflows, so damped
    // Newton alone fails; the bracketing fallback finds the current that takes the 1000 V:
    // R_s i + V_t ln(1 + i/I_s) = 1000 V.
    let p = m::Params::default();
    let x = SVector::from([-1.0]);
    let u = SVector::from([0.0]);
    let i = match m::solve_loops(&p, 0.0, &x, &u) {
        Ok(z) => z[0],
        Err(e) => panic!("{e}"),
    };
    let drop = p.R_s * i + p.V_t * (i / p.I_s).ln_1p();
    assert!(
        (drop - 1000.0).abs() <= 1e-9 * 1000.0,
        "i = {i}: drop {drop}"
    );
    assert!(m::rhs(&p, 0.0, &x, &u)[0].is_finite());
}

#[test]
fn a_loop_without_a_finite_solution_is_an_error_and_nan() {
    let p = m::Params::default();
    // A source voltage that is not a number: no current satisfies the loop.
    let x = SVector::from([0.0]);
    let u = SVector::from([f64::NAN]);
    let err = match m::solve_loops(&p, 0.0, &x, &u) {
        Ok(z) => panic!("solved to {z:?}"),
        Err(e) => e,
    };
    assert_eq!((err.block, err.tear), (0, 0));
    assert!(err.to_string().contains("`loop_f_diode`"), "{err}");
    assert!(m::rhs(&p, 0.0, &x, &u)[0].is_nan());
    let y = m::outputs(&p, 0.0, &x, &u);
    assert!(y[0].is_nan() && y[1].is_nan(), "{y:?}");
    let mut jac = m::JacX::zeros();
    m::jac_x_into(&p, 0.0, &x, &u, &mut jac);
    assert!(jac[(0, 0)].is_nan());
    // The compiler's own solve fails there too.
    let eqs = support_equations();
    let values: Vec<f64> = (0..m::N_PARAMS)
        .map(|i| p.get(i).unwrap_or(f64::NAN))
        .collect();
    assert!(eqs.rates_at(&values, &[0.0], &[f64::NAN], 0.0).is_err());
}

fn support_equations() -> bgc::equations::Equations {
    support::equations_of("bgc/tests/corpus/diode_rc.bg")
}

/// The ladder of `tests/models/ladder_loops.bg` by nodal analysis: node voltages `v_1 … v_8` with `v_0 = u` at the
/// source and `v_8 = q/c` across the capacitor; Kirchhoff's current law at nodes 1 … 7,
/// `(v_{k−1} − v_k)/ra_k = v_k/rb_k + (v_k − v_{k+1})/ra_{k+1}`; the capacitor takes what rung 8 leaves,
/// `q̇ = (v_7 − v_8)/ra_8 − v_8/rb_8`, and the output is the current into the ladder, `i_1 = (u − v_1)/ra_1`.
/// Returns `(q̇, i_1)`.
fn ladder_by_nodes(p: &bgc_models::corpus::ladder_loops::Params, u: f64, q: f64) -> (f64, f64) {
    use bgc_models::corpus::ladder_loops as l;
    let get = |name: &str| {
        l::PARAM_NAMES
            .iter()
            .position(|n| *n == name)
            .and_then(|i| p.get(i))
            .unwrap_or_else(|| panic!("no parameter {name}"))
    };
    let (ra, rb): (Vec<f64>, Vec<f64>) = (1..=8)
        .map(|k| (get(&format!("ra{k}")), get(&format!("rb{k}"))))
        .unzip();
    let v8 = q / get("c");
    // Unknowns v_1 … v_7; row k − 1 is node k's balance.
    let mut g = nalgebra::DMatrix::<f64>::zeros(7, 7);
    let mut rhs = nalgebra::DVector::<f64>::zeros(7);
    for k in 1..=7 {
        let (into, out) = (1.0 / ra[k - 1], 1.0 / ra[k]);
        g[(k - 1, k - 1)] = into + 1.0 / rb[k - 1] + out;
        if k > 1 {
            g[(k - 1, k - 2)] = -into;
        } else {
            rhs[0] += into * u;
        }
        if k < 7 {
            g[(k - 1, k)] = -out;
        } else {
            rhs[6] += out * v8;
        }
    }
    let v = g.lu().solve(&rhs).unwrap_or_else(|| panic!("singular"));
    let q_dot = (v[6] - v8) / ra[7] - v8 / rb[7];
    (q_dot, (u - v[0]) / ra[0])
}

/// A linear model whose algebraic loops are solved numerically (no symbolic state space) has a generated
/// `state_space`: its Jacobians through the loops, which are `A, B, C, D` by nodal analysis.
#[test]
fn a_linear_ladder_solved_numerically_has_its_state_space() {
    use bgc_models::corpus::ladder_loops as l;
    // The ladder's loops are a numeric block (else the module would not compile: `N_TEARS` exists only then).
    assert_eq!(l::TEAR_NAMES.len(), l::N_TEARS);
    assert_eq!(l::N_TEARS, 4);
    let p = l::Params::default();
    let (a, b, c, d) = l::state_space(&p);
    let (a_ref, c_ref) = ladder_by_nodes(&p, 0.0, 1.0);
    let (b_ref, d_ref) = ladder_by_nodes(&p, 1.0, 0.0);
    for (name, got, want) in [
        ("A", a[(0, 0)], a_ref),
        ("B", b[(0, 0)], b_ref),
        ("C", c[(0, 0)], c_ref),
        ("D", d[(0, 0)], d_ref),
    ] {
        assert!(
            (got - want).abs() <= 1e-12 * want.abs(),
            "{name}: generated {got}, nodal analysis {want}"
        );
    }
}
