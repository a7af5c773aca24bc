//! A simulated 2-D lidar on an occupancy grid: exact ray casting
//! ([`OccupancyGrid::raycast`]), Gaussian range noise, max-range readings when
//! nothing is within range, and optional random outliers (the phenomena the beam
//! model's four components describe, thesis `000` Sec. 3.5.1).

use rand::Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::Pose2;
use slamlab_core::grid::OccupancyGrid;
use slamlab_core::particle::Scan;
use std::f64::consts::TAU;

/// The lidar's parameters. The sensor sits at the robot's centre, facing forward.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Lidar {
    /// Beams per scan.
    pub beams: usize,
    /// Field of view, radians (2π: all around).
    pub fov: f64,
    /// Maximum range, metres.
    pub max_range: f64,
    /// Standard deviation of the range noise, metres.
    pub range_std: f64,
    /// Probability that a beam returns a uniform random range instead.
    pub outlier_prob: f64,
}

impl Default for Lidar {
    fn default() -> Self {
        Self {
            beams: 180,
            fov: TAU,
            max_range: 12.0,
            range_std: 0.03,
            outlier_prob: 0.0,
        }
    }
}

impl Lidar {
    /// The beam angles in the robot frame: evenly spaced over the field of view
    /// (a full circle does not repeat its first beam).
    pub fn angles(&self) -> Vec<f64> {
        let n = self.beams.max(1);
        let fov = self.fov.clamp(0.0, TAU);
        if fov >= TAU - 1e-9 {
            (0..n)
                .map(|k| -TAU / 2.0 + TAU * k as f64 / n as f64)
                .collect()
        } else if n == 1 {
            vec![0.0]
        } else {
            (0..n)
                .map(|k| -fov / 2.0 + fov * k as f64 / (n - 1) as f64)
                .collect()
        }
    }

    /// The noise-free ranges from `pose`.
    pub fn true_ranges(&self, grid: &OccupancyGrid, pose: &Pose2) -> Vec<f64> {
        self.angles()
            .iter()
            .map(|a| grid.raycast(pose.x, pose.y, pose.theta + a, self.max_range))
            .collect()
    }

    /// One noisy scan from `pose`: a beam that hits nothing reads exactly
    /// `max_range`; a hit gets Gaussian noise (clamped to `[0, max_range]`); with
    /// probability `outlier_prob` a beam reads a uniform random range instead.
    pub fn scan<R: Rng + ?Sized>(&self, grid: &OccupancyGrid, pose: &Pose2, rng: &mut R) -> Scan {
        let angles = self.angles();
        let std = if self.range_std > 0.0 && self.range_std.is_finite() {
            self.range_std
        } else {
            0.0
        };
        let ranges = angles
            .iter()
            .map(|a| {
                let truth = grid.raycast(pose.x, pose.y, pose.theta + a, self.max_range);
                if self.outlier_prob > 0.0 && rng.random::<f64>() < self.outlier_prob {
                    return rng.random::<f64>() * self.max_range;
                }
                if truth >= self.max_range {
                    return self.max_range;
                }
                let n: f64 = slamlab_core::random::standard_normal(rng);
                (truth + std * n).clamp(0.0, self.max_range)
            })
            .collect();
        Scan {
            angles,
            ranges,
            range_min: 0.0,
            range_max: self.max_range,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use slamlab_core::grid::Cell;

    #[test]
    fn scan_reads_walls_with_noise_and_max_range_beyond() {
        let mut g = OccupancyGrid::filled(100, 100, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for j in 0..100 {
            g.set(80, j, Cell::Occupied);
        }
        let lidar = Lidar {
            beams: 4,
            max_range: 20.0,
            range_std: 0.05,
            ..Default::default()
        };
        // Beams at -π, -π/2, 0, π/2 from (5.05, 5.05): the wall face at x = 8.
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut sum = 0.0;
        let mut sum_sq = 0.0;
        let n = 2000;
        for _ in 0..n {
            let s = lidar.scan(&g, &Pose2::new(5.05, 5.05, 0.0), &mut rng);
            assert_eq!(s.ranges[0], 20.0);
            assert_eq!(s.ranges[1], 20.0);
            let e = s.ranges[2] - 2.95;
            sum += e;
            sum_sq += e * e;
        }
        let mean = sum / n as f64;
        let std = (sum_sq / n as f64 - mean * mean).sqrt();
        assert!(mean.abs() < 0.005, "{mean}");
        assert!((std - 0.05).abs() < 0.004, "{std}");
        let outliers = Lidar {
            outlier_prob: 1.0,
            ..lidar
        };
        let s = outliers.scan(&g, &Pose2::new(5.05, 5.05, 0.0), &mut rng);
        assert!(s.ranges.iter().all(|r| *r < 20.0));
    }
}
