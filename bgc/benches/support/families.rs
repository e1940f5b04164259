//! The model families whose cost the equations-core issue bounds, as `.bg` text: one copy, shared by the benches
//! (`#[path]`) and by the tests (`tests/equations_support`), which check the same families at small sizes against
//! hand-derived values.
// Each includer uses some of the families.
#![allow(dead_code)]

/// The benchmark chain of the equations-core issue: `Se` drives mass 1; each 1-junction has `I` (m = 1) and `R`
/// (b = 0.5); a `C` to the wall at the first; a 0-junction and a `C` between neighbours; `2N` states.
pub fn benchmark_chain(n: usize) -> String {
    chain_with(n, 1.0, 1.0)
}

/// The benchmark chain with masses `m` and springs `1/k` (the dampers keep `b = 0.5`): `2n` states `q_wall,
/// p_mass1, q_spring1, ..., p_mass<n>`.
pub fn chain_with(n: usize, m: f64, k: f64) -> String {
    let mut s = format!(
        "model chain {{\n    domain translational;\n    param m = {m} [kg];\n    param b = 0.5 [N s/m];\n    param k = {k} [N/m];\n    input u [N];\n    Se drive = u;\n    C wall = 1/k;\n    bond drive -> v1;\n    bond v1 -> wall;\n",
    );
    for i in 1..=n {
        s += &format!(
            "    1 v{i};\n    I mass{i} = m;\n    R damp{i} = b;\n    bond v{i} -> mass{i};\n    bond v{i} -> damp{i};\n"
        );
        if i < n {
            let j = i + 1;
            s += &format!(
                "    0 x{i};\n    C spring{i} = 1/k;\n    bond v{i} -> x{i};\n    bond x{i} -> v{j};\n    bond x{i} -> spring{i};\n"
            );
        }
    }
    s + "}\n"
}

/// `Se u -> 1 s1 (R r) -> 0 n1 (R 1·r) -> 1 s2 (R r) -> 0 n2 (R 2·r) -> … -> C c`: every rung's resistors form an
/// algebraic loop with the next rung's.
pub fn ladder(rungs: usize) -> String {
    let mut s = String::from(
        "model ladder {\n    domain electrical;\n    input u [V];\n    param r = 1 [Ohm];\n    param c = 1e-3 [F];\n    Se src = u;\n    C cap = c;\n",
    );
    let mut chain = String::from("src");
    for k in 1..=rungs {
        s += &format!("    1 s{k};\n    R rs{k} = r;\n    0 n{k};\n    R rp{k} = {k}*r;\n");
        s += &format!("    bond s{k} -> rs{k};\n    bond n{k} -> rp{k};\n");
        chain += &format!(" -> s{k} -> n{k}");
    }
    s += &format!("    bond {chain} -> cap;\n    output i1 [A] = f(rs1);\n}}\n");
    s
}

/// The ladder of [`ladder`] with a parameter of its own for every resistor (`ra<k> = 1 + 0.1 k`, `rb<k> = 2 +
/// 0.05 k`): nothing collects when its loops are solved one inside the other, so their closed forms grow
/// geometrically with the rungs.
pub fn ladder_distinct(rungs: usize) -> String {
    let mut s = String::from(
        "model ladder {\n    domain electrical;\n    input u [V];\n    param c = 1e-3 [F];\n    Se src = u;\n    C cap = c;\n",
    );
    let mut chain = String::from("src");
    for k in 1..=rungs {
        let (ra, rb) = ladder_distinct_resistances(k);
        s += &format!("    param ra{k} = {ra} [Ohm];\n    param rb{k} = {rb} [Ohm];\n");
        s += &format!("    1 s{k};\n    R rs{k} = ra{k};\n    0 n{k};\n    R rp{k} = rb{k};\n");
        s += &format!("    bond s{k} -> rs{k};\n    bond n{k} -> rp{k};\n");
        chain += &format!(" -> s{k} -> n{k}");
    }
    s += &format!("    bond {chain} -> cap;\n    output i1 [A] = f(rs1);\n}}\n");
    s
}

/// The series and shunt resistances of rung `k` (from 1) of [`ladder_distinct`].
pub fn ladder_distinct_resistances(k: usize) -> (f64, f64) {
    (1.0 + 0.1 * k as f64, 2.0 + 0.05 * k as f64)
}

