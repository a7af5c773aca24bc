//! The pose estimate of a particle cloud as ROS amcl reports it: particles are
//! binned into cells of `cell_size x cell_size` metres and `angle_bin` radians
//! (amcl's `pf_kdtree`: 0.5 m, 0.5 m, 10°), neighbouring occupied bins (the 26
//! around a bin, heading bins wrapping around) form clusters, and the estimate is
//! the weighted mean and covariance of the heaviest cluster.
//!
//! amcl finds the bins with a kd-tree; here the bins are sorted and neighbours
//! found by binary search, which gives the same clusters and a result that does
//! not depend on any hash order (so a seed replays bit for bit).

use crate::geometry::{Pose2, wrap_angle};
use crate::math;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Bin sizes for clustering.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterBins {
    /// Side of a position bin, metres (amcl: 0.5).
    pub cell_size: f64,
    /// Width of a heading bin, radians (amcl: 10°).
    pub angle_bin: f64,
}

impl Default for ClusterBins {
    fn default() -> Self {
        Self {
            cell_size: 0.5,
            angle_bin: 10f64.to_radians(),
        }
    }
}

/// The weighted mean of the heaviest cluster and its covariance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseEstimate {
    /// Weighted mean (heading: circular mean).
    pub pose: Pose2,
    /// Weighted covariance of `[x, y, θ]` around the mean, heading differences
    /// wrapped.
    pub covariance: Matrix3<f64>,
    /// Total normalized weight of the cluster (1 if all particles are in it).
    pub weight: f64,
    /// Particles in the cluster.
    pub count: usize,
    /// How many clusters the cloud has.
    pub clusters: usize,
}

/// The heaviest cluster's estimate, or `None` for an empty cloud or a cloud
/// whose weights are all zero or not numbers.
pub fn heaviest_cluster(
    poses: &[Pose2],
    weights: &[f64],
    bins: &ClusterBins,
) -> Option<PoseEstimate> {
    let n = poses.len().min(weights.len());
    if n == 0 {
        return None;
    }
    let cell = if bins.cell_size > 0.0 && bins.cell_size.is_finite() {
        bins.cell_size
    } else {
        0.5
    };
    let angle_bins = if bins.angle_bin > 0.0 && bins.angle_bin.is_finite() {
        ((TAU / bins.angle_bin).round() as i64).max(1)
    } else {
        36
    };
    let key = |p: &Pose2| -> (i64, i64, i64) {
        let a =
            ((wrap_angle(p.theta) + std::f64::consts::PI) / TAU * angle_bins as f64).floor() as i64;
        (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            a.rem_euclid(angle_bins),
        )
    };
    let keyed: Vec<((i64, i64, i64), usize)> = (0..n)
        .filter(|&i| poses[i].is_finite())
        .map(|i| (key(&poses[i]), i))
        .collect();
    let order = sort_by_bin(keyed);
    // Distinct bins and, for each particle in `order`, its bin.
    let mut bin_keys: Vec<(i64, i64, i64)> = Vec::new();
    let mut bin_of: Vec<usize> = Vec::with_capacity(order.len());
    for &(k, _) in &order {
        if bin_keys.last() != Some(&k) {
            bin_keys.push(k);
        }
        bin_of.push(bin_keys.len() - 1);
    }
    // Union-find over bins.
    let mut parent: Vec<usize> = (0..bin_keys.len()).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // Being neighbours is symmetric (heading offsets count modulo the number
    // of heading bins), so looking only in the 13 directions that come after
    // (0, 0, 0) in (x, y, heading) order finds every pair of neighbouring bins
    // from one of its two bins. A union keeps the smaller root, so each
    // cluster's root ends up its smallest bin whatever order the pairs come in.
    for (b, &(x, y, a)) in bin_keys.iter().enumerate() {
        for dx in -1..=1 {
            for dy in -1..=1 {
                for da in -1..=1 {
                    if (dx, dy, da) <= (0, 0, 0) {
                        continue;
                    }
                    let neighbour = (x + dx, y + dy, (a + da).rem_euclid(angle_bins));
                    if let Ok(nb) = bin_keys.binary_search(&neighbour) {
                        let (ra, rb) = (find(&mut parent, b), find(&mut parent, nb));
                        if ra != rb {
                            parent[ra.max(rb)] = ra.min(rb);
                        }
                    }
                }
            }
        }
    }
    let roots: Vec<usize> = (0..bin_keys.len()).map(|b| find(&mut parent, b)).collect();
    let mut cluster_weight = vec![0.0; bin_keys.len()];
    for (k, &(_, i)) in order.iter().enumerate() {
        let w = weights[i];
        if w > 0.0 && w.is_finite() {
            cluster_weight[roots[bin_of[k]]] += w;
        }
    }
    let clusters = (0..bin_keys.len()).filter(|&b| roots[b] == b).count();
    let mut best = None;
    for b in 0..bin_keys.len() {
        if roots[b] == b && cluster_weight[b] > 0.0 {
            match best {
                Some(bb) if cluster_weight[bb] >= cluster_weight[b] => {}
                _ => best = Some(b),
            }
        }
    }
    let best = best?;
    let total = cluster_weight[best];
    let members: Vec<usize> = order
        .iter()
        .enumerate()
        .filter(|(k, _)| roots[bin_of[*k]] == best)
        .map(|(_, o)| o.1)
        .filter(|&i| weights[i] > 0.0 && weights[i].is_finite())
        .collect();
    let (mut mx, mut my, mut ms, mut mc) = (0.0, 0.0, 0.0, 0.0);
    for &i in &members {
        let w = weights[i] / total;
        let (s, c) = math::sin_cos(poses[i].theta);
        mx += w * poses[i].x;
        my += w * poses[i].y;
        ms += w * s;
        mc += w * c;
    }
    let mean = Pose2::new(mx, my, math::atan2(ms, mc));
    let mut cov = Matrix3::zeros();
    for &i in &members {
        let w = weights[i] / total;
        let d = nalgebra::Vector3::new(
            poses[i].x - mean.x,
            poses[i].y - mean.y,
            wrap_angle(poses[i].theta - mean.theta),
        );
        cov += w * d * d.transpose();
    }
    Some(PoseEstimate {
        pose: mean,
        covariance: cov,
        weight: total,
        count: members.len(),
        clusters,
    })
}

