//! Two real photos in the visual-odometry pipeline (thesis `000` Sec. 4.3,
//! Fig. 4.14): decode each (PNG or JPEG, the size checked before the pixels are
//! decoded), FAST-9 corners (Rosten and Drummond 2006) and 256-bit BRIEF
//! descriptors (Calonder et al. 2010) from `imageproc`, brute-force Hamming
//! matching with Lowe's ratio test (the thesis's brute-force matcher), and the
//! same RANSAC as the synthetic pairs, with intrinsics from a focal length.

use std::io::Cursor;

use image::{GrayImage, ImageDecoder, imageops};
use imageproc::binary_descriptors::BinaryDescriptor;
use imageproc::binary_descriptors::brief::{BriefDescriptor, TestPair, brief};
use imageproc::point::Point;
use nalgebra::Vector2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::vision::{
    Correspondence, Intrinsics, Method, RansacConfig, TwoViewEstimate, estimate_two_view,
};

/// Files larger than this are refused unread.
pub const MAX_PHOTO_BYTES: usize = 40 << 20;
/// Photos with more pixels than this (about 50 megapixels, for example
/// 8660 x 5770) are refused from their header, before the pixels are decoded.
pub const MAX_PHOTO_PIXELS: u64 = 50_000_000;
/// Photos are scaled to at most this width (pixels) before features are found:
/// enough corners for RANSAC, a feature search in tens of milliseconds.
pub const WORKING_WIDTH: u32 = 640;
/// FAST-9 threshold: a corner's arc is brighter or darker than the centre by
/// more than this (grey levels).
pub const FAST_THRESHOLD: u8 = 20;
/// At most this many corners per photo (the strongest after non-maximum
/// suppression), so that the brute-force matcher's n² stays small.
pub const MAX_FEATURES: usize = 800;
/// BRIEF descriptor length in bits.
pub const DESCRIPTOR_BITS: usize = 256;
/// Lowe's ratio test: a match is kept when its Hamming distance is below this
/// share of the second-best candidate's.
pub const RATIO: f64 = 0.8;
/// Fewer features or matches than this cannot feed RANSAC usefully.
pub const MIN_MATCHES: usize = 16;
/// BRIEF's 31 x 31 patch needs this margin (pixels) around a corner.
const MARGIN: u32 = 17;

/// Why a photo or a photo pair gives no estimate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhotoError {
    /// Not a PNG or JPEG image.
    #[error("{name} is not an image SLAM Lab reads (PNG or JPEG): {why}")]
    NotAnImage {
        /// The file's name.
        name: String,
        /// The decoder's words.
        why: String,
    },
    /// Larger than the caps.
    #[error("{name} is {what}, more than the {cap} SLAM Lab reads")]
    TooLarge {
        /// The file's name.
        name: String,
        /// Its size.
        what: String,
        /// The cap.
        cap: String,
    },
    /// Too small for BRIEF's patches.
    #[error(
        "{name} is {width} x {height} pixels: too small to find features in (at least 64 x 64)"
    )]
    TooSmall {
        /// The file's name.
        name: String,
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// Too few corners or matches.
    #[error("{0}")]
    TooFew(String),
    /// The two photos are not the same size (one camera is assumed).
    #[error("the photos are {0} and {1} pixels: both must come from one camera at one size")]
    DifferentSizes(String, String),
    /// RANSAC found no estimate.
    #[error("RANSAC: {0}")]
    Estimate(String),
    /// RANSAC's best motion is backed by too few matches to be believed.
    #[error("{0}")]
    NoConsensus(String),
}

/// A decoded photo, grey and scaled to [`WORKING_WIDTH`].
#[derive(Debug, Clone)]
pub struct Photo {
    /// The file's name.
    pub name: String,
    /// The grey image features are found in.
    pub gray: GrayImage,
    /// The size of the file's image, pixels.
    pub original: (u32, u32),
}

impl Photo {
    /// Working pixels per original pixel.
    pub fn scale(&self) -> f64 {
        f64::from(self.gray.width()) / f64::from(self.original.0.max(1))
    }
}

