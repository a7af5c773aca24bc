//! The estimators before any SLAM (thesis `000` ch. 2; thesis `002` ch. 2): one
//! Gaussian pushed through one nonlinear function by linearization (the EKF's
//! step), by the unscented transform (the UKF's step) and by particles
//! ([`one_step`]); a 1-D Bayes filter on a histogram ([`histogram`]); and the
//! 1-D Kalman filter with its gain ([`kalman1`]).

pub mod histogram;
pub mod kalman1;
pub mod one_step;

pub use histogram::{Corridor, Histogram};
pub use kalman1::{Kalman1, KalmanUpdate};
pub use one_step::{Comparison, Gaussian2, OneStepError, StepFunction};
