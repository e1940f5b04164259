//! A model read from standard input (`-`), as formatters and checkers take one from editors, hooks and pipes.

use crate::cli_support;

use cli_support::{bgc_stdin, corpus};

const UNFORMATTED: &str = "model a{domain translational;param m=1[kg];Sf s=1;I i=m;bond s->i;}";

const FORMATTED: &str = "model a {
    domain translational;
    param m = 1 [kg];
    Sf s = 1;
    I i = m;
    bond s -> i;
}
";

/// `bgc fmt -` is a filter: the canonical layout on standard output, whether or not the text changes; `--check`
/// prints the diff and exits 1. Before, `-` was a file that did not exist (exit 2).
#[test]
fn fmt_of_standard_input_prints_the_canonical_layout() {
    let dir = crate::scratch::path("stdin");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    for input in [UNFORMATTED, FORMATTED] {
        let (code, out, err) = bgc_stdin(&["fmt", "-"], input, &dir);
        assert_eq!((code, out.as_str()), (0, FORMATTED), "{err}");
    }
    let (code, out, err) = bgc_stdin(&["fmt", "--check", "-"], UNFORMATTED, &dir);
    assert_eq!(code, 1, "{err}");
    assert!(
        out.starts_with("--- <stdin>\n+++ <stdin> (canonical layout)\n"),
        "{out}"
    );
    assert!(
        err.contains("<stdin>: not in the canonical layout"),
        "{err}"
    );
    let (code, out, _) = bgc_stdin(&["fmt", "--check", "-"], FORMATTED, &dir);
    assert_eq!((code, out.as_str()), (0, ""));
    // A syntax error is shown in `<stdin>`, and nothing is printed as formatted.
    let (code, out, err) = bgc_stdin(&["fmt", "-"], "model a { param m = 1 [kg] }", &dir);
    assert_eq!((code, out.as_str()), (1, ""));
    assert!(err.contains("<stdin>:1:"), "{err}");
}

/// Every command reads `-`: the oscillator through `check` and `simulate` gives what the file gives, and an
/// import is looked up in the current directory.
#[test]
fn commands_read_a_model_from_standard_input() {
    let path = corpus("oscillator.bg");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let dir = crate::scratch::path("stdin-imports");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let (code, out, err) = bgc_stdin(&["check", "-"], &text, &dir);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out,
        "<stdin>: model `oscillator`: 5 elements and junctions, 4 bonds, 3 parameters\n"
    );
    let run = ["--t-end", "0.01", "--dt-out", "0.005", "--input", "F=1"];
    let from_stdin = bgc_stdin(&[&["simulate", "-"][..], &run[..]].concat(), &text, &dir);
    let from_file = bgc_stdin(
        &[&["simulate", path.as_str()][..], &run[..]].concat(),
        "",
        &dir,
    );
    assert_eq!(from_stdin.0, 0, "{}", from_stdin.2);
    assert_eq!(from_stdin.1, from_file.1);
    // `import` from standard input: beside it is the current directory.
    std::fs::write(
        dir.join("parts.bg"),
        "component Mass { domain translational; param m = 1 [kg]; I i = m; port p = i; }\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let model = "import \"parts.bg\";\nmodel a { domain translational; Sf s = 1; Mass body; bond s -> body.p; }\n";
    let (code, out, err) = bgc_stdin(&["check", "-"], model, &dir);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("<stdin>: model `a`"), "{out}");
}
