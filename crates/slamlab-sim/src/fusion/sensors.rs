//! The drive and the three simulated sensors: wheel odometry, IMU and SLAM pose,
//! recorded in one [`SensorLog`].

use super::log::{Arrival, IMU, ODOMETRY, SLAM, SensorLog, TruthSample};
use super::scenario::{DriveKind, FusionScenario, ScenarioError, SlamSource};
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slamlab_core::geometry::{Pose2, wrap_angle};
use slamlab_core::kalman::fusion::Reading;
use slamlab_core::math;
use slamlab_core::motion::{Control, MotionModel};

/// The random streams of a fusion scenario: one per source, so changing one
/// sensor's parameters never changes another's noise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FusionStream {
    Drive = 21,
    Odometry = 22,
    Imu = 23,
    Slam = 24,
}

fn stream(seed: u64, which: FusionStream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(which as u64);
    rng
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    slamlab_core::random::standard_normal(rng)
}

/// A sensor's sample clock: fires at `k / rate`.
struct Clock {
    period: f64,
    next: f64,
}

impl Clock {
    fn new(rate: f64) -> Self {
        Self {
            period: 1.0 / rate,
            next: 0.0,
        }
    }

    /// Whether a sample is due at `t` (and schedules the next one).
    fn due(&mut self, t: f64) -> bool {
        if t + 1e-9 >= self.next {
            self.next += self.period;
            // A sensor faster than the truth fires once per tick.
            if self.next <= t {
                self.next = t + self.period;
            }
            true
        } else {
            false
        }
    }
}

