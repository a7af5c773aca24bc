//! Filter consistency over many runs: the same scenario run with `trials` seeds,
//! and each estimator's robot-pose NEES averaged over the runs tick by tick.
//!
//! One run's NEES scatters widely (a 3-dof chi-square sample lies anywhere in
//! [0.22, 9.35] 95% of the time), so a single run cannot say whether a filter is
//! honest. The average over `N` independent runs, `ε̄_k = (1/N) Σᵢ εᵢ,ₖ`, is a
//! chi-square variable with `3N` degrees of freedom divided by `N` when the filter
//! is consistent, so at each tick it lies in the band
//! `[χ²₃ₙ(0.025), χ²₃ₙ(0.975)] / N` 95% of the time: `[2.36, 3.72]` for 50 runs
//! (Bar-Shalom, Li and Kirubarajan 2001, Sec. 5.4.2).
//!
//! [`ConsistencyStudy`] runs the trials a bounded number of ticks at a time, so the
//! app can show the average building up without stalling a frame; the command
//! line and the tests run it to the end.

use crate::landmark_slam::experiment::{DIVERGED_ERROR, has_diverged};
use crate::world::landmark_scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
use crate::world::landmark_session::LandmarkSession;
use serde::Serialize;
use slamlab_core::Control;
use slamlab_core::stats::chi2_band_95;

/// Degrees of freedom of the robot-pose NEES (x, y, θ).
const NEES_DOF: f64 = 3.0;
/// Degrees of freedom of one landmark update's NIS (range, bearing).
const NIS_DOF: f64 = 2.0;

/// One estimator's running sums.
#[derive(Clone, Debug)]
struct FilterSums {
    kind: EstimatorKind,
    /// Per tick: the sum of the NEES over the trials where it is defined, and how many.
    nees: Vec<(f64, u32)>,
    nis_sum: f64,
    nis_count: usize,
    diverged: usize,
}

/// Many seeded runs of one scenario, advanced a bounded number of ticks at a time.
#[derive(Debug)]
pub struct ConsistencyStudy {
    template: LandmarkScenario,
    /// Commands to drive every trial with, one per tick (a recorded manual drive);
    /// `None` drives with the scenario's controller.
    commands: Option<Vec<Control>>,
    trials: usize,
    steps: u64,
    trials_done: usize,
    current: Option<LandmarkSession>,
    filters: Vec<FilterSums>,
}

impl ConsistencyStudy {
    /// `trials` runs of `steps` ticks of `template`; trial `i` uses seed
    /// `template.seed + i` (the world's random layout too, when it is random).
    pub fn new(template: LandmarkScenario, trials: usize, steps: u64) -> Self {
        let steps_len = usize::try_from(steps).unwrap_or(usize::MAX);
        let filters = template
            .estimators
            .iter()
            .map(|&kind| FilterSums {
                kind,
                nees: vec![(0.0, 0); steps_len],
                nis_sum: 0.0,
                nis_count: 0,
                diverged: 0,
            })
            .collect();
        Self {
            template,
            commands: None,
            trials,
            steps,
            trials_done: 0,
            current: None,
            filters,
        }
    }

    /// The same study with every trial driven by `commands`, one per tick (a drive
    /// recorded by hand, replayed with each trial's noise); it has as many ticks as
    /// there are commands.
    pub fn replaying(template: LandmarkScenario, trials: usize, commands: Vec<Control>) -> Self {
        let mut study = Self::new(template, trials, commands.len() as u64);
        study.commands = Some(commands);
        study
    }

    /// Runs at most `max_ticks` ticks, finishing and starting trials as needed.
    /// Returns `true` once every trial is done.
    pub fn advance(&mut self, max_ticks: u64) -> bool {
        let mut budget = max_ticks;
        while budget > 0 && !self.is_done() {
            let seed = self.template.seed.wrapping_add(self.trials_done as u64);
            let session = self.current.get_or_insert_with(|| {
                let mut session = LandmarkSession::new(LandmarkScenario {
                    seed,
                    ..self.template.clone()
                });
                if self.commands.is_some() {
                    session.set_controller(ControllerKind::Manual);
                }
                session
            });
            while budget > 0 && session.tick() < self.steps {
                if let Some(command) = self
                    .commands
                    .as_ref()
                    .and_then(|c| c.get(session.tick() as usize))
                {
                    session.set_teleop(*command);
                }
                session.step_tick();
                budget -= 1;
            }
            if session.tick() >= self.steps
                && let Some(finished) = self.current.take()
            {
                self.add_trial(&finished);
            }
        }
        self.is_done()
    }

