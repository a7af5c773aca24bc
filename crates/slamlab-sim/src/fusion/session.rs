//! The fusion lesson's run under the generic [`Stepper`](crate::stepper::Stepper):
//! every chosen mode's [`ModeRun`] on one drive's sensor data, stepped one
//! measurement at a time (a phase) or one second at a time (a tick).
//!
//! The live changes a student makes are events, recorded so that stepping back
//! replays them exactly: switching a sensor on or off, changing a sensor's noise
//! (the readings that arrive from now on are simulated again with the new noise;
//! the truth and every random draw stay the same), and injecting a bad reading
//! (NaN, zero noise, a stamp before the start or from the past) that the filters
//! skip, name and count.

use super::log::{Arrival, IMU, ODOMETRY, SLAM, SensorLog};
use super::params::FusionLessonScenario;
use super::runner::{FusionMode, ModeRun};
use super::scenario::FusionScenario;
use super::sensors::simulate;
use crate::stepper::Simulation;
use nalgebra::{Matrix3, Vector3};
use slamlab_core::geometry::Pose2;
use slamlab_core::kalman::fusion::{Measurement, Outcome, Reading, StepReport};
use slamlab_core::motion::{Control, MotionModel};
use std::sync::Arc;

/// A sensor noise the student can change while the run goes on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LiveNoise {
    /// Wheel odometry's forward-speed noise, m/s.
    OdometrySpeed,
    /// Wheel odometry's yaw-rate noise, rad/s.
    OdometryTurn,
    /// The IMU's gyroscope noise, rad/s.
    ImuGyro,
    /// The SLAM pose's position noise, metres.
    SlamPosition,
    /// The SLAM pose's heading noise, radians.
    SlamYaw,
}

impl LiveNoise {
    /// Every live noise, in panel order.
    pub const ALL: [LiveNoise; 5] = [
        LiveNoise::OdometrySpeed,
        LiveNoise::OdometryTurn,
        LiveNoise::ImuGyro,
        LiveNoise::SlamPosition,
        LiveNoise::SlamYaw,
    ];

    /// The sensor it belongs to.
    pub fn sensor(self) -> usize {
        match self {
            LiveNoise::OdometrySpeed | LiveNoise::OdometryTurn => ODOMETRY,
            LiveNoise::ImuGyro => IMU,
            LiveNoise::SlamPosition | LiveNoise::SlamYaw => SLAM,
        }
    }

    /// Its value in `scenario` (SI units).
    pub fn get(self, scenario: &FusionScenario) -> f64 {
        match self {
            LiveNoise::OdometrySpeed => scenario.odometry.speed_noise_std,
            LiveNoise::OdometryTurn => scenario.odometry.turn_noise_std,
            LiveNoise::ImuGyro => scenario.imu.gyro_noise_std,
            LiveNoise::SlamPosition => scenario.slam.position_noise_std,
            LiveNoise::SlamYaw => scenario.slam.yaw_noise_std,
        }
    }

    fn set(self, scenario: &mut FusionScenario, value: f64) {
        let field = match self {
            LiveNoise::OdometrySpeed => &mut scenario.odometry.speed_noise_std,
            LiveNoise::OdometryTurn => &mut scenario.odometry.turn_noise_std,
            LiveNoise::ImuGyro => &mut scenario.imu.gyro_noise_std,
            LiveNoise::SlamPosition => &mut scenario.slam.position_noise_std,
            LiveNoise::SlamYaw => &mut scenario.slam.yaw_noise_std,
        };
        *field = value;
    }

    /// What it is, for messages.
    pub fn label(self) -> &'static str {
        match self {
            LiveNoise::OdometrySpeed => "wheel odometry speed noise",
            LiveNoise::OdometryTurn => "wheel odometry yaw-rate noise",
            LiveNoise::ImuGyro => "IMU gyroscope noise",
            LiveNoise::SlamPosition => "SLAM position noise",
            LiveNoise::SlamYaw => "SLAM heading noise",
        }
    }
}

/// A bad reading the student can inject, to see the filters skip and count it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BadReading {
    /// An IMU reading whose yaw rate is NaN.
    NanImu,
    /// A wheel-odometry twist whose covariance is zero (zero noise).
    ZeroNoiseOdometry,
    /// A SLAM pose stamped one second before the filters' start.
    SlamBeforeStart,
    /// A SLAM pose stamped half a second before the filters' current time
    /// (time going backwards).
    SlamFromThePast,
}

