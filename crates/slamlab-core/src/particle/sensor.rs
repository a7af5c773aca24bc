//! Range-finder measurement models on an occupancy grid, as log likelihoods
//! `ln p(z | x, m)` of a whole scan (the beams taken as independent, so the scan's
//! log likelihood is the sum over beams).
//!
//! - [`BeamModel`]: thesis `000` Sec. 3.5.1, Probabilistic Robotics Table 6.1: a
//!   mixture of a Gaussian around the ray-cast range (`z_hit`, `sigma_hit`), an
//!   exponential for unexpected short readings (`z_short`, `lambda_short`), a
//!   point mass at the maximum range (`z_max`) and a uniform (`z_rand`).
//! - [`LikelihoodFieldModel`]: Probabilistic Robotics Table 6.3 and ROS amcl's
//!   default `likelihood_field`: each beam end point is scored by its distance to
//!   the nearest obstacle (`z_hit`, `sigma_hit`) plus a uniform (`z_rand`);
//!   max-range readings are skipped.
//!
//! Two ways to combine the beams of a scan ([`ScanAggregation`]):
//!
//! - [`ScanAggregation::Product`] (Probabilistic Robotics Tables 6.1 and 6.3):
//!   the scan likelihood is the product `Π p_k` and the Gaussian is a density.
//!   The beam model's `p_hit` is not renormalized to `[0, z_max]` (the factor is
//!   within 1% of one when the expected range is more than `2.4 σ` from both
//!   ends).
//! - [`ScanAggregation::AmclCubes`] (ROS amcl, `amcl_laser.cpp`,
//!   `BeamModel` and `LikelihoodFieldModel`): the scan scores `1 + Σ p_k³`,
//!   with amcl's per-beam `p_k`, whose Gaussian has no normalizing constant
//!   (`z_hit exp(−d² / 2σ²)`) and whose short-reading term has no `η`. The sum
//!   is an ad hoc combination, far flatter than the product: a scan that
//!   contradicts every particle still scores at least 1, so after a kidnap the
//!   average likelihood falls by a bounded factor and Augmented MCL's `w_fast`
//!   drops below `w_slow` as amcl's does.
//!
//! In both, a max-range reading of the beam model keeps its hit and short
//! terms (Table 6.1 defines `p_hit` on `[0, z_max]`; amcl adds `z_max` to them):
//! a particle that expects a wall at 2 m is penalised against one that expects
//! open space.
//!
//! Ray casting (the beam model's expected range) departs from amcl's
//! `map_calc_range`: amcl stops a ray at the first cell that is occupied *or
//! unknown*; SLAM Lab stops only at occupied cells and sees through unknown ones
//! (see [`OccupancyGrid::raycast`]). On maps whose free space is closed by walls
//! the two agree; where a map's free space borders unknown cells, amcl expects
//! a reading at the border and SLAM Lab expects nothing within range.

use super::super::grid::{DistanceField, OccupancyGrid, floor_to_i64};
use crate::geometry::Pose2;
use crate::math;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub use crate::laser::Scan;

/// `ln(1 / sqrt(2π))`.
const LN_INV_SQRT_2PI: f64 = -0.918_938_533_204_672_7;

/// How the beams' likelihoods combine into a scan's (amcl has the sum of cubes
/// only; Probabilistic Robotics the product).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanAggregation {
    /// `p(z | x) = Π p_k` (Probabilistic Robotics Tables 6.1 and 6.3), with the
    /// Gaussian a density. Usually tempered by an exponent (see
    /// `MclConfig::likelihood_exponent`).
    #[default]
    Product,
    /// `p(z | x) = 1 + Σ p_k³` with amcl's per-beam `p_k` (ROS amcl
    /// `amcl_laser.cpp`; ROS 1 and Nav2 alike).
    AmclCubes,
}

impl ScanAggregation {
    /// The name in the URL and on the command line: `product` or `amcl`.
    pub fn name(self) -> &'static str {
        match self {
            ScanAggregation::Product => "product",
            ScanAggregation::AmclCubes => "amcl",
        }
    }
}