/// Simulates the drive and all three sensors (each enabled or not, they are all
/// simulated so that switching one off never changes another's noise).
pub fn simulate(scenario: &FusionScenario) -> Result<SensorLog, ScenarioError> {
    scenario.validate()?;
    let d = &scenario.drive;
    let (o, imu, s) = (&scenario.odometry, &scenario.imu, &scenario.slam);
    let dt = 1.0 / d.truth_rate;
    let ticks = (d.duration * d.truth_rate).round() as usize;
    let mut drive_rng = stream(scenario.seed, FusionStream::Drive);
    let mut odo_rng = stream(scenario.seed, FusionStream::Odometry);
    let mut imu_rng = stream(scenario.seed, FusionStream::Imu);
    let mut slam_rng = stream(scenario.seed, FusionStream::Slam);

    // Per-drive errors: wheel scales, gyro bias.
    let scale_left = 1.0 + o.scale_error_std * normal(&mut odo_rng);
    let scale_right = 1.0 + o.scale_error_std * normal(&mut odo_rng);
    let mut bias = imu.gyro_bias_std * normal(&mut imu_rng);
    let mut drift = Vector3::<f64>::zeros();

    let mut log = SensorLog {
        truth: Vec::with_capacity(ticks + 1),
        truth_dt: dt,
        measurements: Vec::with_capacity(ticks),
        odometry_path: Vec::new(),
        slam_poses: Vec::new(),
        relocalizations: Vec::new(),
        gyro_bias: Vec::new(),
    };
    let (mut odo_clock, mut imu_clock, mut slam_clock) =
        (Clock::new(o.rate), Clock::new(imu.rate), Clock::new(s.rate));
    let mut last_odometry: Option<(f64, Control)> = None;
    let mut dead_reckoning = Pose2::IDENTITY;
    let mut last_imu_t = 0.0;
    let mut last_slam_t = 0.0;

    let mut pose = Pose2::IDENTITY;
    let (mut v, mut w) = (0.0_f64, 0.0_f64);
    let mut accel = 0.0;
    let mut waypoint = pose.translation();
    for k in 0..=ticks {
        let t = k as f64 * dt;
        log.truth.push(TruthSample { t, pose, v, w });

        if odo_clock.due(t) {
            // Wheel speeds as the encoders see them: skid makes the wheels turn
            // (1 + slip) times more differentially than the body, each wheel's
            // radius error scales its speed.
            let half = 0.5 * (1.0 + o.turn_slip) * w * o.wheel_base;
            let (v_l, v_r) = ((v - half) * scale_left, (v + half) * scale_right);
            let v_o = 0.5 * (v_l + v_r) + o.speed_noise_std * normal(&mut odo_rng);
            let w_o = (v_r - v_l) / o.wheel_base + o.turn_noise_std * normal(&mut odo_rng);
            if let Some((t0, c)) = last_odometry {
                dead_reckoning = MotionModel::ExactArc.predict(&dead_reckoning, &c, t - t0);
            }
            last_odometry = Some((t, Control::new(v_o, w_o)));
            log.odometry_path.push((t, dead_reckoning));
            let reading = Reading::Twist {
                twist: Vector3::new(v_o, 0.0, w_o),
                covariance: variances(o.speed_noise_std, o.lateral_std, o.turn_noise_std),
            };
            log.measurements.push(Arrival::new(ODOMETRY, t, t, reading));
        }
        if imu_clock.due(t) {
            bias += imu.gyro_bias_walk * (t - last_imu_t).sqrt() * normal(&mut imu_rng);
            last_imu_t = t;
            let yaw_rate = w + bias + imu.gyro_noise_std * normal(&mut imu_rng);
            let a_x = accel + imu.accel_noise_std * normal(&mut imu_rng);
            let a_y = v * w + imu.accel_noise_std * normal(&mut imu_rng);
            log.gyro_bias.push((t, bias));
            let reading = Reading::Imu {
                values: Vector3::new(yaw_rate, a_x, a_y),
                covariance: variances(imu.gyro_noise_std, imu.accel_noise_std, imu.accel_noise_std),
            };
            log.measurements.push(Arrival::new(IMU, t, t, reading));
        }
        if slam_clock.due(t) {
            let gap = t - last_slam_t;
            last_slam_t = t;
            // The map drifts between relocalizations; a relocalization resets it.
            let step = s.drift_per_sqrt_s * gap.sqrt();
            drift += Vector3::new(
                step * normal(&mut slam_rng),
                step * normal(&mut slam_rng),
                step * normal(&mut slam_rng),
            );
            let relocalize = s.relocalization_interval > 0.0
                && gap > 0.0
                && slam_rng.random::<f64>() < 1.0 - math::exp(-gap / s.relocalization_interval);
            if relocalize {
                drift = Vector3::zeros();
                log.relocalizations.push(t);
            }
            let mut error = drift
                + Vector3::new(
                    s.position_noise_std * normal(&mut slam_rng),
                    s.position_noise_std * normal(&mut slam_rng),
                    s.yaw_noise_std * normal(&mut slam_rng),
                );
            if slam_rng.random::<f64>() < s.outlier_probability {
                error[0] += s.outlier_std * normal(&mut slam_rng);
                error[1] += s.outlier_std * normal(&mut slam_rng);
            }
            let reported = Pose2::new(pose.x + error[0], pose.y + error[1], pose.theta + error[2]);
            log.slam_poses.push((t, reported));
            let reading = Reading::Pose {
                pose: reported,
                covariance: variances(s.position_noise_std, s.position_noise_std, s.yaw_noise_std),
            };
            log.measurements
                .push(Arrival::new(SLAM, t, t + s.latency, reading));
        }

        // The next tick's controls.
        let (v_new, w_new) = match d.kind {
            DriveKind::RandomWalk {
                speed_density,
                turn_density,
            } => (
                v + (speed_density * dt).sqrt() * normal(&mut drive_rng),
                w + (turn_density * dt).sqrt() * normal(&mut drive_rng),
            ),
            DriveKind::Waypoints if t < d.standstill => (0.0, 0.0),
            DriveKind::Waypoints => {
                let to = waypoint - pose.translation();
                if to.norm() < 0.15 {
                    waypoint = next_waypoint(&mut drive_rng, &pose, d.room);
                }
                let to = waypoint - pose.translation();
                let heading_error = wrap_angle(math::atan2(to[1], to[0]) - pose.theta);
                let w_cmd = (1.0 * heading_error).clamp(-d.max_turn_rate, d.max_turn_rate);
                let along = math::cos(heading_error).max(0.0);
                let v_cmd = d.max_speed * along * along * (to.norm() / 0.3).min(1.0);
                let dv = (v_cmd - v).clamp(-d.max_acceleration * dt, d.max_acceleration * dt);
                let dw =
                    (w_cmd - w).clamp(-d.max_turn_acceleration * dt, d.max_turn_acceleration * dt);
                (v + dv, w + dw)
            }
        };
        accel = (v_new - v) / dt;
        // Exact arc with the average of the old and new controls over the tick.
        let control = Control::new(0.5 * (v + v_new), 0.5 * (w + w_new));
        pose = MotionModel::ExactArc.predict(&pose, &control, dt);
        (v, w) = (v_new, w_new);
    }
    if s.source == SlamSource::LandmarkEkf {
        super::landmark_pose::replace_slam_with_landmark_ekf(
            &mut log,
            scenario.seed,
            s.rate,
            s.latency,
        );
        return Ok(log);
    }
    log.measurements.sort_by(|a, b| {
        a.arrival
            .total_cmp(&b.arrival)
            .then(a.measurement.stamp.total_cmp(&b.measurement.stamp))
    });
    Ok(log)
}

/// A waypoint inside the room (centred on the start), at least 1 m away when the
/// room allows it.
fn next_waypoint(rng: &mut ChaCha8Rng, pose: &Pose2, room: [f64; 2]) -> nalgebra::Vector2<f64> {
    let mut candidate = pose.translation();
    for _ in 0..20 {
        candidate = nalgebra::Vector2::new(
            (rng.random::<f64>() - 0.5) * room[0] * 0.8,
            (rng.random::<f64>() - 0.5) * room[1] * 0.8,
        );
        if (candidate - pose.translation()).norm() >= 1.0 {
            break;
        }
    }
    candidate
}

/// The covariance of independent errors: `diag(σ₁², σ₂², σ₃²)`.
fn variances(s1: f64, s2: f64, s3: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(s1.powi(2), s2.powi(2), s3.powi(2)))
}