impl BadReading {
    /// Every kind, in panel order.
    pub const ALL: [BadReading; 4] = [
        BadReading::NanImu,
        BadReading::ZeroNoiseOdometry,
        BadReading::SlamBeforeStart,
        BadReading::SlamFromThePast,
    ];

    /// A button's text.
    pub fn label(self) -> &'static str {
        match self {
            BadReading::NanImu => "NaN IMU reading",
            BadReading::ZeroNoiseOdometry => "zero-noise odometry",
            BadReading::SlamBeforeStart => "SLAM pose before the start",
            BadReading::SlamFromThePast => "SLAM pose from the past",
        }
    }

    /// The reading, arriving at `now`.
    fn measurement(self, now: f64) -> Measurement {
        let small = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-4));
        match self {
            BadReading::NanImu => Measurement {
                sensor: IMU,
                stamp: now,
                reading: Reading::Imu {
                    values: Vector3::new(f64::NAN, 0.0, 0.0),
                    covariance: small,
                },
            },
            BadReading::ZeroNoiseOdometry => Measurement {
                sensor: ODOMETRY,
                stamp: now,
                reading: Reading::Twist {
                    twist: Vector3::zeros(),
                    covariance: Matrix3::zeros(),
                },
            },
            BadReading::SlamBeforeStart | BadReading::SlamFromThePast => Measurement {
                sensor: SLAM,
                stamp: if self == BadReading::SlamBeforeStart {
                    -1.0
                } else {
                    now - 0.5
                },
                reading: Reading::Pose {
                    pose: Pose2::IDENTITY,
                    covariance: small,
                },
            },
        }
    }
}

/// A live change to the lesson's run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FusionEvent {
    /// Switch a sensor (index [`ODOMETRY`], [`IMU`], [`SLAM`]) on or off in every run.
    SetSensor {
        /// The sensor's index.
        sensor: usize,
        /// On or off.
        on: bool,
    },
    /// Change a sensor's noise for the readings that arrive from now on.
    SetNoise {
        /// Which noise.
        noise: LiveNoise,
        /// Its new standard deviation (SI units); not finite or not above 0 is refused.
        value: f64,
    },
    /// Hand every run a bad reading now.
    Inject(BadReading),
}

impl FusionEvent {
    /// What happened, for the lesson's note.
    pub fn describe(&self) -> String {
        match *self {
            FusionEvent::SetSensor { sensor, on } => format!(
                "{} switched {}",
                sensor_name(sensor),
                if on { "on" } else { "off" }
            ),
            FusionEvent::SetNoise { noise, value } => {
                format!("{} set to {value:.4} from now on", noise.label())
            }
            FusionEvent::Inject(bad) => format!("injected a {}", bad.label()),
        }
    }
}

/// A sensor's name ("wheel odometry", "IMU", "SLAM pose").
pub fn sensor_name(sensor: usize) -> &'static str {
    match sensor {
        ODOMETRY => "wheel odometry",
        IMU => "IMU",
        SLAM => "SLAM pose",
        _ => "unknown sensor",
    }
}

/// What one phase did.
#[derive(Clone, Debug, PartialEq)]
pub enum FusionPhase {
    /// One reading, applied (or stored, rejected, skipped) by every run that uses
    /// its sensor; the label names it ("IMU: yaw rate at 12.34 s").
    Measurement {
        /// The sensor's index.
        sensor: usize,
        /// The reading's stamp, seconds.
        stamp: f64,
        /// The lead run's one-line report.
        label: String,
    },
    /// A second without any reading of a sensor in use: the filters only predict.
    Quiet {
        /// The time reached, seconds.
        until: f64,
    },
    /// The drive is over.
    End,
}

impl FusionPhase {
    /// The phase's name on screen.
    pub fn label(&self) -> String {
        match self {
            FusionPhase::Measurement { label, .. } => label.clone(),
            FusionPhase::Quiet { until } => {
                format!("no reading in use up to {until:.2} s: prediction only")
            }
            FusionPhase::End => "end of the drive".to_owned(),
        }
    }
}

/// How many skipped-reading messages the run keeps.
const KEPT_NOTES: usize = 6;

/// The lesson's simulation: every mode's run on one sensor log; a clone is a
/// checkpoint (the log is shared, not copied).
#[derive(Clone, Debug)]
pub struct FusionSim {
    setup: Arc<FusionLessonScenario>,
    live: FusionScenario,
    log: Arc<SensorLog>,
    runs: Vec<ModeRun>,
    lead: usize,
    last: Vec<Option<StepReport>>,
    cursor: usize,
    pending_injected: usize,
    started: bool,
    tick: u64,
    mid_tick: bool,
    finished: bool,
    notes: Vec<String>,
    injected: usize,
}

