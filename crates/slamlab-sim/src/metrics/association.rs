//! Which pose of the estimate goes with which pose of the reference: the nearest
//! time within a tolerance, as evo's `associate_trajectories` pairs them.
//!
//! evo walks the **shorter** of the two trajectories and gives each of its poses
//! the pose of the longer one whose time (the estimate's shifted by `offset`) is
//! nearest, keeping the pair when the two times are at most `max_diff` apart. A
//! pose of the longer trajectory can so serve two neighbours; the first of two
//! equally near times wins. evo's defaults: `max_diff = 0.01 s`, `offset = 0`.

use super::MetricsError;
use super::Trajectory;

/// evo's default tolerance, seconds (`evo_ape --t_max_diff`).
pub const DEFAULT_MAX_DIFF: f64 = 0.01;

/// The pairs of an estimate and a reference, index by index.
#[derive(Clone, Debug, PartialEq)]
pub struct Association {
    /// For each pair, the estimate's pose index.
    pub estimate: Vec<usize>,
    /// For each pair, the reference's pose index.
    pub reference: Vec<usize>,
    /// The tolerance, seconds.
    pub max_diff: f64,
    /// The time added to the estimate's stamps, seconds.
    pub offset: f64,
    /// The estimate's poses.
    pub estimate_poses: usize,
    /// The reference's poses.
    pub reference_poses: usize,
}

impl Association {
    /// The number of pairs.
    pub fn len(&self) -> usize {
        self.estimate.len()
    }

    /// Whether no pose found a partner.
    pub fn is_empty(&self) -> bool {
        self.estimate.is_empty()
    }
}

/// The index of the time in `sorted` (shifted by `shift`, as evo adds the offset
/// before it compares) nearest to `t`, and how far it is; the lower of two
/// equally near ones. `sorted` must be in increasing order.
fn nearest(sorted: &[f64], shift: f64, t: f64) -> Option<(usize, f64)> {
    if sorted.is_empty() {
        return None;
    }
    // The first index whose shifted time is at least t.
    let upper = sorted.partition_point(|&s| s + shift < t);
    let candidates = [
        upper.checked_sub(1),
        (upper < sorted.len()).then_some(upper),
    ];
    candidates
        .into_iter()
        .flatten()
        .map(|k| (k, ((sorted[k] + shift) - t).abs()))
        .fold(None, |best: Option<(usize, f64)>, (k, d)| match best {
            Some((_, bd)) if bd <= d => best,
            _ => Some((k, d)),
        })
}