/// A mass on a spring with outputs `y_1 = sin((q/q0)²) + cos(q/q0)`, `y_i = sin(y_{i-1}·y_{i-1}) + cos(y_{i-1})`,
/// `q0 = 1`.
pub fn output_chain(levels: usize) -> String {
    output_chain_with(levels, 1.0)
}

/// [`output_chain`] with the length scale `q0`.
pub fn output_chain_with(levels: usize, q0: f64) -> String {
    let mut s = format!(
        "model outchain {{\n    domain translational;\n    param m = 1 [kg];\n    param k = 1 [N/m];\n    param q0 = {q0} [m];\n    1 j;\n    I mass = m;\n    C spring = 1/k;\n    bond j -> mass;\n    bond j -> spring;\n    output y1 [1] = sin(q(spring)*q(spring)/(q0*q0)) + cos(q(spring)/q0);\n",
    );
    for i in 2..=levels {
        let p = i - 1;
        s += &format!("    output y{i} [1] = sin(y{p}*y{p}) + cos(y{p});\n");
    }
    s + "}\n"
}

/// `Se tau -> 1 j0 {I J, R b} -> MTF g1 -> 1 j1 {I J} -> … -> MTF gN -> 1 jN {I J}`, every modulus
/// `1 + 0.1 cos(theta)` with `theta = ∫ f(j0)`.
pub fn mtf_chain(n: usize) -> String {
    mtf_chain_of(n, |_| "1 + 0.1*cos(theta)".to_string())
}

/// [`mtf_chain`] with a phase per link: modulus `k` is `1 + 0.1 cos(theta + k/100)`, so the flows are products of
/// distinct factors rather than powers of one.
pub fn mtf_chain_with_phases(n: usize) -> String {
    mtf_chain_of(n, |k| format!("1 + 0.1*cos(theta + {k}*0.01)"))
}

/// The chain of [`mtf_chain`] with modulus `k` (from 1) written as `modulus(k)`.
fn mtf_chain_of(n: usize, modulus: impl Fn(usize) -> String) -> String {
    let mut s = String::from(
        "model mtfchain {\n    domain rotational;\n    param J = 1 [kg m^2];\n    param b = 0.1 [N m s/rad];\n    input tau [N m];\n    var theta [rad] = int(f(j0));\n    Se drive = tau;\n    1 j0;\n    I i0 = J;\n    R r0 = b;\n    bond drive -> j0;\n    bond j0 -> i0;\n    bond j0 -> r0;\n",
    );
    for k in 1..=n {
        let p = k - 1;
        let g = modulus(k);
        s += &format!(
            "    1 j{k};\n    I i{k} = J;\n    MTF g{k} = {g};\n    bond j{p} -> g{k} -> j{k};\n    bond j{k} -> i{k};\n"
        );
    }
    s + "}\n"
}

/// `Se tau -> 1 j0 {I J, R b} -> GY g1 -> 0 z1 {C 1/k} -> 1 j1 {I J, R b} -> GY g2 -> … -> 1 jN`: each gyrator
/// turns the inertia's flow before it into the effort of the compliance after it, so every compliance is in
/// derivative causality, coupled to its neighbours through the rates.
pub fn gyrator_chain(n: usize) -> String {
    let mut s = String::from(
        "model gychain {\n    domain rotational;\n    param J = 1 [kg m^2];\n    param b = 0.1 [N m s/rad];\n    param k = 2 [N m/rad];\n    param gr = 1.5 [N m s/rad];\n    input tau [N m];\n    Se drive = tau;\n    1 j0;\n    I i0 = J;\n    R r0 = b;\n    bond drive -> j0;\n    bond j0 -> i0;\n    bond j0 -> r0;\n",
    );
    for i in 1..=n {
        let p = i - 1;
        s += &format!(
            "    0 z{i};\n    C c{i} = 1/k;\n    GY g{i} = gr;\n    bond j{p} -> g{i} -> z{i};\n    bond z{i} -> c{i};\n    1 j{i};\n    I i{i} = J;\n    R r{i} = b;\n    bond z{i} -> j{i};\n    bond j{i} -> i{i};\n    bond j{i} -> r{i};\n"
        );
    }
    s + "}\n"
}

