//! The `bgc` command against hostile and careless input: many errors, long lines, special files, imports that
//! reach out of the project, output that cannot be written, models that would exhaust the stack or the memory.
//! Each gets a clear answer (exit 0, 1 or 2 with a message), never a crash, a hang or a leak of another file.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Run {
    status: i32,
    stdout: String,
    stderr: String,
}

impl Run {
    fn transcript(&self) -> String {
        let cut = |s: &str| s.chars().take(4000).collect::<String>();
        format!(
            "exit: {}\n--- stdout ({} bytes)\n{}\n--- stderr ({} bytes)\n{}",
            self.status,
            self.stdout.len(),
            cut(&self.stdout),
            self.stderr.len(),
            cut(&self.stderr)
        )
    }
}

/// How long a run may take before it counts as a hang. Far above what any of these runs needs; it only turns a
/// process that would never end (a FIFO read, `/dev/zero`) into a failed test instead of a stuck one.
const HANG: Duration = Duration::from_secs(120);

/// Runs bgc in `dir` with standard output to `stdout`; kills it when it hangs.
fn bgc_to(dir: &Path, args: &[&str], stdout: Stdio) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(args)
        .arg("--color=never")
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start bgc: {e}"));
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    let readers = std::thread::spawn(move || {
        let mut o = Vec::new();
        let mut e = Vec::new();
        if let Some(s) = err.as_mut() {
            let _ = s.take(64 << 20).read_to_end(&mut e);
        }
        if let Some(s) = out.as_mut() {
            let _ = s.take(64 << 20).read_to_end(&mut o);
        }
        (o, e)
    });
    let start = Instant::now();
    let status = loop {
        if let Ok(Some(s)) = child.try_wait() {
            break s.code().unwrap_or(-1);
        }
        if start.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            panic!("bgc {args:?} hangs");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (o, e) = readers.join().unwrap_or_default();
    Run {
        status,
        stdout: String::from_utf8_lossy(&o).into_owned(),
        stderr: String::from_utf8_lossy(&e).into_owned(),
    }
}

fn bgc(dir: &Path, args: &[&str]) -> Run {
    bgc_to(dir, args, Stdio::piped())
}

