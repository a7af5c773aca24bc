//! The round two-wheel robot in the grid world, and its wheel odometry.
//!
//! The robot is a disc of radius `radius`. It moves on the exact arc of its
//! commanded `(v, ω)` (thesis `000` Eq. 2.70, with the erratum in the seeds'
//! README: the closed form is used, and the straight line when `|ω| → 0`), and a
//! move that would bring any part of the disc over an occupied cell (its centre
//! onto an invalid cell of the map inflated by the radius, checked every half
//! cell along the way) does not happen: the robot stops, with a note.

use rand::Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::grid::Costmap;
use slamlab_core::odometry::{OdometryNoise, odometry_increment, sample_increment};
use slamlab_core::{Pose2, math};

/// The robot: its true pose and its radius.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridRobot {
    /// True pose in the map frame.
    pub pose: Pose2,
    /// Radius, metres.
    pub radius: f64,
}

impl GridRobot {
    /// The pose after driving `(v, ω)` for `dt` seconds on the exact arc.
    pub fn arc(pose: &Pose2, v: f64, w: f64, dt: f64) -> Pose2 {
        if w.abs() < 1e-9 {
            let (s, c) = math::sin_cos(pose.theta);
            Pose2::new(pose.x + v * dt * c, pose.y + v * dt * s, pose.theta)
        } else {
            let r = v / w;
            let th = pose.theta + w * dt;
            Pose2::new(
                pose.x + r * (math::sin(th) - math::sin(pose.theta)),
                pose.y + r * (math::cos(pose.theta) - math::cos(th)),
                th,
            )
        }
    }

    /// Drives `(v, ω)` for `dt` seconds. `collision` is the map inflated by the
    /// robot's radius. Returns a note if the robot stopped against a wall (its
    /// pose is then unchanged).
    pub fn drive(&mut self, collision: &Costmap, v: f64, w: f64, dt: f64) -> Option<String> {
        let (v, w) = (
            if v.is_finite() { v } else { 0.0 },
            if w.is_finite() { w } else { 0.0 },
        );
        let next = Self::arc(&self.pose, v, w, dt);
        if collision.is_path_valid(self.pose.x, self.pose.y, next.x, next.y) {
            self.pose = next;
            None
        } else if next.x == self.pose.x && next.y == self.pose.y {
            // Turning on the spot never collides.
            self.pose = next;
            None
        } else {
            Some(format!(
                "collision: the robot stopped against a wall at ({:.2}, {:.2})",
                self.pose.x, self.pose.y
            ))
        }
    }
}

/// The wheel odometry noise of the simulated laser robot (the localization and
/// mapping lessons' default): α1 = α3 = 0.05, α2 = α4 = 0.01 (Probabilistic
/// Robotics Table 5.6's parameters).
pub const ROBOT_ODOMETRY_NOISE: OdometryNoise = OdometryNoise {
    alpha1: 0.05,
    alpha2: 0.01,
    alpha3: 0.05,
    alpha4: 0.01,
};

/// Wheel odometry: integrates each true motion increment with noise drawn from
/// the odometry motion model (Probabilistic Robotics Table 5.6), so the odometry
/// frame drifts from the map frame as real wheel odometry does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometrySensor {
    /// The odometry pose (odom frame).
    pub pose: Pose2,
    /// Noise per increment.
    pub noise: OdometryNoise,
}

impl OdometrySensor {
    /// Odometry starting at `start` (the odom frame then coincides with the map
    /// frame at the start, which no filter is told).
    pub fn new(start: Pose2, noise: OdometryNoise) -> Self {
        Self {
            pose: start,
            noise: noise.sanitized(),
        }
    }

    /// Accumulates the true motion from `before` to `after`, with noise.
    pub fn record<R: Rng + ?Sized>(&mut self, before: &Pose2, after: &Pose2, rng: &mut R) {
        let (rot1, trans, rot2) = odometry_increment(*before, *after);
        if trans == 0.0 && rot2 == 0.0 && rot1 == 0.0 {
            return;
        }
        self.pose = sample_increment(self.pose, rot1, trans, rot2, &self.noise, rng);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_core::grid::{Cell, OccupancyGrid};

    #[test]
    fn the_robot_stops_at_a_wall_and_turns_freely() {
        let mut g = OccupancyGrid::filled(40, 20, 0.1, Pose2::IDENTITY, Cell::Free).unwrap();
        for j in 0..20 {
            g.set(30, j, Cell::Occupied);
        }
        let c = Costmap::inflate(&g, 0.2);
        let mut r = GridRobot {
            pose: Pose2::new(2.0, 1.0, 0.0),
            radius: 0.2,
        };
        let mut note = None;
        for _ in 0..100 {
            note = r.drive(&c, 0.5, 0.0, 0.1);
            if note.is_some() {
                break;
            }
        }
        assert!(note.is_some_and(|n| n.contains("collision")));
        // The wall's cells start at x = 3.0; centres at 3.05; the disc's centre
        // must stay more than 0.2 from 3.05 (valid cells have centres < 2.85).
        assert!(r.pose.x < 2.9 && r.pose.x > 2.7, "{:?}", r.pose);
        assert!(r.drive(&c, 0.0, 1.0, 0.1).is_none());
        assert!((r.pose.theta - 0.1).abs() < 1e-12);
        // Straight-line limit of the arc.
        let a = GridRobot::arc(&Pose2::IDENTITY, 1.0, 1e-12, 1.0);
        assert!((a.x - 1.0).abs() < 1e-9 && a.y.abs() < 1e-9);
        let b = GridRobot::arc(&Pose2::IDENTITY, 1.0, std::f64::consts::PI, 1.0);
        assert!(b.x.abs() < 1e-9 && (b.y - 2.0 / std::f64::consts::PI).abs() < 1e-9);
    }
}
