//! Directed neighbour lists (CSR): j is listed under i when j lies in i's horizon.
//!
//! The relation is directed because horizons differ from node to node (seed 004 eqs 19–22:
//! the α masks); each entry carries the partial-volume factor β_ij (formulation §2.3) and
//! the distance at which the kernel profile is evaluated. Built once, in parallel.

use crate::cloud::Cloud;
use crate::kernel::Kernel;
use crate::math::NodeId;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Directed bonds in CSR form: row i lists the nodes inside H_i.
#[derive(Debug, Clone, Default)]
pub struct Horizons {
    /// Row offsets, length n + 1.
    pub offsets: Vec<usize>,
    /// Neighbour index j of each directed bond, sorted within a row.
    pub targets: Vec<NodeId>,
    /// Partial-volume factor β_ij ∈ (0, 1].
    pub beta: Vec<f64>,
    /// Distance at which w(·/δ_i) is evaluated (Algorithm 1 lines 6 and 9), m.
    pub eval_at: Vec<f64>,
}

impl Horizons {
    /// Finds, for every node, the neighbours inside its horizon (kiddo fixed-radius search,
    /// radius δ_i plus the partial-volume band). Bonds between two fictitious nodes are dropped.
    pub fn build(cloud: &Cloud, kernel: &Kernel) -> Self {
        let pts: Vec<[f64; 3]> = cloud.pos.iter().map(|p| [p.x, p.y, p.z]).collect();
        let n = pts.len();
        if n == 0 {
            return Horizons {
                offsets: vec![0],
                ..Default::default()
            };
        }
        let tree: ImmutableKdTree<f64, 3> =
            ImmutableKdTree::new_from_slice(&pts).expect("a non-empty cloud builds a k-d tree");
        let dmax = cloud.spacing.iter().cloned().fold(0.0, f64::max);
        let rows: Vec<Vec<(NodeId, f64, f64)>> = (0..n)
            .into_par_iter()
            .with_min_len(256)
            .map(|i| {
                let delta = cloud.horizon[i];
                let reach = kernel.reach(delta, dmax);
                let found = tree
                    .query(&pts[i])
                    .within::<SquaredEuclidean<f64>>(reach * reach * (1.0 + 1e-12))
                    .unsorted()
                    .execute();
                let mut row: Vec<(NodeId, f64, f64)> = Vec::with_capacity(found.len());
                for it in found {
                    let j = it.item as usize;
                    if j == i || (i >= cloud.n_body && j >= cloud.n_body) {
                        continue;
                    }
                    let r = (cloud.pos[j] - cloud.pos[i]).norm();
                    let (beta, at) = kernel.coverage(r, delta, cloud.spacing[j]);
                    if beta > 0.0 {
                        row.push((j as NodeId, beta, at));
                    }
                }
                row.sort_unstable_by_key(|e| e.0);
                row
            })
            .collect();
        let mut h = Horizons {
            offsets: Vec::with_capacity(n + 1),
            ..Default::default()
        };
        let total: usize = rows.iter().map(Vec::len).sum();
        h.targets.reserve(total);
        h.beta.reserve(total);
        h.eval_at.reserve(total);
        h.offsets.push(0);
        for row in rows {
            for (j, b, at) in row {
                h.targets.push(j);
                h.beta.push(b);
                h.eval_at.push(at);
            }
            h.offsets.push(h.targets.len());
        }
        h
    }

    /// Number of nodes (rows).
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when there is no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of directed bonds.
    pub fn n_bonds(&self) -> usize {
        self.targets.len()
    }

    /// Splits a per-bond array into one mutable slice per row, tagged with the row index,
    /// so that rows can be filled in parallel (gather form: each row writes only its own).
    pub fn rows_mut<'a, T>(&self, per_bond: &'a mut [T]) -> Vec<(usize, &'a mut [T])> {
        let mut out = Vec::with_capacity(self.len());
        let mut rest = per_bond;
        for i in 0..self.len() {
            let (a, b) = rest.split_at_mut(self.row(i).len());
            out.push((i, a));
            rest = b;
        }
        out
    }

    /// Range of bond indices of row i.
    pub fn row(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i]..self.offsets[i + 1]
    }
}
