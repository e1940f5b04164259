//! The integration tests of this crate, in one test binary: one module per concern.

mod analysis_freqresp;
mod analysis_gain;
mod analysis_interconnect;
mod analysis_margins;
mod analysis_robustness;
mod control_gait;
mod control_impedance;
mod design_ltr;
mod estimation_alloc;
mod estimation_dual;
mod estimation_equivalence;
mod estimation_faults;
mod estimation_health;
mod estimation_reference;
mod estimation_robustness;
mod linalg_care;
mod linalg_dare;
mod linalg_design;
mod linalg_expm;
mod linalg_lyapunov;
mod linalg_pbh;
mod linalg_sylvester;
mod sim_linear;
mod sim_open_loop;
mod sim_sampled;
mod user_drive_example;
