//! The Bayes filter on a 1-D histogram (thesis `000` Sec. 2.1, Algorithm 1 and
//! Fig. 2.1, after Probabilistic Robotics): a robot in a corridor with doors.
//!
//! The belief is a probability per cell. The prediction convolves it with the
//! motion kernel (Eq. 2.14, `b̄el(x) = Σ p(x | u, x') bel(x')`); the update
//! multiplies it by the measurement likelihood and normalizes (Eq. 2.16,
//! `bel(x) = η p(z | x) b̄el(x)`). Nothing in it is Gaussian, so after seeing a
//! door the belief has one peak per door.

use crate::math;
use serde::{Deserialize, Serialize};

/// Why a histogram step could not be taken (the belief is kept).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HistogramError {
    /// The grid's shape is not usable.
    #[error("histogram: {0}")]
    Shape(String),
    /// A motion or noise value is NaN, infinite or negative.
    #[error("histogram: {name} = {value} must be finite (and not negative for a deviation)")]
    Parameter {
        /// Its name.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The measurement has zero probability everywhere the belief has mass.
    #[error(
        "the measurement is impossible under the current belief (total likelihood {total:e}); \
         the belief was kept"
    )]
    Impossible {
        /// `Σ p(z | x) b̄el(x)`.
        total: f64,
    },
}

/// The cumulative distribution of the standard normal.
fn normal_cdf(x: f64) -> f64 {
    0.5 * (1.0 + math::erf(x / std::f64::consts::SQRT_2))
}

/// A belief over equal cells `[origin + i c, origin + (i + 1) c)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    origin: f64,
    cell: f64,
    belief: Vec<f64>,
}

impl Default for Histogram {
    /// The uniform belief over 400 cells of 5 cm from 0: the default corridor's.
    fn default() -> Self {
        Self {
            origin: 0.0,
            cell: 0.05,
            belief: vec![1.0 / 400.0; 400],
        }
    }
}

/// At most this many cells.
pub const MAX_CELLS: usize = 100_000;

impl Histogram {
    /// The uniform belief over `cells` cells of width `cell` from `origin`.
    pub fn uniform(origin: f64, cell: f64, cells: usize) -> Result<Self, HistogramError> {
        if !(origin.is_finite() && cell.is_finite() && cell > 0.0) {
            return Err(HistogramError::Shape(format!(
                "origin {origin} and cell width {cell} must be finite and the width positive"
            )));
        }
        if cells == 0 || cells > MAX_CELLS {
            return Err(HistogramError::Shape(format!(
                "{cells} cells: between 1 and {MAX_CELLS}"
            )));
        }
        Ok(Self {
            origin,
            cell,
            belief: vec![1.0 / cells as f64; cells],
        })
    }

    /// The Gaussian `N(mean, std²)` binned into the cells (the mass of each
    /// cell; what falls outside goes to the end cells).
    pub fn gaussian(
        origin: f64,
        cell: f64,
        cells: usize,
        mean: f64,
        std: f64,
    ) -> Result<Self, HistogramError> {
        let mut h = Self::uniform(origin, cell, cells)?;
        if !mean.is_finite() {
            return Err(HistogramError::Parameter {
                name: "mean",
                value: mean,
            });
        }
        h.belief.iter_mut().for_each(|b| *b = 0.0);
        h.belief[0] = 1.0;
        h.predict(mean - h.center(0), std)?;
        Ok(h)
    }

    /// The probabilities, one per cell, summing to one.
    pub fn belief(&self) -> &[f64] {
        &self.belief
    }

    /// The cell width, metres.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// The left edge of cell 0, metres.
    pub fn origin(&self) -> f64 {
        self.origin
    }

    /// The centre of cell `i`.
    pub fn center(&self, i: usize) -> f64 {
        self.origin + (i as f64 + 0.5) * self.cell
    }

    /// The belief's mean.
    pub fn mean(&self) -> f64 {
        self.belief
            .iter()
            .enumerate()
            .map(|(i, p)| p * self.center(i))
            .sum()
    }

