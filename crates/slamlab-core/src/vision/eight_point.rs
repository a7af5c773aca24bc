//! The eight-point algorithm (thesis `000` Sec. 4.3, Eq. 4.18-4.21) with
//! Hartley's normalization ("In defense of the eight-point algorithm", 1997).

use nalgebra::{DMatrix, Matrix3, SVector, Vector2, Vector3};

use super::linear::{null_space, smallest_right_singular_vector3};
use super::{Correspondence, Intrinsics, VisionError, check_finite};

/// Minimal number of matches of the eight-point algorithm.
pub const EIGHT: usize = 8;

/// Hartley's normalizing similarity for a set of pixels: translate the centroid
/// to the origin and scale so that the mean distance from it is √2. Returns `T`
/// with `x̂ = T x`.
pub fn hartley_normalization<'a>(
    points: impl Iterator<Item = &'a Vector2<f64>> + Clone,
) -> Matrix3<f64> {
    let n = points.clone().count().max(1) as f64;
    let centroid = points.clone().fold(Vector2::zeros(), |acc, p| acc + p) / n;
    let mean_distance = points.map(|p| (p - centroid).norm()).sum::<f64>() / n;
    let scale = if mean_distance > 1e-12 {
        std::f64::consts::SQRT_2 / mean_distance
    } else {
        1.0
    };
    Matrix3::new(
        scale,
        0.0,
        -scale * centroid.x,
        0.0,
        scale,
        -scale * centroid.y,
        0.0,
        0.0,
        1.0,
    )
}

/// The row of `A` for one match (thesis Eq. 4.20):
/// `a = [x_r x_l, x_r y_l, x_r, y_r x_l, y_r y_l, y_r, x_l, y_l, 1]`, so that
/// `a · f = x_rᵀ F x_l` with `f` the entries of F row by row.
pub fn constraint_row(left: &Vector3<f64>, right: &Vector3<f64>) -> [f64; 9] {
    let (xl, yl, wl) = (left.x, left.y, left.z);
    let (xr, yr, wr) = (right.x, right.y, right.z);
    [
        xr * xl,
        xr * yl,
        xr * wl,
        yr * xl,
        yr * yl,
        yr * wl,
        wr * xl,
        wr * yl,
        wr * wl,
    ]
}

/// The unit vector `f` minimizing `‖A f‖` (Eq. 4.21): the right singular vector
/// of the smallest singular value, as a 3x3 matrix row by row.
pub(crate) fn smallest_right_singular(rows: &[[f64; 9]]) -> Result<Matrix3<f64>, VisionError> {
    if let Ok(minimal) = <&[[f64; 9]; EIGHT]>::try_from(rows) {
        return null_vector_of_eight(minimal);
    }
    // At least 9 rows (zero rows pad a shorter system) so the SVD returns all of V.
    let mut a = DMatrix::<f64>::zeros(rows.len().max(9), 9);
    for (i, row) in rows.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            a[(i, j)] = *v;
        }
    }
    let svd = a
        .try_svd(false, true, f64::EPSILON, 500)
        .ok_or(VisionError::Degenerate("the SVD did not converge"))?;
    check_rank(svd.singular_values.as_slice())?;
    let v_t = svd
        .v_t
        .ok_or(VisionError::Degenerate("the SVD returned no V"))?;
    // Sorted descending: the last row of Vᵀ belongs to the smallest value.
    let last_row = SVector::<f64, 9>::from_iterator(v_t.row(8).iter().copied());
    as_matrix(&last_row)
}

/// The 3x3 matrix of a 9-vector read row by row; an error if a value is not
/// finite.
fn as_matrix(f: &SVector<f64, 9>) -> Result<Matrix3<f64>, VisionError> {
    if f.iter().any(|v| !v.is_finite()) {
        return Err(VisionError::Degenerate(
            "the SVD returned non-finite values",
        ));
    }
    Ok(Matrix3::new(
        f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8],
    ))
}

/// The null vector of a minimal sample's 8x9 matrix `A` (Eq. 4.21 with eight
/// rows: `A f = 0` exactly, so the smallest right singular vector is the null
/// vector), by a Householder QR factorization ([`null_space`]), about ten
/// times cheaper than an SVD inside RANSAC's loop. The rank test is the
/// factorization's: a diagonal entry of R below `1e-9` times the largest row
/// of `A` means rank below 8 (the matches fit more than one F), the
/// counterpart of [`check_rank`]'s test on the singular values.
fn null_vector_of_eight(rows: &[[f64; 9]; EIGHT]) -> Result<Matrix3<f64>, VisionError> {
    let ([f], rank) = null_space::<EIGHT, 1>(rows);
    if !(rank > 1e-9) {
        return Err(VisionError::Degenerate(
            "the matches fit more than one F (all scene points on one plane, or repeated matches)",
        ));
    }
    as_matrix(&SVector::<f64, 9>::from_row_slice(&f))
}

/// `A` must have rank 8 for a unique F: a second zero singular value means the
/// matches fit a whole family of F, as when every scene point lies on one
/// plane (the eight-point algorithm's degenerate case; five points still work).
fn check_rank(singular_values: &[f64]) -> Result<(), VisionError> {
    let largest = singular_values.first().copied().unwrap_or(0.0);
    let eighth = singular_values.get(7).copied().unwrap_or(0.0);
    if !(eighth > 1e-9 * largest) {
        return Err(VisionError::Degenerate(
            "the matches fit more than one F (all scene points on one plane, or repeated matches)",
        ));
    }
    Ok(())
}

