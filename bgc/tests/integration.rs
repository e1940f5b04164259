//! The integration tests of this crate, in one test binary: one module per concern.

mod cli_support;
mod codegen_support;
mod equations_support;

mod causality_allow;
mod causality_models;
mod cli;
mod cli_equations;
mod cli_hostile;
mod cli_messages;
mod cli_simulate;
mod cli_units;
mod codegen_build;
mod codegen_generate;
mod codegen_hostile_names;
mod codegen_no_std;
mod codegen_rustfmt;
mod codegen_state_space;
mod equations_back_support;
mod equations_corpus;
mod equations_derivative;
mod equations_fields;
mod equations_linear;
mod equations_loops;
mod equations_nonlinear;
mod equations_robustness;
mod front_end_props;
mod language_examples;
mod loops_globalised;
mod syntax_fixtures;
mod syntax_fuzz;
