//! The four `(R, t)` in an essential matrix and the choice among them by
//! cheirality (thesis `000` Eq. 4.26-4.28).

use nalgebra::{Matrix3, Vector3};

use super::eight_point::svd3;

/// The motion between two cameras: a point seen by both satisfies
/// `X_r = R X_l + t` (thesis Eq. 4.9). From an essential matrix, `t` has unit
/// length: monocular images fix its direction, never its scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativePose {
    /// `R`: right camera from left camera.
    pub rotation: Matrix3<f64>,
    /// `t`, in the right camera frame.
    pub translation: Vector3<f64>,
}

impl RelativePose {
    /// The right camera's centre in the left camera frame, `−Rᵀ t`.
    pub fn right_centre_in_left(&self) -> Vector3<f64> {
        -(self.rotation.transpose() * self.translation)
    }
}

/// The four decompositions of an essential matrix and how many of the given
/// points each puts in front of both cameras.
#[derive(Debug, Clone, PartialEq)]
pub struct Decomposition {
    /// `(R₁, u₃)`, `(R₁, −u₃)`, `(R₂, u₃)`, `(R₂, −u₃)`.
    pub candidates: [RelativePose; 4],
    /// Points with positive depth in both cameras, per candidate.
    pub in_front: [usize; 4],
    /// The candidate with the most points in front (the first on a tie).
    pub best: usize,
    /// The singular values of E, descending.
    pub singular_values: Vector3<f64>,
}

impl Decomposition {
    /// The chosen motion.
    pub fn pose(&self) -> RelativePose {
        self.candidates[self.best]
    }
}

/// `W` of Hartley and Zisserman (Result 9.19): a rotation by +90° about z.
fn w_matrix() -> Matrix3<f64> {
    Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
}

/// The four `(R, t)` of an essential matrix `E = U diag(s, s, 0) Vᵀ`: `R₁ = U W
/// Vᵀ`, `R₂ = U Wᵀ Vᵀ`, `t = ±u₃` (the last column of U), with U and V taken
/// with determinant +1 so that both R are rotations (Hartley and Zisserman,
/// Result 9.19).
///
/// The thesis's Eq. 4.28 writes `[T]x = U D Σ Uᵀ` and `R = U D⁻¹ Vᵀ` with its
/// `D` (Eq. 4.27) equal to `Wᵀ`: that is `R₁` here together with one sign of t
/// (`U Wᵀ Σ Uᵀ = [u₃]x` up to scale). It is one of the four; the other three
/// are equally consistent with E, and only triangulating points (cheirality)
/// tells which one has the scene in front of both cameras. Eq. 4.28 also needs
/// det U = det V = +1, or R is a reflection.
///
/// `None` if the SVD fails (non-finite E).
pub fn decompose_essential(essential: &Matrix3<f64>) -> Option<([RelativePose; 4], Vector3<f64>)> {
    let (mut u, s, mut v_t) = svd3(essential)?;
    if u.determinant() < 0.0 {
        u = -u;
    }
    if v_t.determinant() < 0.0 {
        v_t = -v_t;
    }
    let w = w_matrix();
    let r1 = u * w * v_t;
    let r2 = u * w.transpose() * v_t;
    let t: Vector3<f64> = u.column(2).into_owned();
    let pose = |rotation, translation| RelativePose {
        rotation,
        translation,
    };
    Some(([pose(r1, t), pose(r1, -t), pose(r2, t), pose(r2, -t)], s))
}

/// The midpoint triangulation of one match in normalized coordinates
/// (`x = K⁻¹ [u, v, 1]ᵀ`): the point halfway between the closest points of
/// the two viewing rays, in the left camera frame, and its depths `(z_l, z_r)`
/// along the rays (signed: negative means behind that camera). `None` when the
/// rays are parallel (no parallax).
pub fn triangulate_midpoint(
    pose: &RelativePose,
    left: &Vector3<f64>,
    right: &Vector3<f64>,
) -> Option<(Vector3<f64>, f64, f64)> {
    // Left ray: λ_l x_l. Right ray, in the left frame: c + λ_r d, c = −Rᵀ t, d = Rᵀ x_r.
    let c = pose.right_centre_in_left();
    let d = pose.rotation.transpose() * right;
    let a = left;
    // Minimize |λ_l a − c − λ_r d|²: normal equations of a 2x2 system.
    let aa = a.dot(a);
    let dd = d.dot(&d);
    let ad = a.dot(&d);
    let det = aa * dd - ad * ad;
    if !(det > 1e-12 * aa * dd) {
        return None;
    }
    let ac = a.dot(&c);
    let dc = d.dot(&c);
    let lambda_l = (ac * dd - ad * dc) / det;
    let lambda_r = (ad * ac - aa * dc) / det;
    let point = (a * lambda_l + c + d * lambda_r) / 2.0;
    let depth_left = point.z;
    let depth_right = (pose.rotation * point + pose.translation).z;
    Some((point, depth_left, depth_right))
}

/// Decomposes E and counts, for each candidate, the matches (normalized
/// coordinates) that triangulate in front of both cameras; the candidate with
/// the most is the motion (cheirality).
pub fn choose_by_cheirality(
    essential: &Matrix3<f64>,
    left: &[Vector3<f64>],
    right: &[Vector3<f64>],
) -> Option<Decomposition> {
    let (candidates, singular_values) = decompose_essential(essential)?;
    let mut in_front = [0usize; 4];
    for (count, pose) in in_front.iter_mut().zip(candidates.iter()) {
        *count = left
            .iter()
            .zip(right.iter())
            .filter(|(l, r)| {
                matches!(triangulate_midpoint(pose, l, r), Some((_, zl, zr)) if zl > 0.0 && zr > 0.0)
            })
            .count();
    }
    let mut best = 0;
    for i in 1..4 {
        if in_front[i] > in_front[best] {
            best = i;
        }
    }
    Some(Decomposition {
        candidates,
        in_front,
        best,
        singular_values,
    })
}
