//! The fusion EKF: a time-ordered queue of measurements, a prediction to each
//! stamp and one update per measurement (robot_localization `ros_filter.cpp`
//! `integrateMeasurements`, `filter_base.cpp`, `ekf.cpp` `EKF::correct`).

use super::model::{self, STATE_SIZE, StateIndex, StateMatrix, StateVector};
use super::{FusionConfig, FusionError, FusionStats, Measurement, PoseMode, Reading, SensorConfig};
use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use std::collections::VecDeque;

/// What one update did, for the lesson's explanation panel.
#[derive(Clone, Debug, PartialEq)]
pub struct UpdateReport {
    /// The state variables this update measured, in order.
    pub variables: Vec<StateIndex>,
    /// The measurement `z` as fused (after the relative or differential
    /// conversion of a pose).
    pub measured: Vec<f64>,
    /// The predicted measurement `H x̄`.
    pub predicted: Vec<f64>,
    /// The innovation `ν = z − H x̄` (heading wrapped).
    pub innovation: Vec<f64>,
    /// The innovation covariance `S = H P̄ Hᵀ + R`.
    pub innovation_covariance: DMatrix<f64>,
    /// The normalized innovation squared `νᵀ S⁻¹ ν` (the squared Mahalanobis
    /// distance; `variables.len()` degrees of freedom).
    pub nis: f64,
    /// The Frobenius norm of the Kalman gain `K = P̄ Hᵀ S⁻¹`.
    pub gain_norm: f64,
    /// Whether the Mahalanobis test rejected it (then the state did not change).
    pub rejected: bool,
    /// For a pose reading: the mode it was taken in.
    pub pose_mode: Option<PoseMode>,
}

/// What became of one measurement.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It was fused (see [`UpdateReport::rejected`] for the Mahalanobis test: a
    /// rejected update is reported here with `rejected = true`).
    Updated(UpdateReport),
    /// A first pose in differential mode: stored for the next difference.
    Stored,
    /// It was skipped, for this reason (counted in [`FusionStats`]).
    Skipped(FusionError),
}

/// One measurement's step: which sensor, when, and what happened.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// The sensor's index.
    pub sensor: usize,
    /// The sensor's name ("" when the index is unknown).
    pub sensor_name: String,
    /// The measurement's stamp, seconds.
    pub stamp: f64,
    /// The reading's kind ("pose", "twist", "IMU").
    pub kind: &'static str,
    /// What happened.
    pub outcome: Outcome,
}

impl StepReport {
    /// A one-line name for the step, e.g. "IMU: yaw rate at 12.34 s" or
    /// "SLAM pose (differential): v_x, v_y, yaw rate at 3.00 s (rejected)".
    pub fn label(&self) -> String {
        match &self.outcome {
            Outcome::Updated(u) => {
                let names: Vec<&str> = u.variables.iter().map(|v| v.label()).collect();
                let mode = u
                    .pose_mode
                    .map_or(String::new(), |m| format!(" ({})", m.name()));
                let rejected = if u.rejected { " (rejected)" } else { "" };
                format!(
                    "{}{mode}: {} at {:.2} s{rejected}",
                    self.sensor_name,
                    names.join(", "),
                    self.stamp
                )
            }
            Outcome::Stored => format!(
                "{}: first pose stored for differencing at {:.2} s",
                self.sensor_name, self.stamp
            ),
            Outcome::Skipped(e) => format!("skipped: {e}"),
        }
    }

    /// The update report, when the measurement reached the update.
    pub fn update(&self) -> Option<&UpdateReport> {
        match &self.outcome {
            Outcome::Updated(u) => Some(u),
            _ => None,
        }
    }
}

/// What a pose sensor remembers between readings.
#[derive(Clone, Debug, Default)]
struct PoseMemory {
    /// Relative mode: the first reading.
    origin: Option<Pose2>,
    /// Differential mode: the previous reading, its stamp and covariance.
    previous: Option<(f64, Pose2, Matrix3<f64>)>,
}