    /// Runs every remaining trial; `progress(done, total)` is called after each.
    pub fn run_to_end(&mut self, mut progress: impl FnMut(usize, usize)) {
        while !self.is_done() {
            let before = self.trials_done;
            self.advance(self.steps.max(1));
            if self.trials_done != before {
                progress(self.trials_done, self.trials);
            }
        }
    }

    fn add_trial(&mut self, session: &LandmarkSession) {
        // By kind, not position: an estimator that could not start (impossible UKF
        // parameters) is missing from the session, and the others must not shift.
        for run in session.filters() {
            let Some(sums) = self.filters.iter_mut().find(|f| f.kind == run.kind) else {
                continue;
            };
            for (slot, metrics) in sums.nees.iter_mut().zip(&run.history) {
                if let Some(nees) = metrics.nees {
                    slot.0 += nees;
                    slot.1 += 1;
                }
            }
            sums.nis_sum += run.nis.iter().map(|s| s.nis).sum::<f64>();
            sums.nis_count += run.nis.len();
            if has_diverged(&run) {
                sums.diverged += 1;
            }
        }
        self.trials_done += 1;
    }

    /// True when every trial has run.
    pub fn is_done(&self) -> bool {
        self.trials_done >= self.trials || self.steps == 0
    }

    /// Trials finished so far.
    pub fn trials_done(&self) -> usize {
        self.trials_done
    }

    /// Trials in all.
    pub fn trials(&self) -> usize {
        self.trials
    }

    /// Ticks per trial.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The scenario every trial runs (with the first trial's seed).
    pub fn scenario(&self) -> &LandmarkScenario {
        &self.template
    }

    /// Is every trial driven by a recorded list of commands?
    pub fn is_replay(&self) -> bool {
        self.commands.is_some()
    }

    /// The 95% band of a consistent filter's average NEES over the finished trials.
    pub fn nees_band(&self) -> (f64, f64) {
        chi2_band_95(NEES_DOF, self.trials_done.max(1))
    }

    /// Each estimator's average NEES per tick over the finished trials (`None`
    /// where no trial has one: the first tick, before the covariance has full rank).
    pub fn average_nees(&self) -> Vec<(String, Vec<Option<f64>>)> {
        self.filters
            .iter()
            .map(|f| {
                let series = f
                    .nees
                    .iter()
                    .map(|&(sum, n)| (n > 0).then(|| sum / f64::from(n)))
                    .collect();
                (f.kind.name().to_owned(), series)
            })
            .collect()
    }

    /// The summary over the finished trials.
    pub fn result(&self) -> ConsistencyResult {
        let (lo, hi) = self.nees_band();
        let average = self.average_nees();
        let filters = self
            .filters
            .iter()
            .zip(&average)
            .map(|(sums, (_, series))| {
                let defined: Vec<(usize, f64)> = series
                    .iter()
                    .enumerate()
                    .filter_map(|(k, v)| v.map(|v| (k, v)))
                    .collect();
                let mean_of = |range: std::ops::Range<usize>| {
                    let values: Vec<f64> = defined
                        .iter()
                        .filter(|(k, _)| range.contains(k))
                        .map(|(_, v)| *v)
                        .collect();
                    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
                };
                let steps = series.len();
                let quarter = steps.div_ceil(4);
                let count = |keep: &dyn Fn(f64) -> bool| {
                    defined.iter().filter(|(_, v)| keep(*v)).count() as f64
                        / defined.len().max(1) as f64
                };
                let nis_band = chi2_band_95(NIS_DOF, sums.nis_count.max(1));
                FilterConsistency {
                    name: sums.kind.name().to_owned(),
                    nees_mean: mean_of(0..steps),
                    nees_first_quarter: mean_of(0..quarter),
                    nees_last_quarter: mean_of(steps.saturating_sub(quarter)..steps),
                    ticks_in_band: count(&|v| (lo..=hi).contains(&v)),
                    ticks_above_band: count(&|v| v > hi),
                    nis_mean: (sums.nis_count > 0).then(|| sums.nis_sum / sums.nis_count as f64),
                    nis_updates: sums.nis_count,
                    nis_band: [nis_band.0, nis_band.1],
                    diverged: sums.diverged,
                }
            })
            .collect();
        let mut parameters = crate::landmark_slam::summary::parameters_json(&self.template);
        parameters.insert("trials".into(), self.trials.into());
        parameters.insert("steps".into(), self.steps.into());
        parameters.insert(
            "trial-seeds".into(),
            format!("seed + trial index (0..{})", self.trials).into(),
        );
        if self.is_replay() {
            parameters.insert("controller".into(), "replay of recorded commands".into());
        }
        parameters.insert(
            "diverged-if-final-error-above-m".into(),
            DIVERGED_ERROR.into(),
        );
        ConsistencyResult {
            experiment: "consistency".to_owned(),
            trials_done: self.trials_done,
            parameters,
            nees_band: [lo, hi],
            filters,
        }
    }

