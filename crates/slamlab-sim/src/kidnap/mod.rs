//! Monte Carlo localization in the grid world, headless: the scenario, a runner
//! that steps the world and the filters phase by phase, and the metrics the CLI
//! and the experiments report.

pub mod assignment;
pub mod experiment;
pub mod export;
pub mod params;
pub mod run;
pub mod scenario;
pub mod session;

#[cfg(test)]
mod replay_tests;

pub use run::{FilterRun, FilterSummary, MclPhase, MclRun, MclRunError, TickError, UpdateRecord};
pub use scenario::{InitMode, LaserModelType, LocalizationEstimator, MclScenario};
