//! The compiler's test corpus (`bgc/tests/corpus/*.bg`) and this crate's test models (`tests/models/*.bg`),
//! generated like the models so that the tests of this crate check the generated code of every corpus model. Not
//! part of the public API.

macro_rules! corpus {
    ($($name:ident),* $(,)?) => {
        $(
            pub mod $name {
                include!(concat!(env!("OUT_DIR"), "/corpus/", stringify!($name), ".rs"));
            }
        )*
    };
}

corpus!(
    dc_motor_load,
    diode_rc,
    gear_train,
    hydraulic_cylinder,
    msd_chain,
    oscillator,
    parallel_rlc,
    pendulum,
    quarter_car,
    resistive_network,
    series_rlc,
    two_tank,
    // This crate's test models (`tests/models`).
    chained_loops,
    ladder_closed,
    ladder_loops,
);