/// The likelihood of one beam, for the explanation panel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamLikelihood {
    /// Beam angle in the robot frame, radians.
    pub angle: f64,
    /// Measured range, metres.
    pub range: f64,
    /// Beam model: the ray-cast range from the particle. Likelihood field: the
    /// distance from the beam's end point to the nearest obstacle (capped).
    /// Metres.
    pub expected: f64,
    /// `ln p(z_k | x, m)` (with [`ScanAggregation::AmclCubes`], `ln` of amcl's
    /// per-beam `p_k`, whose cube enters the sum); `None` for a beam the model
    /// skips (a max-range reading in the likelihood field, or an unusable
    /// number).
    pub log_likelihood: Option<f64>,
}

/// The beam model's parameters (thesis `000` Sec. 3.5.1; amcl `laser_z_hit`,
/// `laser_z_short`, `laser_z_max`, `laser_z_rand`, `laser_sigma_hit`,
/// `laser_lambda_short`; defaults are ROS 1 amcl's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamModel {
    /// Weight of the Gaussian around the expected range.
    pub z_hit: f64,
    /// Weight of unexpected short readings.
    pub z_short: f64,
    /// Weight of max-range readings.
    pub z_max: f64,
    /// Weight of uniform noise.
    pub z_rand: f64,
    /// Standard deviation of the Gaussian, metres.
    pub sigma_hit: f64,
    /// Rate of the exponential of short readings, 1/m.
    pub lambda_short: f64,
}

impl Default for BeamModel {
    fn default() -> Self {
        Self {
            z_hit: 0.95,
            z_short: 0.1,
            z_max: 0.05,
            z_rand: 0.05,
            sigma_hit: 0.2,
            lambda_short: 0.1,
        }
    }
}

impl BeamModel {
    /// `ln p(z | z*)` of one reading `z` given the ray-cast range `expected`
    /// (Probabilistic Robotics Table 6.1). A reading at `range_max` or beyond
    /// is a max-range reading: it keeps the hit term (Table 6.1 defines `p_hit`
    /// on `[0, z_max]`, so a particle expecting a wall short of `z_max` scores
    /// lower than one expecting open space) and the short term, gains the point
    /// mass `z_max` and loses the uniform `z_rand / z_max` (defined on
    /// `[0, z_max)`).
    pub fn log_likelihood(&self, z: f64, expected: f64, range_max: f64) -> f64 {
        let sigma = self.sigma_hit;
        let z = z.min(range_max);
        let u = (z - expected) / sigma;
        let mut p = self.z_hit * math::exp(LN_INV_SQRT_2PI - 0.5 * u * u) / sigma;
        if z <= expected && self.lambda_short > 0.0 {
            let eta = 1.0 / (1.0 - math::exp(-self.lambda_short * expected));
            if eta.is_finite() {
                p += self.z_short * eta * self.lambda_short * math::exp(-self.lambda_short * z);
            }
        }
        if z < range_max {
            p += self.z_rand / range_max;
        } else {
            p += self.z_max;
        }
        math::ln(p)
    }

    /// amcl's per-beam probability (`BeamModel` in `amcl_laser.cpp`): the
    /// Gaussian without its normalizing constant, the short term without `η`
    /// and only for readings short of the expected range, `z_max` for a
    /// max-range reading, `z_rand / z_max` for the others.
    pub fn amcl_probability(&self, z: f64, expected: f64, range_max: f64) -> f64 {
        let z = z.min(range_max);
        let d = z - expected;
        let mut p = self.z_hit * math::exp(-(d * d) / (2.0 * self.sigma_hit * self.sigma_hit));
        if d < 0.0 {
            p += self.z_short * self.lambda_short * math::exp(-self.lambda_short * z);
        }
        if z < range_max {
            p += self.z_rand / range_max;
        } else {
            p += self.z_max;
        }
        p
    }

