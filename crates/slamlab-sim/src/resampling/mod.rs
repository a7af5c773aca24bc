//! The resampling lesson (`lesson=resampling`): four resamplers side by side on
//! one row of weighted particles.
//!
//! - [`session`]: the scenario, its parameter table and the run.
//! - [`experiment`]: the resampling experiment of `slamlab experiment resampling`.

pub mod experiment;
pub mod session;

pub use session::{LabRun, LabScenario};