    /// The belief's variance.
    pub fn variance(&self) -> f64 {
        let m = self.mean();
        self.belief
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let d = self.center(i) - m;
                p * d * d
            })
            .sum()
    }

    /// The probability that the robot is in `[a, b]` (whole cells whose centre is inside).
    pub fn mass_within(&self, a: f64, b: f64) -> f64 {
        self.belief
            .iter()
            .enumerate()
            .filter(|(i, _)| (a..=b).contains(&self.center(*i)))
            .map(|(_, p)| p)
            .sum()
    }

    /// The centre of the most probable cell.
    pub fn mode(&self) -> f64 {
        let best = self
            .belief
            .iter()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |(bi, bp), (i, &p)| {
                if p > bp { (i, p) } else { (bi, bp) }
            })
            .0;
        self.center(best)
    }

    /// The prediction (thesis `000` Algorithm 1 line 3, Eq. 2.14): the robot moved
    /// `shift` metres with Gaussian noise of deviation `std`. Each cell's mass is
    /// spread over the cells by the noise's probability of landing in each
    /// (normal CDF differences). The corridor closes on itself (a loop, as the
    /// classic histogram-filter exercises have it): mass that leaves one end comes
    /// in at the other, so none piles against a wall. `std = 0` moves the mass to
    /// the cell the shift lands in.
    pub fn predict(&mut self, shift: f64, std: f64) -> Result<(), HistogramError> {
        if !shift.is_finite() {
            return Err(HistogramError::Parameter {
                name: "motion",
                value: shift,
            });
        }
        if !(std.is_finite() && std >= 0.0) {
            return Err(HistogramError::Parameter {
                name: "motion noise",
                value: std,
            });
        }
        let n = self.belief.len() as i64;
        let c = self.cell;
        // The kernel over cell offsets k: P(shift + noise ∈ [(k − ½) c, (k + ½) c)).
        let kernel: Vec<(i64, f64)> = if std < 1e-9 * c {
            vec![(math_round(shift / c), 1.0)]
        } else {
            let lo = ((shift - 6.0 * std) / c).floor() as i64 - 1;
            let hi = ((shift + 6.0 * std) / c).ceil() as i64 + 1;
            let lo = lo.max(-n);
            let hi = hi.min(n).max(lo);
            (lo..=hi)
                .map(|k| {
                    let a = ((k as f64 - 0.5) * c - shift) / std;
                    let b = ((k as f64 + 0.5) * c - shift) / std;
                    (k, normal_cdf(b) - normal_cdf(a))
                })
                .filter(|(_, p)| *p > 0.0)
                .collect()
        };
        let total: f64 = kernel.iter().map(|(_, p)| p).sum();
        let mut next = vec![0.0; self.belief.len()];
        for (i, &mass) in self.belief.iter().enumerate() {
            if mass == 0.0 {
                continue;
            }
            for &(k, p) in &kernel {
                let j = (i as i64 + k).rem_euclid(n) as usize;
                next[j] += mass * p / total;
            }
        }
        self.belief = next;
        self.renormalize();
        Ok(())
    }

    /// The update (thesis `000` Algorithm 1 line 4, Eq. 2.16): multiplies each
    /// cell by `likelihood(centre)` and normalizes. Returns the normalizer's
    /// inverse, `p(z) = Σ p(z | x) b̄el(x)`. An impossible measurement (total zero,
    /// or a NaN likelihood) keeps the belief and says so.
    pub fn update(&mut self, likelihood: impl Fn(f64) -> f64) -> Result<f64, HistogramError> {
        let weighted: Vec<f64> = self
            .belief
            .iter()
            .enumerate()
            .map(|(i, p)| p * likelihood(self.center(i)).max(0.0))
            .collect();
        let total: f64 = weighted.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(HistogramError::Impossible { total });
        }
        self.belief = weighted.into_iter().map(|p| p / total).collect();
        Ok(total)
    }

    fn renormalize(&mut self) {
        let total: f64 = self.belief.iter().sum();
        if total > 0.0 && total.is_finite() {
            self.belief.iter_mut().for_each(|p| *p /= total);
        }
    }
}

