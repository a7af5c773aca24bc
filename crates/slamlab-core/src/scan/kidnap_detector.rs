//! Kidnap detection from the local scan-matching cost (thesis `000`
//! Sec. 5.2.1, Algorithm 13, Figs. 5.8-5.9): a robot carried elsewhere
//! suddenly sees scans that fit its submap badly, so the cost of local
//! matching jumps. An average filter of `f_size` costs smooths the cost scan
//! by scan; a kidnap is declared when the filtered value exceeds `T` times the
//! previous filtered value,
//!
//! ```text
//! y_t = (1 / f_size) Σ_{k = t − f_size + 1}^{t} c_k,     trigger when y_t > T · y_{t−1}
//! ```
//!
//! The thesis's pseudo code pops the oldest cost at every call, which would
//! keep the list below `f_size` forever; here the list holds the last
//! `f_size` costs (pops once full), as the text describes. Until it is full
//! there is no filtered value and nothing triggers; a cost that is not a
//! finite number is skipped.

use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// The largest filter accepted.
pub const MAX_FILTER_SIZE: usize = 1000;

/// Algorithm 13's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KidnapDetectorParams {
    /// The trigger threshold `T`: a kidnap when the filtered cost exceeds `T`
    /// times its previous value (above 1).
    pub threshold: f64,
    /// The average filter's size `f_size`, scans.
    pub filter_size: usize,
}

impl Default for KidnapDetectorParams {
    fn default() -> Self {
        Self {
            threshold: 1.5,
            filter_size: 4,
        }
    }
}

impl KidnapDetectorParams {
    /// The parameters made usable: `T` not above 1 or not finite becomes the
    /// default, `f_size` is clamped to `1..=`[`MAX_FILTER_SIZE`]. Returns a
    /// note for each change.
    pub fn sanitized(self) -> (Self, Vec<String>) {
        let mut notes = Vec::new();
        let mut out = self;
        if !(self.threshold.is_finite() && self.threshold > 1.0) {
            out.threshold = Self::default().threshold;
            notes.push(format!(
                "kidnap threshold T = {} must be a number above 1; {} is used",
                self.threshold, out.threshold
            ));
        }
        if !(1..=MAX_FILTER_SIZE).contains(&self.filter_size) {
            out.filter_size = self.filter_size.clamp(1, MAX_FILTER_SIZE);
            notes.push(format!(
                "filter size f_size = {} must be 1 to {MAX_FILTER_SIZE}; {} is used",
                self.filter_size, out.filter_size
            ));
        }
        (out, notes)
    }
}

/// What one cost did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DetectorStep {
    /// The filtered cost `y_t` (None until `f_size` costs are in).
    pub filtered: Option<f64>,
    /// The level it had to exceed, `T · y_{t−1}` (None without a previous
    /// filtered value).
    pub trigger_level: Option<f64>,
    /// Whether this cost declared a kidnap.
    pub triggered: bool,
}

/// Algorithm 13: the average filter over the local matching cost and its
/// trigger.
#[derive(Clone, Debug, PartialEq)]
pub struct KidnapDetector {
    params: KidnapDetectorParams,
    costs: VecDeque<f64>,
    last_filtered: Option<f64>,
}

impl KidnapDetector {
    /// A detector with `params` (sanitized; see
    /// [`KidnapDetectorParams::sanitized`]).
    pub fn new(params: KidnapDetectorParams) -> Self {
        let (params, _) = params.sanitized();
        Self {
            params,
            costs: VecDeque::with_capacity(params.filter_size),
            last_filtered: None,
        }
    }

    /// The parameters in use.
    pub fn params(&self) -> KidnapDetectorParams {
        self.params
    }

    /// The last filtered value `y_{t−1}`.
    pub fn last_filtered(&self) -> Option<f64> {
        self.last_filtered
    }

    /// Forgets every cost (a new trajectory starts).
    pub fn reset(&mut self) {
        self.costs.clear();
        self.last_filtered = None;
    }

