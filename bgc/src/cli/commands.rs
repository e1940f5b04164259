//! The subcommands. Each returns the process status; all printing happens here.

use super::io::{
    Root, is_stdin, keep_until_exit, output_failed, read_root, read_source, stderr, stderrln,
    stdin_once, stdout, stdoutln,
};
use super::{DiagFormat, DrawFormat, ReportFormat, Status};
use bgc::diagnostic::unprintable::shown;
use bgc::diagnostic::{Diagnostic, Severity, has_errors, render};
use bgc::span::SourceMap;
use std::path::{Path, PathBuf};

/// `bgc check FILE...`
pub fn check(files: &[PathBuf], format: DiagFormat, color: bool) -> Status {
    if let Err(status) = stdin_once(files.iter().map(PathBuf::as_path)) {
        return status;
    }
    let mut sources = SourceMap::new();
    let mut all_diags: Vec<Diagnostic> = Vec::new();
    let mut status = Status::Ok;
    let mut summaries = Vec::new();
    for path in files {
        let Root {
            id,
            decode_error,
            mut loader,
        } = match read_root(&mut sources, path) {
            Ok(x) => x,
            Err(e) => {
                stderrln(&format!("error: cannot read {}: {e}", path.display()));
                status = Status::UsageOrIo;
                continue;
            }
        };
        if let Some(d) = decode_error {
            all_diags.push(d);
            continue;
        }
        let (models, mut diags) = bgc::lower::lower(&mut sources, id, &mut loader);
        if !has_errors(&diags) {
            for m in &models {
                let mut found = bgc::causality::analyse(m).1;
                bgc::lower::add_instance_context(m, &mut found);
                diags.extend(found);
            }
        }
        if !has_errors(&diags) {
            if models.is_empty() {
                summaries.push(no_model_summary(&sources, id));
            }
            for m in &models {
                summaries.push(format!(
                    "{}: model `{}`: {}",
                    sources.get(id).map(|f| f.name.as_str()).unwrap_or_default(),
                    m.name,
                    m.size_in_words()
                ));
            }
        }
        all_diags.extend(diags);
    }
    emit(&sources, &all_diags, format, color);
    if format == DiagFormat::Text {
        for s in &summaries {
            // A summary names its file as given: without the control characters a file name may hold.
            stdoutln(&shown(s));
        }
        if !all_diags.is_empty() {
            stderrln(&count_line(&all_diags));
        }
    }
    if has_errors(&all_diags) && status == Status::Ok {
        status = Status::InputErrors;
    }
    status
}

/// The summary line of a file that declares no model: what it holds instead (components for other files to
/// import), or that it declares nothing at all, so that an empty or truncated file does not pass unremarked.
fn no_model_summary(sources: &SourceMap, id: bgc::span::FileId) -> String {
    let (name, text) = sources
        .get(id)
        .map(|f| (f.name.as_str(), f.text.as_str()))
        .unwrap_or_default();
    let (file, _) = bgc::syntax::parse(id, text);
    let components = file
        .items
        .iter()
        .filter(|i| matches!(i, bgc::syntax::ast::Item::Model(_)))
        .count();
    let imports = file.items.len() - components;
    match (components, imports) {
        (0, 0) => format!("{name}: no model: the file declares nothing"),
        (c, i) => {
            let plural =
                |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
            let held: Vec<String> = [(c, "component"), (i, "import")]
                .into_iter()
                .filter(|(n, _)| *n > 0)
                .map(|(n, what)| plural(n, what))
                .collect();
            format!("{name}: no model; {}", held.join(", "))
        }
    }
}

/// `bgc fmt [--check] FILE...`
pub fn fmt(files: &[PathBuf], check_only: bool, color: bool) -> Status {
    if let Err(status) = stdin_once(files.iter().map(PathBuf::as_path)) {
        return status;
    }
    let mut status = Status::Ok;
    for path in files {
        match fmt_one(path, check_only, color) {
            Ok(true) => {}
            Ok(false) => {
                if status == Status::Ok {
                    status = Status::InputErrors;
                }
            }
            Err(e) => {
                stderrln(&format!("error: {}: {e}", path.display()));
                status = Status::UsageOrIo;
            }
        }
    }
    status
}

