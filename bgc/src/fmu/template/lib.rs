//! A Functional Mock-up Unit of a bgc model: the generated model module (`model`), seen through slices
//! (`plant`), an instance with the standard's state machine (`instance`), the Co-Simulation integrator
//! (`solver`) and the C interfaces of FMI 2.0 (`fmi2`) and 3.0 (`fmi3`).

mod model;
mod instance;
mod plant;
mod solver;
#[cfg(feature = "fmi2")]
mod fmi2;
#[cfg(feature = "fmi3")]
mod fmi3;

/// The GUID (FMI 2.0) or instantiation token (FMI 3.0) of `modelDescription.xml`, derived from the model's hash:
/// an importer that pairs this binary with another model's description is refused at instantiation.
pub const GUID: &str = "@GUID@";
