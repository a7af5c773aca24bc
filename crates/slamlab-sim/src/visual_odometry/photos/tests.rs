//! The photo pipeline on a rendered pair ([`super::synthetic`]).

use super::synthetic::{camera, cast, png_bytes, pose, render};
use super::*;
use nalgebra::{Matrix3, Vector3};
use slamlab_core::vision::{Method, RansacConfig, estimate_two_view, rotation_angle};

fn rendered_pair() -> (Photo, Photo) {
    let (left, right) = super::synthetic::photo_pair();
    (
        decode_photo("left.png", &left).expect("left"),
        decode_photo("right.png", &right).expect("right"),
    )
}

#[test]
fn a_rendered_photo_pair_gives_the_rotation() {
    let (left, right) = rendered_pair();
    let matched = match_photos(&left, &right).expect("matches");
    let k = working_intrinsics(&left, focal_for_fov(640.0, 60.0));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let config = RansacConfig {
        method: Method::FivePoint,
        ..RansacConfig::default()
    };
    let estimate = estimate_two_view(&matched.matches, &k, config, &mut rng).expect("estimate");
    let (rotation, translation) = pose();
    let error = rotation_angle(&(estimate.rotation.transpose() * rotation)).to_degrees();
    let t = estimate.translation.expect("general motion");
    let t_error = slamlab_core::vision::angle_between(&t, &translation).to_degrees();
    eprintln!(
        "features {:?}, {} matches, {} ambiguous, {} inliers, rotation error {error:.3} deg, translation direction {t_error:.2} deg",
        matched.features,
        matched.matches.len(),
        matched.ambiguous,
        estimate.inlier_count
    );
    assert!(error < 0.3, "{error}");
    assert!(t_error < 5.0, "{t_error}");
    assert!(matched.matches.len() >= 150, "{}", matched.matches.len());
}

#[test]
fn the_ratio_test_drops_mostly_wrong_matches() {
    let (left, right) = rendered_pair();
    let (rotation, translation) = pose();
    let k = camera();
    let pairs = test_pairs();
    let (a, b) = (features(&left, &pairs), features(&right, &pairs));
    // Where a left corner truly lands in the right image.
    let truth = |c: &imageproc::corners::Corner| {
        let ray = k.normalize(&Vector2::new(f64::from(c.x) + 0.5, f64::from(c.y) + 0.5));
        let (p, _) = cast(&Vector3::zeros(), &ray)?;
        k.project(&(rotation * p + translation))
    };
    let (mut kept, mut kept_right, mut dropped, mut dropped_right) = (0, 0, 0, 0);
    for l in &a {
        let mut d: Vec<(u32, usize)> = b
            .iter()
            .enumerate()
            .map(|(j, r)| (l.hamming_distance(r), j))
            .collect();
        d.sort();
        let Some(expected) = truth(&l.corner) else {
            continue;
        };
        let r = &b[d[0].1].corner;
        let right_match =
            (Vector2::new(f64::from(r.x) + 0.5, f64::from(r.y) + 0.5) - expected).norm() < 3.0;
        if f64::from(d[0].0) < RATIO * f64::from(d[1].0) {
            kept += 1;
            kept_right += usize::from(right_match);
        } else {
            dropped += 1;
            dropped_right += usize::from(right_match);
        }
    }
    let precision_kept = kept_right as f64 / kept.max(1) as f64;
    let precision_dropped = dropped_right as f64 / dropped.max(1) as f64;
    eprintln!(
        "kept {kept} ({precision_kept:.3} right), dropped {dropped} ({precision_dropped:.3} right)"
    );
    assert!(dropped > 0);
    assert!(precision_kept > 0.8, "{precision_kept}");
    assert!(
        precision_dropped < precision_kept - 0.3,
        "{precision_dropped}"
    );
    // The matcher keeps exactly the ones the ratio test keeps.
    assert_eq!(match_descriptors(&a, &b).matches.len(), kept_all(&a, &b));
}

fn kept_all(a: &[BriefDescriptor], b: &[BriefDescriptor]) -> usize {
    a.iter()
        .filter(|l| {
            let mut d: Vec<u32> = b.iter().map(|r| l.hamming_distance(r)).collect();
            d.sort();
            f64::from(d[0]) < RATIO * f64::from(d[1])
        })
        .count()
}

