//! What the Cartographer lesson needs beyond the run's public API: a kidnap
//! made live (the input swapped for one that agrees on every scan already
//! processed).

use super::CartographerSim;
use crate::grid::MappingInput;
use std::sync::Arc;

impl CartographerSim {
    /// Goes on with the scans of `input` from the next scan: a kidnap made
    /// live, `input` being the same simulated log with the robot carried
    /// elsewhere from a later scan. Refused (false, nothing changes) when
    /// `input` is shorter than what was processed or differs on a processed
    /// scan's time or odometry.
    pub fn replace_input(&mut self, input: Arc<MappingInput>) -> bool {
        let done = self.next.min(self.input.scans.len());
        if input.scans.len() < done {
            return false;
        }
        let agrees = self.input.scans[..done]
            .iter()
            .zip(&input.scans[..done])
            .all(|(a, b)| {
                a.time.to_bits() == b.time.to_bits()
                    && a.odometry.x.to_bits() == b.odometry.x.to_bits()
                    && a.odometry.y.to_bits() == b.odometry.y.to_bits()
                    && a.odometry.theta.to_bits() == b.odometry.theta.to_bits()
            });
        if agrees {
            self.input = input;
        }
        agrees
    }
}
