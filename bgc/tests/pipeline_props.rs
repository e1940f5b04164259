//! The later stages on mutated models: the mutations of `front_end_props`, and hostile numbers written over the
//! numeric literals (0, negative, huge, tiny, subnormal values that keep a file valid and reach the equations), run
//! through the equations stage and Rust generation in the library, and `bgc rust` as a process, on every input:
//! nothing panics, the command exits 0, 1 or 2 (never a signal or Rust's panic status 101), and what bgc accepts
//! generates code. A deterministic sample of 8 accepted mutants is compiled by rustc, in one invocation, as
//! `#![no_std]` modules: bgc never generates code that rustc rejects.

use crate::codegen_support::rustc::{compile_against_stand_ins, stand_ins};
use crate::codegen_support::scratch;
use crate::front_end_props::{Mutation, apply, mutation, seeds};

use bgc::codegen::{self, rust};
use bgc::lower::MemoryLoader;
use bgc::span::SourceMap;
use proptest::prelude::*;
use std::path::Path;
use std::process::Command;

/// Numbers that keep a file parseable but stress the later stages.
const NUMBERS: &[&str] = &[
    "0", "-1", "1e300", "1e-300", "5e-324", "-0.0", "1e308", "3", "0.5", "2e9",
];

/// `mutated` with the `k`-th numeric literal (counted cyclically) replaced by `number`.
fn replace_number(bytes: &[u8], k: usize, number: &str) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let mut spans = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let start = i;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            i += 1;
            if i < b.len() && (b[i] == b'-' || b[i] == b'+') {
                i += 1;
            }
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
        spans.push((start, i));
    }
    let Some(&(start, end)) = spans.get(k % spans.len().max(1)) else {
        return bytes.to_vec();
    };
    let mut out = bytes[..start].to_vec();
    out.extend_from_slice(number.as_bytes());
    out.extend_from_slice(&bytes[end..]);
    out
}

/// The whole library pipeline; the generated module when bgc accepts the file.
fn library(bytes: &[u8]) -> Option<String> {
    let text = bgc::syntax::decode(bgc::span::FileId(0), bytes)
        .ok()?
        .to_string();
    let mut sources = SourceMap::new();
    let id = sources.add("mutant.bg", text);
    let compiled = codegen::compile(&mut sources, id, &mut MemoryLoader::new()).ok()?;
    Some(rust::generate_with(
        &compiled,
        "mutant.bg",
        rust::Options { runtime: false },
    ))
}

/// `bgc rust` on the file, output discarded; its exit status.
fn bgc_rust(dir: &Path, bytes: &[u8]) -> Option<i32> {
    let path = dir.join("mutant.bg");
    std::fs::write(&path, bytes).ok()?;
    let out = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(["rust", "--color=never"])
        .arg(&path)
        .output()
        .ok()?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "bgc rust panicked: {stderr}");
    out.status.code()
}

fn mutant(seed: &prop::sample::Index, muts: &[Mutation], number: Option<(usize, &str)>) -> Vec<u8> {
    let seeds = seeds();
    let base = seeds[seed.index(seeds.len())].clone();
    let mutated = apply(base, muts);
    match number {
        Some((k, n)) => replace_number(&mutated, k, n),
        None => mutated,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn later_stages_never_crash_on_mutated_models(
        seed in any::<prop::sample::Index>(),
        muts in prop::collection::vec(mutation(), 0..3),
        number in prop::option::of((any::<usize>(), prop::sample::select(NUMBERS))),
    ) {
        prop_assume!(!seeds().is_empty());
        let bytes = mutant(&seed, &muts, number);
        let generated = library(&bytes);
        let dir = scratch("pipeline-props");
        let status = bgc_rust(&dir, &bytes);
        let _ = std::fs::remove_dir_all(&dir);
        prop_assert!(matches!(status, Some(0..=2)), "bgc rust exited with {status:?}");
        // The library and the command agree on whether the file is accepted.
        prop_assert_eq!(generated.is_some(), status == Some(0));
        if let Some(code) = generated {
            prop_assert!(code.contains("pub struct Params"), "no Params in the generated module");
        }
    }
}

/// A small deterministic generator (SplitMix64), so that the sample compiled by rustc is the same on every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// How many accepted mutants rustc compiles.
const SAMPLE: usize = 8;

#[test]
fn a_sample_of_accepted_mutants_compiles_with_rustc() {
    let seeds = seeds();
    assert!(!seeds.is_empty());
    let mut rng = SplitMix(14);
    let mut modules: Vec<String> = Vec::new();
    let mut tried = 0;
    while modules.len() < SAMPLE && tried < 2000 {
        tried += 1;
        let base = seeds[(rng.next() % seeds.len() as u64) as usize].clone();
        let k = rng.next() as usize;
        let number = NUMBERS[(rng.next() % NUMBERS.len() as u64) as usize];
        let bytes = replace_number(&base, k, number);
        if let Some(code) = library(&bytes)
            && !modules.contains(&code)
        {
            modules.push(code);
        }
    }
    assert_eq!(
        modules.len(),
        SAMPLE,
        "only {} accepted mutants in {tried}",
        modules.len()
    );
    let dir = scratch("pipeline-rustc");
    stand_ins(&dir);
    let mut root = String::from("#![no_std]\n//! Generated modules of mutated models.\n\n");
    for (k, code) in modules.iter().enumerate() {
        std::fs::write(dir.join(format!("m{k}.module")), code).unwrap_or_else(|e| panic!("{e}"));
        root.push_str(&format!(
            "/// Mutant {k}.\npub mod m{k} {{\n    include!(\"m{k}.module\");\n}}\n"
        ));
    }
    std::fs::write(dir.join("mutants.rs"), root).unwrap_or_else(|e| panic!("{e}"));
    let compiled = compile_against_stand_ins(&dir, "rlib", "mutants", "mutants.rs", &[]);
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(stderr) = compiled {
        panic!("{stderr}");
    }
}
