//! A photo pair rendered from a pinhole camera, for tests and for trying the
//! photo pipeline without a camera: a facade 9 m away covered in random grey
//! cells (8 cm and 24 cm), a box face 5 m away and the ground 1.2 m below the
//! camera, seen from two poses and written as PNG bytes.

use std::io::Cursor;

use image::GrayImage;
use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};
use slamlab_core::vision::Intrinsics;

/// A plane's texture coordinates of a point on it, `None` off its extent.
type PlaneCoordinates<'a> = &'a dyn Fn(&Vector3<f64>) -> Option<(f64, f64)>;

/// A deterministic grey level for a cell of a plane's texture.
pub fn cell_value(plane: u64, a: i64, b: i64) -> f64 {
    let mut h = plane
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((a as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add((b as u64).wrapping_mul(0x1656_67B1_9E37_79F9));
    h ^= h >> 31;
    h = h.wrapping_mul(0xD6E8_FEB8_6659_FD93);
    h ^= h >> 29;
    (h % 256) as f64
}

/// Two octaves of random cells (8 cm and 24 cm).
pub fn texture(plane: u64, a: f64, b: f64) -> f64 {
    let fine = cell_value(plane, (a / 0.08).floor() as i64, (b / 0.08).floor() as i64);
    let coarse = cell_value(
        plane + 7,
        (a / 0.24).floor() as i64,
        (b / 0.24).floor() as i64,
    );
    0.5 * fine + 0.5 * coarse
}

/// The scene point seen along a ray (origin and direction in the left
/// camera's frame: x right, y down, z forward) and its grey level.
pub fn cast(origin: &Vector3<f64>, direction: &Vector3<f64>) -> Option<(Vector3<f64>, f64)> {
    let mut best: Option<(f64, Vector3<f64>, f64)> = None;
    let mut consider = |s: f64, plane: u64, coords: PlaneCoordinates<'_>| {
        if s > 1e-6 && best.as_ref().is_none_or(|b| s < b.0) {
            let p = origin + direction * s;
            if let Some((a, b)) = coords(&p) {
                best = Some((s, p, texture(plane, a, b)));
            }
        }
    };
    // The facade at z = 9 m.
    consider((9.0 - origin.z) / direction.z, 1, &|p| Some((p.x, p.y)));
    // A box face at z = 5 m, 2 m wide, 1.6 m high.
    consider((5.0 - origin.z) / direction.z, 2, &|p| {
        (p.x > -1.6 && p.x < 0.4 && p.y > -0.6 && p.y < 1.0).then_some((p.x, p.y))
    });
    // The ground, 1.2 m below the camera.
    consider((1.2 - origin.y) / direction.y, 3, &|p| {
        (p.z > 0.5).then_some((p.x, p.z))
    });
    best.map(|(_, p, v)| (p, v))
}

/// The camera of both photos: 640 x 480, a 60° horizontal field of view.
pub fn camera() -> Intrinsics {
    Intrinsics::from_fov(640.0, 480.0, 60.0)
}

/// The image of the camera with `X_cam = R X_left + t`, 2 x 2 samples a pixel.
pub fn render(rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> GrayImage {
    let k = camera();
    let origin = -(rotation.transpose() * translation);
    GrayImage::from_fn(640, 480, |u, v| {
        let mut sum = 0.0;
        for (du, dv) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
            let ray = k.normalize(&Vector2::new(f64::from(u) + du, f64::from(v) + dv));
            let direction = rotation.transpose() * ray;
            sum += cast(&origin, &direction).map_or(128.0, |(_, g)| g);
        }
        image::Luma([(sum / 4.0).round().clamp(0.0, 255.0) as u8])
    })
}

/// A grey image as PNG bytes.
pub fn png_bytes(image: &GrayImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    // Encoding into memory fails only on an allocation failure.
    if image
        .write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
        .is_err()
    {
        bytes.clear();
    }
    bytes
}

/// The right camera's pose: 4° about the vertical, 0.5 m to the side.
pub fn pose() -> (Matrix3<f64>, Vector3<f64>) {
    let rotation = *Rotation3::from_euler_angles(0.01, 4f64.to_radians(), 0.0).matrix();
    (rotation, Vector3::new(-0.5, 0.02, -0.15))
}

/// The two photos as PNG bytes: the left camera at the origin, the right one
/// at [`pose`] (`X_right = R X_left + t`).
pub fn photo_pair() -> (Vec<u8>, Vec<u8>) {
    let (rotation, translation) = pose();
    (
        png_bytes(&render(&Matrix3::identity(), &Vector3::zeros())),
        png_bytes(&render(&rotation, &translation)),
    )
}
