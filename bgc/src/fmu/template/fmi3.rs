//! The FMI 3.0 C interface (to come).