#[test]
fn bad_photos_get_a_message() {
    let not_image = decode_photo("notes.txt", b"hello, not a photo").unwrap_err();
    assert!(
        matches!(not_image, PhotoError::NotAnImage { .. }),
        "{not_image}"
    );
    assert!(not_image.to_string().contains("notes.txt"));
    // A PNG whose header says 10000 x 10000: refused before decoding.
    let mut png = png_bytes(&GrayImage::new(64, 64));
    // IHDR data starts at byte 16 (8 signature + 4 length + 4 type).
    png[16..20].copy_from_slice(&10_000u32.to_be_bytes());
    png[20..24].copy_from_slice(&10_000u32.to_be_bytes());
    let mut crc = flate2::Crc::new();
    crc.update(&png[12..29]);
    png[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    let large = decode_photo("huge.png", &png).unwrap_err();
    assert!(matches!(large, PhotoError::TooLarge { .. }), "{large}");
    assert!(large.to_string().contains("10000 x 10000"), "{large}");
    // A truncated photo.
    let truncated = png_bytes(&render(&Matrix3::identity(), &Vector3::zeros()));
    let cut = decode_photo("cut.png", &truncated[..truncated.len() / 2]).unwrap_err();
    assert!(matches!(cut, PhotoError::NotAnImage { .. }), "{cut}");
    // A blank photo has no corners.
    let blank = decode_photo(
        "blank.png",
        &png_bytes(&GrayImage::from_pixel(320, 240, image::Luma([90]))),
    )
    .unwrap();
    let few = match_photos(&blank, &blank).unwrap_err();
    assert!(matches!(few, PhotoError::TooFew(_)), "{few}");
    assert!(few.to_string().contains("blank.png has 0 corners"), "{few}");
    // Too small.
    let small = decode_photo("tiny.png", &png_bytes(&GrayImage::new(20, 20))).unwrap_err();
    assert!(matches!(small, PhotoError::TooSmall { .. }), "{small}");
}

/// Bad pairs the lesson must explain rather than estimate from: the same photo
/// twice (no translation: every match has zero parallax), two photos of
/// unrelated scenes (too few matches), a file over the byte cap.
#[test]
fn degenerate_pairs_and_oversized_files_get_a_message() {
    let (left, _) = rendered_pair();
    // The same photo twice: a pure rotation by 0°, no translation reported.
    let same = estimate_photos(&left, &left, focal_for_fov(640.0, 60.0)).expect("an estimate");
    eprintln!(
        "identical photos: {} matches, {} inliers, parallax {:.3} px, motion {:?}",
        same.matched.matches.len(),
        same.estimate.inlier_count,
        same.estimate.parallax_px,
        same.estimate.motion
    );
    assert_eq!(
        same.estimate.motion,
        slamlab_core::vision::Motion::PureRotation
    );
    assert!(same.estimate.translation.is_none());
    assert!(rotation_angle(&same.estimate.rotation).to_degrees() < 0.01);
    assert!(
        same.estimate.parallax_px < 0.01,
        "{}",
        same.estimate.parallax_px
    );

    // Unrelated textures: corners in both, fewer than 16 matches kept by the ratio test.
    let noise = |seed: u64| {
        GrayImage::from_fn(320, 240, |x, y| {
            image::Luma([
                super::synthetic::cell_value(seed, i64::from(x / 6), i64::from(y / 6)) as u8,
            ])
        })
    };
    let a = decode_photo("a.png", &png_bytes(&noise(11))).expect("a");
    let b = decode_photo("b.png", &png_bytes(&noise(12))).expect("b");
    match estimate_photos(&a, &b, focal_for_fov(320.0, 60.0)) {
        Err(PhotoError::TooFew(why)) => {
            eprintln!("unrelated photos: {why}");
            assert!(why.contains("at least 16 are needed"), "{why}");
        }
        Err(PhotoError::NoConsensus(why)) => {
            // Measured: 55 matches kept by the ratio test, 12 of them agree with
            // RANSAC's best motion (enough for RANSAC's own 10 % / 2s rule).
            eprintln!("unrelated photos: {why}");
            assert!(why.contains("agree with one motion"), "{why}");
        }
        Err(other) => panic!("unrelated photos: {other}"),
        Ok(e) => panic!(
            "unrelated photos gave {} inliers of {} matches",
            e.estimate.inlier_count,
            e.matched.matches.len()
        ),
    }

    // Over the byte cap: refused unread.
    let huge = vec![0u8; MAX_PHOTO_BYTES + 1];
    let error = decode_photo("huge.jpg", &huge).unwrap_err();
    assert!(matches!(error, PhotoError::TooLarge { .. }), "{error}");
    assert!(error.to_string().contains("huge.jpg"), "{error}");
}
