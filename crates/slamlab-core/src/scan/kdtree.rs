//! Nearest neighbours among 2-D points with a k-d tree (slides 001, "Iterative
//! closest point algorithm": the 2-D tree by median slicing, search by descent
//! then backtracking into branches that branch-and-bound cannot eliminate).
//!
//! The tree itself is the `kiddo` crate's immutable k-d tree: the lesson is ICP,
//! not the tree. [`PointTree`] wraps it in the few queries ICP needs, answers in
//! the indices of the slice it was built from, and refuses what the crate must
//! not see (non-finite coordinates, more points than its `u32` items hold).
//! Brute force would cost `O(n)` per query (`O(n²)` per ICP iteration); the tree
//! costs `O(log n)` per query after an `O(n log n)` build.

use super::Point2;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZero;
use thiserror::Error;

/// Why a [`PointTree`] could not be built.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum PointTreeError {
    /// A coordinate was NaN or infinite.
    #[error("point {index} is not finite ({x}, {y})")]
    NonFinitePoint {
        /// Its index in the input slice.
        index: usize,
        /// Its x coordinate, metres.
        x: f64,
        /// Its y coordinate, metres.
        y: f64,
    },
    /// More points than the tree can index.
    #[error("{count} points are more than a k-d tree holds ({max})")]
    TooManyPoints {
        /// How many were given.
        count: usize,
        /// The most it takes.
        max: usize,
    },
    /// The k-d tree crate refused the points.
    #[error("the k-d tree could not be built: {0}")]
    Construction(String),
}

/// A neighbour found by a query: its index in the slice the tree was built
/// from and its squared distance to the query point, m².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Index of the point in the slice given to [`PointTree::new`].
    pub index: usize,
    /// Squared Euclidean distance to the query point, m².
    pub distance_squared: f64,
}

/// A k-d tree over a fixed set of finite 2-D points.
pub struct PointTree {
    /// `None` when built from no points (the crate needs at least one).
    tree: Option<ImmutableKdTree<f64, 2>>,
    len: usize,
}

impl std::fmt::Debug for PointTree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointTree").field("len", &self.len).finish()
    }
}

impl PointTree {
    /// The largest number of points a tree indexes (the crate's `u32` items).
    pub const MAX_POINTS: usize = u32::MAX as usize;