    /// The average NEES per tick as CSV: `step,time_s,band_lo,band_hi,<filter>_nees,…`.
    pub fn series_csv(&self) -> String {
        let (lo, hi) = self.nees_band();
        let average = self.average_nees();
        let mut out = String::from("step,time_s,band_lo,band_hi");
        for (name, _) in &average {
            out.push_str(&format!(",{name}_nees"));
        }
        out.push('\n');
        for k in 0..self.steps as usize {
            out.push_str(&format!(
                "{},{:.3},{lo:.6},{hi:.6}",
                k + 1,
                (k + 1) as f64 * self.template.dt
            ));
            for (_, series) in &average {
                match series.get(k).copied().flatten() {
                    Some(v) => out.push_str(&format!(",{v:.6}")),
                    None => out.push(','),
                }
            }
            out.push('\n');
        }
        out
    }
}

/// One estimator's consistency over the trials.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FilterConsistency {
    /// The estimator ("ekf").
    pub name: String,
    /// The average NEES, averaged again over every tick where it is defined.
    pub nees_mean: Option<f64>,
    /// The same over the first quarter of the ticks.
    pub nees_first_quarter: Option<f64>,
    /// The same over the last quarter of the ticks.
    pub nees_last_quarter: Option<f64>,
    /// Fraction of ticks whose average NEES lies in the 95% band (about 0.95 for
    /// a consistent filter).
    pub ticks_in_band: f64,
    /// Fraction of ticks whose average NEES lies above the band (overconfident).
    pub ticks_above_band: f64,
    /// Mean NIS over every landmark update of every trial (2 dof: expected 2).
    pub nis_mean: Option<f64>,
    /// How many updates that mean is over.
    pub nis_updates: usize,
    /// The 95% band of that mean for a consistent filter.
    pub nis_band: [f64; 2],
    /// Trials whose final robot error exceeds [`DIVERGED_ERROR`] (they stay in the averages).
    pub diverged: usize,
}