/// Pairs `estimate` with `reference` by time, as evo does (see the module's
/// documentation). Both must be in time order (the readers make sure of it).
pub fn associate(
    reference: &Trajectory,
    estimate: &Trajectory,
    max_diff: f64,
    offset: f64,
) -> Result<Association, MetricsError> {
    if !(max_diff >= 0.0) || !offset.is_finite() {
        return Err(MetricsError::BadSetting(format!(
            "the time tolerance must be a number of seconds, at least 0 (was {max_diff}), and the offset finite (was {offset})"
        )));
    }
    let mut pairs = Association {
        estimate: Vec::new(),
        reference: Vec::new(),
        max_diff,
        offset,
        estimate_poses: estimate.len(),
        reference_poses: reference.len(),
    };
    // evo: the second (the estimate) is the longer one only when it has more poses.
    let estimate_longer = estimate.len() > reference.len();
    if estimate_longer {
        for (r, &t) in reference.stamps().iter().enumerate() {
            if let Some((e, d)) = nearest(estimate.stamps(), offset, t)
                && d <= max_diff
            {
                pairs.reference.push(r);
                pairs.estimate.push(e);
            }
        }
    } else {
        for (e, &t) in estimate.stamps().iter().enumerate() {
            if let Some((r, d)) = nearest(reference.stamps(), -offset, t)
                && d <= max_diff
            {
                pairs.reference.push(r);
                pairs.estimate.push(e);
            }
        }
    }
    if pairs.is_empty() {
        let span = |t: &Trajectory| {
            t.span()
                .map_or("no poses".to_owned(), |(a, b)| format!("{a} to {b} s"))
        };
        return Err(MetricsError::NoOverlap(format!(
            "no pose of the estimate ({}) is within {max_diff} s of a pose of the reference ({}){}",
            span(estimate),
            span(reference),
            if offset != 0.0 {
                format!(" with the estimate's times shifted by {offset} s")
            } else {
                String::new()
            }
        )));
    }
    Ok(pairs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use slamlab_core::Pose2;

    fn at(stamps: &[f64]) -> Trajectory {
        Trajectory::new(stamps.to_vec(), vec![Pose2::IDENTITY; stamps.len()])
    }

    /// The brute-force search evo runs: for each time of the shorter list, the
    /// first index of the smallest difference in the longer one.
    fn brute(short: &[f64], long: &[f64], shift: f64, max_diff: f64) -> Vec<(usize, usize)> {
        let shifted: Vec<f64> = long.iter().map(|s| s + shift).collect();
        let mut out = Vec::new();
        for (i, &t) in short.iter().enumerate() {
            let diffs: Vec<f64> = shifted.iter().map(|s| (s - t).abs()).collect();
            let mut best = 0;
            for (k, d) in diffs.iter().enumerate() {
                if *d < diffs[best] {
                    best = k;
                }
            }
            if diffs[best] <= max_diff {
                out.push((i, best));
            }
        }
        out
    }

    #[test]
    fn pairs_as_evo_pairs_them() {
        let reference = at(&[0.0, 0.1, 0.2, 0.3, 0.4, 0.5]);
        // Jittered, one missing, one far off, one exactly between two.
        let estimate = at(&[0.004, 0.098, 0.25, 0.31, 0.7]);
        let a = associate(&reference, &estimate, 0.01, 0.0).unwrap();
        assert_eq!(a.estimate, vec![0, 1]);
        assert_eq!(a.reference, vec![0, 1]);
        let wide = associate(&reference, &estimate, 0.05, 0.0).unwrap();
        // 0.25 is as near 0.2 as 0.3: the first wins.
        assert_eq!(wide.reference, vec![0, 1, 2, 3]);
        assert_eq!(wide.estimate, vec![0, 1, 2, 3]);
        // The estimate longer: the reference's poses look for partners.
        let long = at(&[0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3]);
        let short = at(&[0.049, 0.26]);
        let a = associate(&short, &long, 0.02, 0.0).unwrap();
        assert_eq!(
            (a.reference.clone(), a.estimate.clone()),
            (vec![0, 1], vec![1, 5])
        );
        // An offset moves the estimate's times: 0.05 - 0.001 meets 0.049; 0.26 now
        // has nothing within 2 ms.
        let a = associate(&short, &long, 0.002, -0.001).unwrap();
        assert_eq!(
            (a.reference.clone(), a.estimate.clone()),
            (vec![0], vec![1])
        );
        let a = associate(&short, &long, 0.002, 0.01).unwrap();
        assert_eq!(
            (a.reference.clone(), a.estimate.clone()),
            (vec![1], vec![5])
        );
        assert!(matches!(
            associate(&reference, &at(&[9.0]), 0.01, 0.0),
            Err(MetricsError::NoOverlap(_))
        ));
    }

    #[test]
    fn the_binary_search_finds_what_the_brute_force_finds() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let mut make = |n: usize| {
                let mut t = 0.0;
                (0..n)
                    .map(|_| {
                        t += rng.random_range(0.001..0.2);
                        t
                    })
                    .collect::<Vec<f64>>()
            };
            let (a, b) = (make(40), make(55));
            let offset = 0.03;
            for max_diff in [0.0, 0.01, 0.05, 1.0] {
                let got = associate(&at(&a), &at(&b), max_diff, offset);
                let want = brute(&a, &b, offset, max_diff);
                match got {
                    Ok(got) => {
                        let pairs: Vec<(usize, usize)> =
                            got.reference.into_iter().zip(got.estimate).collect();
                        assert_eq!(pairs, want);
                    }
                    Err(_) => assert!(want.is_empty()),
                }
            }
        }
    }
}
