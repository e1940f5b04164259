//! Code generation: Rust model modules from `.bg` files.
//!
//! [`compile`] runs the pipeline on a file (lowering with its imports, causality, equations) and refuses it when
//! any stage reports an error; [`rust::generate`] turns the result into the source of a Rust module. The module
//! is plain Rust over `nalgebra` fixed-size types that implements `bgc_runtime::model::ContinuousModel` and
//! `Parametric` (unless [`rust::Options::runtime`] is off); its functions allocate nothing, never panic and need
//! only `core`, `nalgebra` and `libm`. Its text is what `rustfmt` makes of it: `layout` breaks long statements into
//! `let` lines, `format` lays out comments, lists and signatures. [`crate::build`] wraps both for build scripts.
//! Nonlinear algebraic loops are solved inside the generated functions by Newton's method (`loops`); I-fields'
//! mass matrices by Gaussian elimination (`mass`).
//!
//! Diagnostics of this stage:
//!
//! | code | finding |
//! |---|---|
//! | BG0700 | the file declares no `model` (components alone generate nothing) |
//! | BG0701 | equations that cannot be generated (incomplete, or an expression with no value in code) |
//! | BG0702 | warning: a linear model whose loops are solved numerically and which has more than 181 states gets no `state_space` |
//! | BG0703 | warning: the generated Jacobians keep a matrix of more than 256 KiB on the stack (a loop block's tears or a mass block's rows by the states they reach) |

mod adapter;
pub(crate) mod emit;
mod format;
mod layout;
mod layout_widths;
mod loops;
mod loops_dogleg;
pub(crate) mod mass;
mod names;
pub mod rust;
mod shared;
#[cfg(test)]
mod test_support;

pub use adapter::{AdaptError, explicit_outputs, to_symbolic};

use crate::diagnostic::{Diagnostic, has_errors};
use crate::equations::Equations;
use crate::ir;
use crate::lower::SourceLoader;
use crate::span::{FileId, SourceMap};

/// The diagnostic codes of this stage.
pub mod codes {
    pub const NO_MODEL: &str = "BG0700";
    pub const NOT_GENERATABLE: &str = "BG0701";
    pub const NO_STATE_SPACE: &str = "BG0702";
    pub const LARGE_STACK_MATRIX: &str = "BG0703";
}

/// One model with its derived equations.
#[derive(Clone, Debug)]
pub struct CompiledModel {
    pub model: ir::Model,
    pub equations: Equations,
    /// What the generators print, computed once when the model is checked.
    pub(crate) plan: std::sync::Arc<emit::Plan>,
}

/// The models of one file, ready for generation.
#[derive(Clone, Debug)]
pub struct CompiledFile {
    pub models: Vec<CompiledModel>,
    /// Warnings of all stages (errors make [`compile`] fail instead).
    pub warnings: Vec<Diagnostic>,
    /// [`input_hash`] of every file the compilation read.
    pub hash: u64,
}

/// Runs lowering, causality and equations on the models of file `root` (already in `sources`; imports are added).
///
/// Returns every diagnostic when any is an error, so that nothing is generated from a model with a known problem.
pub fn compile(
    sources: &mut SourceMap,
    root: FileId,
    loader: &mut dyn SourceLoader,
) -> Result<CompiledFile, Vec<Diagnostic>> {
    let (models, mut diags) = crate::lower::lower(sources, root, loader);
    if has_errors(&diags) {
        return Err(diags);
    }
    if models.is_empty() {
        let name = sources.get(root).map(|f| f.name.as_str()).unwrap_or("?");
        diags.push(
            Diagnostic::error(
                codes::NO_MODEL,
                format!("`{name}` declares no model: there is nothing to generate"),
            )
            .with_help("declare a `model` that instantiates the components"),
        );
        return Err(diags);
    }
    let mut compiled = Vec::with_capacity(models.len());
    for model in models {
        let (causality, cdiags) = crate::causality::analyse(&model);
        diags.extend(cdiags);
        if has_errors(&diags) {
            return Err(diags);
        }
        let (equations, ediags) = crate::equations::derive(&model, &causality);
        diags.extend(ediags);
        if has_errors(&diags) {
            return Err(diags);
        }
        let plan = match emit::plan(&equations) {
            Ok(plan) => std::sync::Arc::new(plan),
            Err(why) => {
                let d = Diagnostic::error(
                    codes::NOT_GENERATABLE,
                    format!("cannot generate code for `{}`: {why}", model.name),
                );
                diags.push(d.with_primary(model.spans.model, "this model"));
                return Err(diags);
            }
        };
        if plan.linear_through_loops && !rust::state_space_through_loops(&plan) {
            diags.push(no_state_space_note(&model, &equations));
        }
        if let Some(d) = large_stack_matrix_warning(&model, &plan) {
            diags.push(d);
        }
        compiled.push(CompiledModel {
            model,
            equations,
            plan,
        });
    }
    Ok(CompiledFile {
        models: compiled,
        warnings: diags,
        hash: input_hash(sources),
    })
}

