//! The headless visual-odometry run: RANSAC two-view estimates chained along
//! the docking approach, with the scale of each step from the wheel speeds
//! (the thesis's choice, Sec. 4.3) or fixed to 1, beside wheel odometry.

use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::math;
use slamlab_core::random::standard_normal;
use slamlab_core::vision::{
    Correspondence, EarlyRejection, Method, Motion, RansacConfig, RelativePose, angle_between,
    estimate_two_view, rotation_angle,
};

use super::world::{CameraWorld, FRAME_DT, Frame, arc, relative_pose, world_from_camera};

/// The settings of a run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VoSettings {
    /// Frames of the approach (0.1 s each).
    pub frames: usize,
    /// Seed of the world, the noise and RANSAC.
    pub seed: u64,
    /// The minimal solver.
    pub method: Method,
    /// Hartley normalization in the eight-point solver.
    pub normalize: bool,
    /// Pixel noise, standard deviation, pixels.
    pub noise_px: f64,
    /// Share of wrong matches, 0 .. 1.
    pub outliers: f64,
    /// Frames between the two images of a VO step.
    pub stride: usize,
    /// A 20-frame turn on the spot a third of the way.
    pub pure_rotation_segment: bool,
    /// The middle third sees only the facade (a planar scene).
    pub planar_segment: bool,
    /// Early rejection of RANSAC's hypotheses (none, or Matas and Chum's SPRT).
    #[serde(default)]
    pub early_rejection: EarlyRejection,
    /// Levenberg-Marquardt refinement of each step's `(R, t)` on the Sampson
    /// distances of its inliers (`RansacConfig::refine`).
    #[serde(default = "refine_by_default")]
    pub refine: bool,
}

/// Levenberg-Marquardt refinement is on where a stored run or experiment
/// predates the switch (the lesson's step and the two-view experiment alike).
pub(super) fn refine_by_default() -> bool {
    true
}

impl Default for VoSettings {
    fn default() -> Self {
        Self {
            frames: 200,
            seed: 1,
            method: Method::FivePoint,
            normalize: true,
            noise_px: 1.0,
            outliers: 0.3,
            stride: 5,
            pure_rotation_segment: false,
            planar_segment: false,
            early_rejection: EarlyRejection::None,
            refine: true,
        }
    }
}

/// A planar pose for the top view.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TopPose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub theta: f64,
}

/// One VO step, between frames `from` and `to`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VoStep {
    /// The earlier frame.
    pub from: usize,
    /// The later frame.
    pub to: usize,
    /// Matches offered to RANSAC.
    pub matches: usize,
    /// Inliers / matches, 0 when the estimate failed.
    pub inlier_ratio: f64,
    /// RANSAC samples drawn.
    pub iterations: usize,
    /// Rotation error against the truth, degrees (None when the step failed).
    pub rotation_error_deg: Option<f64>,
    /// Angle between the estimated and true translation directions, degrees
    /// (None for a pure rotation or a failure).
    pub translation_angle_error_deg: Option<f64>,
    /// "general", "pure-rotation", or the error message.
    pub outcome: String,
}

/// Position RMSE of each trajectory against the truth over the VO frames, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryRmse {
    /// Integrated wheel speeds.
    pub wheel_odometry: f64,
    /// VO with each step's length from the wheel speeds.
    pub visual_odometry: f64,
    /// VO with each step of length 1 (scale unknown).
    pub visual_odometry_unit_scale: f64,
}

/// What a VO step saw, kept for the lesson to replay its RANSAC one sample at
/// a time: the matches, which are wrong (truth, for drawing only), the true
/// motion and the random generator as RANSAC found it, so that a replay draws
/// the same samples as the run did.
#[derive(Debug, Clone, PartialEq)]
pub struct VoPair {
    /// The matches offered to RANSAC.
    pub matches: Vec<Correspondence>,
    /// Which matches are wrong (the truth: metrics and drawing only).
    pub wrong: Vec<bool>,
    /// The true motion between the two camera frames.
    pub truth: RelativePose,
    /// RANSAC's random generator before this step.
    pub ransac_rng: ChaCha8Rng,
}

/// The result of [`run_visual_odometry`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VoRun {
    /// The settings.
    pub settings: VoSettings,
    /// Truth at the VO frames.
    pub truth: Vec<TopPose>,
    /// Wheel odometry at the VO frames.
    pub wheel_odometry: Vec<TopPose>,
    /// VO scaled by the wheel speeds.
    pub visual_odometry: Vec<TopPose>,
    /// VO with unit steps.
    pub visual_odometry_unit_scale: Vec<TopPose>,
    /// Each step's numbers.
    pub steps: Vec<VoStep>,
    /// The RMSEs.
    pub trajectory_rmse: TrajectoryRmse,
    /// Each step's matches and RANSAC generator, for replaying it.
    #[serde(skip)]
    pub pairs: Vec<VoPair>,
    /// The camera.
    #[serde(skip)]
    pub camera: Option<slamlab_core::vision::Intrinsics>,
    /// The RANSAC settings every step used.
    #[serde(skip)]
    pub config: Option<RansacConfig>,
}

