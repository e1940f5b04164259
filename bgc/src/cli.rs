//! Command-line parsing and dispatch.

mod commands;
mod io;

use clap::{Parser, Subcommand, ValueEnum};
use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;

/// bgc: the bond-graph compiler.
#[derive(Parser, Debug)]
#[command(name = "bgc", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Colour in diagnostics: auto (when stderr is a terminal), always, never.
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, global = true)]
    color: ColorChoice,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorChoice {
    Auto,
    Always,
    Never,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DiagFormat {
    /// rustc-like text with the source excerpt.
    Text,
    /// A JSON array of diagnostics, for tools and editors.
    Json,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReportFormat {
    Text,
    Json,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DrawFormat {
    /// A standalone SVG picture.
    Svg,
    /// Graphviz DOT source.
    Dot,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check .bg files: syntax, names, structure, domains and units.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[arg(long, value_enum, default_value_t = DiagFormat::Text)]
        format: DiagFormat,
    },
    /// Causality analysis: who sets the effort on every bond, integral or derivative causality of every storage,
    /// algebraic loops.
    Causality {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
        format: ReportFormat,
    },
    /// Draw the bond graph with power half-arrows and causal strokes.
    Draw {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        /// Where to write the drawing; standard output when absent.
        #[arg(short, long)]
        output: Option<PathBuf>,
        #[arg(long, value_enum, default_value_t = DrawFormat::Svg)]
        format: DrawFormat,
    },
    /// Print .bg files in the canonical layout (in place), or with --check report the files that differ.
    Fmt {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Change nothing; exit 1 when a file is not in the canonical layout.
        #[arg(long)]
        check: bool,
    },
}

/// Parses the arguments and runs the command.
pub fn run(args: impl IntoIterator<Item = OsString>) -> ExitCode {
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            // clap prints help and version to stdout with success, usage errors to stderr.
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let color = match cli.color {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => std::io::IsTerminal::is_terminal(&std::io::stderr()),
    };
    let status = match cli.command {
        Command::Check { files, format } => commands::check(&files, format, color),
        Command::Fmt { files, check } => commands::fmt(&files, check, color),
        Command::Causality {
            file,
            model,
            format,
        } => commands::causality(&file, model.as_deref(), format, color),
        Command::Draw {
            file,
            model,
            output,
            format,
        } => commands::draw(&file, model.as_deref(), output.as_deref(), format, color),
    };
    ExitCode::from(status as u8)
}

/// The three outcomes of a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Ok = 0,
    InputErrors = 1,
    UsageOrIo = 2,
}
