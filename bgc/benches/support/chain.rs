//! The benchmark chain of the equations-core issue, shared by the benches: `Se` drives mass 1; each 1-junction has
//! `I` (m = 1) and `R` (b = 0.5); a `C` to the wall at the first; a 0-junction and a `C` between neighbours; `2N`
//! states.

/// The chain of `n` masses as `.bg` text.
pub fn benchmark_chain(n: usize) -> String {
    let mut s = String::from(
        "model chain {\n    domain translational;\n    param m = 1 [kg];\n    param b = 0.5 [N s/m];\n    param k = 1 [N/m];\n    input u [N];\n    Se drive = u;\n    C wall = 1/k;\n    bond drive -> v1;\n    bond v1 -> wall;\n",
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
