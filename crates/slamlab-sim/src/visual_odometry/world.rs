//! The docking world: 3D points on the station, the ground and a facade, the
//! vehicle's path and what its camera sees.

use nalgebra::{Matrix3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::math;
use slamlab_core::random::standard_normal;
use slamlab_core::vision::{Correspondence, Intrinsics, RelativePose};

/// Where a world point lies (the planar-scene segment keeps only the facade).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SceneKind {
    /// On the docking station (a box at the end of the approach).
    Station,
    /// On the ground (z = 0).
    Ground,
    /// On the facade behind the station (the thesis's white house), x = const.
    Facade,
}

/// One 3D point of the world, metres, z up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WorldPoint {
    /// Position in the world frame (x forward along the approach, y left, z up).
    pub position: Vector3<f64>,
    /// What it lies on.
    pub kind: SceneKind,
}

/// The vehicle at one frame: planar pose and the wheel speeds' (v, ω).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub theta: f64,
    /// Forward speed over the step that ends here, m/s.
    pub v: f64,
    /// Turn rate over the step that ends here, rad/s.
    pub w: f64,
}

/// Height of the camera above the ground, metres.
pub const CAMERA_HEIGHT: f64 = 1.0;
/// x of the station's front face, metres.
pub const STATION_X: f64 = 26.0;
/// x of the facade, metres.
pub const FACADE_X: f64 = 40.0;
/// Time between frames, seconds.
pub const FRAME_DT: f64 = 0.1;

/// The world of one seed: points, camera and path.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraWorld {
    /// Every 3D point.
    pub points: Vec<WorldPoint>,
    /// The camera (same for every frame).
    pub camera: Intrinsics,
    /// The true path, one entry per frame.
    pub frames: Vec<Frame>,
}

/// Rotation from the camera frame (z forward, x right, y down) to the vehicle
/// frame (x forward, y left, z up).
fn vehicle_from_camera() -> Matrix3<f64> {
    Matrix3::new(0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0)
}

/// `(R_wc, p_wc)`: the camera's orientation and position in the world.
pub fn world_from_camera(frame: &Frame) -> (Matrix3<f64>, Vector3<f64>) {
    let (s, c) = math::sin_cos(frame.theta);
    let yaw = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    (
        yaw * vehicle_from_camera(),
        Vector3::new(frame.x, frame.y, CAMERA_HEIGHT),
    )
}

/// The true motion between two frames as the estimators define it:
/// `X_b = R X_a + t` for a point in camera frames a and b.
pub fn relative_pose(a: &Frame, b: &Frame) -> RelativePose {
    let (r_a, p_a) = world_from_camera(a);
    let (r_b, p_b) = world_from_camera(b);
    RelativePose {
        rotation: r_b.transpose() * r_a,
        translation: r_b.transpose() * (p_a - p_b),
    }
}

impl CameraWorld {
    /// The world of a seed: `frames` frames of the docking approach, with an
    /// optional turn on the spot (pure rotation) from frame `frames / 3` for
    /// 20 frames.
    pub fn new(seed: u64, frames: usize, pure_rotation_segment: bool) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut points = Vec::new();
        // Station: a 3 m wide, 2 m tall box, points on its front face and sides.
        for _ in 0..150 {
            let (x, y) = if rng.random::<f64>() < 0.6 {
                (STATION_X, rng.random_range(-1.5..1.5))
            } else {
                let side = if rng.random::<bool>() { 1.5 } else { -1.5 };
                (STATION_X + rng.random_range(0.0..2.0), side)
            };
            points.push(WorldPoint {
                position: Vector3::new(x, y, rng.random_range(0.0..2.0)),
                kind: SceneKind::Station,
            });
        }
        for _ in 0..300 {
            points.push(WorldPoint {
                position: Vector3::new(
                    rng.random_range(2.0..FACADE_X),
                    rng.random_range(-12.0..12.0),
                    0.0,
                ),
                kind: SceneKind::Ground,
            });
        }
        for _ in 0..400 {
            points.push(WorldPoint {
                position: Vector3::new(
                    FACADE_X,
                    rng.random_range(-20.0..20.0),
                    rng.random_range(0.0..9.0),
                ),
                kind: SceneKind::Facade,
            });
        }
        let camera = Intrinsics::from_fov(640.0, 480.0, 60.0);
        Self {
            points,
            camera,
            frames: docking_path(frames, pure_rotation_segment),
        }
    }

    /// Pixels of every point in front of the camera and inside the image at a
    /// frame, noise-free: `(point index, pixel)`.
    pub fn visible(&self, frame: &Frame, planar_only: bool) -> Vec<(usize, Vector2<f64>)> {
        let (r, p) = world_from_camera(frame);
        self.points
            .iter()
            .enumerate()
            .filter(|(_, wp)| !planar_only || wp.kind == SceneKind::Facade)
            .filter_map(|(i, wp)| {
                let in_camera = r.transpose() * (wp.position - p);
                let pixel = self.camera.project(&in_camera)?;
                (self.camera.contains(&pixel) && in_camera.z < 80.0).then_some((i, pixel))
            })
            .collect()
    }

    /// Matches between frames a and b: points seen in both, pixel noise of
    /// standard deviation `noise_px` in both images, and a share `outliers` of
    /// them whose right pixel is replaced by a random one. Returns the matches
    /// and which are wrong (the truth, for metrics and drawing only).
    pub fn matches<R: Rng + ?Sized>(
        &self,
        a: usize,
        b: usize,
        noise_px: f64,
        outliers: f64,
        planar_only: bool,
        rng: &mut R,
    ) -> (Vec<Correspondence>, Vec<bool>) {
        let (Some(fa), Some(fb)) = (self.frames.get(a), self.frames.get(b)) else {
            return (Vec::new(), Vec::new());
        };
        let seen_b = self.visible(fb, planar_only);
        let mut matches = Vec::new();
        let mut wrong = Vec::new();
        for (i, pa) in self.visible(fa, planar_only) {
            let Some((_, pb)) = seen_b.iter().find(|(j, _)| *j == i) else {
                continue;
            };
            let left = add_noise(&pa, noise_px, rng);
            let is_wrong = rng.random::<f64>() < outliers;
            let right = if is_wrong {
                Vector2::new(
                    rng.random_range(0.0..self.camera.width),
                    rng.random_range(0.0..self.camera.height),
                )
            } else {
                add_noise(pb, noise_px, rng)
            };
            matches.push(Correspondence::new(left, right));
            wrong.push(is_wrong);
        }
        (matches, wrong)
    }
}