    /// Takes the local matching cost of the current scan (Algorithm 13, one
    /// call).
    pub fn push(&mut self, cost: f64) -> DetectorStep {
        if !cost.is_finite() {
            return DetectorStep {
                filtered: None,
                trigger_level: None,
                triggered: false,
            };
        }
        self.costs.push_back(cost);
        if self.costs.len() > self.params.filter_size {
            self.costs.pop_front();
        }
        if self.costs.len() < self.params.filter_size {
            return DetectorStep {
                filtered: None,
                trigger_level: None,
                triggered: false,
            };
        }
        let filtered = self.costs.iter().sum::<f64>() / self.costs.len() as f64;
        let trigger_level = self.last_filtered.map(|y| self.params.threshold * y);
        let triggered = trigger_level.is_some_and(|level| filtered > level);
        self.last_filtered = Some(filtered);
        DetectorStep {
            filtered: Some(filtered),
            trigger_level,
            triggered,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triggers_at_the_jump_and_not_before() {
        // f_size 4, T 1.5. Costs hover near 0.1 (filtered values 0.1, 0.105,
        // 0.1, 0.1075, ... each within 1.5x of the last), a slow drift to
        // 0.14 that the filter follows without triggering, then the kidnap
        // at index 12: 0.6.
        let costs = [
            0.10, 0.09, 0.11, 0.10, 0.12, 0.08, 0.13, 0.10, 0.12, 0.13, 0.14, 0.14, 0.60, 0.62,
            0.61,
        ];
        let mut d = KidnapDetector::new(KidnapDetectorParams {
            threshold: 1.5,
            filter_size: 4,
        });
        let steps: Vec<DetectorStep> = costs.iter().map(|&c| d.push(c)).collect();
        let first = steps.iter().position(|s| s.triggered);
        assert_eq!(first, Some(12));
        // Nothing filtered before four costs; the level is 1.5 y_{t−1}.
        assert!(steps[..3].iter().all(|s| s.filtered.is_none()));
        assert!((steps[3].filtered.unwrap() - 0.1).abs() < 1e-12);
        assert_eq!(steps[3].trigger_level, None);
        let y11 = (0.13 + 0.14 + 0.14 + 0.12) / 4.0;
        let y12 = (0.14 + 0.14 + 0.13 + 0.60) / 4.0;
        assert!((steps[11].filtered.unwrap() - y11).abs() < 1e-12);
        assert!((steps[12].filtered.unwrap() - y12).abs() < 1e-12);
        assert!((steps[12].trigger_level.unwrap() - 1.5 * y11).abs() < 1e-12);
        // y12 / y11 = 0.2525 / 0.1325 = 1.906 > 1.5; the next value,
        // 0.375 / 0.2525 = 1.485, stays below: one detection.
        assert!(!steps[13].triggered && !steps[14].triggered);
        // With T = 2 the jump (1.906x) does not trigger, nor does any later
        // step: a threshold too high misses the kidnap.
        let mut strict = KidnapDetector::new(KidnapDetectorParams {
            threshold: 2.0,
            filter_size: 4,
        });
        assert!(costs.iter().all(|&c| !strict.push(c).triggered));
    }

    #[test]
    fn bad_parameters_and_costs_are_handled() {
        let (p, notes) = KidnapDetectorParams {
            threshold: f64::NAN,
            filter_size: 0,
        }
        .sanitized();
        assert_eq!(p.threshold, 1.5);
        assert_eq!(p.filter_size, 1);
        assert_eq!(notes.len(), 2);
        let mut d = KidnapDetector::new(KidnapDetectorParams {
            threshold: 0.5,
            filter_size: 2,
        });
        assert_eq!(d.params().threshold, 1.5);
        assert!(!d.push(f64::NAN).triggered);
        assert!(d.push(1.0).filtered.is_none());
        assert_eq!(d.push(1.0).filtered, Some(1.0));
        assert!(d.push(f64::INFINITY).filtered.is_none());
        assert!(d.push(5.0).triggered);
        d.reset();
        assert_eq!(d.last_filtered(), None);
    }
}
