//! A Functional Mock-up Unit of a bgc model: the generated model module (`model`), seen through slices
//! (`plant`), an instance with the standard's state machine (`instance`), the Co-Simulation integrator
//! (`solver`) and the C interfaces of FMI 2.0 (`fmi2`, `fmi2_solving`) and 3.0 (`fmi3`, `fmi3_solving`, `fmi3_absent`), with
//! their shared checks (`ffi`).

mod ffi;
#[cfg(feature = "fmi2")]
mod fmi2;
#[cfg(feature = "fmi2")]
mod fmi2_solving;
#[cfg(feature = "fmi3")]
mod fmi3;
#[cfg(feature = "fmi3")]
mod fmi3_absent;
#[cfg(feature = "fmi3")]
mod fmi3_solving;
mod instance;
mod model;
mod plant;
mod solver;

/// The GUID (FMI 2.0) or instantiation token (FMI 3.0) of `modelDescription.xml`, derived from the model's hash:
/// an importer that pairs this binary with another model's description is refused at instantiation.
pub const GUID: &str = "@GUID@";
