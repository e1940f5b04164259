//! Command-line parsing and dispatch.

mod commands;
mod fit;
mod fit_model;
mod fit_plot;
mod fit_record;
mod fit_report;
mod fmu;
mod io;
mod matrix_text;
mod model;
mod params;
mod quantities;
mod record_text;
mod replay;
mod simulate;
mod sparse;

use clap::{Parser, Subcommand, ValueEnum};
use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;

/// bgc: the bond-graph compiler.
#[derive(Parser, Debug)]
#[command(
    name = "bgc",
    version,
    about,
    long_about = None,
    after_help = "A FILE given as `-` is read from standard input (its imports from the current directory)."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Colour in diagnostics: auto (when stderr is a terminal), always, never.
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, global = true)]
    color: ColorChoice,
    /// A directory where imports are looked up when they are not beside the importing file (repeatable). Imports
    /// resolve only to `.bg` files inside the input file's directory and the include directories.
    #[arg(short = 'I', long = "include", value_name = "DIR", global = true)]
    include: Vec<PathBuf>,
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum EquationsFormat {
    Text,
    /// LaTeX `align` blocks.
    Latex,
    Json,
}

/// The state coordinates of `bgc statespace`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Coords {
    /// The energy variables (momenta, displacements) of the storages in integral causality.
    Energy,
    /// The coordinates the model declares with `coords`.
    Declared,
}

/// How `bgc fit` and `bgc simulate --data` reconstruct a record's inputs between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum InputInterp {
    /// Zero-order hold: each sample holds until the next (the way loggers record commands).
    Zoh,
    /// Straight lines between samples.
    Linear,
}