/// Rounds half away from zero, as an integer.
fn math_round(x: f64) -> i64 {
    x.round() as i64
}

/// A corridor with doors, closed into a loop: the world of the Bayes-filter
/// example.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Corridor {
    /// Length, metres (positions from 0).
    pub length: f64,
    /// Door centres, metres.
    pub doors: Vec<f64>,
    /// Door width, metres.
    pub door_width: f64,
}

impl Default for Corridor {
    /// Three doors, unevenly spaced (so two sightings and the distance between
    /// them tell where the robot is), in a 20 m corridor.
    fn default() -> Self {
        Self {
            length: 20.0,
            doors: vec![3.0, 6.0, 14.0],
            door_width: 1.0,
        }
    }
}

impl Corridor {
    /// `x` wrapped into `[0, length)`: the corridor is a loop.
    pub fn wrap(&self, x: f64) -> f64 {
        if self.length > 0.0 {
            x.rem_euclid(self.length)
        } else {
            x
        }
    }

    /// The door `d` as seen from `x` around the loop: `d + k L` nearest to `x`.
    fn unwrapped(&self, d: f64, x: f64) -> f64 {
        if self.length > 0.0 {
            d + ((x - d) / self.length).round() * self.length
        } else {
            d
        }
    }

    /// True when `x` is in front of a door.
    pub fn at_door(&self, x: f64) -> bool {
        self.doors
            .iter()
            .any(|&d| (x - self.unwrapped(d, x)).abs() <= 0.5 * self.door_width)
    }

    /// The door nearest to `x` around the loop, as the position nearest to `x`
    /// (possibly beyond an end, so that `z − x` is the short way round).
    pub fn nearest_door(&self, x: f64) -> Option<f64> {
        self.doors
            .iter()
            .map(|&d| self.unwrapped(d, x))
            .fold(None, |best, d| match best {
                Some(b) if (b - x).abs() <= (d - x).abs() => Some(b),
                _ => Some(d),
            })
    }

    /// `p(z | x)` of the door sensor: it says "door" with probability `p_hit` in
    /// front of a door and `p_false` elsewhere.
    pub fn door_likelihood(&self, x: f64, saw_door: bool, p_hit: f64, p_false: f64) -> f64 {
        let p = if self.at_door(x) { p_hit } else { p_false };
        if saw_door { p } else { 1.0 - p }
    }
}