    /// `ln p(z | x, m)` of the beams `beams` of `scan` from `pose`, each expected
    /// range ray-cast on `grid`, the beams combined by `aggregation`.
    pub fn scan_log_likelihood(
        &self,
        grid: &OccupancyGrid,
        pose: &Pose2,
        scan: &Scan,
        beams: &[usize],
        aggregation: ScanAggregation,
    ) -> f64 {
        let mut sum = 0.0;
        for &k in beams {
            let z = scan.ranges[k];
            if !z.is_finite() || z < scan.range_min.max(0.0) {
                continue;
            }
            let expected =
                grid.raycast(pose.x, pose.y, pose.theta + scan.angles[k], scan.range_max);
            sum += match aggregation {
                ScanAggregation::Product => self.log_likelihood(z, expected, scan.range_max),
                ScanAggregation::AmclCubes => {
                    let p = self.amcl_probability(z, expected, scan.range_max);
                    p * p * p
                }
            };
        }
        match aggregation {
            ScanAggregation::Product => sum,
            ScanAggregation::AmclCubes => math::ln(1.0 + sum),
        }
    }
}

/// The likelihood-field model's parameters (Probabilistic Robotics Table 6.3; amcl
/// `laser_z_hit`, `laser_z_rand`, `laser_sigma_hit`; the distance field's cap is
/// `laser_likelihood_max_dist`, a property of the [`DistanceField`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LikelihoodFieldModel {
    /// Weight of the Gaussian in the distance to the nearest obstacle.
    pub z_hit: f64,
    /// Weight of uniform noise.
    pub z_rand: f64,
    /// Standard deviation of the Gaussian, metres.
    pub sigma_hit: f64,
}

impl Default for LikelihoodFieldModel {
    fn default() -> Self {
        Self {
            z_hit: 0.95,
            z_rand: 0.05,
            sigma_hit: 0.2,
        }
    }
}

impl LikelihoodFieldModel {
    /// `ln(z_hit N(d; 0, σ) + z_rand / z_max)` for an end point at distance `d`
    /// from the nearest obstacle.
    pub fn log_likelihood(&self, distance: f64, range_max: f64) -> f64 {
        let u = distance / self.sigma_hit;
        let p = self.z_hit * math::exp(LN_INV_SQRT_2PI - 0.5 * u * u) / self.sigma_hit
            + self.z_rand / range_max;
        math::ln(p)
    }

    /// amcl's per-beam probability (`LikelihoodFieldModel` in
    /// `amcl_laser.cpp`): `z_hit exp(−d² / 2σ²) + z_rand / z_max`, the Gaussian
    /// without its normalizing constant.
    pub fn amcl_probability(&self, distance: f64, range_max: f64) -> f64 {
        self.z_hit * math::exp(-(distance * distance) / (2.0 * self.sigma_hit * self.sigma_hit))
            + self.z_rand / range_max
    }

    /// The log likelihood of every squared cell distance the field can hold
    /// (`0 ..= cap`), so that scoring a beam is a table lookup.
    pub fn table(&self, field: &DistanceField, range_max: f64) -> Vec<f64> {
        (0..=field.cap_squared_cells())
            .map(|sq| self.log_likelihood(field.metres(sq), range_max))
            .collect()
    }

    /// What one beam adds to the scan score for every squared cell distance
    /// (`0 ..= cap`): `ln p_k` for the product, amcl's `p_k³` for the sum of
    /// cubes.
    pub fn term_table(
        &self,
        field: &DistanceField,
        range_max: f64,
        aggregation: ScanAggregation,
    ) -> Vec<f64> {
        match aggregation {
            ScanAggregation::Product => self.table(field, range_max),
            ScanAggregation::AmclCubes => (0..=field.cap_squared_cells())
                .map(|sq| {
                    let p = self.amcl_probability(field.metres(sq), range_max);
                    p * p * p
                })
                .collect(),
        }
    }
}

/// Which measurement model weights the particles (amcl `laser_model_type`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MeasurementModel {
    /// Ray casting per beam (thesis Sec. 3.5.1). Exact but slow: one ray per beam
    /// per particle.
    Beam(BeamModel),
    /// End-point scoring on the distance field (amcl's default).
    LikelihoodField(LikelihoodFieldModel),
}