    /// Builds the tree over `points`; an empty slice gives an empty tree that
    /// finds nothing. Every coordinate must be finite.
    pub fn new(points: &[Point2]) -> Result<Self, PointTreeError> {
        if points.len() > Self::MAX_POINTS {
            return Err(PointTreeError::TooManyPoints {
                count: points.len(),
                max: Self::MAX_POINTS,
            });
        }
        if let Some((index, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(PointTreeError::NonFinitePoint {
                index,
                x: p[0],
                y: p[1],
            });
        }
        if points.is_empty() {
            return Ok(Self { tree: None, len: 0 });
        }
        let tree = ImmutableKdTree::new_from_slice(points)
            .map_err(|e| PointTreeError::Construction(e.to_string()))?;
        Ok(Self {
            tree: Some(tree),
            len: points.len(),
        })
    }

    /// How many points the tree holds.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the tree holds no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The point nearest to `query` (Euclidean distance), or `None` if the
    /// tree is empty or `query` is not finite. Between points at exactly the
    /// same distance, which one is returned is the crate's choice.
    pub fn nearest(&self, query: Point2) -> Option<Neighbour> {
        let tree = self.tree.as_ref()?;
        if !(query[0].is_finite() && query[1].is_finite()) {
            return None;
        }
        let found = tree
            .query(&query)
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        let index = found.item as usize;
        (index < self.len).then_some(Neighbour {
            index,
            distance_squared: found.distance,
        })
    }

    /// [`PointTree::nearest_k`] with a guess of how far the `k`-th nearest point
    /// lies: the tree is asked for every point within `radius` (a cheaper query
    /// than `k` nearest); if there are at least `k`, the `k` nearest of them
    /// are the answer, else [`PointTree::nearest_k`] is. Same answer either way
    /// (between points at exactly the same distance, the lower index first).
    pub fn nearest_k_near(&self, query: Point2, k: usize, radius: f64, out: &mut Vec<Neighbour>) {
        out.clear();
        let Some(tree) = self.tree.as_ref() else {
            return;
        };
        if k > 0
            && radius > 0.0
            && radius.is_finite()
            && query[0].is_finite()
            && query[1].is_finite()
        {
            let found = tree
                .query(&query)
                .within::<SquaredEuclidean<f64>>(radius * radius)
                .unsorted()
                .execute();
            if found.len() >= k {
                out.extend(
                    found
                        .into_iter()
                        .filter_map(|n| self.neighbour(n.item, n.distance)),
                );
                let order = |a: &Neighbour, b: &Neighbour| {
                    a.distance_squared
                        .total_cmp(&b.distance_squared)
                        .then(a.index.cmp(&b.index))
                };
                if out.len() > k {
                    out.select_nth_unstable_by(k - 1, order);
                    out.truncate(k);
                }
                out.sort_unstable_by(order);
                if out.len() == k {
                    return;
                }
            }
        }
        self.nearest_k(query, k, out);
    }

    /// The `k` points nearest to `query`, nearest first, written into `out`
    /// (cleared first; fewer if the tree holds fewer). Nothing for an empty
    /// tree, `k = 0` or a non-finite query.
    pub fn nearest_k(&self, query: Point2, k: usize, out: &mut Vec<Neighbour>) {
        out.clear();
        let (Some(tree), Some(k)) = (self.tree.as_ref(), NonZero::new(k.min(self.len))) else {
            return;
        };
        if !(query[0].is_finite() && query[1].is_finite()) {
            return;
        }
        let found = tree
            .query(&query)
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute();
        out.extend(
            found
                .into_iter()
                .filter_map(|n| self.neighbour(n.item, n.distance)),
        );
    }

    /// A query result as a [`Neighbour`], if its index is one of this tree's.
    fn neighbour(&self, item: u32, distance_squared: f64) -> Option<Neighbour> {
        let index = item as usize;
        (index < self.len).then_some(Neighbour {
            index,
            distance_squared,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute_force(points: &[Point2], q: Point2) -> Vec<Neighbour> {
        let mut all: Vec<Neighbour> = points
            .iter()
            .enumerate()
            .map(|(index, p)| Neighbour {
                index,
                distance_squared: (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]),
            })
            .collect();
        all.sort_by(|a, b| {
            a.distance_squared
                .total_cmp(&b.distance_squared)
                .then(a.index.cmp(&b.index))
        });
        all
    }

    /// 2,000 seeded uniform points in a 10 m square, 500 queries in a slightly
    /// larger square: the tree's nearest point and its 5 nearest points are
    /// exactly the brute-force answer (same indices, same squared distances).
    #[test]
    fn neighbours_equal_brute_force_on_seeded_random_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let points: Vec<Point2> = (0..2000)
            .map(|_| [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)])
            .collect();
        let tree = PointTree::new(&points).unwrap();
        assert_eq!(tree.len(), 2000);
        let mut out = Vec::new();
        for _ in 0..500 {
            let q = [rng.random_range(-6.0..6.0), rng.random_range(-6.0..6.0)];
            let expected = brute_force(&points, q);
            let nearest = tree.nearest(q).unwrap();
            assert_eq!(nearest.index, expected[0].index, "query {q:?}");
            assert_eq!(nearest.distance_squared, expected[0].distance_squared);
            tree.nearest_k(q, 5, &mut out);
            let got: Vec<usize> = out.iter().map(|n| n.index).collect();
            let want: Vec<usize> = expected[..5].iter().map(|n| n.index).collect();
            assert_eq!(got, want, "query {q:?}");
            for (g, w) in out.iter().zip(&expected) {
                assert_eq!(g.distance_squared, w.distance_squared);
            }
            // With a radius guess too small (fallback), about right, and far
            // too large, or not a number: the same answer.
            for radius in [0.01, 0.2, 0.4, 30.0, f64::NAN] {
                tree.nearest_k_near(q, 5, radius, &mut out);
                let got: Vec<usize> = out.iter().map(|n| n.index).collect();
                assert_eq!(got, want, "query {q:?}, radius {radius}");
            }
        }
    }

    /// A query on a stored point finds it at distance 0; k larger than the
    /// tree gives every point.
    #[test]
    fn exact_hits_and_small_trees() {
        let points = [[1.0, 2.0], [3.0, -1.0], [-2.0, 0.5]];
        let tree = PointTree::new(&points).unwrap();
        for (i, &p) in points.iter().enumerate() {
            assert_eq!(
                tree.nearest(p),
                Some(Neighbour {
                    index: i,
                    distance_squared: 0.0
                })
            );
        }
        let mut out = Vec::new();
        tree.nearest_k([0.0, 0.0], 10, &mut out);
        assert_eq!(out.len(), 3);
        // |(1,2)|² = 5, |(3,-1)|² = 10, |(-2,0.5)|² = 4.25.
        assert_eq!(
            out.iter().map(|n| n.index).collect::<Vec<_>>(),
            vec![2, 0, 1]
        );
        assert_eq!(out[0].distance_squared, 4.25);
    }

    /// No points, NaN points, NaN queries, many identical points: answers or
    /// errors, never a panic.
    #[test]
    fn bad_input_is_refused_without_panic() {
        let empty = PointTree::new(&[]).unwrap();
        assert!(empty.is_empty());
        assert_eq!(empty.nearest([0.0, 0.0]), None);
        let mut out = vec![Neighbour {
            index: 9,
            distance_squared: 1.0,
        }];
        empty.nearest_k([0.0, 0.0], 3, &mut out);
        assert!(out.is_empty());

        let err = PointTree::new(&[[0.0, 0.0], [f64::NAN, 1.0]]).unwrap_err();
        assert!(matches!(
            err,
            PointTreeError::NonFinitePoint { index: 1, .. }
        ));
        let err = PointTree::new(&[[f64::INFINITY, 0.0]]).unwrap_err();
        assert!(matches!(
            err,
            PointTreeError::NonFinitePoint { index: 0, .. }
        ));

        let tree = PointTree::new(&[[0.0, 0.0], [1.0, 0.0]]).unwrap();
        assert_eq!(tree.nearest([f64::NAN, 0.0]), None);
        tree.nearest_k([0.0, f64::NAN], 1, &mut out);
        assert!(out.is_empty());

        let same = vec![[2.0, 3.0]; 1000];
        let tree = PointTree::new(&same).unwrap();
        let n = tree.nearest([0.0, 0.0]).unwrap();
        assert!(n.index < 1000);
        assert_eq!(n.distance_squared, 13.0);
        tree.nearest_k([2.0, 3.0], 4, &mut out);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|n| n.distance_squared == 0.0));
    }
}
