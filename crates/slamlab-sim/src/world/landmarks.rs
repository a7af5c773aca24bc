//! The landmark world: a square arena and the landmarks in it.

use crate::noise::{Stream, stream_rng};
use nalgebra::Vector2;
use rand::Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::math;
use std::f64::consts::PI;

/// A landmark with its identity (the sensor reports it: known data association).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Landmark {
    /// The identity the sensor reports.
    pub id: usize,
    /// True position, metres.
    pub position: Vector2<f64>,
}

/// Where the landmarks go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LandmarkLayout {
    /// A fixed layout for teaching: landmarks on two rings around the robot's
    /// circle, inner and outer alternating, so every part of the lap sees some.
    #[default]
    Teaching,
    /// Uniformly random positions in the square, from the scenario's seed.
    Random,
}

impl LandmarkLayout {
    /// The name used in URLs and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            LandmarkLayout::Teaching => "teaching",
            LandmarkLayout::Random => "random",
        }
    }
}

/// The square arena `[-size/2, size/2]²` and its landmarks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LandmarkWorld {
    /// Side length of the square, metres.
    pub size: f64,
    /// The landmarks.
    pub landmarks: Vec<Landmark>,
}

impl LandmarkWorld {
    /// Builds the world. `ring_radius` is the radius of the robot's circle, around
    /// which the teaching layout places its rings (centred on the origin).
    pub fn generate(
        layout: LandmarkLayout,
        count: usize,
        size: f64,
        ring_radius: f64,
        seed: u64,
    ) -> Self {
        let half = 0.5 * size;
        let margin = (0.05 * size).min(0.5);
        let limit = (half - margin).max(0.0);
        let landmarks = match layout {
            LandmarkLayout::Teaching => {
                let inner = (0.7 * ring_radius).min(limit);
                let outer = (1.55 * ring_radius).min(limit);
                (0..count)
                    .map(|i| {
                        // A golden-angle offset keeps neighbouring landmarks apart for any count.
                        let angle = 2.0 * PI * i as f64 / count.max(1) as f64 + 0.35;
                        let radius = if i % 2 == 0 { outer } else { inner };
                        let jitter = 0.15 * (math::sin(i as f64 * 2.399_963));
                        let r = (radius + jitter * ring_radius * 0.2).clamp(0.0, limit);
                        Landmark {
                            id: i,
                            position: Vector2::new(r * math::cos(angle), r * math::sin(angle)),
                        }
                    })
                    .collect()
            }
            LandmarkLayout::Random => {
                let mut rng = stream_rng(seed, Stream::Layout);
                (0..count)
                    .map(|i| {
                        let x = if limit > 0.0 {
                            rng.random_range(-limit..=limit)
                        } else {
                            0.0
                        };
                        let y = if limit > 0.0 {
                            rng.random_range(-limit..=limit)
                        } else {
                            0.0
                        };
                        Landmark {
                            id: i,
                            position: Vector2::new(x, y),
                        }
                    })
                    .collect()
            }
        };
        Self { size, landmarks }
    }

    /// The landmark with this id.
    pub fn landmark(&self, id: usize) -> Option<&Landmark> {
        self.landmarks.iter().find(|l| l.id == id)
    }

    /// The squared distance from `p` to the nearest landmark (`None` for a
    /// world without landmarks): how far off an estimate is when the filter
    /// labels its landmarks itself.
    pub fn nearest_squared_distance(&self, p: &Vector2<f64>) -> Option<f64> {
        self.landmarks
            .iter()
            .map(|t| (t.position - p).norm_squared())
            .min_by(f64::total_cmp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_landmark_is_the_closest_one() {
        let world = LandmarkWorld::generate(LandmarkLayout::Random, 10, 16.0, 3.2, 5);
        let p = Vector2::new(0.3, -0.7);
        let brute = world
            .landmarks
            .iter()
            .map(|l| (l.position - p).norm_squared())
            .fold(f64::INFINITY, f64::min);
        assert_eq!(world.nearest_squared_distance(&p), Some(brute));
        assert_eq!(
            world.nearest_squared_distance(&world.landmarks[3].position),
            Some(0.0)
        );
        let empty = LandmarkWorld::generate(LandmarkLayout::Random, 0, 16.0, 3.2, 5);
        assert_eq!(empty.nearest_squared_distance(&p), None);
    }

    #[test]
    fn layouts_fit_the_world_and_are_reproducible() {
        for layout in [LandmarkLayout::Teaching, LandmarkLayout::Random] {
            let a = LandmarkWorld::generate(layout, 40, 16.0, 3.2, 5);
            let b = LandmarkWorld::generate(layout, 40, 16.0, 3.2, 5);
            assert_eq!(a, b);
            assert_eq!(a.landmarks.len(), 40);
            for l in &a.landmarks {
                assert!(
                    l.position[0].abs() <= 8.0 && l.position[1].abs() <= 8.0,
                    "{l:?}"
                );
            }
        }
        let other_seed = LandmarkWorld::generate(LandmarkLayout::Random, 10, 16.0, 3.2, 6);
        assert_ne!(
            other_seed,
            LandmarkWorld::generate(LandmarkLayout::Random, 10, 16.0, 3.2, 5)
        );
        assert!(
            LandmarkWorld::generate(LandmarkLayout::Teaching, 0, 16.0, 3.2, 5)
                .landmarks
                .is_empty()
        );
    }
}