impl Default for MeasurementModel {
    fn default() -> Self {
        MeasurementModel::LikelihoodField(LikelihoodFieldModel::default())
    }
}

impl MeasurementModel {
    /// amcl's name: `beam` or `likelihood_field`.
    pub fn name(&self) -> &'static str {
        match self {
            MeasurementModel::Beam(_) => "beam",
            MeasurementModel::LikelihoodField(_) => "likelihood_field",
        }
    }
}

/// A measurement model bound to its map: scores whole scans and explains single
/// beams. Built once per map and scan maximum range (the likelihood field
/// tabulates its values).
#[derive(Clone, Debug)]
pub struct PreparedModel {
    model: MeasurementModel,
    aggregation: ScanAggregation,
    /// Likelihood field: what a beam ending in each cell of the distance
    /// field adds to the scan score (row-major, `width x height`): `ln p` for
    /// the product, amcl's `p³` for the sum of cubes; empty for the beam model.
    ///
    /// Cell `(i, j)` holds `table[squared_cells(i, j)]`, where `table` is
    /// [`LikelihoodFieldModel::term_table`] (the term of every squared cell
    /// distance): the very number the formula gives for an end point in
    /// that cell, computed once when the model is prepared (8 bytes per cell).
    /// Scoring a beam is then one load instead of a distance lookup followed
    /// by a table lookup. Never changes, so filters share it (an `Arc`).
    cell_log_likelihood: Arc<[f64]>,
    /// Likelihood field: the term of an end point outside the map, where the
    /// distance field reads its cap (as amcl's `max_occ_dist`).
    outside_log_likelihood: f64,
    /// Cells per row and rows of `cell_log_likelihood`.
    width: usize,
    height: usize,
    range_max: f64,
}

impl PreparedModel {
    /// Prepares `model`, its beams combined by `aggregation`, for `field`
    /// (likelihood field) and scans of maximum range `range_max`.
    pub fn new(
        model: MeasurementModel,
        aggregation: ScanAggregation,
        field: &DistanceField,
        range_max: f64,
    ) -> Self {
        let (width, height) = field.size();
        let (cells, outside): (Arc<[f64]>, f64) = match &model {
            MeasurementModel::LikelihoodField(lf) => {
                let table = lf.term_table(field, range_max, aggregation);
                let last = table.len() - 1;
                let lookup = |sq: u32| table[(sq as usize).min(last)];
                let cells = (0..height as i64)
                    .flat_map(|j| (0..width as i64).map(move |i| (i, j)))
                    .map(|(i, j)| lookup(field.squared_cells(i, j)))
                    .collect();
                (cells, lookup(field.cap_squared_cells()))
            }
            MeasurementModel::Beam(_) => (Arc::from([]), 0.0),
        };
        Self {
            model,
            aggregation,
            cell_log_likelihood: cells,
            outside_log_likelihood: outside,
            width,
            height,
            range_max,
        }
    }

    /// The model.
    pub fn model(&self) -> &MeasurementModel {
        &self.model
    }

    /// How it combines the beams.
    pub fn aggregation(&self) -> ScanAggregation {
        self.aggregation
    }

    /// The maximum range it was prepared for.
    pub fn range_max(&self) -> f64 {
        self.range_max
    }

    /// Likelihood field: the term of a beam ending in cell `(i, j)` (the cap's
    /// value outside the map, as [`DistanceField::squared_cells`] reads it).
    fn log_likelihood_in_cell(&self, i: i64, j: i64) -> f64 {
        if i >= 0 && j >= 0 && (i as usize) < self.width && (j as usize) < self.height {
            self.cell_log_likelihood[j as usize * self.width + i as usize]
        } else {
            self.outside_log_likelihood
        }
    }

