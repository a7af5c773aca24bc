//! The filters lesson (`lesson=filters`): one Gaussian through one nonlinear
//! function by the EKF, the unscented transform and particles; a histogram Bayes
//! filter beside a Kalman filter in a corridor.
//!
//! - [`session`]: the scenario, its parameter table, the one-step comparison and
//!   the corridor run.

pub mod session;

pub use session::FiltersScenario;
