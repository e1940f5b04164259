//! Test support for the layout of generated code: `rustfmt` as the reference, and a small generator.

/// `text` as `rustfmt --edition 2024` formats it (the toolchain's `rustfmt`, which `cargo fmt` needs too).
pub(crate) fn rustfmt(text: &str) -> String {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new("rustfmt")
        .args(["--edition", "2024", "--emit", "stdout"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            panic!("cannot run rustfmt (install it with `rustup component add rustfmt`): {e}")
        });
    if let Some(mut stdin) = child.stdin.take() {
        stdin.write_all(text.as_bytes()).expect("rustfmt's stdin");
    }
    let out = child.wait_with_output().expect("rustfmt's output");
    assert!(
        out.status.success(),
        "rustfmt failed: {}\n{text}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("rustfmt prints UTF-8")
}

/// Asserts that `text` is what rustfmt makes of it, showing the first lines that differ.
pub(crate) fn assert_rustfmt_stable(text: &str) {
    let formatted = rustfmt(text);
    if formatted == text {
        return;
    }
    let ours: Vec<&str> = text.lines().collect();
    let theirs: Vec<&str> = formatted.lines().collect();
    let first = ours
        .iter()
        .zip(&theirs)
        .position(|(a, b)| a != b)
        .unwrap_or(ours.len().min(theirs.len()));
    let from = first.saturating_sub(3);
    panic!(
        "rustfmt changes line {}:\n--- generated\n{}\n--- rustfmt\n{}",
        first + 1,
        ours[from..(first + 6).min(ours.len())].join("\n"),
        theirs[from..(first + 6).min(theirs.len())].join("\n")
    );
}

/// A small deterministic generator for the tests (xorshift64*).
pub(crate) struct TestRng(pub u64);

impl TestRng {
    pub fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n.max(1)
    }
}