    /// `ln p(z | x, m)` over the beams `beams` of `scan` from `pose`: the sum
    /// of the beams' `ln p_k` (product), or `ln(1 + Σ p_k³)` (amcl).
    ///
    /// `field` must be the distance field the model was prepared on (the
    /// likelihood field reads its frame; the values come from the cells).
    /// `beam_ends` holds the beam end points in the robot frame for the hits
    /// among `beams` (see [`beam_end_points`]); the likelihood field uses them,
    /// the beam model does not.
    pub fn scan_log_likelihood(
        &self,
        grid: &OccupancyGrid,
        field: &DistanceField,
        pose: &Pose2,
        scan: &Scan,
        beams: &[usize],
        beam_ends: &[(f64, f64)],
    ) -> f64 {
        match &self.model {
            MeasurementModel::Beam(b) => {
                b.scan_log_likelihood(grid, pose, scan, beams, self.aggregation)
            }
            MeasurementModel::LikelihoodField(_) => {
                // Everything in the grid frame, in cells: one transform per
                // particle, then a rotation and one lookup per beam.
                let (px, py) = field.world_to_cells(pose.x, pose.y);
                let (s, c) = math::sin_cos(pose.theta - field.frame_yaw());
                let inv = 1.0 / field.resolution();
                let (s, c) = (s * inv, c * inv);
                let (w, h) = (self.width as f64, self.height as f64);
                let mut sum = 0.0;
                for &(bx, by) in beam_ends {
                    let x = px + c * bx - s * by;
                    let y = py + s * bx + c * by;
                    sum += if x >= 0.0 && x < w && y >= 0.0 && y < h {
                        // Inside the map the coordinates are not negative, so
                        // truncating them is flooring them. (Through `i64`:
                        // `f64 as usize` compiles to a longer sequence.)
                        let (i, j) = (x as i64 as usize, y as i64 as usize);
                        self.cell_log_likelihood[j * self.width + i]
                    } else {
                        // Outside the map, or not a number.
                        self.log_likelihood_in_cell(floor_to_i64(x), floor_to_i64(y))
                    };
                }
                match self.aggregation {
                    ScanAggregation::Product => sum,
                    ScanAggregation::AmclCubes => math::ln(1.0 + sum),
                }
            }
        }
    }

    /// Every beam's likelihood from `pose` (for the explanation panel).
    pub fn explain(
        &self,
        grid: &OccupancyGrid,
        field: &DistanceField,
        pose: &Pose2,
        scan: &Scan,
        beams: &[usize],
    ) -> Vec<BeamLikelihood> {
        beams
            .iter()
            .map(|&k| {
                let angle = scan.angles[k];
                let range = scan.ranges[k];
                match &self.model {
                    MeasurementModel::Beam(b) => {
                        let expected =
                            grid.raycast(pose.x, pose.y, pose.theta + angle, scan.range_max);
                        let usable = range.is_finite() && range >= scan.range_min.max(0.0);
                        BeamLikelihood {
                            angle,
                            range,
                            expected,
                            log_likelihood: usable.then(|| match self.aggregation {
                                ScanAggregation::Product => {
                                    b.log_likelihood(range, expected, scan.range_max)
                                }
                                ScanAggregation::AmclCubes => {
                                    math::ln(b.amcl_probability(range, expected, scan.range_max))
                                }
                            }),
                        }
                    }
                    MeasurementModel::LikelihoodField(lf) => {
                        if scan.is_end_point(k) {
                            let (s, c) = math::sin_cos(pose.theta + angle);
                            let d = field.distance_at(pose.x + range * c, pose.y + range * s);
                            BeamLikelihood {
                                angle,
                                range,
                                expected: d,
                                log_likelihood: Some(match self.aggregation {
                                    ScanAggregation::Product => {
                                        lf.log_likelihood(d, scan.range_max)
                                    }
                                    ScanAggregation::AmclCubes => {
                                        math::ln(lf.amcl_probability(d, scan.range_max))
                                    }
                                }),
                            }
                        } else {
                            BeamLikelihood {
                                angle,
                                range,
                                expected: field.max_distance(),
                                log_likelihood: None,
                            }
                        }
                    }
                }
            })
            .collect()
    }
}