/// Formats one file; `Ok(false)` when it has syntax errors or, with `--check`, is not formatted.
fn fmt_one(path: &Path, check_only: bool, color: bool) -> std::io::Result<bool> {
    let mut sources = SourceMap::new();
    let (id, decode_diag) = read_source(&mut sources, path)?;
    if let Some(d) = decode_diag {
        stderr(&render::to_text(&sources, &[d], color));
        return Ok(false);
    }
    let text = sources.get(id).map(|f| f.text.clone()).unwrap_or_default();
    let formatted = match bgc::syntax::format_source(id, &text) {
        Ok(formatted) => formatted,
        Err(diags) => {
            stderr(&render::to_text(&sources, &diags, color));
            stderrln(&format!(
                "{}: not formatted",
                sources.get(id).map(|f| f.name.as_str()).unwrap_or_default()
            ));
            return Ok(false);
        }
    };
    if is_stdin(path) && !check_only {
        // A filter, as editors and hooks use formatters: the text in the canonical layout goes to standard output.
        stdout(&formatted);
        return Ok(true);
    }
    if formatted == text {
        return Ok(true);
    }
    if check_only {
        let name = match is_stdin(path) {
            true => super::io::STDIN_NAME.to_string(),
            false => path.display().to_string(),
        };
        let diff = bgc::lsp::line_diff::unified(
            &text,
            &formatted,
            &name,
            &format!("{name} (canonical layout)"),
        );
        stdout(&diff);
        stderrln(&format!("{name}: not in the canonical layout"));
        return Ok(false);
    }
    bgc::files::write_whole(path, formatted.as_bytes())?;
    Ok(true)
}

/// `bgc lsp`: serves until the editor ends the session.
pub fn lsp(include: &[PathBuf]) -> Status {
    // The server outlives the working directory it was started in, as far as the editor is concerned: the
    // include directories are made absolute once.
    let include = include
        .iter()
        .map(|d| std::path::absolute(d).unwrap_or_else(|_| d.clone()))
        .collect();
    let options = bgc::lsp::Options {
        include,
        ..bgc::lsp::Options::default()
    };
    match bgc::lsp::run_stdio(options) {
        Ok(bgc::lsp::Ended::Shutdown | bgc::lsp::Ended::Closed) => Status::Ok,
        // The protocol's status for an `exit` that no `shutdown` came before.
        Ok(bgc::lsp::Ended::ExitWithoutShutdown) => Status::InputErrors,
        Err(e) => {
            stderrln(&format!("error: bgc lsp: {e}"));
            Status::UsageOrIo
        }
    }
}

fn emit(sources: &SourceMap, diags: &[Diagnostic], format: DiagFormat, color: bool) {
    match format {
        DiagFormat::Text => stderr(&render::to_text(sources, diags, color)),
        DiagFormat::Json => {
            let v = render::to_json_value(sources, diags);
            stdoutln(&serde_json::to_string_pretty(&v).unwrap_or_else(|_| "[]".into()));
        }
    }
}

pub(super) fn count_line(diags: &[Diagnostic]) -> String {
    let errors = diags
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .count();
    let warnings = diags
        .iter()
        .filter(|d| d.severity == Severity::Warning)
        .count();
    format!(
        "{errors} error{}, {warnings} warning{}",
        if errors == 1 { "" } else { "s" },
        if warnings == 1 { "" } else { "s" }
    )
}

/// A file through the front end: its sources, the one model asked for, and what the front end said.
pub(super) struct Loaded {
    pub(super) sources: SourceMap,
    pub(super) model: bgc::ir::Model,
    pub(super) diags: Vec<Diagnostic>,
}

/// Reads, parses and lowers `path` and picks one model (the one named, or the only one). Prints the diagnostics
/// and returns the status to exit with when the file cannot be used.
pub(super) fn load_one(path: &Path, wanted: Option<&str>, color: bool) -> Result<Loaded, Status> {
    let mut sources = SourceMap::new();
    let Root {
        id,
        decode_error,
        mut loader,
    } = match read_root(&mut sources, path) {
        Ok(x) => x,
        Err(e) => {
            stderrln(&format!("error: cannot read {}: {e}", path.display()));
            return Err(Status::UsageOrIo);
        }
    };
    if let Some(d) = decode_error {
        stderr(&render::to_text(&sources, &[d], color));
        return Err(Status::InputErrors);
    }
    let (models, diags) = bgc::lower::lower(&mut sources, id, &mut loader);
    if has_errors(&diags) {
        stderr(&render::to_text(&sources, &diags, color));
        stderrln(&count_line(&diags));
        return Err(Status::InputErrors);
    }
    let names: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
    let index = match (wanted, models.len()) {
        (_, 0) => {
            stderrln(&format!("error: {} declares no model", path.display()));
            return Err(Status::InputErrors);
        }
        (None, 1) => 0,
        (None, _) => {
            stderrln(&format!(
                "error: {} declares several models ({}); choose one with --model",
                path.display(),
                super::params::name_list(&names)
            ));
            return Err(Status::UsageOrIo);
        }
        (Some(w), _) => match names.iter().position(|n| *n == w) {
            Some(i) => i,
            None => {
                stderrln(&format!(
                    "error: {} has no model `{w}`; it declares {}",
                    path.display(),
                    super::params::name_list(&names)
                ));
                return Err(Status::UsageOrIo);
            }
        },
    };
    let model = models.into_iter().nth(index).ok_or(Status::InputErrors)?;
    Ok(Loaded {
        sources,
        model,
        diags,
    })
}