/// The fusion EKF (module docs: robot_localization's EKF in the plane).
///
/// Cloning it checkpoints everything, the queue included.
#[derive(Clone, Debug)]
pub struct FusionEkf {
    config: FusionConfig,
    sensors: Vec<SensorConfig>,
    memory: Vec<PoseMemory>,
    mean: StateVector,
    covariance: StateMatrix,
    start: f64,
    time: f64,
    queue: VecDeque<Measurement>,
    stats: FusionStats,
}

impl FusionEkf {
    /// A filter starting at time `start` with the given initial mean and
    /// covariance. Without accelerations (`config.use_acceleration = false`) their
    /// mean and variances are set to zero.
    pub fn new(
        config: FusionConfig,
        sensors: Vec<SensorConfig>,
        start: f64,
        initial_mean: StateVector,
        initial_covariance: StateMatrix,
    ) -> Result<Self, FusionError> {
        config.validate()?;
        for s in &sensors {
            if let Some(t) = s.rejection_threshold
                && !(t.is_finite() && t > 0.0)
            {
                return Err(FusionError::InvalidThreshold {
                    sensor: s.name.clone(),
                    value: t,
                });
            }
        }
        let diagonal_ok = (0..STATE_SIZE).all(|i| initial_covariance[(i, i)] >= 0.0);
        if !(start.is_finite()
            && initial_mean.iter().all(|v| v.is_finite())
            && initial_covariance.iter().all(|v| v.is_finite())
            && diagonal_ok)
        {
            return Err(FusionError::InvalidInitialState);
        }
        let mut mean = initial_mean;
        mean[2] = wrap_angle(mean[2]);
        let mut covariance = initial_covariance;
        if !config.use_acceleration {
            for a in [StateIndex::AX as usize, StateIndex::AY as usize] {
                mean[a] = 0.0;
                covariance.row_mut(a).fill(0.0);
                covariance.column_mut(a).fill(0.0);
            }
        }
        let memory = vec![PoseMemory::default(); sensors.len()];
        Ok(Self {
            config,
            sensors,
            memory,
            mean,
            covariance,
            start,
            time: start,
            queue: VecDeque::new(),
            stats: FusionStats::default(),
        })
    }

    /// The filter's parameters.
    pub fn config(&self) -> &FusionConfig {
        &self.config
    }

    /// The sensors, in index order.
    pub fn sensors(&self) -> &[SensorConfig] {
        &self.sensors
    }

    /// The state mean `[x, y, ψ, v_x, v_y, ψ̇, a_x, a_y]`.
    pub fn mean(&self) -> &StateVector {
        &self.mean
    }

    /// The state covariance.
    pub fn covariance(&self) -> &StateMatrix {
        &self.covariance
    }