/// The robot-frame end points of the beams `beams` of `scan` that hit something
/// (finite, at least `range_min`, below `range_max`): what the likelihood field
/// scores.
pub fn beam_end_points(scan: &Scan, beams: &[usize]) -> Vec<(f64, f64)> {
    beams
        .iter()
        .filter(|&&k| scan.is_end_point(k))
        .map(|&k| {
            let (s, c) = math::sin_cos(scan.angles[k]);
            (scan.ranges[k] * c, scan.ranges[k] * s)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Cell, OccupancyGrid};

    #[test]
    fn beam_model_matches_its_mixture() {
        let b = BeamModel::default();
        // z = z* = 2 m: Gaussian peak 1/(σ√2π) = 1.9947, short η λ e^{-λz}
        // with η = 1/(1 − e^{-0.2}), uniform 1/10.
        let p_hit = 1.0 / (0.2 * (2.0 * std::f64::consts::PI).sqrt());
        let eta = 1.0 / (1.0 - math::exp(-0.2));
        let p_short = eta * 0.1 * math::exp(-0.2);
        let expected = 0.95 * p_hit + 0.1 * p_short + 0.05 / 10.0;
        assert!((b.log_likelihood(2.0, 2.0, 10.0) - math::ln(expected)).abs() < 1e-12);
        // Max-range reading with the wall expected at 10 m: hit peak, short
        // term at z = z* = 10 and the point mass z_max.
        let eta10 = 1.0 / (1.0 - math::exp(-1.0));
        let at_max = 0.95 * p_hit + 0.1 * eta10 * 0.1 * math::exp(-1.0) + 0.05;
        assert!((b.log_likelihood(10.0, 10.0, 10.0) - math::ln(at_max)).abs() < 1e-12);
        // Beyond the expected range there is no short component.
        let u: f64 = 0.5 / 0.2;
        let far = 0.95 * p_hit * math::exp(-0.5 * u * u) + 0.005;
        assert!((b.log_likelihood(2.5, 2.0, 10.0) - math::ln(far)).abs() < 1e-12);
    }

    #[test]
    fn a_max_range_reading_penalises_a_particle_that_expects_a_wall() {
        // Probabilistic Robotics Table 6.1 (p_hit on [0, z_max]) and amcl's
        // BeamModel keep the hit term at z_max: a particle expecting a wall at
        // 2 m explains a max-range reading worse than one expecting open space.
        let b = BeamModel::default();
        let wall = b.log_likelihood(10.0, 2.0, 10.0);
        let open = b.log_likelihood(10.0, 10.0, 10.0);
        assert!(open > wall + 1.0, "open {open} wall {wall}");
        // Wall at 2 m: the Gaussian at 8 m (40 σ) is 0 in f64; the short term
        // is not defined beyond z*: only the point mass remains.
        assert!((wall - math::ln(0.05)).abs() < 1e-12, "{wall}");
        // Open space: peak 0.95/(σ√2π), short term η λ e^{-λ z_max}, z_max.
        let p_hit = 0.95 / (0.2 * (2.0 * std::f64::consts::PI).sqrt());
        let eta = 1.0 / (1.0 - math::exp(-1.0));
        let open_expected = p_hit + 0.1 * eta * 0.1 * math::exp(-1.0) + 0.05;
        assert!((open - math::ln(open_expected)).abs() < 1e-12);
        // A reading beyond the maximum is a max-range reading.
        assert_eq!(b.log_likelihood(12.0, 10.0, 10.0), open);
        // amcl's form: z_hit exp(0) + z_max for open space; z_max alone for
        // the wall (exp(−8²/0.08) underflows to 0).
        assert!((b.amcl_probability(10.0, 10.0, 10.0) - (0.95 + 0.05)).abs() < 1e-12);
        assert!((b.amcl_probability(10.0, 2.0, 10.0) - 0.05).abs() < 1e-12);
        // And through a whole scan on a grid: a wall 2 m ahead against open
        // space, one max-range beam, both aggregations.
        let mut g = OccupancyGrid::filled(200, 40, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for j in 0..40 {
            g.set(30, j, Cell::Occupied);
        }
        let scan = Scan {
            angles: vec![0.0],
            ranges: vec![5.0],
            range_min: 0.0,
            range_max: 5.0,
        };
        let facing_wall = Pose2::new(1.0, 2.0, 0.0);
        let facing_open = Pose2::new(3.5, 2.0, 0.0);
        for agg in [ScanAggregation::Product, ScanAggregation::AmclCubes] {
            let w = b.scan_log_likelihood(&g, &facing_wall, &scan, &[0], agg);
            let o = b.scan_log_likelihood(&g, &facing_open, &scan, &[0], agg);
            assert!(o > w, "{agg:?}: open {o} wall {w}");
        }
    }

    /// A 4 x 4 m free grid of 0.1 m cells with a wall along column 30, its
    /// distance field, and three beams straight ahead: 2.0 m, 1.7 m and one at
    /// max range (5 m).
    fn wall_and_three_beams() -> (OccupancyGrid, DistanceField, Scan) {
        let mut g = OccupancyGrid::filled(40, 40, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for j in 0..40 {
            g.set(30, j, Cell::Occupied);
        }
        let field = DistanceField::new(&g, 2.0);
        let scan = Scan {
            angles: vec![0.0, 0.0, 0.0],
            ranges: vec![2.0, 1.7, 5.0],
            range_min: 0.0,
            range_max: 5.0,
        };
        (g, field, scan)
    }

    /// The default likelihood field model, prepared on `field` up to `z_max`.
    fn default_field(
        aggregation: ScanAggregation,
        field: &DistanceField,
        z_max: f64,
    ) -> (LikelihoodFieldModel, PreparedModel) {
        let lf = LikelihoodFieldModel::default();
        let model = PreparedModel::new(
            MeasurementModel::LikelihoodField(lf),
            aggregation,
            field,
            z_max,
        );
        (lf, model)
    }

    /// Every beam of `scan` and the end points of those that hit.
    fn every_beam(scan: &Scan) -> (Vec<usize>, Vec<(f64, f64)>) {
        let beams = scan.subsample(0);
        let ends = beam_end_points(scan, &beams);
        (beams, ends)
    }

    #[test]
    fn amcl_aggregation_is_one_plus_the_sum_of_cubes() {
        // amcl_laser.cpp LikelihoodFieldModel: p = 1 + Σ (z_hit e^{−d²/2σ²} +
        // z_rand/z_max)³ over the hits; max-range readings skipped.
        let (g, field, scan) = wall_and_three_beams();
        let (_, model) = default_field(ScanAggregation::AmclCubes, &field, 5.0);
        let (beams, ends) = every_beam(&scan);
        let pose = Pose2::new(1.05, 2.05, 0.0);
        let ll = model.scan_log_likelihood(&g, &field, &pose, &scan, &beams, &ends);
        // Distances 0 and 0.3 m; σ = 0.2: e^{−0.09/0.08}.
        let p0: f64 = 0.95 + 0.01;
        let p1: f64 = 0.95 * math::exp(-0.09 / 0.08) + 0.01;
        let expected = math::ln(1.0 + p0 * p0 * p0 + p1 * p1 * p1);
        assert!((ll - expected).abs() < 1e-12, "{ll} vs {expected}");
        // A scan that contradicts the pose entirely still scores ln(1 + n p³)
        // with p the uniform floor alone, so the average likelihood cannot
        // collapse after a kidnap: at most a factor (1 + n)/(1 + n 10⁻⁶).
        let far = Pose2::new(1.05, 2.05, std::f64::consts::PI);
        let ll_far = model.scan_log_likelihood(&g, &field, &far, &scan, &beams, &ends);
        assert!(ll_far >= 0.0 && ll_far < ll, "{ll_far}");
        let explained = model.explain(&g, &field, &pose, &scan, &beams);
        assert!((explained[0].log_likelihood.unwrap() - math::ln(p0)).abs() < 1e-12);
        assert_eq!(explained[2].log_likelihood, None);
    }

    #[test]
    fn likelihood_field_scores_end_points_and_skips_max_range() {
        let (g, field, scan) = wall_and_three_beams();
        let (lf, model) = default_field(ScanAggregation::Product, &field, 5.0);
        // From (1.05, 2.05) facing +x the wall's cell centres are at x = 3.05.
        let (beams, ends) = every_beam(&scan);
        assert_eq!(ends.len(), 2);
        let pose = Pose2::new(1.05, 2.05, 0.0);
        let ll = model.scan_log_likelihood(&g, &field, &pose, &scan, &beams, &ends);
        let expected = lf.log_likelihood(0.0, 5.0) + lf.log_likelihood(0.3, 5.0);
        assert!((ll - expected).abs() < 1e-9, "{ll} vs {expected}");
        let explained = model.explain(&g, &field, &pose, &scan, &beams);
        assert_eq!(explained[2].log_likelihood, None);
        assert!((explained[1].expected - 0.3).abs() < 1e-9);
        // The beam model sees the wall face at x = 3.0: 1.95 m.
        let bm = PreparedModel::new(
            MeasurementModel::Beam(BeamModel::default()),
            ScanAggregation::Product,
            &field,
            5.0,
        );
        let e = bm.explain(&g, &field, &pose, &scan, &beams);
        assert!((e[0].expected - 1.95).abs() < 1e-9);
    }

    #[test]
    fn per_cell_values_equal_the_squared_distance_table() {
        // A room with a pillar, off the world origin and rotated.
        let mut g =
            OccupancyGrid::filled(30, 20, 0.1, Pose2::new(-1.0, 0.5, 0.3), Cell::Free).unwrap();
        for k in 0..30 {
            g.set(k, 0, Cell::Occupied);
            g.set(k, 19, Cell::Occupied);
        }
        g.set(12, 9, Cell::Occupied);
        let field = DistanceField::new(&g, 0.7);
        let (lf, model) = default_field(ScanAggregation::Product, &field, 6.0);
        let table = lf.table(&field, 6.0);
        let scan = Scan {
            angles: (0..36).map(|k| k as f64 * 0.17).collect(),
            ranges: (0..36).map(|k| 0.05 + k as f64 * 0.13).collect(),
            range_min: 0.0,
            range_max: 6.0,
        };
        let (beams, ends) = every_beam(&scan);
        // Poses inside, on the edge of and outside the map, and not a number.
        for pose in [
            Pose2::new(0.3, 1.4, 0.2),
            Pose2::new(-1.0, 0.5, 0.3),
            Pose2::new(1.7, 2.2, -2.0),
            Pose2::new(-4.0, 9.0, 1.0),
            Pose2::new(f64::NAN, 1.0, 0.0),
        ] {
            // The model before the per-cell table: floor, squared distance,
            // table.
            let (px, py) = field.world_to_cells(pose.x, pose.y);
            let (s, c) = math::sin_cos(pose.theta - field.frame_yaw());
            let (s, c) = (s / field.resolution(), c / field.resolution());
            let mut expected = 0.0;
            for &(bx, by) in &ends {
                let i = floor_to_i64(px + c * bx - s * by);
                let j = floor_to_i64(py + s * bx + c * by);
                expected += table[field.squared_cells(i, j) as usize];
            }
            let ll = model.scan_log_likelihood(&g, &field, &pose, &scan, &beams, &ends);
            assert_eq!(ll.to_bits(), expected.to_bits(), "{pose:?}");
        }
    }

    #[test]
    fn subsampling_spreads_beams_like_amcl() {
        let scan = Scan {
            angles: vec![0.0; 181],
            ranges: vec![1.0; 181],
            range_min: 0.0,
            range_max: 5.0,
        };
        assert_eq!(scan.subsample(5), vec![0, 45, 90, 135, 180]);
        assert_eq!(scan.subsample(0).len(), 181);
        assert_eq!(scan.subsample(1), vec![0]);
    }
}
