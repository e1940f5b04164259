//! Bounds the nesting of `let` scopes in a generated function body.
//!
//! Every `let` opens a scope that lasts to the end of its block, and the debug information rustc writes (LLVM's
//! DWARF writer) recurses once per nested scope: a function of some 3,000 `let`s overflows rustc's stack in a
//! debug build of the crate that includes it. The bodies stay far below that as a rule (`emit::MAX_LETS`), but a
//! body whose expressions are huge trees binds many parts of them to `let`s to keep its lines short (the energy
//! and parameter Jacobians of a resistor ladder of seven rungs, a resistance per resistor, had 2,916 in one
//! function). A body with more than [`MAX_NESTED_LETS`] top-level `let`s therefore declares its names first,
//! several to a `let (a, b, ...);` line, and assigns each where its `let` was: the same values in the same order,
//! under a few hundred scopes. Each statement keeps the line breaks it had as a `let`, so a statement that fits a
//! line only without its `let ` stays wrapped where `rustfmt` would join it.

/// The most top-level `let`s a body keeps as they are.
pub(super) const MAX_NESTED_LETS: usize = 1_000;

/// A top-level `let` of a body: its line, its name and whether it is `mut`.
struct Let {
    line: usize,
    name: String,
    mutable: bool,
}

/// `body` (lines indented by `indent`) with its top-level `let`s declared up front when there are more than
/// [`MAX_NESTED_LETS`], in declarations of at most `width` columns; `body` itself when there are fewer, or when a
/// `let` binds anything but one name, so that the rewrite never changes what the code means.
pub(super) fn flatten_lets(body: &str, indent: &str, width: usize) -> String {
    let lines: Vec<&str> = body.lines().collect();
    let Some(lets) = top_level_lets(&lines, indent) else {
        return body.to_string();
    };
    if lets.len() <= MAX_NESTED_LETS {
        return body.to_string();
    }
    let mut names = std::collections::HashSet::new();
    if !lets.iter().all(|l| names.insert(l.name.as_str())) {
        // A name bound twice (shadowing) cannot be declared once.
        return body.to_string();
    }
    let mut out = declarations(&lets, indent, width);
    let mut next = lets.iter().peekable();
    for (k, line) in lines.iter().enumerate() {
        match next.peek() {
            Some(l) if l.line == k => {
                let keyword = if l.mutable { "let mut " } else { "let " };
                out.push_str(indent);
                out.push_str(&line[indent.len() + keyword.len()..]);
                next.next();
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

/// The top-level `let NAME = ...` statements of `lines`; `None` when one binds a pattern or has a type.
fn top_level_lets(lines: &[&str], indent: &str) -> Option<Vec<Let>> {
    let mut lets = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let Some(rest) = line
            .strip_prefix(indent)
            .and_then(|r| r.strip_prefix("let "))
        else {
            continue;
        };
        let (mutable, rest) = match rest.strip_prefix("mut ") {
            Some(r) => (true, r),
            None => (false, rest),
        };
        let end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        let (name, after) = rest.split_at(end);
        let assigned = after == " =" || after.starts_with(" = ");
        if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) || !assigned {
            return None;
        }
        lets.push(Let {
            line: k,
            name: name.to_string(),
            mutable,
        });
    }
    Some(lets)
}

/// `let (a, b, ...);` lines declaring every name of `lets`, each at most `width` columns where the names allow, and
/// never a single name (`let a;` followed by `a = ...` is a lint).
fn declarations(lets: &[Let], indent: &str, width: usize) -> String {
    let items: Vec<String> = lets
        .iter()
        .map(|l| {
            if l.mutable {
                format!("mut {}", l.name)
            } else {
                l.name.clone()
            }
        })
        .collect();
    let frame = indent.len() + "let ();".len();
    let mut groups: Vec<Vec<&str>> = Vec::new();
    let mut used = frame;
    for item in &items {
        let extra = item.len() + if used == frame { 0 } else { 2 };
        match groups.last_mut() {
            Some(group) if used + extra <= width => {
                group.push(item);
                used += extra;
            }
            _ => {
                groups.push(vec![item]);
                used = frame + item.len();
            }
        }
    }
    // A last group of one takes the previous group's last name (which keeps that group within the width).
    if let [.., before, last] = groups.as_mut_slice()
        && last.len() == 1
        && let Some(moved) = before.pop()
    {
        last.insert(0, moved);
    }
    groups
        .iter()
        .map(|g| format!("{indent}let ({});\n", g.join(", ")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(n: usize) -> String {
        let mut b = String::from("    let mut total = 0.0;\n");
        for k in 0..n {
            b +=
                &format!("    // t{k} = {k}\n    let t{k} =\n        {k}.0;\n    total += t{k};\n");
        }
        b + "    total\n"
    }

    #[test]
    fn a_body_within_the_bound_is_kept() {
        let b = body(MAX_NESTED_LETS - 1);
        assert_eq!(flatten_lets(&b, "    ", 100), b);
    }

    #[test]
    fn a_larger_body_declares_its_names_first_and_assigns_them_in_place() {
        let b = body(MAX_NESTED_LETS + 1);
        let flat = flatten_lets(&b, "    ", 100);
        let declared: Vec<&str> = flat
            .lines()
            .take_while(|l| l.starts_with("    let ("))
            .collect();
        assert!(declared.len() < 200, "{} declarations", declared.len());
        assert!(declared.iter().all(|l| l.len() <= 100 && l.ends_with(");")));
        let names: Vec<&str> = declared
            .iter()
            .flat_map(|l| l["    let (".len()..l.len() - 2].split(", "))
            .collect();
        assert_eq!(names.len(), MAX_NESTED_LETS + 2);
        assert_eq!(names[0], "mut total");
        assert_eq!(flat.matches("    let ").count(), declared.len());
        // Each statement where it was, without its `let`, with its comment and its line breaks.
        assert!(flat.contains("    // t7 = 7\n    t7 =\n        7.0;\n    total += t7;\n"));
        assert!(flat.contains("\n    total = 0.0;\n"));
        assert_eq!(flat.lines().count(), b.lines().count() + declared.len());
    }

    #[test]
    fn patterns_types_and_shadowing_are_left_alone() {
        for extra in [
            "    let (a, b) = (1.0, 2.0);\n",
            "    let a: f64 = 1.0;\n",
            "    let t3 = 1.0;\n",
        ] {
            let b = body(MAX_NESTED_LETS + 1) + extra;
            assert_eq!(flatten_lets(&b, "    ", 100), b, "{extra}");
        }
    }
}