/// `bgc causality FILE`
pub fn causality(path: &Path, wanted: Option<&str>, format: ReportFormat, color: bool) -> Status {
    let loaded = match load_one(path, wanted, color) {
        Ok(l) => l,
        Err(s) => return s,
    };
    let (result, mut causal_diags) = bgc::causality::analyse(&loaded.model);
    bgc::lower::add_instance_context(&loaded.model, &mut causal_diags);
    let mut diags = loaded.diags;
    diags.extend(causal_diags);
    match format {
        ReportFormat::Text => {
            stdout(&bgc::causality::to_text(&loaded.model, &result));
            stderr(&render::to_text(&loaded.sources, &diags, color));
        }
        ReportFormat::Json => {
            let diag_json = render::to_json_value(&loaded.sources, &diags);
            let v = bgc::causality::to_json(&loaded.model, &result, diag_json);
            stdoutln(&serde_json::to_string_pretty(&v).unwrap_or_else(|_| "{}".into()));
        }
    }
    if has_errors(&diags) {
        Status::InputErrors
    } else {
        Status::Ok
    }
}

/// `bgc draw FILE [-o OUT]`
pub fn draw(
    path: &Path,
    wanted: Option<&str>,
    output: Option<&Path>,
    format: DrawFormat,
    color: bool,
) -> Status {
    let loaded = match load_one(path, wanted, color) {
        Ok(l) => l,
        Err(s) => return s,
    };
    if let Some(out) = output
        && super::io::refuse_overwrite(out, &loaded.sources, &[]).is_err()
    {
        return Status::UsageOrIo;
    }
    // A drawing is most useful exactly when causality has problems, so they are drawn (highlighted), not refused.
    let (result, mut causal_diags) = bgc::causality::analyse(&loaded.model);
    bgc::lower::add_instance_context(&loaded.model, &mut causal_diags);
    stderr(&render::to_text(&loaded.sources, &causal_diags, color));
    let text = match format {
        DrawFormat::Svg => bgc::draw::svg(&loaded.model, Some(&result)),
        DrawFormat::Dot => bgc::draw::dot(&loaded.model, Some(&result)),
    };
    match output {
        Some(out) => {
            if let Err(e) = bgc::files::write_whole(out, text.as_bytes()) {
                stderrln(&format!("error: cannot write {}: {e}", out.display()));
                return Status::UsageOrIo;
            }
        }
        None => stdout(&text),
    }
    Status::Ok
}

/// `bgc rust [--no-runtime] FILE`: the generated Rust module on standard output (`runtime`: with the
/// `bgc_runtime` trait implementations).
pub fn rust(path: &Path, runtime: bool, color: bool) -> Status {
    let mut sources = SourceMap::new();
    let Root {
        id,
        decode_error,
        mut loader,
    } = match read_root(&mut sources, path) {
        Ok(x) => x,
        Err(e) => {
            stderrln(&format!("error: cannot read {}: {e}", path.display()));
            return Status::UsageOrIo;
        }
    };
    if let Some(d) = decode_error {
        stderr(&render::to_text(&sources, &[d], color));
        return Status::InputErrors;
    }
    match bgc::codegen::compile(&mut sources, id, &mut loader) {
        Ok(compiled) => {
            // The warnings and notes on standard error, as `bgc fmu` and the build script give them.
            let findings = render::to_text(&sources, &compiled.warnings, color);
            if !findings.is_empty() {
                stderr(&findings);
            }
            // Named as `bgc::build` names it, so that both print the same text.
            let cwd = std::env::current_dir().ok();
            let name = match is_stdin(path) {
                true => super::io::STDIN_NAME.to_string(),
                false => bgc::build::header_name(path, cwd.as_deref()),
            };
            let options = bgc::codegen::rust::Options { runtime };
            // Streamed: a large model's module (250 MB for 200,000 states) is not held a second time.
            let mut out = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
            let written = bgc::codegen::rust::write_with(&compiled, &name, options, &mut out)
                .and_then(|()| std::io::Write::flush(&mut out));
            drop(out);
            if let Err(e) = written {
                output_failed(&e);
            }
            keep_until_exit(compiled);
            Status::Ok
        }
        Err(diags) => {
            stderr(&render::to_text(&sources, &diags, color));
            stderrln(&count_line(&diags));
            Status::InputErrors
        }
    }
}