/// Decodes a PNG or JPEG photo; the size is checked from the header before
/// any pixel is decoded.
pub fn decode_photo(name: &str, bytes: &[u8]) -> Result<Photo, PhotoError> {
    if bytes.len() > MAX_PHOTO_BYTES {
        return Err(PhotoError::TooLarge {
            name: name.to_owned(),
            what: format!("{} bytes", bytes.len()),
            cap: format!("{MAX_PHOTO_BYTES} bytes"),
        });
    }
    let not_image = |why: String| PhotoError::NotAnImage {
        name: name.to_owned(),
        why,
    };
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| not_image(e.to_string()))?;
    if !matches!(
        reader.format(),
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg)
    ) {
        return Err(not_image("the bytes are not a PNG or JPEG".to_owned()));
    }
    let decoder = reader
        .into_decoder()
        .map_err(|e| not_image(e.to_string()))?;
    let (width, height) = decoder.dimensions();
    if u64::from(width) * u64::from(height) > MAX_PHOTO_PIXELS {
        return Err(PhotoError::TooLarge {
            name: name.to_owned(),
            what: format!("{width} x {height} pixels"),
            cap: format!("{} megapixels", MAX_PHOTO_PIXELS / 1_000_000),
        });
    }
    if width < 64 || height < 64 {
        return Err(PhotoError::TooSmall {
            name: name.to_owned(),
            width,
            height,
        });
    }
    let image = image::DynamicImage::from_decoder(decoder).map_err(|e| not_image(e.to_string()))?;
    let gray = image.to_luma8();
    let gray = if width > WORKING_WIDTH {
        let h = ((u64::from(height) * u64::from(WORKING_WIDTH)) / u64::from(width)).max(1) as u32;
        imageops::resize(&gray, WORKING_WIDTH, h, imageops::FilterType::Triangle)
    } else {
        gray
    };
    Ok(Photo {
        name: name.to_owned(),
        gray,
        original: (width, height),
    })
}

/// BRIEF's test pairs: 256 pairs in the 31 x 31 patch, each coordinate
/// Gaussian about the centre with σ = 6.6 (Calonder et al.'s choice G II),
/// drawn from a fixed seed so that every run and both photos use the same.
pub fn test_pairs() -> Vec<TestPair> {
    let mut rng = ChaCha8Rng::seed_from_u64(0x0b51ef);
    let mut pairs = Vec::with_capacity(DESCRIPTOR_BITS);
    let mut coordinate = || loop {
        let v = 16.0 + 6.6 * slamlab_core::random::standard_normal(&mut rng);
        if (0.0..31.0).contains(&v) {
            return v as u32;
        }
    };
    while pairs.len() < DESCRIPTOR_BITS {
        let (x0, y0, x1, y1) = (coordinate(), coordinate(), coordinate(), coordinate());
        if (x0, y0) != (x1, y1) {
            pairs.push(TestPair {
                p0: Point::new(x0, y0),
                p1: Point::new(x1, y1),
            });
        }
    }
    pairs
}

/// A photo's features: FAST-9 corners, non-maximum suppressed (radius 3), the
/// [`MAX_FEATURES`] strongest away from the border, with BRIEF descriptors.
pub fn features(photo: &Photo, pairs: &[TestPair]) -> Vec<BriefDescriptor> {
    let (w, h) = photo.gray.dimensions();
    if w <= 2 * MARGIN || h <= 2 * MARGIN {
        return Vec::new();
    }
    let corners = imageproc::corners::corners_fast9(&photo.gray, FAST_THRESHOLD);
    let mut corners = imageproc::suppress::local_maxima(&corners, 3);
    corners.retain(|c| c.x >= MARGIN && c.y >= MARGIN && c.x < w - MARGIN && c.y < h - MARGIN);
    corners.sort_by(|a, b| {
        b.score
            .total_cmp(&a.score)
            .then((a.y, a.x).cmp(&(b.y, b.x)))
    });
    corners.truncate(MAX_FEATURES);
    let points: Vec<Point<u32>> = corners.iter().map(|c| Point::new(c.x, c.y)).collect();
    let pairs = pairs.to_vec();
    brief(&photo.gray, &points, DESCRIPTOR_BITS, Some(&pairs))
        .map(|(d, _)| d)
        .unwrap_or_default()
}

/// The matches of two photos and what the matcher dropped.
#[derive(Debug, Clone, Default)]
pub struct PhotoMatches {
    /// Feature pixels in the working images, left then right.
    pub matches: Vec<Correspondence>,
    /// Features found in each photo.
    pub features: (usize, usize),
    /// Matches whose best candidate was not clearly better than the second
    /// (ratio test), dropped.
    pub ambiguous: usize,
}

