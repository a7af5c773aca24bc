//! One VO step's RANSAC stepped one sample at a time, for the lesson: the
//! matches of a [`VoPair`], RANSAC from the generator state the run had, each
//! iteration's report, a step back that replays the run to the sample before
//! (bit for bit: the generator is seeded), and the final estimate once the
//! adaptive bound is reached (the same estimate the run made for this step).

use rand_chacha::ChaCha8Rng;
use slamlab_core::vision::{
    Correspondence, Intrinsics, IterationReport, Ransac, RansacConfig, TwoViewEstimate, VisionError,
};

use super::odometry::VoPair;

/// RANSAC on one pair of images, stepped.
#[derive(Debug, Clone)]
pub struct TwoViewSession {
    matches: Vec<Correspondence>,
    wrong: Vec<bool>,
    camera: Intrinsics,
    config: RansacConfig,
    start_rng: ChaCha8Rng,
    /// `Err` when RANSAC cannot start (too few matches, NaN pixels).
    ransac: Result<Ransac, VisionError>,
    rng: ChaCha8Rng,
    reports: Vec<IterationReport>,
    /// Which matches the best hypothesis so far calls inliers.
    best_inliers: Vec<bool>,
    /// The refit, decomposition and motion once the bound is reached.
    estimate: Option<Result<TwoViewEstimate, VisionError>>,
}

impl TwoViewSession {
    /// RANSAC on `pair`'s matches with `camera` and `config`, before its first sample.
    pub fn new(pair: &VoPair, camera: &Intrinsics, config: RansacConfig) -> Self {
        let ransac = Ransac::new(&pair.matches, camera, config);
        let mut session = Self {
            matches: pair.matches.clone(),
            wrong: pair.wrong.clone(),
            camera: *camera,
            config,
            start_rng: pair.ransac_rng.clone(),
            ransac,
            rng: pair.ransac_rng.clone(),
            reports: Vec::new(),
            best_inliers: vec![false; pair.matches.len()],
            estimate: None,
        };
        session.finish_if_done();
        session
    }

    /// The matches.
    pub fn matches(&self) -> &[Correspondence] {
        &self.matches
    }

    /// Which matches are wrong (the truth).
    pub fn wrong(&self) -> &[bool] {
        &self.wrong
    }

    /// The camera.
    pub fn camera(&self) -> &Intrinsics {
        &self.camera
    }

    /// RANSAC's settings.
    pub fn config(&self) -> &RansacConfig {
        &self.config
    }

    /// Why RANSAC could not start, if it could not.
    pub fn start_error(&self) -> Option<&VisionError> {
        self.ransac.as_ref().err()
    }

    /// The RANSAC run, if it could start.
    pub fn ransac(&self) -> Option<&Ransac> {
        self.ransac.as_ref().ok()
    }

    /// Samples drawn so far.
    pub fn iteration(&self) -> usize {
        self.ransac().map_or(0, Ransac::iteration)
    }

    /// The adaptive bound N now.
    pub fn bound(&self) -> usize {
        self.ransac().map_or(0, Ransac::bound)
    }

    /// Inliers of the best hypothesis so far.
    pub fn best_inlier_count(&self) -> usize {
        self.ransac().map_or(0, Ransac::best_inliers)
    }

    /// Which matches the best hypothesis so far calls inliers (the final
    /// estimate's once it is made).
    pub fn inlier_mask(&self) -> &[bool] {
        match &self.estimate {
            Some(Ok(estimate)) => &estimate.inliers,
            _ => &self.best_inliers,
        }
    }

    /// The fundamental matrix (pixels) whose epipolar lines to draw: the final
    /// estimate's, else the best hypothesis so far.
    pub fn fundamental(&self) -> Option<nalgebra::Matrix3<f64>> {
        match &self.estimate {
            Some(Ok(estimate)) => Some(estimate.fundamental),
            _ => self.ransac().and_then(Ransac::best_fundamental),
        }
    }

    /// Every iteration's report, in order.
    pub fn reports(&self) -> &[IterationReport] {
        &self.reports
    }

    /// The latest iteration's report.
    pub fn last_report(&self) -> Option<&IterationReport> {
        self.reports.last()
    }

    /// Whether the bound is reached (or RANSAC could not start).
    pub fn is_done(&self) -> bool {
        self.ransac().is_none_or(Ransac::is_done)
    }