/// Wheel-speed noise: 5 % of v and 0.03 rad/s on ω, plus a 0.01 rad/s bias.
fn wheel_reading(rng: &mut ChaCha8Rng, frame: &Frame) -> (f64, f64) {
    (
        frame.v * (1.0 + 0.05 * standard_normal(rng)),
        frame.w + 0.03 * standard_normal(rng) + 0.01,
    )
}

fn top(frame: &Frame) -> TopPose {
    TopPose {
        x: frame.x,
        y: frame.y,
        theta: frame.theta,
    }
}

/// The planar pose of a camera pose (camera at the vehicle origin).
fn top_of_camera(rotation: &Matrix3<f64>, position: &Vector3<f64>) -> TopPose {
    // R_wc = yaw · vehicle_from_camera: the camera's z axis is the vehicle's x.
    let forward = rotation.column(2);
    TopPose {
        x: position.x,
        y: position.y,
        theta: math::atan2(forward.y, forward.x),
    }
}

fn rmse(a: &[TopPose], b: &[TopPose]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y))
        .sum();
    (sum / n).sqrt()
}

/// Runs VO along the docking approach. Bad settings are clamped: at least 2
/// frames, stride at least 1, noise and outlier share into their ranges.
pub fn run_visual_odometry(settings: VoSettings) -> VoRun {
    let settings = clamped(settings);
    let world = CameraWorld::new(
        settings.seed,
        settings.frames,
        settings.pure_rotation_segment,
    );
    run_in_world(settings, &world)
}

/// The settings as a run uses them: at least 2 frames, stride at least 1,
/// noise and outlier share into their ranges (NaN to their defaults).
pub fn clamped(mut settings: VoSettings) -> VoSettings {
    settings.frames = settings.frames.clamp(2, 100_000);
    settings.stride = settings.stride.clamp(1, settings.frames - 1);
    settings.noise_px = if settings.noise_px.is_finite() {
        settings.noise_px.clamp(0.0, 20.0)
    } else {
        1.0
    };
    settings.outliers = if settings.outliers.is_finite() {
        settings.outliers.clamp(0.0, 1.0)
    } else {
        0.0
    };
    settings
}