/// The SVD of a 3x3 matrix, `(U, σ, Vᵀ)` with σ descending; `None` if it did
/// not converge (non-finite input).
pub(crate) fn svd3(m: &Matrix3<f64>) -> Option<(Matrix3<f64>, Vector3<f64>, Matrix3<f64>)> {
    let svd = m.try_svd(true, true, f64::EPSILON, 500)?;
    Some((svd.u?, svd.singular_values, svd.v_t?))
}

/// The closest rank-2 matrix in the Frobenius norm: the smallest singular value
/// set to zero (F has rank 2: every epipolar line passes through the epipole).
pub fn project_to_rank_two(m: &Matrix3<f64>) -> Matrix3<f64> {
    match svd3(m) {
        Some((u, s, v_t)) => u * Matrix3::from_diagonal(&Vector3::new(s[0], s[1], 0.0)) * v_t,
        _ => *m,
    }
}

/// [`project_to_rank_two`] for a minimal sample's F inside RANSAC's loop,
/// without the iterative SVD. With `M = U diag(σ₁, σ₂, σ₃) Vᵀ` the closest
/// rank-2 matrix is `M - σ₃ u₃ v₃ᵀ = M (I - v₃ v₃ᵀ)` (since `M v₃ = σ₃ u₃`), so
/// only `v₃` is needed, in closed form ([`smallest_right_singular_vector3`]).
/// That goes through `MᵀM`, which squares M's condition: fine for a
/// hypothesis (Hartley-normalized, or drowned in pixel noise without
/// normalization), while refits and final estimates keep the SVD, which
/// stays exact to 1e-10 on an unnormalized F whose entries span six orders
/// of magnitude.
fn project_to_rank_two_fast(m: &Matrix3<f64>) -> Matrix3<f64> {
    match smallest_right_singular_vector3(m) {
        Some(v) => m - (m * v) * v.transpose(),
        None => project_to_rank_two(m),
    }
}

/// The closest essential matrix: singular values `(s, s, 0)` with
/// `s = (σ₁ + σ₂) / 2` (Hartley and Zisserman, Result 9.18), scaled to
/// `‖E‖_F = 1`. An essential matrix has two equal singular values and a zero
/// one (thesis Eq. 4.15-4.16).
pub fn project_to_essential(m: &Matrix3<f64>) -> Matrix3<f64> {
    match svd3(m) {
        Some((u, _, v_t)) => {
            let s = std::f64::consts::FRAC_1_SQRT_2;
            u * Matrix3::from_diagonal(&Vector3::new(s, s, 0.0)) * v_t
        }
        _ => *m,
    }
}

/// The fundamental matrix of at least eight pixel matches by the eight-point
/// algorithm (Eq. 4.18-4.21), with the rank-2 projection, scaled to `‖F‖_F = 1`.
///
/// With `normalize`, the pixels of each image are first moved to zero mean and
/// a mean distance of √2 (Hartley), and F is mapped back: `F = T_rᵀ F̂ T_l`.
/// Without it the columns of `A` differ by five orders of magnitude (pixels²
/// next to 1) and noise moves the solution far more.
pub fn fundamental_eight_point(
    matches: &[Correspondence],
    normalize: bool,
) -> Result<Matrix3<f64>, VisionError> {
    if matches.len() < EIGHT {
        return Err(VisionError::TooFewMatches {
            method: "the eight-point algorithm",
            needed: EIGHT,
            got: matches.len(),
        });
    }
    check_finite(matches)?;
    let (t_left, t_right) = if normalize {
        (
            hartley_normalization(matches.iter().map(|m| &m.left)),
            hartley_normalization(matches.iter().map(|m| &m.right)),
        )
    } else {
        (Matrix3::identity(), Matrix3::identity())
    };
    let row = |m: &Correspondence| {
        let l = t_left * Vector3::new(m.left.x, m.left.y, 1.0);
        let r = t_right * Vector3::new(m.right.x, m.right.y, 1.0);
        constraint_row(&l, &r)
    };
    let f_hat = if let Ok(minimal) = <&[Correspondence; EIGHT]>::try_from(matches) {
        // A minimal sample (RANSAC's inner loop): no allocation.
        project_to_rank_two_fast(&null_vector_of_eight(&minimal.map(|m| row(&m)))?)
    } else {
        let rows: Vec<[f64; 9]> = matches.iter().map(row).collect();
        project_to_rank_two(&smallest_right_singular(&rows)?)
    };
    let f = t_right.transpose() * f_hat * t_left;
    let norm = f.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(VisionError::Degenerate("the fundamental matrix vanished"));
    }
    Ok(f / norm)
}

/// The essential matrix of at least eight pixel matches from a calibrated
/// camera: F by [`fundamental_eight_point`], then `E = Kᵀ F K` (Eq. 4.17
/// inverted) projected onto the essential matrices ([`project_to_essential`]).
pub fn essential_eight_point(
    matches: &[Correspondence],
    k: &Intrinsics,
    normalize: bool,
) -> Result<Matrix3<f64>, VisionError> {
    k.validate()?;
    let f = fundamental_eight_point(matches, normalize)?;
    Ok(essential_from_fundamental(&f, k))
}

/// The essential matrix closest to `Kᵀ F K` (Eq. 4.17 inverted), `‖E‖_F = 1`.
pub fn essential_from_fundamental(fundamental: &Matrix3<f64>, k: &Intrinsics) -> Matrix3<f64> {
    let km = k.matrix();
    project_to_essential(&(km.transpose() * fundamental * km))
}