/// A pixel plus Gaussian noise of standard deviation `noise_px` on each axis.
fn add_noise<R: Rng + ?Sized>(p: &Vector2<f64>, noise_px: f64, rng: &mut R) -> Vector2<f64> {
    p + Vector2::new(standard_normal(rng), standard_normal(rng)) * noise_px
}

/// The docking approach (thesis Fig. 4.12): 40 % of the frames straight at
/// 1.5 m/s, then slowing to 0.4 m/s with gentle steering corrections toward the
/// station; optionally 20 frames turning on the spot at 0.3 rad/s (a pure
/// rotation) at a third of the way.
pub fn docking_path(frames: usize, pure_rotation_segment: bool) -> Vec<Frame> {
    let mut out = Vec::with_capacity(frames);
    let mut pose = Frame {
        x: 0.0,
        y: -1.0,
        theta: 0.04,
        v: 0.0,
        w: 0.0,
    };
    let straight = frames * 2 / 5;
    let turn_start = frames / 3;
    for k in 0..frames {
        out.push(pose);
        let t = k as f64 * FRAME_DT;
        let (v, w) = if pure_rotation_segment && (turn_start..turn_start + 20).contains(&k) {
            // Out and back: 10 frames left, 10 right.
            (0.0, if k < turn_start + 10 { 0.3 } else { -0.3 })
        } else if k < straight {
            (1.5, 0.0)
        } else {
            let slow = 0.4 + 1.1 * math::exp(-((k - straight) as f64) / 10.0);
            (
                slow,
                0.12 * math::sin(0.8 * t) - 0.5 * (pose.theta + 0.05 * pose.y),
            )
        };
        pose = arc(&pose, v, w, FRAME_DT);
    }
    out
}

/// Exact arc motion (thesis Eq. 2.70, corrected form; straight line at ω = 0).
pub fn arc(pose: &Frame, v: f64, w: f64, dt: f64) -> Frame {
    let theta = pose.theta + w * dt;
    let (x, y) = if w.abs() < 1e-9 {
        let (s, c) = math::sin_cos(pose.theta);
        (pose.x + v * dt * c, pose.y + v * dt * s)
    } else {
        let r = v / w;
        (
            pose.x + r * (math::sin(theta) - math::sin(pose.theta)),
            pose.y + r * (math::cos(pose.theta) - math::cos(theta)),
        )
    };
    Frame { x, y, theta, v, w }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_follow_the_true_motion() {
        let world = CameraWorld::new(1, 100, false);
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let (matches, wrong) = world.matches(10, 15, 0.0, 0.0, false, &mut rng);
        assert!(matches.len() > 100, "{}", matches.len());
        assert!(wrong.iter().all(|w| !w));
        let pose = relative_pose(&world.frames[10], &world.frames[15]);
        let e = slamlab_core::vision::skew(&pose.translation) * pose.rotation;
        for m in &matches {
            let l = world.camera.normalize(&m.left);
            let r = world.camera.normalize(&m.right);
            assert!(r.dot(&(e * l)).abs() < 1e-12);
        }
        // Driving forward 0.75 m: the camera moves along its optical axis (+z).
        let c = pose.right_centre_in_left();
        assert!(c.z > 0.7 && c.z < 0.76 && c.x.abs() < 0.05, "{c}");
    }

    #[test]
    fn the_path_docks_in_front_of_the_station() {
        let path = docking_path(200, false);
        let end = path[199];
        assert!(end.x > 14.0 && end.x < STATION_X - 1.0, "{end:?}");
        assert!(end.y.abs() < 1.5, "{end:?}");
        let turned = docking_path(200, true);
        // The turn on the spot moves nothing but the heading.
        assert_eq!(turned[66].x, turned[86].x);
        assert!((turned[76].theta - turned[66].theta - 0.3).abs() < 1e-12);
    }
}