/// The integration methods of `bgc simulate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Solver {
    /// Variable-order BDF, for stiff models.
    Bdf,
    /// ESDIRK3(4), stiff, one-step.
    Esdirk34,
    /// TR-BDF2, stiff, low order.
    #[value(name = "tr_bdf2")]
    TrBdf2,
    /// Tsitouras 5(4), explicit, for non-stiff models.
    Tsit45,
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
    /// The state equations ẋ = f(x, u, t), the outputs and the energy terms of a model.
    Equations {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        #[arg(long, value_enum, default_value_t = EquationsFormat::Text)]
        format: EquationsFormat,
    },
    /// The linear state space A, B, C, D of a model (its linearisation at --at for a nonlinear model).
    Statespace {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        /// A parameter value other than the default (repeatable, each name once): a number in the unit the file
        /// declares for it, or with its unit in brackets: `L_a=2.5` or `'L_a=2.5 [mH]'`.
        #[arg(long = "param", value_name = "NAME=VALUE", value_parser = params::parse_assignment)]
        params: Vec<params::Assignment>,
        /// The state coordinates.
        #[arg(long, value_enum, default_value_t = Coords::Energy)]
        coords: Coords,
        /// Entries as expressions of the parameters (those given with --param are put in as numbers).
        #[arg(long)]
        symbolic: bool,
        #[arg(long, value_enum, default_value_t = ReportFormat::Json)]
        format: ReportFormat,
        /// The operating point of a nonlinear model: energy states and inputs by name, comma-separated, each once;
        /// a number in the state's SI unit or the input's declared unit, or with its unit in brackets
        /// (`theta=30 [deg]`); those not given are 0.
        #[arg(long, value_name = "NAME=VALUE,...", value_delimiter = ',', value_parser = params::parse_assignment)]
        at: Vec<params::Assignment>,
        /// Print the effective parameter values (declared unit and SI) and the operating point on standard error.
        #[arg(long, short)]
        verbose: bool,
        /// Each matrix as coordinate triplets `[row, column, value]` of its nonzero entries (0-based), with its
        /// size, instead of dense rows: the form for large models.
        #[arg(long)]
        sparse: bool,
    },
    /// Simulate a model and print CSV: t, the states, the outputs, energy (stored), dissipated (in the resistors
    /// since t = 0) and supplied (by the sources since t = 0).
    Simulate {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        /// The end time in seconds (the run starts at t = 0).
        #[arg(long, value_name = "T", allow_hyphen_values = true)]
        t_end: f64,
        /// The sampling interval of the rows; t-end/1000 when absent.
        #[arg(long, value_name = "DT", allow_hyphen_values = true)]
        dt_out: Option<f64>,
        /// A parameter value other than the default (repeatable, each name once): a number in the unit the file
        /// declares for it, or with its unit in brackets: `L_a=2.5` or `'L_a=2.5 [mH]'`.
        #[arg(long = "param", value_name = "NAME=VALUE", value_parser = params::parse_assignment)]
        params: Vec<params::Assignment>,
        /// An input signal as an expression of t in the input's declared unit (or followed by a unit in brackets,
        /// `'theta=30*sin(t) [deg]'`): numbers, t, pi, + - * / ^, step(t0), ramp(t0), sin, cos, tan, exp, ln, sqrt,
        /// abs, sign, min, max (repeatable, each name once). Inputs not given are held at 0, with a warning.
        #[arg(long = "input", value_name = "NAME=EXPR", value_parser = params::parse_assignment)]
        inputs: Vec<params::Assignment>,
        /// An initial state value (a state name as in the CSV header, without the unit; repeatable, each name once):
        /// in the state's unit of the header, or with its unit in brackets. States not given start at 0.
        #[arg(long = "x0", value_name = "STATE=VALUE", value_parser = params::parse_assignment)]
        x0: Vec<params::Assignment>,
        #[arg(long, value_enum, default_value_t = Solver::Bdf)]
        solver: Solver,
        /// Relative tolerance.
        #[arg(long, default_value_t = 1e-6, allow_hyphen_values = true)]
        rtol: f64,
        /// Absolute tolerance (all states and the energy quadratures).
        #[arg(long, default_value_t = 1e-9, allow_hyphen_values = true)]
        atol: f64,
        /// The longest step the solver may take, in seconds (none when absent). The error estimate sees the model
        /// only where its steps evaluate it: a forcing that acts in short windows (a diode conducting near the
        /// peaks of a sine) can fall between them; a bound below the window's length makes the solver see it.
        #[arg(long, value_name = "H", allow_hyphen_values = true)]
        max_step: Option<f64>,
        /// Replay the inputs of a record (a CSV file as for `bgc fit --data`: a `t` column and one column per
        /// input, values in the declared units or in the units of the header; columns of measured outputs are
        /// read and ignored). Inputs given with --input are not in the record.
        #[arg(long, value_name = "LOG.csv")]
        data: Option<PathBuf>,
        /// How the record's inputs are reconstructed between samples (before the first sample the first value
        /// holds, after the last the last).
        #[arg(long, value_enum, default_value_t = InputInterp::Zoh, requires = "data")]
        interp: InputInterp,
        /// Print the effective parameter values (declared unit and SI) and initial state on standard error.
        #[arg(long, short)]
        verbose: bool,
    },
    /// Identify parameters (and initial states) from a measured CSV record: weighted least squares of the output
    /// error by Levenberg–Marquardt, with standard errors, correlations and the combinations the record does not
    /// determine.
    Fit {
        file: PathBuf,
        /// Only this model of the file.
        #[arg(long)]
        model: Option<String>,
        /// The record: a `t` column, one column per model input, one per measured output (by name; an empty cell
        /// is a missing sample), values in the declared units.
        #[arg(long, value_name = "LOG.csv")]
        data: PathBuf,
        /// The parameters to fit, comma-separated; their values (default or --param) are the starting guesses.
        #[arg(long, required = true, value_name = "NAME,...", value_delimiter = ',')]
        free: Vec<String>,
        /// A parameter value other than the default (repeatable), as for `bgc simulate`.
        #[arg(long = "param", value_name = "NAME=VALUE", value_parser = params::parse_assignment)]
        params: Vec<params::Assignment>,
        /// An initial state value (repeatable), as for `bgc simulate`; states not given start at 0.
        #[arg(long = "x0", value_name = "STATE=VALUE", value_parser = params::parse_assignment)]
        x0: Vec<params::Assignment>,
        /// Also fit the initial states: those given with --x0 (from their values), or all when none is given.
        #[arg(long)]
        free_x0: bool,
        /// The weight of an output's squared errors (repeatable; 1 when absent): 1/σ² of its noise makes the
        /// weighted residual variance 1 for a correct model.
        #[arg(long = "weight", value_name = "OUT=W", value_parser = params::parse_assignment)]
        weights: Vec<params::Assignment>,
        /// Bounds on a fitted parameter in its declared unit (repeatable): `NAME=LO..HI`, either side may be empty.
        #[arg(long = "bound", value_name = "NAME=LO..HI", value_parser = params::parse_assignment)]
        bounds: Vec<params::Assignment>,
        #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
        format: ReportFormat,
        /// Write the measured and fitted outputs as an SVG picture.
        #[arg(long, value_name = "OUT.svg")]
        plot: Option<PathBuf>,
        /// How inputs are reconstructed between samples.
        #[arg(long, value_enum, default_value_t = InputInterp::Zoh)]
        interp: InputInterp,
    },
    /// Print the Rust module that `bgc::build` generates for FILE (the same text, byte for byte).
    Rust {
        file: PathBuf,
        /// Leave out the `bgc_runtime` trait implementations (and use a module-local `ParamError`), as
        /// `bgc::build::Config::runtime(false)` does: the module then needs only core, nalgebra and libm.
        #[arg(long)]
        no_runtime: bool,
    },
    /// Run the language server for editors: the Language Server Protocol on standard input and output
    /// (diagnostics as you type, hover, go to definition, references, rename, outline, formatting, completion,
    /// quick fixes). Editors start it; see editors/README.md.
    Lsp {
        /// Speak on standard input and output (the only transport; accepted because editors pass it).
        #[arg(long)]
        stdio: bool,
    },
    /// Export a model as a Functional Mock-up Unit (FMI 2.0 or 3.0, Model Exchange and Co-Simulation in one
    /// FMU), built with cargo; see docs/fmu.md.
    Fmu {
        file: PathBuf,
        /// The model to export (required when the file declares several).
        #[arg(long)]
        model: Option<String>,
        /// The FMI version: 2 (default) or 3.
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(2..=3))]
        fmi: u8,
        /// The FMU file to write.
        #[arg(short, long, value_name = "OUT.fmu")]
        output: PathBuf,
        /// Cargo's target directory for the FMU's library (default: `bgc-fmu` in the temporary directory).
        #[arg(long, value_name = "DIR")]
        target_dir: Option<PathBuf>,
    },
    /// Print .bg files in the canonical layout (in place), or with --check report the files that differ.
    Fmt {
        /// The files to format; `-` formats standard input and prints the result.
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
    if let Err(e) = io::set_include_dirs(&cli.include) {
        io::stderrln(&format!("error: {e}"));
        return ExitCode::from(Status::UsageOrIo as u8);
    }
    let status = match cli.command {
        Command::Check { files, format } => commands::check(&files, format, color),
        Command::Rust { file, no_runtime } => commands::rust(&file, !no_runtime, color),
        Command::Fmt { files, check } => commands::fmt(&files, check, color),
        Command::Fmu {
            file,
            model,
            fmi,
            output,
            target_dir,
        } => fmu::fmu(
            &file,
            model.as_deref(),
            fmi,
            &output,
            target_dir,
            &cli.include,
        ),
        Command::Lsp { stdio: _ } => commands::lsp(&cli.include),
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
        Command::Equations {
            file,
            model,
            format,
        } => model::equations(&file, model.as_deref(), format, color),
        Command::Statespace {
            file,
            model,
            params,
            coords,
            symbolic,
            format,
            at,
            verbose,
            sparse,
        } => {
            let args = model::StateSpaceArgs {
                params: &params,
                coords,
                symbolic,
                format,
                at: &at,
                verbose,
                sparse,
            };
            model::statespace(&file, model.as_deref(), &args, color)
        }
        Command::Simulate {
            file,
            model,
            t_end,
            dt_out,
            params,
            inputs,
            x0,
            solver,
            rtol,
            atol,
            max_step,
            data,
            interp,
            verbose,
        } => {
            let args = simulate::SimulateArgs {
                t_end,
                dt_out,
                params: &params,
                inputs: &inputs,
                x0: &x0,
                solver,
                rtol,
                atol,
                max_step,
                record: data.as_deref().map(|path| simulate::RecordArg {
                    path,
                    replay: match interp {
                        InputInterp::Zoh => bgc::simulate::samples::Replay::Hold,
                        InputInterp::Linear => bgc::simulate::samples::Replay::Linear,
                    },
                }),
                verbose,
            };
            simulate::simulate(&file, model.as_deref(), &args, color)
        }
        Command::Fit {
            file,
            model,
            data,
            free,
            params,
            x0,
            free_x0,
            weights,
            bounds,
            format,
            plot,
            interp,
        } => {
            let args = fit::FitArgs {
                data: &data,
                free: &free,
                params: &params,
                x0: &x0,
                free_x0,
                weights: &weights,
                bounds: &bounds,
                format,
                plot: plot.as_ref(),
                interp: match interp {
                    InputInterp::Zoh => bgc_runtime::fit::Interp::Zoh,
                    InputInterp::Linear => bgc_runtime::fit::Interp::Linear,
                },
            };
            fit::run(&file, model.as_deref(), &args, color)
        }
    };
    ExitCode::from(status as u8)
}

/// The outcomes of a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Ok = 0,
    InputErrors = 1,
    UsageOrIo = 2,
    /// `bgc fit` ran but found no minimum (it stalled or reached the iteration limit): the report is printed, the
    /// estimates are no identification.
    NotConverged = 3,
}