    /// The estimate, once RANSAC is done.
    pub fn estimate(&self) -> Option<&Result<TwoViewEstimate, VisionError>> {
        self.estimate.as_ref()
    }

    /// Draws one sample (thesis Sec. 4.3, "Random Sample Consensus"): the
    /// minimal solver's hypotheses, their inliers, the best so far and the
    /// bound. `None` when RANSAC is done.
    pub fn step(&mut self) -> Option<&IterationReport> {
        let ransac = self.ransac.as_mut().ok()?;
        let report = ransac.step(&mut self.rng)?;
        if report.improved
            && let Some(f) = ransac.best_fundamental()
        {
            self.best_inliers = ransac.classify(&f).0;
        }
        self.reports.push(report);
        self.finish_if_done();
        self.reports.last()
    }

    /// Steps until the bound is reached.
    pub fn run_to_end(&mut self) {
        while self.step().is_some() {}
    }

    /// Goes back one sample: replays RANSAC from its start to the sample
    /// before. False when no sample was drawn.
    pub fn step_back(&mut self) -> bool {
        let target = self.reports.len();
        if target == 0 {
            return false;
        }
        self.replay_to(target - 1);
        true
    }

    /// Replays RANSAC from its start to `iterations` samples.
    pub fn replay_to(&mut self, iterations: usize) {
        self.ransac = Ransac::new(&self.matches, &self.camera, self.config);
        self.rng = self.start_rng.clone();
        self.reports.clear();
        self.best_inliers = vec![false; self.matches.len()];
        self.estimate = None;
        while self.reports.len() < iterations && self.step().is_some() {}
        self.finish_if_done();
    }

    fn finish_if_done(&mut self) {
        if self.estimate.is_some() {
            return;
        }
        self.estimate = match &self.ransac {
            Ok(ransac) if ransac.is_done() => Some(ransac.finish()),
            Ok(_) => None,
            Err(error) => Some(Err(error.clone())),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visual_odometry::{VoSettings, run_visual_odometry};

    #[test]
    fn stepping_to_the_end_gives_the_runs_estimate_and_back_is_exact() {
        let run = run_visual_odometry(VoSettings {
            frames: 60,
            ..VoSettings::default()
        });
        let (Some(camera), Some(config)) = (run.camera, run.config) else {
            panic!("the run keeps its camera and settings");
        };
        let k = 5;
        let mut session = TwoViewSession::new(&run.pairs[k], &camera, config);
        assert_eq!(session.iteration(), 0);
        assert!(session.estimate().is_none());
        let first = session.step().cloned();
        let Some(first) = first else {
            panic!("a first sample");
        };
        assert_eq!(first.iteration, 1);
        assert_eq!(first.sample.len(), 5);
        assert_eq!(session.best_inlier_count(), first.best_inliers);
        let after_one = (session.bound(), session.best_inlier_count());
        session.step();
        session.step();
        assert!(session.step_back());
        session.step_back();
        assert_eq!(session.iteration(), 1);
        assert_eq!(session.last_report(), Some(&first));
        assert_eq!((session.bound(), session.best_inlier_count()), after_one);
        session.run_to_end();
        let Some(Ok(estimate)) = session.estimate() else {
            panic!("an estimate: {:?}", session.estimate());
        };
        let step = &run.steps[k];
        assert_eq!(estimate.iterations, step.iterations);
        assert_eq!(
            estimate.inlier_count as f64 / session.matches().len() as f64,
            step.inlier_ratio
        );
        assert_eq!(session.inlier_mask(), estimate.inliers.as_slice());
    }

    #[test]
    fn too_few_matches_is_a_message_not_a_panic() {
        let run = run_visual_odometry(VoSettings {
            frames: 20,
            ..VoSettings::default()
        });
        let (Some(camera), Some(config)) = (run.camera, run.config) else {
            panic!("the run keeps its camera and settings");
        };
        let mut pair = run.pairs[0].clone();
        pair.matches.truncate(3);
        pair.wrong.truncate(3);
        let mut session = TwoViewSession::new(&pair, &camera, config);
        assert!(session.step().is_none());
        assert!(!session.step_back());
        let message = session.start_error().map(ToString::to_string);
        assert_eq!(
            message.as_deref(),
            Some("the five-point algorithm needs at least 5 matches, got 3")
        );
    }
}
