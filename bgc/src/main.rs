//! The `bgc` command: the only part of the compiler that reads files and prints.
//!
//! Exit status: 0 when the input has no errors (warnings are printed), 1 when it has errors, 2 for usage or I/O
//! errors.

mod cli;

/// See `mimalloc` in Cargo.toml: the command allocates and frees many small values.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::run(std::env::args_os())
}