/// A gear train: `Se u -> 1 j0 {I m0 = 1} -> TF t1 -> 1 j1 {R r1 = 0.1, C c1 = 1} -> TF t2 -> … -> 1 jN`, every
/// ratio the number 1.001, with outputs `e_k = e(g_k)`, the effort on the bond `g_k` into transformer `k`. Each
/// such effort holds the next (`(e(r_k) + e(c_k) + e_{k+1})` through a numeric ratio), a chain of sums.
pub fn gear_train(n: usize) -> String {
    let mut s = String::from(
        "model gears {\n    domain translational;\n    input u [N];\n    Se src = u;\n    1 j0;\n    I m0 = 1;\n    bond src -> j0 -> m0;\n",
    );
    for k in 1..=n {
        let p = k - 1;
        s += &format!(
            "    TF t{k} = 1.001;\n    1 j{k};\n    R r{k} = 0.1;\n    C c{k} = 1;\n    bond g{k}: j{p} -> t{k};\n    bond t{k} -> j{k} -> r{k}, c{k};\n    output e{k} [N] = e(g{k});\n"
        );
    }
    s + "}\n"
}

/// `Se u -> 1 j {I m = 1}` and `n` pairs of resistors in parallel, each pair on a 0-junction bonded to `j`
/// (`a_k = 1 + k mod 3`, `b_k = 2 + k mod 5`): every pair is an algebraic loop of its own.
pub fn parallel_pairs(n: usize) -> String {
    let mut s = String::from(
        "model pairs {\n    domain translational;\n    input u [N];\n    Se src = u;\n    1 j;\n    I m = 1;\n    bond src -> j -> m;\n",
    );
    for k in 0..n {
        let (a, b) = (1 + k % 3, 2 + k % 5);
        s += &format!(
            "    0 n{k};\n    R a{k} = {a};\n    R b{k} = {b};\n    bond j -> n{k} -> a{k}, b{k};\n"
        );
    }
    s + "}\n"
}

/// `loops` diode loops (one tear variable each, as `bgc/tests/corpus/diode_rc.bg`), each with `caps` capacitors in series:
/// every capacitor's rate reads its loop's tear, and every loop's residual reads its capacitors' charges.
pub fn loops_in_series(loops: usize, caps: usize) -> String {
    let mut s = String::from(
        "model star {\n    domain electrical;\n    input u [V];\n    param I_s = 1e-6 [A];\n    param V_t = 0.05 [V];\n",
    );
    for k in 1..=loops {
        s += &format!(
            "    Se s{k} = u;\n    1 l{k};\n    R r{k} = 100;\n    R d{k} {{ f = I_s * (exp(e / V_t) - 1); }}\n    \
             bond s{k} -> l{k} -> r{k}, d{k};\n"
        );
        for c in 1..=caps {
            s += &format!("    C c{k}_{c} = 1e-3;\n    bond l{k} -> c{k}_{c};\n");
        }
    }
    s + "}\n"
}

/// `loops` diode branches (a diode and a resistor each, with `caps` capacitors in series) fed from one source through
/// one shared resistor: every branch current changes the shared resistor's drop, which every diode sees, so the
/// branches are one algebraic loop that reads all `loops × caps` charges: `loops` tear variables, and one more for
/// the shared current when it sums more than 16 branches.
pub fn loops_sharing_a_resistor(loops: usize, caps: usize) -> String {
    let mut s = String::from(
        "model hub {\n    domain electrical;\n    input u [V];\n    param I_s = 1e-6 [A];\n    param V_t = 0.05 [V];\n    \
         Se src = u;\n    1 feed;\n    R r0 = 10;\n    0 hub;\n    bond src -> feed -> r0;\n    bond feed -> hub;\n",
    );
    for k in 1..=loops {
        s += &format!(
            "    1 l{k};\n    R d{k} {{ f = I_s * (exp(e / V_t) - 1); }}\n    R r{k} = 100;\n    \
             bond hub -> l{k} -> d{k}, r{k};\n"
        );
        for c in 1..=caps {
            s += &format!("    C c{k}_{c} = 1e-3;\n    bond l{k} -> c{k}_{c};\n");
        }
    }
    s + "}\n"
}