/// The warning for a linear model whose loops are a block solved numerically and whose `A` is too large for the
/// `state_space` that evaluates its Jacobians: it has no symbolic state space either, so the module has no
/// `state_space`, and a crate that used one would otherwise stop compiling without a reason. A warning, not a note,
/// so that it is among the diagnostics shown after a long ladder's hundreds of notes.
fn no_state_space_note(model: &ir::Model, eqs: &crate::equations::Equations) -> Diagnostic {
    let tears: usize = eqs.tear_blocks.iter().map(|b| b.tears.len()).sum();
    Diagnostic::warning(
        codes::NO_STATE_SPACE,
        format!(
            "`{}` is linear, but {tears} of its algebraic loops are solved numerically and it has more than 181 \
             states: the generated code has no `state_space`",
            model.name
        ),
    )
    .with_primary(model.spans.model, "this model")
    .with_help(
        "`bgc statespace` prints its A, B, C and D (`--sparse` as triplets); with at most 181 states the module's \
         `state_space` evaluates its Jacobians at the origin",
    )
}

/// The warning for generated Jacobian functions that keep a matrix larger than the generated code's bound for
/// dense matrices on the stack ([`rust::MAX_CONSTANT_JACOBIAN_BYTES`]): they still compute, but a thread with a
/// small stack (2 MiB for a spawned thread, less in a debug build, which keeps copies) overflows in them.
fn large_stack_matrix_warning(model: &ir::Model, plan: &emit::Plan) -> Option<Diagnostic> {
    let (bytes, rows) = plan.oversized_stack_matrix()?;
    let kib = bytes / 1024;
    Some(
        Diagnostic::warning(
            codes::LARGE_STACK_MATRIX,
            format!(
                "the generated Jacobian functions of `{}` keep a matrix of {rows} by states, inputs or outputs \
                 ({kib} KiB) on the stack",
                model.name
            ),
        )
        .with_primary(model.spans.model, "this model")
        .with_help(format!(
            "call `jac_x_into` and the other Jacobians on a thread with a stack well above {kib} KiB \
             (`std::thread::Builder::stack_size`); `bgc fmu` refuses such a model"
        )),
    )
}

/// FNV-1a (64 bit) of every file of `sources`: each file's name, a zero byte, its text, a zero byte, in load order.
/// Stable across platforms and Rust versions (unlike `std`'s hashers), so generated headers are reproducible.
pub fn input_hash(sources: &SourceMap) -> u64 {
    let mut h = Fnv1a::new();
    for (_, f) in sources.files() {
        h.write(f.name.as_bytes());
        h.write(&[0]);
        h.write(f.text.as_bytes());
        h.write(&[0]);
    }
    h.finish()
}

/// The 64-bit FNV-1a hash.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(u64);

impl Fnv1a {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    pub fn new() -> Fnv1a {
        Fnv1a(Self::OFFSET)
    }

    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_reference_values() {
        // Reference values of the FNV specification (http://www.isthe.com/chongo/tech/comp/fnv/):
        // FNV-1a 64 of "" and of "a".
        assert_eq!(Fnv1a::new().finish(), 0xcbf29ce484222325);
        let mut h = Fnv1a::new();
        h.write(b"a");
        assert_eq!(h.finish(), 0xaf63dc4c8601ec8c);
        let mut h = Fnv1a::new();
        h.write(b"foobar");
        assert_eq!(h.finish(), 0x85944171f73967e8);
    }
}