/// Sorts `(bin, particle)` pairs, given in increasing particle order, by bin and
/// then by particle: the order that groups each bin's particles together and
/// fixes the order in which their weights are summed.
///
/// Comparing `(i64, i64, i64, usize)` tuples is slow, so when the occupied bins
/// span a small enough box (always, for a cloud on a map), each pair is packed
/// into one `u64`: the bin's rank in that box in row-major order (x, then y,
/// then heading, each counted from the smallest occupied one), shifted left,
/// with the pair's position in `keyed` in the low bits. Ranks preserve the
/// order of the bins and positions that of the particles, so sorting the
/// packed numbers gives exactly the tuple order. A cloud spread too far to
/// pack is sorted as tuples.
fn sort_by_bin(mut keyed: Vec<((i64, i64, i64), usize)>) -> Vec<((i64, i64, i64), usize)> {
    let Some(&(first, _)) = keyed.first() else {
        return keyed;
    };
    let (mut lo, mut hi) = (first, first);
    for &((x, y, a), _) in &keyed {
        lo = (lo.0.min(x), lo.1.min(y), lo.2.min(a));
        hi = (hi.0.max(x), hi.1.max(y), hi.2.max(a));
    }
    // Bits for a position in `keyed`.
    let shift = usize::BITS - (keyed.len() - 1).leading_zeros();
    // Bins along each axis, `None` if the box (times the positions) does not
    // fit in a u64.
    let span = |l: i64, h: i64| h.abs_diff(l).checked_add(1);
    let bins_per_axis = (|| {
        let (nx, ny, na) = (span(lo.0, hi.0)?, span(lo.1, hi.1)?, span(lo.2, hi.2)?);
        let ranks = nx.checked_mul(ny)?.checked_mul(na)?;
        (ranks <= u64::MAX >> shift).then_some((ny, na))
    })();
    let Some((ny, na)) = bins_per_axis else {
        keyed.sort_unstable();
        return keyed;
    };
    let mut packed: Vec<u64> = keyed
        .iter()
        .zip(0u64..)
        .map(|(&((x, y, a), _), position)| {
            let rank = (x.abs_diff(lo.0) * ny + y.abs_diff(lo.1)) * na + a.abs_diff(lo.2);
            rank << shift | position
        })
        .collect();
    packed.sort_unstable();
    let mask = (1u64 << shift) - 1;
    packed.iter().map(|&p| keyed[(p & mask) as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_clusters_the_heavier_wins_with_its_own_statistics() {
        let mut poses = Vec::new();
        let mut weights = Vec::new();
        // Cluster A at (1, 1) across the ±π seam: headings π − 0.05 and −π + 0.05.
        for (dx, th) in [(0.0, 3.09), (0.1, -3.09), (0.2, 3.09), (0.3, -3.09)] {
            poses.push(Pose2::new(1.0 + dx, 1.0, th));
            weights.push(0.15);
        }
        // Cluster B at (5, 5), lighter.
        for dx in [0.0, 0.1] {
            poses.push(Pose2::new(5.0 + dx, 5.0, 0.0));
            weights.push(0.2);
        }
        let e = heaviest_cluster(&poses, &weights, &ClusterBins::default()).unwrap();
        assert_eq!(e.clusters, 2);
        assert_eq!(e.count, 4);
        assert!((e.weight - 0.6).abs() < 1e-12);
        assert!((e.pose.x - 1.15).abs() < 1e-12 && (e.pose.y - 1.0).abs() < 1e-12);
        assert!(
            (e.pose.theta.abs() - std::f64::consts::PI).abs() < 1e-9,
            "{:?}",
            e.pose
        );
        // Var x of {0, .1, .2, .3} = 0.0125; heading deviations ±0.0516.
        assert!((e.covariance[(0, 0)] - 0.0125).abs() < 1e-12);
        let dev = std::f64::consts::PI - 3.09;
        assert!((e.covariance[(2, 2)] - dev * dev).abs() < 1e-9);
        assert!(heaviest_cluster(&poses, &[0.0; 6], &ClusterBins::default()).is_none());
        assert!(heaviest_cluster(&[], &[], &ClusterBins::default()).is_none());
    }

    #[test]
    fn bins_touching_diagonally_across_the_heading_seam_are_one_cluster() {
        // Bins (0, 0, 0) and (1, −1, 35): x + 1, y − 1 and heading bin 0 − 1
        // wrapped to 35. A third particle far away is its own cluster.
        let poses = [
            Pose2::new(0.25, 0.25, -std::f64::consts::PI + 0.05),
            Pose2::new(0.75, -0.25, std::f64::consts::PI - 0.05),
            Pose2::new(5.0, 5.0, 0.0),
        ];
        let e = heaviest_cluster(&poses, &[0.3, 0.3, 0.4], &ClusterBins::default()).unwrap();
        assert_eq!((e.clusters, e.count), (2, 2));
        assert!((e.weight - 0.6).abs() < 1e-12);
        assert!((e.pose.x - 0.5).abs() < 1e-12 && e.pose.y.abs() < 1e-12);
    }

    #[test]
    fn packed_sort_gives_the_tuple_order() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        // Small boxes (packed), and bins far apart (sorted as tuples).
        for spread in [1, 3, 40, i64::MAX / 2] {
            let keyed: Vec<((i64, i64, i64), usize)> = (0..500)
                .map(|i| {
                    let mut r = || rng.random_range(-spread..=spread);
                    ((r(), r(), r().rem_euclid(36)), i * 2)
                })
                .collect();
            let mut expected = keyed.clone();
            expected.sort_unstable();
            assert_eq!(sort_by_bin(keyed), expected, "spread {spread}");
        }
        assert!(sort_by_bin(Vec::new()).is_empty());
        assert_eq!(sort_by_bin(vec![((4, -2, 7), 3)]), vec![((4, -2, 7), 3)]);
    }
}
