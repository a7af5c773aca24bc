//! Seeded random streams.
//!
//! Each source of randomness has its own stream of one ChaCha8 generator seeded
//! with the scenario's seed, so that changing one part of a scenario (say, the
//! sensor's field of view, which changes how many measurement draws happen) never
//! changes another (the landmark layout or the control noise), and a seed replays
//! the same run natively and in the browser.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The random streams of a landmark scenario.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// Random landmark layouts.
    Layout = 1,
    /// Noise on the executed controls.
    Control = 2,
    /// Noise on the measurements.
    Measurement = 3,
}

/// The generator for one stream of `seed`.
pub fn stream_rng(seed: u64, stream: Stream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream as u64);
    rng
}

/// One draw from `N(0, std²)`.
pub fn gaussian(rng: &mut ChaCha8Rng, std: f64) -> f64 {
    let z: f64 = slamlab_core::random::standard_normal(rng);
    std * z
}

/// SplitMix64: derives independent stream seeds from the master seed (the grid
/// world's streams: start pose, lidar, odometry, explorer, kidnaps, filters).
pub fn stream_seed(seed: u64, stream: u64) -> u64 {
    let mut z = seed
        .wrapping_add(stream.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_independent() {
        let a: Vec<f64> = (0..5)
            .map(|_| 0.0)
            .scan(stream_rng(7, Stream::Control), |r, _| {
                Some(gaussian(r, 1.0))
            })
            .collect();
        let b: Vec<f64> = (0..5)
            .map(|_| 0.0)
            .scan(stream_rng(7, Stream::Control), |r, _| {
                Some(gaussian(r, 1.0))
            })
            .collect();
        let c: Vec<f64> = (0..5)
            .map(|_| 0.0)
            .scan(stream_rng(7, Stream::Measurement), |r, _| {
                Some(gaussian(r, 1.0))
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn gaussian_has_the_requested_spread() {
        let mut rng = stream_rng(1, Stream::Control);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| gaussian(&mut rng, 0.5)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var.sqrt() - 0.5).abs() < 0.01, "std {}", var.sqrt());
    }
}
