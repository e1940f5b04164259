//! Property tests that keep the hostile-input classes fixed: the text rendering stays bounded whatever the number of
//! errors and the length of the lines; generated code keeps the user's names out of the generated methods' and
//! descriptions inert in comments; a steep one-tear loop that has a root is solved.

use crate::codegen_support;

use bgc::codegen::rust::Options;
use bgc::diagnostic::render::{MAX_SHOWN, to_text};
use bgc::equations::newton::{Problem, Settings, solve};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use codegen_support::generate_text;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// `errors` unknown components on one line padded to any length: at most `MAX_SHOWN` are rendered, every
    /// excerpt line is short, and the closing line counts the rest.
    #[test]
    fn rendering_is_bounded(errors in 1usize..2500, pad in 0usize..400, lines in 1usize..3) {
        let mut text = String::from("model m {\n");
        for l in 0..lines {
            text.push_str(&" ".repeat(pad));
            for k in 0..errors / lines {
                text.push_str(&format!("c{l}_{k} x{l}_{k}; "));
            }
            text.push('\n');
        }
        text.push_str("}\n");
        let mut sources = SourceMap::new();
        let id = sources.add("many.bg", text);
        let (_, diags) = lower(&mut sources, id, &mut MemoryLoader::new());
        let out = to_text(&sources, &diags, false);
        let shown = out.matches("error[").count();
        prop_assert!(shown <= MAX_SHOWN, "{shown} shown");
        for line in out.lines() {
            prop_assert!(line.chars().count() <= 700, "a line of {} chars", line.chars().count());
        }
        if diags.len() > MAX_SHOWN {
            let note = format!("{} more not shown", diags.len() - MAX_SHOWN);
            prop_assert!(out.contains(&note), "no closing count");
        }
    }

    /// Derived parameters with any of the generated methods' names, descriptions with fences and indents: each
    /// method of `Params` is defined once and no doc line opens a code block. (Bidirectional controls are refused
    /// in strings by the lexer.)
    #[test]
    fn generated_code_keeps_names_apart_and_comments_inert(
        names in prop::collection::vec(prop::sample::select(NAMES), 1..6),
        descriptions in prop::collection::vec(prop::sample::select(DESCRIPTIONS), 6),
        runtime in any::<bool>(),
    ) {
        let mut unique: Vec<&str> = Vec::new();
        for n in names {
            if !unique.contains(&n) {
                unique.push(n);
            }
        }
        let mut model = String::from("model m {\n    domain translational;\n    param base = 2 [kg] \"base\";\n");
        let mut previous = "base".to_string();
        for (k, name) in unique.iter().enumerate() {
            let desc = descriptions[k % descriptions.len()];
            model.push_str(&format!("    param {name} = 2 * {previous} [kg] \"{desc}\";\n"));
            previous = name.to_string();
        }
        model.push_str(&format!(
            "    input F [N] \"{}\";\n    Se push = F;\n    I mass = {previous};\n    1 v;\n    bond push -> v -> mass;\n}}\n",
            descriptions[5]
        ));
        let code = generate_text("props.bg", &model, Options { runtime });
        for line in code.lines() {
            if let Some(doc) = line.trim_start().strip_prefix("///") {
                let doc = doc.strip_prefix(' ').unwrap_or(doc);
                prop_assert!(!doc.starts_with("```") && !doc.starts_with("~~~"), "a fence: {line}");
                prop_assert!(!doc.starts_with("    "), "an indented code block: {line}");
            }
        }
        // The methods of `Params` (its own impl and its trait impls) keep their names apart from the
        // parameters' accessors.
        let params_impls: String = code
            .split("\nimpl ")
            .filter(|block| block.starts_with("Params ") || block.contains(" for Params "))
            .map(|block| &block[..block.find("\n}\n").unwrap_or(block.len())])
            .collect();
        prop_assert!(params_impls.contains("fn validate("), "no Params impl found");
        for method in ["get", "set", "validate", "default", "clone", "fmt", "eq", "ne"] {
            let defined = params_impls.matches(&format!("    pub fn {method}(")).count()
                + params_impls.matches(&format!("    fn {method}(")).count();
            prop_assert!(defined <= 1, "`{method}` defined {defined} times");
        }
    }

    /// The diode loop `i = I_s (exp((u − R i)/V_t) − 1)` from `i = 0`, over decades of each parameter: the root
    /// exists (the residual goes from negative at 0 to positive at u/R) and is found to the tolerance, or to the
    /// last bit where the law is too steep for any float to meet it.
    #[test]
    fn a_steep_scalar_loop_with_a_root_is_solved(
        u in 0.01f64..1000.0,
        r in 1.0f64..1e4,
        i_s in 1e-12f64..1e-3,
        v_t in 0.01f64..0.1,
    ) {
        let mut diode = Diode { u, r, i_s, v_t };
        let mut z = [0.0];
        let solved = solve(&mut diode, &mut z, Settings::default());
        prop_assert!(solved.is_ok(), "{solved:?}");
        prop_assert!(z[0] > 0.0 && z[0] < u / r, "{z:?}");
        let mut at = |v: f64| {
            let (mut res, mut scale) = ([0.0], [0.0]);
            diode.residual(&[v], &mut res, &mut scale);
            (res[0], scale[0])
        };
        let (res, scale) = at(z[0]);
        // Within the tolerance, or (a law too steep for any float to meet it) the root to the last bit: the
        // residual changes sign within one float either side.
        let below = at(f64::from_bits(z[0].to_bits() - 1)).0;
        let above = at(f64::from_bits(z[0].to_bits() + 1)).0;
        let last_bit = below <= 0.0 && above >= 0.0 && res.abs() <= 1.5e-8 * scale;
        prop_assert!(res.abs() <= 1e-12 * scale || last_bit, "r = {res} s = {scale}");
    }
}

const NAMES: &[&str] = &[
    "get", "set", "validate", "default", "clone", "fmt", "eq", "ne", "get_", "k", "new",
];

const DESCRIPTIONS: &[&str] = &[
    "```",
    "~~~",
    "    fn main() { panic!() }",
    "``two`` and ````four````",
    "plain words",
    "```rust",
];

struct Diode {
    u: f64,
    r: f64,
    i_s: f64,
    v_t: f64,
}

impl Problem for Diode {
    fn size(&self) -> usize {
        1
    }
    fn residual(&mut self, z: &[f64], res: &mut [f64], s: &mut [f64]) {
        let e = ((self.u - self.r * z[0]) / self.v_t).exp();
        res[0] = z[0] - self.i_s * (e - 1.0);
        s[0] = z[0].abs() + self.i_s * (e + 1.0);
    }
    fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
        let e = ((self.u - self.r * z[0]) / self.v_t).exp();
        j[0] = 1.0 + self.i_s * e * self.r / self.v_t;
    }
}
