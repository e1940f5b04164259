//! Frequency-domain analysis of linear models: frequency response and Bode data, stability margins and
//! bandwidth, and the block-diagram algebra needed to form a loop transfer.
//!
//! - [`freqresp`]: `G(jω) = C (jωI − A)⁻¹ B + D` (or at `z = e^{jωT}`), Bode magnitude and unwrapped phase.
//! - [`margins`]: gain, phase, delay and stability margins of a SISO loop (python-control's
//!   `stability_margins` conventions) and the search grid they use.
//! - [`gain`]: the −3 dB bandwidth, the first crossing of a gain level, the peak gain.
//! - [`interconnect`]: `series`, `parallel`, `feedback`, `append`, and loops broken at the plant input or
//!   output of an observer-based state-feedback controller.

pub mod error;
pub mod freqresp;
pub mod gain;
pub mod interconnect;
pub mod margins;
mod resolvent;
mod scalar_search;

pub use error::AnalysisError;
pub use freqresp::{
    Bode, C64, Resolvent, bode, dc_gain, frequency_response, logspace, siso_response,
    unwrap_degrees,
};
pub use gain::{LevelCrossing, bandwidth, first_level_crossing, peak_gain};
pub use interconnect::{
    FeedbackSign, append, feedback, loop_at_plant_input, loop_at_plant_output, negate,
    observer_controller, parallel, series, static_gain,
};
pub use margins::{StabilityMargins, search_grid, stability_margins};
