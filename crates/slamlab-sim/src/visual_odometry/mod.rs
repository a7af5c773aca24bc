//! The synthetic camera world of the visual-odometry lesson (thesis `000`
//! Sec. 4.3, Figs. 4.11-4.14): a pinhole camera on a ground vehicle driving a
//! docking approach toward a station in front of a white facade, the features
//! it sees (projections with pixel noise, a share of wrong matches), the
//! two-view experiment, the headless visual-odometry run, the lesson's
//! parameter table and its RANSAC stepped one sample at a time, and two real
//! photos matched by FAST corners and BRIEF descriptors ([`photos`]).
//!
//! Only this module holds the truth; the estimators in
//! `slamlab_core::vision` see pixel matches and the intrinsics.

pub mod assignment;
pub mod experiment;
pub mod export;
pub mod odometry;
pub mod photos;
pub mod scenario;
pub mod session;
pub mod world;

pub use experiment::{
    SprtSummary, TwoViewReport, TwoViewResult, TwoViewSettings, two_view_experiment,
};
pub use odometry::{VoPair, VoRun, VoSettings, run_visual_odometry};
pub use scenario::VoScenario;
pub use session::TwoViewSession;
pub use world::{CameraWorld, Frame, SceneKind, WorldPoint};