/// [`run_visual_odometry`] in a world already built for these settings.
pub fn run_in_world(settings: VoSettings, world: &CameraWorld) -> VoRun {
    let settings = clamped(settings);
    let mut noise_rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x5eed_0001);
    let mut wheel_rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x5eed_0002);
    let mut ransac_rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x5eed_0003);
    let config = RansacConfig {
        method: settings.method,
        normalize: settings.normalize,
        early_rejection: settings.early_rejection,
        refine: settings.refine,
        ..RansacConfig::default()
    };
    // Wheel odometry for every frame.
    let mut wheel = vec![world.frames[0]];
    let mut distance = vec![0.0];
    for k in 1..world.frames.len() {
        let (v, w) = wheel_reading(&mut wheel_rng, &world.frames[k]);
        let prev = wheel[k - 1];
        wheel.push(arc(&prev, v, w, FRAME_DT));
        distance.push(distance[k - 1] + v.abs() * FRAME_DT);
    }
    let keyframes: Vec<usize> = (0..world.frames.len()).step_by(settings.stride).collect();
    let planar = |k: usize| {
        settings.planar_segment && (settings.frames / 3..2 * settings.frames / 3).contains(&k)
    };
    let (mut r_scaled, mut p_scaled) = world_from_camera(&world.frames[0]);
    let (mut r_unit, mut p_unit) = (r_scaled, p_scaled);
    let mut run = VoRun {
        settings,
        truth: vec![top(&world.frames[0])],
        wheel_odometry: vec![top(&wheel[0])],
        visual_odometry: vec![top(&world.frames[0])],
        visual_odometry_unit_scale: vec![top(&world.frames[0])],
        steps: Vec::new(),
        trajectory_rmse: TrajectoryRmse {
            wheel_odometry: 0.0,
            visual_odometry: 0.0,
            visual_odometry_unit_scale: 0.0,
        },
        pairs: Vec::new(),
        camera: Some(world.camera),
        config: Some(config),
    };
    for pair in keyframes.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (matches, wrong) = world.matches(
            a,
            b,
            settings.noise_px,
            settings.outliers,
            planar(a) || planar(b),
            &mut noise_rng,
        );
        let truth = relative_pose(&world.frames[a], &world.frames[b]);
        let step_length = distance[b] - distance[a];
        let pair = VoPair {
            matches: Vec::new(),
            wrong: Vec::new(),
            truth,
            ransac_rng: ransac_rng.clone(),
        };
        let mut step = VoStep {
            from: a,
            to: b,
            matches: matches.len(),
            inlier_ratio: 0.0,
            iterations: 0,
            rotation_error_deg: None,
            translation_angle_error_deg: None,
            outcome: String::new(),
        };
        // The step's rotation and the right camera's centre in the left frame
        // per unit of length (zero for a pure rotation).
        let (rotation, direction) =
            match estimate_two_view(&matches, &world.camera, config, &mut ransac_rng) {
                Ok(estimate) => {
                    step.inlier_ratio = estimate.inlier_count as f64 / matches.len().max(1) as f64;
                    step.iterations = estimate.iterations;
                    step.rotation_error_deg = Some(
                        rotation_angle(&(estimate.rotation.transpose() * truth.rotation))
                            .to_degrees(),
                    );
                    match (estimate.motion, estimate.translation) {
                        (Motion::General, Some(t)) => {
                            step.translation_angle_error_deg =
                                Some(angle_between(&t, &truth.translation).to_degrees());
                            step.outcome = "general".into();
                            (estimate.rotation, -(estimate.rotation.transpose() * t))
                        }
                        _ => {
                            step.outcome = "pure-rotation".into();
                            (estimate.rotation, Vector3::zeros())
                        }
                    }
                }
                Err(error) => {
                    // No estimate: hold the camera still for this step.
                    step.outcome = error.to_string();
                    (Matrix3::identity(), Vector3::zeros())
                }
            };
        p_scaled += r_scaled * direction * step_length;
        r_scaled *= rotation.transpose();
        p_unit += r_unit * direction;
        r_unit *= rotation.transpose();
        run.truth.push(top(&world.frames[b]));
        run.wheel_odometry.push(top(&wheel[b]));
        run.visual_odometry
            .push(top_of_camera(&r_scaled, &p_scaled));
        run.visual_odometry_unit_scale
            .push(top_of_camera(&r_unit, &p_unit));
        run.steps.push(step);
        run.pairs.push(VoPair {
            matches,
            wrong,
            ..pair
        });
    }
    run.trajectory_rmse = TrajectoryRmse {
        wheel_odometry: rmse(&run.wheel_odometry, &run.truth),
        visual_odometry: rmse(&run.visual_odometry, &run.truth),
        visual_odometry_unit_scale: rmse(&run.visual_odometry_unit_scale, &run.truth),
    };
    run
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_docking_run_pins_its_trajectory_errors() {
        let run = run_visual_odometry(VoSettings::default());
        let r = run.trajectory_rmse;
        eprintln!("{r:?}");
        let rotation: Vec<f64> = run
            .steps
            .iter()
            .filter_map(|s| s.rotation_error_deg)
            .collect();
        let mean_rotation = rotation.iter().sum::<f64>() / rotation.len().max(1) as f64;
        eprintln!("mean rotation error per step {mean_rotation:.4} deg");
        // Measured (seed 1): wheel odometry 0.47 m, VO scaled by the wheel
        // speeds 0.91 m, unit-scale VO 6.5 m; a mean rotation error of 0.185 deg
        // per step. Over 20 m with a 0.01 rad/s gyro bias the wheels still win:
        // each VO step's rotation error accumulates into heading drift as fast.
        // (When RANSAC locally optimized the first of a sample's hypotheses to
        // beat the best, in the order the five-point solver returned them, this
        // seed gave 0.161 deg and 0.87 m; over 48 seeds the two rules give a
        // mean of 0.193 and 0.195 deg, per-seed differences either way. With
        // local optimization stopped after three refits the steps' mean
        // rotation error was 0.196 deg, the chained RMSE 0.66 m by the luck of
        // how the errors cancelled along this one run.)
        assert!(mean_rotation < 0.19, "{mean_rotation}");
        assert!((r.wheel_odometry - 0.473).abs() < 0.01, "{r:?}");
        assert!((r.visual_odometry - 0.906).abs() < 0.01, "{r:?}");
        // Unit steps are 1 m where the vehicle moved 0.2-0.75 m: the scale is lost.
        assert!(
            r.visual_odometry_unit_scale > 3.0 * r.visual_odometry,
            "{r:?}"
        );
        let general = run.steps.iter().filter(|s| s.outcome == "general").count();
        // Measured: 31 of 39; the slow steps near the station (0.2 m) have too
        // little parallax and are reported as pure rotations.
        assert!(general >= 30, "{general} of {}", run.steps.len());
    }

    #[test]
    fn the_turn_on_the_spot_is_reported_as_pure_rotation() {
        let run = run_visual_odometry(VoSettings {
            pure_rotation_segment: true,
            stride: 5,
            ..VoSettings::default()
        });
        // Frames 66..86 turn on the spot: the steps 70→75 and 75→80 lie inside.
        for s in run.steps.iter().filter(|s| s.from >= 66 && s.to <= 86) {
            assert_eq!(s.outcome, "pure-rotation", "{s:?}");
        }
    }

    #[test]
    fn bad_settings_are_clamped_not_fatal() {
        let run = run_visual_odometry(VoSettings {
            frames: 0,
            stride: 0,
            noise_px: f64::NAN,
            outliers: 7.0,
            ..VoSettings::default()
        });
        assert_eq!(run.truth.len(), 2);
        assert_eq!(run.settings.outliers, 1.0);
        // All matches wrong: the step fails with a message, nothing panics.
        assert!(
            run.steps[0].outcome.contains("consensus"),
            "{:?}",
            run.steps[0]
        );
    }
}