    /// The estimated pose.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.mean[0], self.mean[1], self.mean[2])
    }

    /// The pose's 3x3 covariance block (x, y, ψ).
    pub fn pose_covariance(&self) -> Matrix3<f64> {
        self.covariance.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// The time the state refers to, seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The filter's start time (measurements before it are refused).
    pub fn start(&self) -> f64 {
        self.start
    }

    /// Counts of fused, rejected and skipped measurements.
    pub fn stats(&self) -> &FusionStats {
        &self.stats
    }

    /// The state predicted to `stamp` without changing the filter (what
    /// robot_localization publishes at its output rate between measurements).
    /// `None` when `stamp` is before the filter's time or not finite.
    pub fn predicted_at(&self, stamp: f64) -> Option<(StateVector, StateMatrix)> {
        let dt = stamp - self.time;
        if !(dt >= 0.0 && dt.is_finite()) {
            return None;
        }
        Some(self.propagate(dt))
    }

    fn process_noise(&self) -> StateMatrix {
        let mut q = StateMatrix::zeros();
        for i in 0..STATE_SIZE {
            q[(i, i)] = self.config.process_noise[i];
        }
        if !self.config.use_acceleration {
            q[(6, 6)] = 0.0;
            q[(7, 7)] = 0.0;
        }
        q
    }

    /// Mean and covariance after `dt` seconds of the motion model:
    /// `x̄ = f(x, Δt)`, `P̄ = F P Fᵀ + Q Δt` (robot_localization `EKF::predict`).
    fn propagate(&self, dt: f64) -> (StateVector, StateMatrix) {
        if dt == 0.0 {
            return (self.mean, self.covariance);
        }
        let f = model::predict_jacobian(&self.mean, dt);
        let mean = model::predict_state(&self.mean, dt);
        let mut p = f * self.covariance * f.transpose() + self.process_noise() * dt;
        p = 0.5 * (p + p.transpose());
        (mean, p)
    }

    /// The prediction phase: moves the state to `stamp`. Refuses a stamp before the
    /// filter's time (time going backwards) or one that is not finite.
    pub fn predict_to(&mut self, stamp: f64) -> Result<(), FusionError> {
        if !stamp.is_finite() {
            return Err(FusionError::NonFiniteStamp {
                sensor: "prediction".to_owned(),
                stamp,
            });
        }
        if stamp < self.time {
            return Err(FusionError::TimeWentBackwards {
                sensor: "prediction".to_owned(),
                stamp,
                now: self.time,
            });
        }
        let (mean, covariance) = self.propagate(stamp - self.time);
        if !(mean.iter().all(|v| v.is_finite()) && covariance.iter().all(|v| v.is_finite())) {
            return Err(FusionError::Numerical {
                sensor: "prediction".to_owned(),
                stamp,
                what: "the prediction came out NaN or infinite",
            });
        }
        self.mean = mean;
        self.covariance = covariance;
        self.time = stamp;
        Ok(())
    }

    /// Adds a measurement to the queue, sorted by stamp (equal stamps keep their
    /// arrival order). Out-of-order arrivals are applied in stamp order as long
    /// as nothing later has been applied yet. A stamp that is not finite goes to
    /// the front, to be skipped and counted by the next [`FusionEkf::step`].
    pub fn enqueue(&mut self, measurement: Measurement) {
        let stamp = measurement.stamp;
        let at = if stamp.is_finite() {
            self.queue
                .partition_point(|q| q.stamp <= stamp || !q.stamp.is_finite())
        } else {
            0
        };
        self.queue.insert(at, measurement);
    }

    /// The queued measurements, earliest first.
    pub fn pending(&self) -> impl Iterator<Item = &Measurement> {
        self.queue.iter()
    }

    /// How many measurements wait in the queue.
    pub fn pending_len(&self) -> usize {
        self.queue.len()
    }

    /// Applies the earliest queued measurement; `None` when the queue is empty.
    pub fn step(&mut self) -> Option<StepReport> {
        let measurement = self.queue.pop_front()?;
        Some(self.apply(&measurement))
    }

    /// Applies every queued measurement stamped at or before `stamp`; returns how
    /// many were taken from the queue.
    pub fn process_until(&mut self, stamp: f64) -> usize {
        let mut count = 0;
        while let Some(front) = self.queue.front() {
            let s = front.stamp;
            if s.is_finite() && s > stamp {
                break;
            }
            self.step();
            count += 1;
        }
        count
    }

    /// Predicts to the measurement's stamp and applies it: the whole
    /// per-measurement cycle of robot_localization. Bad input is skipped with a
    /// typed reason in the report and counted; the state is then unchanged.
    pub fn apply(&mut self, m: &Measurement) -> StepReport {
        let sensor_name = self
            .sensors
            .get(m.sensor)
            .map_or_else(String::new, |s| s.name.clone());
        let outcome = match self.apply_inner(m) {
            Ok(outcome) => {
                match &outcome {
                    Outcome::Updated(u) if u.rejected => self.stats.rejected += 1,
                    Outcome::Updated(_) => self.stats.fused += 1,
                    Outcome::Stored => self.stats.stored += 1,
                    Outcome::Skipped(_) => {}
                }
                outcome
            }
            Err(e) => {
                self.stats.count(&e);
                Outcome::Skipped(e)
            }
        };
        StepReport {
            sensor: m.sensor,
            sensor_name,
            stamp: m.stamp,
            kind: m.reading.kind(),
            outcome,
        }
    }

    fn apply_inner(&mut self, m: &Measurement) -> Result<Outcome, FusionError> {
        let Some(sensor) = self.sensors.get(m.sensor) else {
            return Err(FusionError::UnknownSensor {
                sensor: m.sensor,
                stamp: m.stamp,
                count: self.sensors.len(),
            });
        };
        let name = || sensor.name.clone();
        if !m.stamp.is_finite() {
            return Err(FusionError::NonFiniteStamp {
                sensor: name(),
                stamp: m.stamp,
            });
        }
        if m.stamp < self.start {
            return Err(FusionError::BeforeStart {
                sensor: name(),
                stamp: m.stamp,
                start: self.start,
            });
        }
        if m.stamp < self.time {
            return Err(FusionError::TimeWentBackwards {
                sensor: name(),
                stamp: m.stamp,
                now: self.time,
            });
        }
        let values = m.reading.values();
        let cov = m.reading.covariance();
        if !(values.iter().all(|v| v.is_finite()) && cov.iter().all(|v| v.is_finite())) {
            return Err(FusionError::NonFiniteReading {
                sensor: name(),
                stamp: m.stamp,
            });
        }
        // Which of the reading's three values are fused.
        let carried = m.reading.variables();
        let selected: Vec<usize> = (0..3)
            .filter(|&k| sensor.fuse.contains(carried[k]))
            .collect();
        if selected.is_empty() {
            return Err(FusionError::NothingToFuse {
                sensor: name(),
                kind: m.reading.kind(),
            });
        }
        for &k in &selected {
            if !(cov[(k, k)] > 0.0) {
                return Err(FusionError::NonPositiveNoise {
                    sensor: name(),
                    stamp: m.stamp,
                    variable: carried[k].label(),
                    value: cov[(k, k)],
                });
            }
        }
        let threshold = sensor.rejection_threshold;
        let pose_mode = match m.reading {
            Reading::Pose { .. } => Some(sensor.pose_mode),
            _ => None,
        };
        // Prepare the measured vector, its covariance and the variables it measures.
        let (z, r, variables) = match (m.reading, sensor.pose_mode) {
            (Reading::Pose { pose, covariance }, PoseMode::Relative) => {
                let memory = &mut self.memory[m.sensor];
                let origin = *memory.origin.get_or_insert(pose);
                // P₀⁻¹ ∘ P; its covariance rotated into the first reading's frame
                // (robot_localization `preparePose` step 7g leaves the origin's own
                // uncertainty out, as here).
                let relative = origin.between(&pose);
                let (s, c) = math::sin_cos(origin.theta);
                let rot = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
                (
                    relative.to_vector(),
                    rot * covariance * rot.transpose(),
                    carried,
                )
            }
            (Reading::Pose { pose, covariance }, PoseMode::Differential) => {
                let memory = &mut self.memory[m.sensor];
                let previous = memory.previous.replace((m.stamp, pose, covariance));
                let Some((before, prev_pose, prev_cov)) = previous else {
                    return Ok(Outcome::Stored);
                };
                let dt = m.stamp - before;
                if !(dt > 0.0) {
                    return Err(FusionError::ZeroInterval {
                        sensor: name(),
                        stamp: m.stamp,
                    });
                }
                // Velocity = Δ / Δt with Δ = P_{k−1}⁻¹ ∘ P_k; its covariance is the
                // first-order propagation of both poses' covariances, divided by
                // Δt². robot_localization (`preparePose` step 7e) adds the two
                // covariances unrotated and multiplies by Δt; at the 1 Hz of the
                // thesis's SLAM pose the two agree up to the rotation terms.
                let (delta, j_prev, j_cur) = model::pose_delta(&prev_pose, &pose);
                let twist = delta / dt;
                let cov = (j_prev * prev_cov * j_prev.transpose()
                    + j_cur * covariance * j_cur.transpose())
                    / (dt * dt);
                (
                    twist,
                    cov,
                    [StateIndex::VX, StateIndex::VY, StateIndex::YawRate],
                )
            }
            (reading, _) => (reading.values(), *reading.covariance(), carried),
        };
        self.predict_to(m.stamp).map_err(|e| match e {
            FusionError::Numerical { what, .. } => FusionError::Numerical {
                sensor: name_of(&self.sensors, m.sensor),
                stamp: m.stamp,
                what,
            },
            other => other,
        })?;
        let update = self.update(&selected, &variables, &z, &r, threshold, pose_mode);
        update
            .map(Outcome::Updated)
            .map_err(|what| FusionError::Numerical {
                sensor: name_of(&self.sensors, m.sensor),
                stamp: m.stamp,
                what,
            })
    }

    /// The EKF correction (robot_localization `EKF::correct`) with the measured
    /// components `selected` of `z`, which measure `variables[selected]`:
    /// `ν = z − H x̄` (heading wrapped), `S = H P̄ Hᵀ + R`, optional Mahalanobis
    /// test `νᵀ S⁻¹ ν < threshold²`, `K = P̄ Hᵀ S⁻¹`, `x = x̄ + K ν`, and the Joseph
    /// form `P = (I − K H) P̄ (I − K H)ᵀ + K R Kᵀ`.
    ///
    /// `H` is 3x8 with a zero row for each component that is not fused; that
    /// component's `R` row and column are those of the identity and its innovation
    /// is zero, so it adds nothing to `S⁻¹`, `K`, `ν` or `P` (exactly), and every
    /// matrix keeps a fixed size.
    fn update(
        &mut self,
        selected: &[usize],
        variables: &[StateIndex; 3],
        z: &Vector3<f64>,
        r: &Matrix3<f64>,
        threshold: Option<f64>,
        pose_mode: Option<PoseMode>,
    ) -> Result<UpdateReport, &'static str> {
        let mut used = [false; 3];
        for &k in selected {
            used[k] = true;
        }
        let mut h = SMatrix::<f64, 3, STATE_SIZE>::zeros();
        let mut innovation = Vector3::zeros();
        let mut r_used = Matrix3::identity();
        for a in 0..3 {
            if !used[a] {
                continue;
            }
            let i = variables[a] as usize;
            h[(a, i)] = 1.0;
            let nu = z[a] - self.mean[i];
            innovation[a] = if variables[a].is_angle() {
                wrap_angle(nu)
            } else {
                nu
            };
            for b in 0..3 {
                if used[b] {
                    r_used[(a, b)] = r[(a, b)];
                }
            }
        }
        let pht = self.covariance * h.transpose();
        let s = h * pht + r_used;
        let Some(chol) = s.cholesky() else {
            return Err("the innovation covariance is not positive definite");
        };
        let nis = innovation.dot(&chol.solve(&innovation));
        let gain = chol.solve(&pht.transpose()).transpose();
        let m = selected.len();
        let mut s_selected = DMatrix::zeros(m, m);
        for (a, &ka) in selected.iter().enumerate() {
            for (b, &kb) in selected.iter().enumerate() {
                s_selected[(a, b)] = s[(ka, kb)];
            }
        }
        let report = UpdateReport {
            variables: selected.iter().map(|&k| variables[k]).collect(),
            measured: selected.iter().map(|&k| z[k]).collect(),
            predicted: selected
                .iter()
                .map(|&k| self.mean[variables[k] as usize])
                .collect(),
            innovation: selected.iter().map(|&k| innovation[k]).collect(),
            innovation_covariance: s_selected,
            nis,
            gain_norm: gain.norm(),
            rejected: threshold.is_some_and(|t| !(nis < t * t)),
            pose_mode,
        };
        if report.rejected {
            return Ok(report);
        }
        let mut mean = self.mean + gain * innovation;
        mean[2] = wrap_angle(mean[2]);
        let ikh = StateMatrix::identity() - gain * h;
        // K R Kᵀ with the fused block of R (the unused rows of K are zero).
        let mut r_fused = Matrix3::zeros();
        for &a in selected {
            for &b in selected {
                r_fused[(a, b)] = r[(a, b)];
            }
        }
        let mut covariance =
            ikh * self.covariance * ikh.transpose() + gain * r_fused * gain.transpose();
        covariance = 0.5 * (covariance + covariance.transpose());
        if !(mean.iter().all(|v| v.is_finite()) && covariance.iter().all(|v| v.is_finite())) {
            return Err("the update came out NaN or infinite");
        }
        self.mean = mean;
        self.covariance = covariance;
        Ok(report)
    }
}

fn name_of(sensors: &[SensorConfig], index: usize) -> String {
    sensors
        .get(index)
        .map_or_else(String::new, |s| s.name.clone())
}
