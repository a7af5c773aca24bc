//! A laser scan and the geometry of its points: what the lidar's estimators
//! (Monte Carlo localization's sensor models, grid mapping, the scan matchers)
//! share, with nothing of any one of them.

use crate::geometry::Pose2;
use crate::math;
use serde::{Deserialize, Serialize};

/// A laser scan in the robot frame: the sensor sits at the robot's centre
/// facing forward; beam `k` points at `angles[k]` (radians, counter-clockwise)
/// and measured `ranges[k]` metres. A reading at or beyond `range_max` means
/// "nothing within range"; NaN or negative readings are ignored.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Scan {
    /// Beam angles in the robot frame, radians.
    pub angles: Vec<f64>,
    /// Measured ranges, metres.
    pub ranges: Vec<f64>,
    /// Shortest valid reading, metres.
    pub range_min: f64,
    /// Maximum range, metres.
    pub range_max: f64,
}

impl Scan {
    /// The indices of at most `max_beams` beams, evenly spread as amcl picks them
    /// (`laser_max_beams`: every `(n − 1)/(max_beams − 1)`-th beam); all beams if
    /// `max_beams` is 0 or at least the beam count.
    pub fn subsample(&self, max_beams: usize) -> Vec<usize> {
        let n = self.ranges.len().min(self.angles.len());
        if max_beams == 0 || max_beams >= n {
            return (0..n).collect();
        }
        if max_beams == 1 {
            return vec![0];
        }
        let step = (n - 1) as f64 / (max_beams - 1) as f64;
        (0..max_beams)
            .map(|k| ((k as f64 * step).round() as usize).min(n - 1))
            .collect()
    }
}

/// A point in a plane frame, metres: `[x, y]`.
pub type Point2 = [f64; 2];

impl Scan {
    /// Whether reading `k` is a usable end point: a finite number at least
    /// `range_min` and below `range_max` (max-range, NaN and negative readings
    /// are not).
    pub fn is_end_point(&self, k: usize) -> bool {
        let Some(&z) = self.ranges.get(k) else {
            return false;
        };
        z.is_finite() && z >= self.range_min.max(0.0) && z < self.range_max
    }

    /// Whether reading `k` says "nothing within range": at or beyond
    /// `range_max` (an infinite reading counts too).
    pub fn is_max_range(&self, k: usize) -> bool {
        self.ranges
            .get(k)
            .is_some_and(|&z| !z.is_nan() && z >= self.range_max)
    }

    /// The end points of the usable readings in the sensor frame, in beam order.
    pub fn points(&self) -> Vec<Point2> {
        let n = self.ranges.len().min(self.angles.len());
        (0..n)
            .filter(|&k| self.is_end_point(k))
            .map(|k| {
                let (s, c) = math::sin_cos(self.angles[k]);
                [self.ranges[k] * c, self.ranges[k] * s]
            })
            .collect()
    }

    /// The number of beams (angles and ranges paired).
    pub fn len(&self) -> usize {
        self.ranges.len().min(self.angles.len())
    }

    /// Whether the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// `pose` applied to a point: `R p + t`.
pub fn transform_point(pose: &Pose2, p: Point2) -> Point2 {
    PointTransform::new(pose).apply(p)
}

/// A pose ready to apply to many points: its sine and cosine taken once
/// (a matcher moves hundreds of points per candidate pose, and a sine per
/// point would cost more than the rest of the work on it). Gives exactly what
/// [`transform_point`] gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTransform {
    sin: f64,
    cos: f64,
    x: f64,
    y: f64,
}

impl PointTransform {
    /// The transform of `pose`: `p ↦ R(θ) p + (x, y)`.
    pub fn new(pose: &Pose2) -> Self {
        let (sin, cos) = math::sin_cos(pose.theta);
        Self {
            sin,
            cos,
            x: pose.x,
            y: pose.y,
        }
    }

    /// `R p + t`.
    #[inline]
    pub fn apply(&self, p: Point2) -> Point2 {
        [
            self.cos * p[0] - self.sin * p[1] + self.x,
            self.sin * p[0] + self.cos * p[1] + self.y,
        ]
    }
}

/// A room of line segments and a lidar in it, for the tests and benchmarks of
/// everything that reads scans (matchers, grids, grid FastSLAM).
pub mod test_room {
    use super::{Point2, Scan};
    use crate::geometry::Pose2;
    use crate::math;
    use crate::random::gaussian;
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    /// A wall from one end to the other.
    pub type Segment = (Point2, Point2);

    /// A lidar on line segments: `beams` beams over 360° from `pose`, exact ranges
    /// (plus Gaussian noise of `noise` m if given), `range_max` where nothing is hit.
    pub fn ray_cast(
        walls: &[Segment],
        pose: Pose2,
        beams: usize,
        range_max: f64,
        noise: Option<(f64, &mut ChaCha8Rng)>,
    ) -> Scan {
        let mut angles = Vec::with_capacity(beams);
        let mut ranges = Vec::with_capacity(beams);
        let mut noise = noise;
        for k in 0..beams {
            let angle = -PI + 2.0 * PI * k as f64 / beams as f64;
            let (s, c) = math::sin_cos(pose.theta + angle);
            let mut best = range_max;
            for &(a, b) in walls {
                // pose + r d = a + u (b − a), 0 ≤ u ≤ 1, r > 0.
                let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
                let den = c * ey - s * ex;
                if den.abs() < 1e-12 {
                    continue;
                }
                let (wx, wy) = (a[0] - pose.x, a[1] - pose.y);
                let r = (wx * ey - wy * ex) / den;
                let u = (wx * s - wy * c) / den;
                if r > 1e-9 && (0.0..=1.0).contains(&u) && r < best {
                    best = r;
                }
            }
            if best < range_max
                && let Some((sigma, rng)) = noise.as_mut()
            {
                best += gaussian(*rng, *sigma);
            }
            angles.push(angle);
            ranges.push(best);
        }
        Scan {
            angles,
            ranges,
            range_min: 0.0,
            range_max,
        }
    }

    /// The four walls of the rectangle `[x0, x1] × [y0, y1]`, counter-clockwise.
    pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Segment> {
        vec![
            ([x0, y0], [x1, y0]),
            ([x1, y0], [x1, y1]),
            ([x1, y1], [x0, y1]),
            ([x0, y1], [x0, y0]),
        ]
    }

    /// A 6 m × 4 m room with a cupboard and a pillar.
    pub fn room() -> Vec<Segment> {
        let mut walls = rectangle(-3.0, -2.0, 3.0, 2.0);
        walls.extend(rectangle(1.8, 1.2, 2.6, 2.0));
        walls.extend(rectangle(-1.2, -0.9, -0.8, -0.5));
        walls
    }
}
