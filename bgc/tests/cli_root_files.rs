//! The file named on the command line is read only when it is a `.bg` source: any other file (a system file, a
//! text file, a link named `.bg` that leads to another file) is refused before it is read, so no diagnostic can
//! quote its lines. Before, `bgc check /etc/passwd` printed the file's first line in a BG0101 excerpt.

use crate::cli_support::bgc;
use crate::codegen_support::scratch;

/// A line that must never appear in bgc's output, whichever file it is in.
const SECRET: &str = "secret-token-4711 is the password";

#[test]
fn a_root_file_that_is_not_a_bg_source_is_refused_unread() {
    let dir = scratch("root-not-bg");
    let text = dir.join("notes.txt");
    std::fs::write(&text, format!("{SECRET}\nmodel m {{ }}\n")).unwrap_or_else(|e| panic!("{e}"));
    let bare = dir.join("notes");
    std::fs::write(&bare, format!("{SECRET}\n")).unwrap_or_else(|e| panic!("{e}"));
    let link = dir.join("link.bg");
    std::os::unix::fs::symlink(&text, &link).unwrap_or_else(|e| panic!("{e}"));
    let text = text.display().to_string();
    let bare = bare.display().to_string();
    let link = link.display().to_string();
    for (file, leak) in [
        (text.as_str(), SECRET),
        (bare.as_str(), SECRET),
        (link.as_str(), SECRET),
        ("/etc/passwd", "root:"),
    ] {
        for command in [
            vec!["check", file],
            vec!["rust", file],
            vec!["equations", file],
            vec!["simulate", file, "--t-end", "1"],
        ] {
            let (code, out, err) = bgc(&command);
            assert_eq!(code, 2, "{command:?}\nstdout: {out}\nstderr: {err}");
            assert!(
                err.contains(&format!("error: cannot read {file}: "))
                    && err.contains("not a `.bg` file"),
                "{command:?}: {err}"
            );
            assert!(
                !out.contains(leak) && !err.contains(leak),
                "{command:?} quotes the file: {out}{err}"
            );
        }
    }
}

#[test]
fn a_bg_root_file_is_still_read_and_quoted() {
    let dir = scratch("root-bg");
    let file = dir.join("broken.bg");
    std::fs::write(&file, "model m { oops }\n").unwrap_or_else(|e| panic!("{e}"));
    let (code, _, err) = bgc(&["check", &file.display().to_string()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("model m { oops }"), "{err}");
}