/// The Gaussian likelihood `N(z; x, std²)` of a position measurement.
pub fn gaussian_likelihood(z: f64, x: f64, std: f64) -> f64 {
    let d = (z - x) / std;
    math::exp(-0.5 * d * d) / (std * (2.0 * std::f64::consts::PI).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filters::Kalman1;

    #[test]
    fn the_belief_sums_to_one_after_every_step() {
        let corridor = Corridor::default();
        let mut h = Histogram::uniform(0.0, 0.1, 200).unwrap();
        for step in 0..40 {
            h.predict(0.37, 0.15).unwrap();
            assert!(
                (h.belief().iter().sum::<f64>() - 1.0).abs() < 1e-12,
                "{step}"
            );
            let saw = step % 3 == 0;
            h.update(|x| corridor.door_likelihood(x, saw, 0.8, 0.1))
                .unwrap();
            assert!(
                (h.belief().iter().sum::<f64>() - 1.0).abs() < 1e-12,
                "{step}"
            );
        }
    }

    #[test]
    fn one_door_gives_one_peak_per_door() {
        let corridor = Corridor::default();
        let mut h = Histogram::uniform(0.0, 0.1, 200).unwrap();
        h.update(|x| corridor.door_likelihood(x, true, 0.8, 0.1))
            .unwrap();
        // Three doors of 1 m (30 of 200 cells) at likelihood 0.8, the rest 0.1:
        // each door holds 10·0.8 / (30·0.8 + 170·0.1) = 0.1951.
        for d in &corridor.doors {
            let m = h.mass_within(d - 0.5, d + 0.5);
            assert!((m - 8.0 / 41.0).abs() < 1e-12, "{d}: {m}");
        }
    }

    #[test]
    fn the_corridor_localizes_after_the_expected_doors() {
        // The robot starts at 2 m, knowing nothing, and moves 0.5 m a step. It
        // sees doors at 3 m and 6 m; the gap of 3 m fits only the first pair.
        let corridor = Corridor::default();
        let mut h = Histogram::uniform(0.0, 0.05, 400).unwrap();
        let mut x = 2.0;
        let mut localized_at = None;
        for step in 0..16 {
            x += 0.5;
            h.predict(0.5, 0.05).unwrap();
            let saw = corridor.at_door(x);
            h.update(|c| corridor.door_likelihood(c, saw, 0.9, 0.05))
                .unwrap();
            if localized_at.is_none() && h.mass_within(x - 0.5, x + 0.5) > 0.9 {
                localized_at = Some((step, x));
            }
        }
        // After the first door (2.5..3.5 m) it cannot tell the doors apart; by
        // the end of the second (5.5..6.5 m) it knows where it is.
        let (step, at) = localized_at.unwrap();
        assert!(
            (5.5..=6.5).contains(&at),
            "localized at {at} m (step {step})"
        );
        assert!(h.mass_within(x - 0.5, x + 0.5) > 0.9);
        assert!((h.mode() - x).abs() < 0.3);
    }

    #[test]
    fn on_a_gaussian_case_the_kalman_filter_equals_the_histogram() {
        let (cell, cells) = (0.01, 2000);
        let mut h = Histogram::gaussian(0.0, cell, cells, 8.0, 0.5).unwrap();
        let mut kf = Kalman1::new(8.0, 0.25);
        for (u, q, z, r) in [
            (1.0, 0.3, 9.2, 0.4),
            (0.5, 0.2, 9.5, 0.3),
            (-0.7, 0.1, 8.9, 0.2),
        ] {
            h.predict(u, q).unwrap();
            kf.predict(u, q * q).unwrap();
            h.update(|x| gaussian_likelihood(z, x, r)).unwrap();
            kf.update(z, r * r).unwrap();
            // Binning adds c²/12 of variance; the mean is exact to a cell.
            assert!(
                (h.mean() - kf.mean).abs() < 0.5 * cell,
                "{} vs {}",
                h.mean(),
                kf.mean
            );
            assert!(
                (h.variance() - kf.variance).abs() < cell * cell,
                "{} vs {}",
                h.variance(),
                kf.variance
            );
        }
    }

    #[test]
    fn zero_noise_shifts_by_whole_cells_around_the_loop() {
        let mut h = Histogram::uniform(0.0, 1.0, 5).unwrap();
        h.update(|x| if x < 1.0 { 1.0 } else { 0.0 }).unwrap();
        h.predict(2.0, 0.0).unwrap();
        assert_eq!(h.belief(), &[0.0, 0.0, 1.0, 0.0, 0.0]);
        h.predict(4.0, 0.0).unwrap();
        assert_eq!(h.belief(), &[0.0, 1.0, 0.0, 0.0, 0.0]);
        h.predict(-1.4, 0.0).unwrap();
        assert_eq!(h.belief(), &[1.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(h.predict(f64::NAN, 0.1).is_err());
        assert!(h.predict(1.0, -0.1).is_err());
        let before = h.clone();
        assert!(h.update(|_| 0.0).is_err());
        assert_eq!(h, before);
        assert!(Histogram::uniform(0.0, 0.0, 5).is_err());
        assert!(Histogram::uniform(0.0, 1.0, 0).is_err());
    }
}
