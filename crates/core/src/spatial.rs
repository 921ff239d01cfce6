//! Point search (kiddo k-d tree) behind two small calls, for setup code outside the hot loops.

use crate::math::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// A static k-d tree over points.
pub struct PointIndex {
    tree: Option<ImmutableKdTree<f64, 3>>,
}

impl PointIndex {
    /// Indexes `points` (an empty slice gives an index that finds nothing).
    pub fn new(points: &[Point]) -> Self {
        let pts: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree = if pts.is_empty() {
            None
        } else {
            ImmutableKdTree::new_from_slice(&pts).ok()
        };
        PointIndex { tree }
    }

    /// The `k` nearest points to `p` as (index, distance), nearest first.
    pub fn nearest(&self, p: &Point, k: usize) -> Vec<(usize, f64)> {
        let (Some(tree), Some(k)) = (&self.tree, NonZero::new(k)) else {
            return Vec::new();
        };
        tree.query(&[p.x, p.y, p.z])
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute()
            .into_iter()
            .map(|n| (n.item as usize, n.distance.sqrt()))
            .collect()
    }

    /// Indices of the points within distance `r` of `p` (inclusive), in no particular order.
    pub fn within(&self, p: &Point, r: f64) -> Vec<usize> {
        let Some(tree) = &self.tree else {
            return Vec::new();
        };
        tree.query(&[p.x, p.y, p.z])
            .within::<SquaredEuclidean<f64>>(r * r * (1.0 + 1e-12))
            .unsorted()
            .execute()
            .into_iter()
            .map(|n| n.item as usize)
            .collect()
    }
}
