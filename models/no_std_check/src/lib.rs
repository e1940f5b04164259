//! Generated models in a `#![no_std]` library: the modules `bgc::build::Config::runtime(false)` generates need
//! only `core`, `nalgebra` without its default `std` feature, and `libm`.
//!
//! `cargo build -p bgc-no-std-check` is the proof: built alone, nothing in this crate's dependency graph links
//! `std`, so a generated function calling one of `std`'s `f64` methods (`sin`, `powi`, `sqrt`, ...) would not
//! compile. (In `cargo build --workspace` Cargo unifies `nalgebra`'s features with the other members', which
//! turns `std` on; the crate still compiles there, but proves less.) A `#![no_std]` library needs no panic
//! handler; the binary that links it provides one.
//!
//! The tests (which have `std`) check that these modules compute what the models crate's modules, generated with
//! the runtime's implementations, compute.

#![no_std]

pub mod back_support {
    include!(concat!(env!("OUT_DIR"), "/back_support.rs"));
}

pub mod pendulum_rig {
    include!(concat!(env!("OUT_DIR"), "/pendulum_rig.rs"));
}

pub mod rehab_leg {
    include!(concat!(env!("OUT_DIR"), "/rehab_leg.rs"));
}

pub mod walking_leg {
    include!(concat!(env!("OUT_DIR"), "/walking_leg.rs"));
}

pub mod pendulum {
    include!(concat!(env!("OUT_DIR"), "/pendulum.rs"));
}