/// A scratch directory of this test's own.
fn scratch(name: &str) -> PathBuf {
    let dir = crate::scratch::path(&format!("hostile-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

fn write(path: &Path, text: &str) {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{e}"));
    }
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn corpus(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/corpus")
        .join(name)
        .display()
        .to_string()
}

/// A one-line file with 16,000 errors: before, each diagnostic echoed the whole 40 KB line (about 640 MB of
/// stderr). Now the first 100 are shown, each with a window of the line, and one line counts the rest.
#[test]
fn many_errors_on_one_long_line_give_a_short_report() {
    let dir = scratch("many");
    let text = format!("model m {{ {}}}\n", "x x; ".repeat(8000));
    write(&dir.join("long.bg"), &text);
    let run = bgc(&dir, &["check", "long.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(run.stderr.len() < 200_000, "{}", run.transcript());
    assert!(
        run.stderr.contains(
            "only the 100 most severe diagnostics are shown; 15899 more not shown (15899 errors"
        ),
        "{}",
        run.transcript()
    );
    assert!(run.stderr.contains("15999 errors"), "{}", run.transcript());
    // The 50th `x` that is an unknown component is at byte 10 + 5 * 49 of line 1: column 256, far into the line.
    // Its excerpt starts with an ellipsis, the caret stands under that `x` and the location is the real one.
    let block = run
        .stderr
        .split("\n\n")
        .find(|b| b.contains("long.bg:1:256"))
        .unwrap_or_else(|| panic!("no diagnostic at 1:256\n{}", run.transcript()));
    let lines: Vec<&str> = block.lines().collect();
    let source = lines
        .iter()
        .find(|l| l.starts_with("1 │ "))
        .unwrap_or_else(|| panic!("{block}"));
    assert!(source.starts_with("1 │ …x x;"), "{block}");
    assert!(source.ends_with('…'), "{block}");
    assert!(source.chars().count() < 300, "{block}");
    let caret = lines
        .iter()
        .find(|l| l.contains('^'))
        .unwrap_or_else(|| panic!("{block}"));
    let col = caret.chars().position(|c| c == '^');
    let x_col = col.and_then(|c| source.chars().nth(c));
    assert_eq!(x_col, Some('x'), "{block}");
}

/// `'model a {' * 10000`: before 66 s, 4 GB of memory and 4 GB of stderr; now a capped report.
#[test]
fn ten_thousand_open_models_give_a_short_report() {
    let dir = scratch("open");
    write(&dir.join("open.bg"), &"model a {".repeat(10_000));
    let run = bgc(&dir, &["check", "open.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(run.stderr.len() < 200_000, "{}", run.transcript());
    assert!(run.stderr.contains("open.bg:1:"), "{}", run.transcript());
    assert!(
        run.stderr.contains("more not shown"),
        "{}",
        run.transcript()
    );
}

fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap_or_else(|e| panic!("mkfifo: {e}"));
    assert!(made.success(), "mkfifo {}", path.display());
}

/// Devices, FIFOs and directories are refused as the input (exit 2) and as an import (BG0108, exit 1), without
/// reading them: before, `/dev/zero` filled the memory and a FIFO blocked forever.
#[test]
fn special_files_are_refused_without_reading_them() {
    let dir = scratch("special");
    mkfifo(&dir.join("fifo.bg"));
    std::fs::create_dir_all(dir.join("folder.bg")).unwrap_or_else(|e| panic!("{e}"));
    for (input, kind) in [
        ("/dev/zero", "a device"),
        ("/dev/urandom", "a device"),
        ("fifo.bg", "a FIFO"),
        ("folder.bg", "a directory"),
    ] {
        for command in [
            vec!["check", input],
            vec!["rust", input],
            vec!["simulate", input, "--t-end", "1"],
        ] {
            let run = bgc(&dir, &command);
            assert_eq!(run.status, 2, "{command:?}\n{}", run.transcript());
            assert!(
                run.stderr
                    .contains(&format!("cannot read {input}: not a regular file ({kind})")),
                "{command:?}\n{}",
                run.transcript()
            );
        }
    }
    for (import, why) in [
        ("fifo.bg", "not a regular file (a FIFO)"),
        ("folder.bg", "not a regular file (a directory)"),
    ] {
        write(
            &dir.join("importer.bg"),
            &format!("import \"{import}\";\nmodel m {{ }}\n"),
        );
        let run = bgc(&dir, &["check", "importer.bg"]);
        assert_eq!(run.status, 1, "{}", run.transcript());
        assert!(
            run.stderr
                .contains(&format!("error[BG0108]: cannot import `{import}`: {why}")),
            "{}",
            run.transcript()
        );
        assert!(
            run.stderr.contains("importer.bg:1:1"),
            "{}",
            run.transcript()
        );
    }
}

/// A source file above the 64 MiB bound is refused before it is read whole.
#[test]
fn an_oversized_source_is_refused() {
    let dir = scratch("big");
    let mut text = String::from("model m { }\n");
    text.push_str(
        &"// padding padding padding padding padding padding padding padding\n".repeat(1_100_000),
    );
    assert!(text.len() as u64 > bgc::build::MAX_SOURCE_BYTES);
    write(&dir.join("big.bg"), &text);
    let run = bgc(&dir, &["check", "big.bg"]);
    assert_eq!(run.status, 2, "{}", run.transcript());
    assert!(
        run.stderr.contains(
            "cannot read big.bg: the file is larger than the 64 MiB a source file may have"
        ),
        "{}",
        run.transcript()
    );
    write(&dir.join("main.bg"), "import \"big.bg\";\nmodel m { }\n");
    let run = bgc(&dir, &["check", "main.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("cannot import `big.bg`: the file is larger"),
        "{}",
        run.transcript()
    );
}

/// Imports reach only `.bg` files inside the input's directory tree and the include directories; the message of
/// a refused import never shows what the file holds. Before, `import "/etc/passwd";` printed its first line and
/// `/proc/self/environ` the whole environment.
#[cfg(unix)]
#[test]
fn imports_cannot_read_files_outside_the_project() {
    let dir = scratch("confined");
    let project = dir.join("project");
    write(
        &dir.join("outside/secret.bg"),
        "component leaked { domain rotational; param J = 1 [kg m^2]; 1 j; I i = J; bond j -> i; port p = j; }\n",
    );
    write(&dir.join("outside/plain.txt"), "SECRET-CONTENT\n");
    std::fs::create_dir_all(project.join("sub")).unwrap_or_else(|e| panic!("{e}"));
    std::os::unix::fs::symlink(dir.join("outside/plain.txt"), project.join("link.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    std::os::unix::fs::symlink(dir.join("outside/secret.bg"), project.join("secret.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    let cases = [
        ("/etc/passwd", "an import names a `.bg` source file"),
        (
            "../../../../../../etc/passwd",
            "an import names a `.bg` source file",
        ),
        ("/proc/self/environ", "an import names a `.bg` source file"),
        (
            "../outside/plain.txt",
            "an import names a `.bg` source file",
        ),
        ("link.bg", "the file it leads to is not a `.bg` file"),
        (
            "../outside/secret.bg",
            "outside the importing file's directory",
        ),
        ("secret.bg", "outside the importing file's directory"),
        (
            "sub/../../outside/secret.bg",
            "outside the importing file's directory",
        ),
    ];
    for (import, why) in cases {
        write(
            &project.join("main.bg"),
            &format!(
                "import \"{import}\";\nmodel m {{ domain rotational; leaked c; 1 j; bond j -> c.p; }}\n"
            ),
        );
        let run = bgc(&project, &["check", "main.bg"]);
        assert_eq!(run.status, 1, "{import}\n{}", run.transcript());
        assert!(
            run.stderr.contains(&format!("cannot import `{import}`: ")) && run.stderr.contains(why),
            "{import}\n{}",
            run.transcript()
        );
        for leak in ["root:", "SECRET-CONTENT", "PATH=", "component leaked"] {
            assert!(
                !run.stderr.contains(leak),
                "{import}: {leak}\n{}",
                run.transcript()
            );
        }
    }
    // The same file in an include directory the user gave is fine (through the link or found by the search), with
    // the CLI flag and with `Config`.
    write(
        &project.join("main.bg"),
        "import \"secret.bg\";\nmodel m { domain rotational; leaked c; input tau [N m]; Se s = tau; bond s -> c.p; }\n",
    );
    let outside = dir.join("outside").display().to_string();
    let run = bgc(&project, &["check", "-I", &outside, "main.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    std::fs::remove_file(project.join("secret.bg")).unwrap_or_else(|e| panic!("{e}"));
    let run = bgc(&project, &["check", "-I", &outside, "main.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    let run = bgc(&project, &["check", "main.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    let out = dir.join("out");
    let built = bgc::build::Config::new()
        .out_dir(&out)
        .cargo_output(false)
        .include_dir(dir.join("outside"))
        .compile(&[project.join("main.bg")]);
    assert!(built.is_ok(), "{:?}", built.err());
    let refused = bgc::build::Config::new()
        .out_dir(&out)
        .cargo_output(false)
        .compile(&[project.join("main.bg")]);
    assert!(
        matches!(&refused, Err(bgc::build::Error::Diagnostics { rendered, .. }) if rendered.contains("BG0108")),
        "{:?}",
        refused.err()
    );
    let run = bgc(&project, &["check", "-I", "no-such-dir", "main.bg"]);
    assert_eq!(run.status, 2, "{}", run.transcript());
    assert!(
        run.stderr.contains("include directory no-such-dir"),
        "{}",
        run.transcript()
    );
}

/// Files are identified by their canonical path: a diamond works from any working directory, and a file that
/// imports itself by another path or through a link is a cycle (BG0107), not two files declaring one name twice.
#[cfg(unix)]
#[test]
fn import_identity_is_the_canonical_path() {
    let dir = scratch("identity");
    write(
        &dir.join("top/top.bg"),
        "import \"x/a.bg\";\nimport \"y/b.bg\";\nmodel m { domain rotational; cc c; input tau [N m]; Se s = tau; bond s -> c.p; }\n",
    );
    write(&dir.join("top/x/a.bg"), "import \"../common.bg\";\n");
    write(&dir.join("top/y/b.bg"), "import \"../y/../common.bg\";\n");
    write(
        &dir.join("top/common.bg"),
        "component cc { domain rotational; 1 j; param J = 1 [kg m^2]; I i = J; bond j -> i; port p = j; }\n",
    );
    for (cwd, path) in [
        (dir.clone(), "top/top.bg"),
        (dir.join("top"), "top.bg"),
        (dir.join("top/x"), "../top.bg"),
        (dir.join("top/y"), "../x/../top.bg"),
    ] {
        let run = bgc(&cwd, &["check", path]);
        assert_eq!(
            run.status,
            0,
            "{path} from {}\n{}",
            cwd.display(),
            run.transcript()
        );
    }
    write(
        &dir.join("imp/self.bg"),
        "import \"../imp/self.bg\";\nmodel m { }\n",
    );
    std::os::unix::fs::symlink("self2.bg", dir.join("imp/link.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    write(
        &dir.join("imp/self2.bg"),
        "import \"link.bg\";\nmodel n { }\n",
    );
    for (cwd, path) in [
        (dir.clone(), "imp/self.bg"),
        (dir.join("imp"), "self.bg"),
        (dir.join("imp"), "self2.bg"),
        (dir.join("imp"), "link.bg"),
    ] {
        let run = bgc(&cwd, &["check", path]);
        assert_eq!(run.status, 1, "{path}\n{}", run.transcript());
        assert!(
            run.stderr.contains("error[BG0107]: import cycle"),
            "{path}\n{}",
            run.transcript()
        );
        assert!(
            !run.stderr.contains("BG0202"),
            "{path}\n{}",
            run.transcript()
        );
    }
}

/// Output that cannot be written is an error (exit 2 with the OS error), not a silent success.
#[cfg(target_os = "linux")]
#[test]
fn write_errors_exit_2_with_the_os_error() {
    let dir = scratch("full");
    let oscillator = corpus("oscillator.bg");
    for command in [
        vec!["rust", oscillator.as_str()],
        vec!["simulate", oscillator.as_str(), "--t-end", "1"],
        vec!["equations", oscillator.as_str()],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap_or_else(|e| panic!("/dev/full: {e}"));
        let run = bgc_to(&dir, &command, Stdio::from(full));
        assert_eq!(run.status, 2, "{command:?}\n{}", run.transcript());
        assert!(
            run.stderr
                .contains("error: cannot write the output: No space left on device"),
            "{command:?}\n{}",
            run.transcript()
        );
    }
}

/// `simulate` streams its rows: a reader that closes the pipe after the first lines ends a run of five million rows
/// at once (before, every row was computed and kept in memory before the first was printed).
#[test]
fn simulate_streams_and_stops_at_a_closed_pipe() {
    let dir = scratch("pipe");
    let oscillator = corpus("oscillator.bg");
    let mut child = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args([
            "simulate",
            &oscillator,
            "--t-end",
            "5e3",
            "--dt-out",
            "1e-3",
            "--input",
            "F=sin(t)",
        ])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{e}"));
    let mut first = [0u8; 4096];
    let got = child
        .stdout
        .as_mut()
        .map(|o| o.read(&mut first).unwrap_or(0))
        .unwrap_or(0);
    let text = String::from_utf8_lossy(&first[..got]).into_owned();
    assert!(
        text.starts_with("t [s],p_mass [N s],q_spring [m],"),
        "{text}"
    );
    drop(child.stdout.take());
    let start = Instant::now();
    let status = loop {
        if let Ok(Some(s)) = child.try_wait() {
            break s;
        }
        if start.elapsed() > HANG {
            let _ = child.kill();
            panic!("bgc simulate goes on after its output was closed");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    assert_eq!(status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// Components nested 4,000 deep overflowed the stack (SIGABRT); nesting is bounded with BG0204, and so is the
/// number of instances a model expands to (two instances per level would double it 40 times).
#[test]
fn deep_and_exploding_component_nesting_is_a_diagnostic() {
    let dir = scratch("nesting");
    let n = 4000;
    let mut deep = String::new();
    for i in 0..n - 1 {
        deep.push_str(&format!(
            "component c{i} {{ domain rotational; 1 j; c{} inner; port p = j; bond j -> inner.p; }}\n",
            i + 1
        ));
    }
    deep.push_str(&format!(
        "component c{} {{ domain rotational; 1 j; param J = 1 [kg m^2]; I i = J; bond j -> i; port p = j; }}\n",
        n - 1
    ));
    deep.push_str(
        "model m { domain rotational; c0 top; input tau [N m]; Se s = tau; bond s -> top.p; }\n",
    );
    write(&dir.join("deep.bg"), &deep);
    let run = bgc(&dir, &["check", "deep.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("error[BG0204]: components nest more than 100 deep here"),
        "{}",
        run.transcript()
    );
    let levels = 40;
    let mut wide = String::new();
    for i in 0..levels {
        wide.push_str(&format!(
            "component w{i} {{ domain rotational; 0 j; w{n} a; w{n} b; port p = j; bond j -> a.p; bond j -> b.p; }}\n",
            n = i + 1
        ));
    }
    wide.push_str(&format!(
        "component w{levels} {{ domain rotational; 1 j; param J = 1 [kg m^2]; I i = J; bond j -> i; port p = j; }}\n"
    ));
    wide.push_str(
        "model m { domain rotational; w0 top; input tau [N m]; Se s = tau; bond s -> top.p; }\n",
    );
    write(&dir.join("wide.bg"), &wide);
    let run = bgc(&dir, &["check", "wide.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("the model expands to more than 100000 component instances"),
        "{}",
        run.transcript()
    );
}

/// An import chain of 9,000 files overflowed the stack; the walk is iterative now.
#[test]
fn a_long_import_chain_loads() {
    let dir = scratch("chain");
    let n = 9000;
    for i in 0..n {
        let import = if i + 1 < n {
            format!("import \"f{}.bg\";\n", i + 1)
        } else {
            String::new()
        };
        write(
            &dir.join(format!("f{i}.bg")),
            &format!(
                "{import}component c{i} {{ domain rotational; 1 j; param J = 1 [kg m^2]; I i = J; bond j -> i; port p = j; }}\n"
            ),
        );
    }
    write(
        &dir.join("main.bg"),
        &format!(
            "import \"f0.bg\";\nmodel m {{ domain rotational; c{} x; input tau [N m]; Se s = tau; bond s -> x.p; }}\n",
            n - 1
        ),
    );
    let run = bgc(&dir, &["check", "main.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    assert!(run.stdout.contains("model `m`"), "{}", run.transcript());
}

/// `RF r(30000)` allocated a 30000² table (28.8 GB); a field's port count is bounded with BG0115 and its laws are
/// stored sparsely.
#[test]
fn a_huge_field_is_a_diagnostic() {
    let dir = scratch("field");
    write(
        &dir.join("rf.bg"),
        "model m { domain electrical; RF r(30000) { e[1] = f[1]; }; }\n",
    );
    let run = bgc(&dir, &["check", "rf.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("error[BG0115]: a field has at most 1000 ports, `r` declares 30000"),
        "{}",
        run.transcript()
    );
    assert!(run.stderr.contains("rf.bg:1:"), "{}", run.transcript());
}

/// `--t-end 5e-324` without `--dt-out` said "dt_out = 0 is not allowed", naming an option that was not given.
#[test]
fn a_tiny_t_end_is_refused_in_its_own_name() {
    let dir = scratch("tiny");
    let oscillator = corpus("oscillator.bg");
    for t_end in ["5e-324", "1e-310"] {
        let run = bgc(&dir, &["simulate", &oscillator, "--t-end", t_end]);
        assert_eq!(run.status, 1, "{}", run.transcript());
        assert!(
            run.stderr
                .contains(&format!("error: --t-end {t_end} is too small")),
            "{}",
            run.transcript()
        );
        assert!(!run.stderr.contains("dt_out"), "{}", run.transcript());
    }
}

/// An option no run can have is named as the command line spells it, before anything else is said about the run.
/// Before, `--t-end nan` said "t_end = NaN is not allowed" after a warning about the inputs not given.
#[test]
fn an_impossible_simulate_option_is_named_as_the_flag_and_said_first() {
    let dir = scratch("bad-options");
    let oscillator = corpus("oscillator.bg");
    for (flag, value) in [
        ("--t-end", "nan"),
        ("--t-end", "-inf"),
        ("--dt-out", "-1"),
        ("--atol", "0"),
        ("--rtol", "1e-20"),
    ] {
        let mut args = vec!["simulate", oscillator.as_str(), flag, value];
        if flag != "--t-end" {
            args.extend(["--t-end", "1"]);
        }
        let run = bgc(&dir, &args);
        assert_eq!(run.status, 1, "{}", run.transcript());
        let first = run.stderr.lines().next().unwrap_or("");
        let value = if value == "nan" { "NaN" } else { value };
        assert!(
            first.starts_with(&format!("error: {flag} {value} is not allowed: ")),
            "{}",
            run.transcript()
        );
    }
}

/// A dense state space of 4,002 states (16 million entries in `A`) is refused before any matrix is formed, with the
/// way out named; `--sparse` gives the same model's non-zero entries.
#[test]
fn a_dense_state_space_too_large_to_print_is_refused_and_sparse_is_offered() {
    let dir = scratch("dense-limit");
    write(&dir.join("chain.bg"), &crate::equations_sparse::chain(2001));
    for extra in [&[][..], &["--symbolic"][..]] {
        let mut args = vec!["statespace", "chain.bg"];
        args.extend_from_slice(extra);
        let run = bgc(&dir, &args);
        assert_eq!(run.status, 1, "{}", run.transcript());
        assert!(run.stderr.contains("4002 states"), "{}", run.transcript());
        assert!(run.stderr.contains("--sparse"), "{}", run.transcript());
        assert!(run.stdout.is_empty(), "{}", run.transcript());
    }
    // Standard output to a file: the triplets are larger than a pipe holds while the reader drains stderr first.
    let out = dir.join("ss.json");
    let file = std::fs::File::create(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    let run = bgc_to(
        &dir,
        &["statespace", "chain.bg", "--sparse"],
        Stdio::from(file),
    );
    assert_eq!(run.status, 0, "{}", run.transcript());
    let text = std::fs::read_to_string(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["A"]["rows"], 4002);
    // Each mass reads its own momentum and both neighbouring springs (at most three entries), each spring the
    // two masses beside it: about 5 per pair of states, not 4002² = 1.6e7.
    let nonzero = v["A"]["entries"].as_array().map_or(0, Vec::len);
    assert!(
        (6_000..12_000).contains(&nonzero),
        "{nonzero} non-zero entries"
    );
}

/// An output named like an input was written over it: `bgc fmu lib.bg -o lib.bg` replaced the model (or a file it
/// imports) with the FMU's zip, `bgc draw m.bg -o m.bg` with the SVG, and `bgc fit --plot rig.csv --data rig.csv`
/// the measured record with the plot. Each is now refused (exit 2) with the input named, the file untouched, also
/// through a link or another spelling of the path.
#[test]
fn an_output_over_an_input_is_refused_and_the_input_kept() {
    let dir = scratch("overwrite");
    let lib = "component load {\n    domain electrical;\n    param r = 10 [Ohm];\n    1 j;\n    R res = r;\n    \
               bond j -> res;\n    port a = j;\n}\n";
    let model = "import \"lib.bg\";\nmodel m {\n    domain electrical;\n    input v [V];\n    Se s = v;\n    \
                 load h;\n    bond s -> h.a;\n    output i [A] = f(h.res);\n}\n";
    write(&dir.join("lib.bg"), lib);
    write(&dir.join("m.bg"), model);
    write(
        &dir.join("rig.csv"),
        "t,v,i\n0,1,0.1\n0.1,2,0.2\n0.2,3,0.3\n",
    );
    #[cfg(unix)]
    let _ = std::os::unix::fs::symlink("m.bg", dir.join("link.bg"));
    let cases: [(&[&str], &str); 5] = [
        (
            &["fmu", "m.bg", "-o", "m.bg"],
            "m.bg is the model's source file m.bg",
        ),
        (
            &["fmu", "m.bg", "-o", "lib.bg"],
            "lib.bg is the model's source file",
        ),
        (
            &["draw", "m.bg", "-o", "./m.bg"],
            "./m.bg (the same file as m.bg) is an input",
        ),
        (
            &["draw", "m.bg", "-o", "link.bg"],
            "link.bg (the same file as m.bg) is an input",
        ),
        (
            &[
                "fit", "m.bg", "--data", "rig.csv", "--free", "r", "--plot", "rig.csv",
            ],
            "rig.csv is an input of this command",
        ),
    ];
    for (args, said) in cases {
        let run = bgc(&dir, args);
        assert_eq!(run.status, 2, "{args:?}\n{}", run.transcript());
        assert!(run.stderr.contains(said), "{args:?}\n{}", run.transcript());
    }
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap_or_default();
    assert_eq!(read("m.bg"), model);
    assert_eq!(read("lib.bg"), lib);
    assert!(read("rig.csv").starts_with("t,v,i\n"));
    // A plot that cannot be written is an I/O error, status 2 as for `draw -o`, after the fit's report (it was 1).
    let args = [
        "fit",
        "m.bg",
        "--data",
        "rig.csv",
        "--free",
        "h.r",
        "--plot",
        "no_dir/fit.svg",
    ];
    let run = bgc(&dir, &args);
    assert_eq!(run.status, 2, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("error: cannot write the plot no_dir/fit.svg"),
        "{}",
        run.transcript()
    );
    assert!(!run.stdout.is_empty(), "{}", run.transcript());
}

/// `bgc fmt` rewrote a CRLF file (a Windows checkout) with `\n` line breaks, and `bgc fmt --check` failed on every
/// formatted CRLF file with a diff of all its lines; the file's line breaks are now kept.
#[test]
fn fmt_keeps_a_files_crlf_line_breaks() {
    let dir = scratch("crlf");
    let canonical = "model a {\r\n    domain electrical;\r\n    param r = 1 [Ohm];\r\n}\r\n";
    write(&dir.join("ok.bg"), canonical);
    let run = bgc(&dir, &["fmt", "--check", "ok.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    write(
        &dir.join("messy.bg"),
        "model a {\r\n  domain electrical;\r\n  param r=1 [Ohm];}\r\n",
    );
    let run = bgc(&dir, &["fmt", "messy.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    assert_eq!(
        std::fs::read_to_string(dir.join("messy.bg")).unwrap_or_default(),
        canonical
    );
}

/// `bgc fmt` wrote the file in place, which truncates it first: a full disk or a stop halfway left a cut model.
/// It now writes a file beside it and renames it over the original, keeping its permissions and any link to
/// it, and leaves no file of its own behind.
#[cfg(unix)]
#[test]
fn fmt_replaces_a_file_whole_through_its_link_with_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("fmt-replace");
    write(&dir.join("real.bg"), "model a {\n  domain electrical;\n}\n");
    let mode = |p: &Path| {
        std::fs::metadata(p)
            .map(|m| m.permissions().mode() & 0o777)
            .unwrap_or(0)
    };
    let _ = std::fs::set_permissions(dir.join("real.bg"), std::fs::Permissions::from_mode(0o640));
    let _ = std::os::unix::fs::symlink("real.bg", dir.join("link.bg"));
    let run = bgc(&dir, &["fmt", "link.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    let link = std::fs::symlink_metadata(dir.join("link.bg")).map(|m| m.file_type().is_symlink());
    assert!(matches!(link, Ok(true)), "the link is kept");
    assert_eq!(
        std::fs::read_to_string(dir.join("real.bg")).unwrap_or_default(),
        "model a {\n    domain electrical;\n}\n"
    );
    assert_eq!(mode(&dir.join("real.bg")), 0o640);
    let names: Vec<String> = std::fs::read_dir(&dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(names.len(), 2, "{names:?}");
}

/// A description with terminal escapes, a direction override and U+FFFE was accepted: `check` passed, `fmu` wrote
/// a `modelDescription.xml` that XML readers refuse, and a diagnostic on such a line sent the escape to the
/// terminal (a red screen, or a line overwritten by a lone `\r`). Each is now an error at its character, and
/// every excerpt shows control characters by visible stand-ins.
#[test]
fn control_characters_are_refused_in_strings_and_never_echoed() {
    let dir = scratch("controls");
    write(
        &dir.join("a.bg"),
        "model a {\n  domain electrical;\n  param r = 1 [Ohm] \"x\u{1b}[2J\u{7}y\u{202e}z\u{fffe}\";\n  Se s = 1;\n  R res = r;\n  bond s -> res;\n}\n",
    );
    for args in [&["check", "a.bg"][..], &["fmu", "a.bg", "-o", "a.fmu"]] {
        let run = bgc(&dir, args);
        assert_eq!(run.status, 1, "{}", run.transcript());
        assert_eq!(
            run.stderr
                .matches("error[BG0104]: invalid character")
                .count(),
            4,
            "{}",
            run.transcript()
        );
        assert!(
            run.stderr.contains("\"x␛[2J␇y\u{fffd}z\u{fffd}\""),
            "{}",
            run.transcript()
        );
        let raw = run
            .stderr
            .chars()
            .filter(|&c| c.is_control() && c != '\n')
            .count();
        assert_eq!(raw, 0, "{}", run.transcript());
    }
    assert!(!dir.join("a.fmu").exists());
    // A stray control character elsewhere on a line: named, and shown by its stand-in under a caret.
    write(
        &dir.join("b.bg"),
        "model b {\u{1}\r  domain electrical;\r}\r",
    );
    let run = bgc(&dir, &["check", "b.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(
        run.stderr
            .contains("1 │ model b {␁\n  │          ^ not part of the language"),
        "{}",
        run.transcript()
    );
    // A line that codespan shows between two labels (a comment holding an escape sequence): `?` in its place.
    write(
        &dir.join("d.bg"),
        "model d {\n  domain translational;\n  Se s = 1;\n  1 j;\n  // \u{1b}[2J between\n  I a = 1;\n  I b = 2;\n  bond s -> j;\n  bond j -> a;\n  bond j -> b;\n}\n",
    );
    let run = bgc(&dir, &["check", "d.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    assert!(
        run.stderr.contains("5 │   // ?[2J between\n"),
        "{}",
        run.transcript()
    );
    // What a message quotes of the command line or a record: a file name, an option's value, a column.
    let no_raw_controls = |run: &Run| {
        let raw = run
            .stdout
            .chars()
            .chain(run.stderr.chars())
            .filter(|&c| c.is_control() && c != '\n')
            .count();
        assert_eq!(raw, 0, "{}", run.transcript());
    };
    let model = "model m {\n  domain electrical;\n  input v [V];\n  Se s = v;\n  R res = 2;\n  bond s -> res;\n}\n";
    write(&dir.join("m\u{1b}[31m.bg"), model);
    let run = bgc(&dir, &["check", "m\u{1b}[31m.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    assert!(
        run.stdout.starts_with("m␛[31m.bg: model `m`"),
        "{}",
        run.transcript()
    );
    no_raw_controls(&run);
    write(&dir.join("m.bg"), model);
    write(&dir.join("rec.csv"), "t,v\u{1b}[2J\n0,1\n1,1\n");
    for args in [
        &["check", "gone\u{1b}[2J.bg"][..],
        &[
            "simulate",
            "m.bg",
            "--t-end",
            "1",
            "--input",
            "v=1\u{1b}[2J",
        ],
        &["simulate", "m.bg", "--t-end", "1", "--data", "rec.csv"],
    ] {
        let run = bgc(&dir, args);
        assert!(run.status != 0, "{}", run.transcript());
        assert!(run.stderr.contains("␛[2J"), "{}", run.transcript());
        no_raw_controls(&run);
    }
}

/// A file with classic Mac OS line breaks (a lone `\r`): its first comment ran to the end of the file, so the
/// whole model was "unclosed" on "line 1". Each `\r` now ends a line, for the lexer, the line numbers and `fmt`.
#[test]
fn a_file_with_carriage_return_line_breaks_reads_as_lines() {
    let dir = scratch("cr-lines");
    let text = "model a {\r  // the source\r  domain electrical;\r  Se s = 1;\r  R res = 2 [Ohm]\r  bond s -> res;\r}\r";
    write(&dir.join("a.bg"), text);
    let run = bgc(&dir, &["check", "a.bg"]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert!(run.stderr.contains("┌─ a.bg:5:13"), "{}", run.transcript());
    assert!(
        run.stderr.contains("5 │   R res = 2 [Ohm]\n"),
        "{}",
        run.transcript()
    );
    write(&dir.join("a.bg"), &text.replace(" [Ohm]", ";"));
    let run = bgc(&dir, &["fmt", "a.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    let formatted = std::fs::read_to_string(dir.join("a.bg")).unwrap_or_default();
    assert!(
        formatted.starts_with("model a {\n    // the source\n    domain electrical;\n"),
        "{formatted:?}"
    );
}

/// An import saved as UTF-16 was "not valid UTF-8 (first bad byte at offset 0)"; it is now said to be UTF-16, as
/// for a file on the command line, and a Latin-1 import names its first bad byte.
#[test]
fn an_import_in_another_encoding_says_which() {
    let dir = scratch("import-encoding");
    let component = "component c {\n  port a;\n  R r = 1;\n  bond a -> r;\n}\n";
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(component.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    std::fs::write(dir.join("wide.bg"), utf16).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(
        dir.join("latin.bg"),
        b"// R\xE4der\ncomponent c { port a; R r = 1; bond a -> r; }\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for (import, why) in [
        (
            "wide.bg",
            "cannot import `wide.bg`: UTF-16 text, not UTF-8: it starts with a UTF-16 byte-order mark",
        ),
        (
            "latin.bg",
            "cannot import `latin.bg`: not valid UTF-8: byte 0xE4 at offset 4",
        ),
    ] {
        write(
            &dir.join("m.bg"),
            &format!(
                "import \"{import}\";\nmodel m {{\n  domain electrical;\n  Se s = 1;\n  c x;\n  bond s -> x.a;\n}}\n"
            ),
        );
        let run = bgc(&dir, &["check", "m.bg"]);
        assert_eq!(run.status, 1, "{}", run.transcript());
        assert!(run.stderr.contains(why), "{}", run.transcript());
    }
}