impl FusionSim {
    /// Simulates `setup`'s drive and opens one run per mode (duplicates dropped).
    pub fn new(setup: FusionLessonScenario) -> Result<Self, String> {
        let log = simulate(&setup.scenario).map_err(|e| e.to_string())?;
        let mut modes: Vec<FusionMode> = Vec::new();
        for m in &setup.modes {
            if !modes.contains(m) {
                modes.push(*m);
            }
        }
        if modes.is_empty() {
            modes = FusionLessonScenario::default().modes;
        }
        let runs = modes
            .iter()
            .map(|&m| ModeRun::new(&setup.scenario, m).map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()?;
        let lead = runs
            .iter()
            .position(|r| r.mode() != FusionMode::Odometry)
            .unwrap_or(0);
        Ok(Self {
            live: setup.scenario.clone(),
            setup: Arc::new(setup),
            log: Arc::new(log),
            last: vec![None; runs.len()],
            runs,
            lead,
            cursor: 0,
            pending_injected: 0,
            started: false,
            tick: 0,
            mid_tick: false,
            finished: false,
            notes: Vec::new(),
            injected: 0,
        })
    }

    /// The setup the run started from.
    pub fn setup(&self) -> &FusionLessonScenario {
        &self.setup
    }

    /// The scenario as it is now (live noise and sensor switches applied).
    pub fn live(&self) -> &FusionScenario {
        &self.live
    }

    /// The truth and every reading (with live changes spliced in).
    pub fn log(&self) -> &SensorLog {
        &self.log
    }

    /// The runs, one per mode.
    pub fn runs(&self) -> &[ModeRun] {
        &self.runs
    }

    /// Each run's report of the last phase (`None`: the run did not take part).
    pub fn last_reports(&self) -> &[Option<StepReport>] {
        &self.last
    }

    /// The run's time, seconds (the lead run's).
    pub fn now(&self) -> f64 {
        self.runs.get(self.lead).map_or(0.0, ModeRun::now)
    }

    /// Whether the drive is over.
    pub fn finished(&self) -> bool {
        self.finished
    }

    /// Whether sensor `sensor` is switched on now.
    pub fn sensor_on(&self, sensor: usize) -> bool {
        match sensor {
            ODOMETRY => self.live.odometry.enabled,
            IMU => self.live.imu.enabled,
            SLAM => self.live.slam.enabled,
            _ => false,
        }
    }

    /// The latest messages about skipped readings, oldest first.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// How many bad readings were injected.
    pub fn injected(&self) -> usize {
        self.injected
    }

    /// The next reading to arrive, for the time bar ("IMU at 12.35 s").
    pub fn next_reading(&self) -> String {
        if self.finished {
            return "none: the drive is over".to_owned();
        }
        let lead = &self.runs[self.lead];
        self.log.measurements[self.cursor.min(self.log.measurements.len())..]
            .iter()
            .find(|a| lead.uses(a.measurement.sensor))
            .map_or_else(
                || "the end of the drive".to_owned(),
                |a| {
                    format!(
                        "{} at {:.2} s",
                        sensor_name(a.measurement.sensor),
                        a.measurement.stamp
                    )
                },
            )
    }

    /// When the lead run applies its next reading, as [`ModeRun::step_one`]
    /// would: the earlier of the next reading in use (once its stamp plus the
    /// filter's delay has passed) and the queue's front. `None`: no reading left.
    fn next_due(&self) -> Option<f64> {
        let lead = &self.runs[self.lead];
        let delay = self.live.filter_delay;
        let queued = lead
            .filter()
            .pending()
            .next()
            .map(|m| (m.stamp + delay).max(lead.now()));
        let arriving = self.log.measurements[self.cursor.min(self.log.measurements.len())..]
            .iter()
            .find(|a| lead.uses(a.measurement.sensor))
            .map(|a| a.arrival.max(a.measurement.stamp + delay));
        match (queued, arriving) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn keep_note(&mut self, report: &StepReport) {
        if let Outcome::Skipped(_) = report.outcome {
            if self.notes.len() >= KEPT_NOTES {
                self.notes.remove(0);
            }
            self.notes.push(report.label());
        }
    }

    fn after_step(&mut self) {
        self.started = true;
        let now = self.now();
        self.cursor = self.log.measurements.partition_point(|a| a.arrival <= now);
        self.pending_injected = 0;
    }

    /// Runs every run to its end (only the last outputs are left to sample).
    fn finish(&mut self) {
        for run in &mut self.runs {
            while run.step_one(&self.log).is_some() {}
        }
        self.finished = true;
        self.mid_tick = false;
    }

    fn step_measurement(&mut self) -> FusionPhase {
        let log = Arc::clone(&self.log);
        let Some(report) = self.runs[self.lead].step_one(&log) else {
            self.finish();
            return FusionPhase::End;
        };
        self.last = vec![None; self.runs.len()];
        for k in 0..self.runs.len() {
            if k == self.lead || !self.runs[k].uses(report.sensor) {
                continue;
            }
            self.last[k] = self.runs[k].step_one(&log);
        }
        self.keep_note(&report);
        let phase = FusionPhase::Measurement {
            sensor: report.sensor,
            stamp: report.stamp,
            label: report.label(),
        };
        self.last[self.lead] = Some(report);
        phase
    }

    fn splice_noise(&mut self, noise: LiveNoise, value: f64) {
        if !(value.is_finite() && value > 0.0) {
            return;
        }
        let mut changed = self.live.clone();
        noise.set(&mut changed, value);
        let Ok(fresh) = simulate(&changed) else {
            return;
        };
        self.live = changed;
        let keep = (self.cursor + self.pending_injected).min(self.log.measurements.len());
        let now = self.now();
        let from = if self.started {
            fresh.measurements.partition_point(|a| a.arrival <= now)
        } else {
            0
        };
        let old = &*self.log;
        let mut measurements = old.measurements[..keep].to_vec();
        measurements.extend_from_slice(&fresh.measurements[from..]);
        // The raw odometry path: as it was up to now, then integrated on with
        // the new readings exactly as the simulator does.
        let mut odometry_path: Vec<(f64, Pose2)> = old
            .odometry_path
            .iter()
            .copied()
            .filter(|(t, _)| !self.started || *t <= now)
            .collect();
        if !self.started {
            odometry_path.clear();
        }
        let genuine_twist = |a: &Arrival| match a.measurement.reading {
            Reading::Twist { twist, covariance }
                if a.measurement.sensor == ODOMETRY
                    && a.measurement.stamp == a.arrival
                    && twist.iter().all(|v| v.is_finite())
                    && covariance[(0, 0)] > 0.0 =>
            {
                Some((a.measurement.stamp, Control::new(twist[0], twist[2])))
            }
            _ => None,
        };
        let mut last = measurements[..keep]
            .iter()
            .rev()
            .find_map(genuine_twist)
            .filter(|_| self.started);
        let mut pose = odometry_path.last().map_or(Pose2::IDENTITY, |p| p.1);
        for a in &measurements[keep..] {
            if let Some((t, control)) = genuine_twist(a) {
                if let Some((t0, c)) = last {
                    pose = MotionModel::ExactArc.predict(&pose, &c, t - t0);
                }
                last = Some((t, control));
                odometry_path.push((t, pose));
            }
        }
        let latency = self.live.slam.latency;
        let mut slam_poses: Vec<(f64, Pose2)> = old
            .slam_poses
            .iter()
            .copied()
            .filter(|(t, _)| self.started && t + latency <= now)
            .collect();
        slam_poses.extend(
            fresh
                .slam_poses
                .iter()
                .copied()
                .filter(|(t, _)| !self.started || t + latency > now),
        );
        self.log = Arc::new(SensorLog {
            truth: fresh.truth,
            truth_dt: fresh.truth_dt,
            measurements,
            odometry_path,
            slam_poses,
            relocalizations: fresh.relocalizations,
            gyro_bias: fresh.gyro_bias,
        });
    }

    fn inject(&mut self, bad: BadReading) {
        let now = self.now();
        let at = (self.cursor + self.pending_injected).min(self.log.measurements.len());
        let mut log = (*self.log).clone();
        log.measurements.insert(
            at,
            Arrival {
                arrival: now,
                measurement: bad.measurement(now),
            },
        );
        self.log = Arc::new(log);
        self.pending_injected += 1;
        self.injected += 1;
    }
}

impl Simulation for FusionSim {
    type Phase = FusionPhase;
    type Event = FusionEvent;
    /// Every run keeps its samples itself, so a checkpoint copies them; the
    /// sensor log is shared.
    type Records = ();

    fn step_phase(&mut self, _records: &mut ()) -> FusionPhase {
        if self.finished {
            return FusionPhase::End;
        }
        if !self.mid_tick {
            self.tick += 1;
        }
        let tick_end = self.tick as f64;
        let phase = match self.next_due() {
            None => {
                self.finish();
                FusionPhase::End
            }
            Some(t) if t <= tick_end => self.step_measurement(),
            Some(_) => {
                let log = Arc::clone(&self.log);
                let until = tick_end.min(log.duration());
                for run in &mut self.runs {
                    run.advance_to(&log, until, |_| {});
                }
                self.last = vec![None; self.runs.len()];
                FusionPhase::Quiet { until }
            }
        };
        if !self.finished {
            self.after_step();
            match self.next_due() {
                None => self.finish(),
                Some(t) => self.mid_tick = t <= tick_end,
            }
        }
        phase
    }

    fn is_mid_tick(&self) -> bool {
        self.mid_tick
    }

    fn tick(&self) -> u64 {
        self.tick
    }

    fn apply_event(&mut self, event: &FusionEvent) {
        match *event {
            FusionEvent::SetSensor { sensor, on } => {
                match sensor {
                    ODOMETRY => self.live.odometry.enabled = on,
                    IMU => self.live.imu.enabled = on,
                    SLAM => self.live.slam.enabled = on,
                    _ => return,
                }
                for run in &mut self.runs {
                    run.set_uses(sensor, on);
                }
            }
            FusionEvent::SetNoise { noise, value } => self.splice_noise(noise, value),
            FusionEvent::Inject(bad) => {
                if !self.finished {
                    self.inject(bad);
                }
            }
        }
    }

    fn checkpoint_bytes(&self) -> usize {
        let per_run: usize = self
            .runs
            .iter()
            .map(|r| std::mem::size_of_val(r.samples()) + r.slam_jumps().len() * 16 + 8192)
            .sum();
        per_run + 4096
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fusion::run_modes;
    use crate::stepper::Stepper;

    fn setup(duration: f64) -> FusionLessonScenario {
        let mut s = FusionLessonScenario::default();
        s.scenario.drive.duration = duration;
        s
    }

    fn fingerprint(sim: &FusionSim) -> Vec<(Vec<f64>, usize, [f64; 3])> {
        sim.runs()
            .iter()
            .map(|r| {
                let e = r.rmse();
                (
                    r.filter().mean().iter().copied().collect(),
                    r.samples().len(),
                    [e.x, e.y, e.yaw],
                )
            })
            .collect()
    }

    #[test]
    fn stepping_to_the_end_matches_the_experiments_runner() {
        let s = setup(30.0);
        let mut stepper = Stepper::new(FusionSim::new(s.clone()).unwrap(), ());
        // The first phase applies the first reading: wheel odometry at 0 s.
        let first = stepper.step_phase();
        assert_eq!(
            first.label(),
            "wheel odometry: v_x, v_y, yaw rate at 0.00 s",
            "{first:?}"
        );
        stepper.step_tick();
        assert_eq!(stepper.sim().tick(), 1);
        // The first second ends with the SLAM pose at 1 s in both modes.
        let reports = stepper.sim().last_reports();
        assert_eq!(
            reports[0].as_ref().map(StepReport::label).as_deref(),
            Some("SLAM pose (differential): v_x, v_y, yaw rate at 1.00 s")
        );
        assert_eq!(
            reports[1].as_ref().map(StepReport::label).as_deref(),
            Some("SLAM pose (relative): x, y, yaw at 1.00 s")
        );
        let mut ticks = 1;
        while !stepper.sim().finished() {
            stepper.step_tick();
            ticks += 1;
        }
        assert_eq!(ticks, 30, "30 seconds: the last one ends the drive");
        let log = simulate(&s.scenario).unwrap();
        let whole = run_modes(&s.scenario, &log, &s.modes).unwrap();
        for (stepped, whole) in stepper.sim().runs().iter().zip(&whole) {
            assert_eq!(stepped.samples().len(), whole.samples().len());
            let (a, b) = (stepped.rmse(), whole.rmse());
            for (x, y) in [(a.x, b.x), (a.y, b.y), (a.yaw, b.yaw)] {
                assert!((x - y).abs() < 1e-9, "{x} vs {y}");
            }
            assert_eq!(stepped.filter().stats(), whole.filter().stats());
        }
    }

    #[test]
    fn stepping_back_over_toggles_noise_changes_and_bad_readings_is_exact() {
        let mut stepper = Stepper::new(FusionSim::new(setup(20.0)).unwrap(), ());
        stepper.run_ticks(3);
        stepper.apply(FusionEvent::SetSensor {
            sensor: SLAM,
            on: false,
        });
        stepper.run_ticks(2);
        stepper.apply(FusionEvent::SetNoise {
            noise: LiveNoise::ImuGyro,
            value: 0.05,
        });
        stepper.apply(FusionEvent::Inject(BadReading::NanImu));
        stepper.apply(FusionEvent::Inject(BadReading::SlamFromThePast));
        stepper.run_ticks(2);
        stepper.apply(FusionEvent::SetSensor {
            sensor: SLAM,
            on: true,
        });
        stepper.apply(FusionEvent::Inject(BadReading::ZeroNoiseOdometry));
        stepper.apply(FusionEvent::Inject(BadReading::SlamBeforeStart));
        stepper.run_ticks(3);
        let end = fingerprint(stepper.sim());
        let phases = stepper.phases_run();
        while stepper.sim().tick() > 2 {
            assert!(stepper.step_back());
        }
        assert!(stepper.sim().sensor_on(SLAM));
        assert_eq!(stepper.sim().injected(), 0);
        while stepper.phases_run() < phases {
            stepper.step_phase();
        }
        assert_eq!(fingerprint(stepper.sim()), end);
        // Each bad reading skipped and counted under its reason, in both modes.
        for run in stepper.sim().runs() {
            let stats = run.filter().stats();
            assert_eq!(stats.non_finite, 1, "{:?}", run.mode());
            assert_eq!(stats.bad_noise, 1, "{:?}", run.mode());
            assert_eq!(stats.before_start, 1, "{:?}", run.mode());
            assert_eq!(stats.out_of_order, 0, "SLAM was off: not fed");
        }
        assert_eq!(stepper.sim().injected(), 4);
        let notes = stepper.sim().notes().join("\n");
        assert!(notes.contains("NaN"), "{notes}");
        assert!(notes.contains("noise must be positive"), "{notes}");
        assert!(notes.contains("before the filter's start"), "{notes}");
    }

    #[test]
    fn a_noise_change_alters_only_the_readings_that_arrive_later() {
        let mut stepper = Stepper::new(FusionSim::new(setup(20.0)).unwrap(), ());
        stepper.run_ticks(5);
        let before = stepper.sim().log().clone();
        let now = stepper.sim().now();
        stepper.apply(FusionEvent::SetNoise {
            noise: LiveNoise::SlamPosition,
            value: 0.5,
        });
        let after = stepper.sim().log();
        assert_eq!(after.measurements.len(), before.measurements.len());
        assert_eq!(after.truth, before.truth);
        let mut changed = 0;
        for (a, b) in after.measurements.iter().zip(&before.measurements) {
            assert_eq!(a.arrival, b.arrival);
            assert_eq!(a.measurement.sensor, b.measurement.sensor);
            if a.arrival <= now || a.measurement.sensor != SLAM {
                assert_eq!(a, b);
            } else {
                assert_ne!(a, b);
                changed += 1;
            }
        }
        assert_eq!(changed, 15, "the SLAM poses at 6..20 s");
        // Odometry untouched: its dead-reckoning path is the same.
        assert_eq!(after.odometry_path, before.odometry_path);
        // Refused: not a noise.
        stepper.apply(FusionEvent::SetNoise {
            noise: LiveNoise::ImuGyro,
            value: f64::NAN,
        });
        assert_eq!(
            stepper.sim().live().imu.gyro_noise_std,
            FusionScenario::default().imu.gyro_noise_std
        );
        // An odometry noise change re-integrates the raw path from now on, as the
        // simulator would have.
        stepper.apply(FusionEvent::SetNoise {
            noise: LiveNoise::OdometryTurn,
            value: 0.2,
        });
        let spliced = stepper.sim().log().odometry_path.clone();
        let mut whole = stepper.sim().live().clone();
        whole.slam.position_noise_std = 0.5;
        let fresh = simulate(&whole).unwrap();
        assert_eq!(spliced.len(), fresh.odometry_path.len());
        assert_eq!(spliced[..=250], before.odometry_path[..=250]);
        assert_ne!(spliced.last(), before.odometry_path.last());
    }
}