/// The outcome of a consistency study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConsistencyResult {
    /// "consistency".
    pub experiment: String,
    /// Trials the numbers are over.
    pub trials_done: usize,
    /// Every parameter used.
    pub parameters: serde_json::Map<String, serde_json::Value>,
    /// The 95% band of a consistent filter's average NEES over that many trials.
    pub nees_band: [f64; 2],
    /// One entry per estimator.
    pub filters: Vec<FilterConsistency>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::landmark_slam::summary::run_headless;

    #[test]
    fn the_average_is_over_trials_tick_by_tick() {
        let scenario = LandmarkScenario {
            seed: 4,
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        let mut study = ConsistencyStudy::new(scenario.clone(), 3, 30);
        // Small budgets split trials across calls; the result does not depend on them.
        let mut calls = 0;
        while !study.advance(7) {
            calls += 1;
        }
        assert!(calls >= 12, "{calls} calls");
        assert_eq!(study.trials_done(), 3);
        let runs: Vec<_> = (4..7)
            .map(|seed| {
                run_headless(
                    LandmarkScenario {
                        seed,
                        ..scenario.clone()
                    },
                    30,
                )
                .0
            })
            .collect();
        let average = study.average_nees();
        for (f, (name, series)) in average.iter().enumerate() {
            assert_eq!(name, ["ekf", "ukf"][f]);
            assert_eq!(series.len(), 30);
            assert_eq!(series[0], None, "the first tick's covariance has rank 2");
            for k in 1..30 {
                let expected = runs
                    .iter()
                    .map(|s| s.filters()[f].history[k].nees.unwrap_or(f64::NAN))
                    .sum::<f64>()
                    / 3.0;
                let got = series[k].unwrap_or(f64::NAN);
                assert!(
                    (got - expected).abs() < 1e-12,
                    "{name} tick {k}: {got} vs {expected}"
                );
            }
        }
        let result = study.result();
        let (lo, hi) = chi2_band_95(3.0, 3);
        assert_eq!(result.nees_band, [lo, hi]);
        let nis: Vec<f64> = runs
            .iter()
            .flat_map(|s| s.filters()[0].records().nis.iter().map(|n| n.nis))
            .collect();
        assert_eq!(result.filters[0].nis_updates, nis.len());
        let nis_mean = nis.iter().sum::<f64>() / nis.len() as f64;
        assert!((result.filters[0].nis_mean.unwrap_or(f64::NAN) - nis_mean).abs() < 1e-12);
        let in_band = result.filters[0].ticks_in_band;
        let above = result.filters[0].ticks_above_band;
        assert!((0.0..=1.0).contains(&in_band) && in_band + above <= 1.0 + 1e-12);
    }

    #[test]
    fn a_replayed_drive_runs_the_recorded_commands_with_each_trials_noise() {
        let commands = vec![Control::new(0.8, 0.3); 10]
            .into_iter()
            .chain(vec![Control::new(0.5, -0.4); 10])
            .collect::<Vec<_>>();
        let scenario = LandmarkScenario {
            controller: ControllerKind::Manual,
            ..Default::default()
        };
        let mut study = ConsistencyStudy::replaying(scenario.clone(), 2, commands.clone());
        assert_eq!(study.steps(), 20);
        study.run_to_end(|_, _| {});
        // The same drive by hand, trial by trial.
        let mut expected = 0.0;
        for seed in [1, 2] {
            let mut session = LandmarkSession::new(LandmarkScenario {
                seed,
                ..scenario.clone()
            });
            for c in &commands {
                session.set_teleop(*c);
                session.step_tick();
            }
            assert_eq!(session.commands(), &commands[..]);
            expected += session.filters()[0].history[19].nees.unwrap_or(f64::NAN);
        }
        let got = study.average_nees()[0].1[19].unwrap_or(f64::NAN);
        assert!(
            (got - expected / 2.0).abs() < 1e-12,
            "{got} vs {}",
            expected / 2.0
        );
        assert_eq!(
            study.result().parameters["controller"],
            "replay of recorded commands"
        );
    }

    #[test]
    fn an_estimator_that_cannot_start_leaves_the_others_in_place() {
        // κ = -9 puts n + λ = α²(n + κ) below zero: the UKF refuses to start.
        let mut scenario = LandmarkScenario {
            estimators: vec![EstimatorKind::Ukf, EstimatorKind::Ekf],
            ..Default::default()
        };
        scenario.ukf.alpha = 0.5;
        scenario.ukf.kappa = -9.0;
        let session = LandmarkSession::new(scenario.clone());
        assert_eq!(session.filters().len(), 1, "{:?}", session.notices());
        let mut study = ConsistencyStudy::new(scenario.clone(), 2, 10);
        study.run_to_end(|_, _| {});
        let result = study.result();
        assert_eq!(result.filters[0].name, "ukf");
        assert_eq!(result.filters[0].nees_mean, None);
        assert_eq!(result.filters[0].nis_updates, 0);
        let ekf_only = {
            let mut s = ConsistencyStudy::new(
                LandmarkScenario {
                    estimators: vec![EstimatorKind::Ekf],
                    ..scenario
                },
                2,
                10,
            );
            s.run_to_end(|_, _| {});
            s.result()
        };
        assert_eq!(result.filters[1], ekf_only.filters[0]);
    }

    #[test]
    fn an_empty_study_is_done_and_says_so() {
        let mut study = ConsistencyStudy::new(LandmarkScenario::default(), 5, 0);
        assert!(study.advance(10));
        let result = study.result();
        assert_eq!(result.filters[0].nees_mean, None);
        assert_eq!(result.filters[0].ticks_in_band, 0.0);
        assert_eq!(study.series_csv().lines().count(), 1);
        let mut none = ConsistencyStudy::new(LandmarkScenario::default(), 0, 20);
        assert!(none.advance(1));
        assert_eq!(none.result().trials_done, 0);
    }

    #[test]
    fn csv_has_a_row_per_tick_and_a_column_per_filter() {
        let mut study = ConsistencyStudy::new(
            LandmarkScenario {
                estimators: vec![EstimatorKind::Ekf, EstimatorKind::FejEkf],
                ..Default::default()
            },
            2,
            12,
        );
        study.run_to_end(|_, _| {});
        let csv = study.series_csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "step,time_s,band_lo,band_hi,ekf_nees,fej-ekf_nees"
        );
        assert_eq!(lines.len(), 13);
        assert!(lines[1].ends_with(",,"), "tick 1 has no NEES: {}", lines[1]);
        let last: Vec<f64> = lines[12]
            .split(',')
            .map(|v| v.parse().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(last[0], 12.0);
        assert!((last[1] - 1.2).abs() < 1e-9);
        assert!(last.iter().all(|v| v.is_finite()));
    }
}