/// Brute-force Hamming matching with the ratio test: each left descriptor's
/// nearest right descriptor is kept when its distance is below [`RATIO`] times
/// the second nearest's.
pub fn match_descriptors(left: &[BriefDescriptor], right: &[BriefDescriptor]) -> PhotoMatches {
    let mut out = PhotoMatches {
        features: (left.len(), right.len()),
        ..PhotoMatches::default()
    };
    if right.len() < 2 {
        return out;
    }
    for l in left {
        let (mut best, mut second, mut best_index) = (u32::MAX, u32::MAX, 0);
        for (j, r) in right.iter().enumerate() {
            let d = l.hamming_distance(r);
            if d < best {
                (second, best, best_index) = (best, d, j);
            } else if d < second {
                second = d;
            }
        }
        if f64::from(best) < RATIO * f64::from(second) {
            let r = &right[best_index];
            out.matches.push(Correspondence::new(
                Vector2::new(f64::from(l.corner.x), f64::from(l.corner.y)),
                Vector2::new(f64::from(r.corner.x), f64::from(r.corner.y)),
            ));
        } else {
            out.ambiguous += 1;
        }
    }
    out
}

/// Matches of two photos, or why there are too few.
pub fn match_photos(left: &Photo, right: &Photo) -> Result<PhotoMatches, PhotoError> {
    let pairs = test_pairs();
    let (a, b) = (features(left, &pairs), features(right, &pairs));
    for (photo, found) in [(left, a.len()), (right, b.len())] {
        if found < MIN_MATCHES {
            return Err(PhotoError::TooFew(format!(
                "{} has {found} corners (FAST threshold {FAST_THRESHOLD}); at least {MIN_MATCHES} are needed: \
                 a photo with more texture, in focus",
                photo.name
            )));
        }
    }
    let matched = match_descriptors(&a, &b);
    if matched.matches.len() < MIN_MATCHES {
        return Err(PhotoError::TooFew(format!(
            "{} of {} corners matched ({} ambiguous); at least {MIN_MATCHES} are needed: \
             two photos of the same scene from nearby places",
            matched.matches.len(),
            a.len(),
            matched.ambiguous
        )));
    }
    Ok(matched)
}

/// The horizontal field of view (degrees) a focal length gives for a width.
pub fn focal_for_fov(width: f64, horizontal_fov_deg: f64) -> f64 {
    (width / 2.0) / slamlab_core::math::tan(horizontal_fov_deg.to_radians() / 2.0)
}

/// The working image's intrinsics for a focal length given in pixels of the
/// photo as taken (the principal point at the centre, square pixels).
pub fn working_intrinsics(photo: &Photo, focal_original_px: f64) -> Intrinsics {
    let (w, h) = (
        f64::from(photo.gray.width()),
        f64::from(photo.gray.height()),
    );
    let f = focal_original_px * photo.scale();
    Intrinsics {
        fx: f,
        fy: f,
        cx: w / 2.0,
        cy: h / 2.0,
        width: w,
        height: h,
    }
}

/// Two photos' matches and RANSAC's estimate from them.
#[derive(Debug, Clone)]
pub struct PhotoEstimate {
    /// The matches (working-image pixels) and the matcher's counts.
    pub matched: PhotoMatches,
    /// The working images' intrinsics.
    pub camera: Intrinsics,
    /// The estimate: inliers, R, t (or a pure rotation).
    pub estimate: TwoViewEstimate,
}

/// Features, matches and five-point RANSAC (seeded: the same photos give the
/// same estimate) for two photos of one camera whose focal length is
/// `focal_original_px` pixels of the photos as taken.
pub fn estimate_photos(
    left: &Photo,
    right: &Photo,
    focal_original_px: f64,
) -> Result<PhotoEstimate, PhotoError> {
    if left.original != right.original {
        let size = |p: &Photo| format!("{} x {}", p.original.0, p.original.1);
        return Err(PhotoError::DifferentSizes(size(left), size(right)));
    }
    let matched = match_photos(left, right)?;
    let camera = working_intrinsics(left, focal_original_px);
    let config = RansacConfig {
        method: Method::FivePoint,
        ..RansacConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let estimate = estimate_two_view(&matched.matches, &camera, config, &mut rng)
        .map_err(|e| PhotoError::Estimate(e.to_string()))?;
    // RANSAC accepts a consensus of a tenth of the matches (at least ten); among a few
    // dozen matches of two unrelated photos, chance alone puts a dozen within 2 px of
    // some epipolar geometry. Photos ask for as many inliers as they ask for matches.
    if estimate.inlier_count < MIN_MATCHES {
        return Err(PhotoError::NoConsensus(format!(
            "only {} of {} matches agree with one motion; at least {MIN_MATCHES} are needed: \
             two photos of the same scene from nearby places",
            estimate.inlier_count,
            matched.matches.len()
        )));
    }
    Ok(PhotoEstimate {
        matched,
        camera,
        estimate,
    })
}

pub mod synthetic;
#[cfg(test)]
mod tests;
