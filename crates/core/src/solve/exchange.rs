//! What the ranks of a distributed run tell one another: ghost temperatures before each
//! boundary application ([`Exchange::halo`]), the whole field at outputs
//! ([`Exchange::all_gather`]), and every global quantity through one reduction
//! ([`Exchange::reduce`]), so that none is left per-rank.
//!
//! The MPI implementation lives with the command line (cargo feature `mpi`); [`InProcess`]
//! runs the same protocol between threads of one process, for tests and for machines
//! without MPI. The partition and the halo lists come from [`crate::partition`].

use crate::math::NodeId;
use crate::partition::{Halo, Partition};
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Barrier};

/// How [`Exchange::reduce`] combines the ranks' values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reduce {
    /// The sum (in rank order).
    Sum,
    /// The smallest.
    Min,
    /// The largest.
    Max,
}

impl Reduce {
    /// Combines two values.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Reduce::Sum => a + b,
            Reduce::Min => a.min(b),
            Reduce::Max => a.max(b),
        }
    }
}

/// The communication of one rank of a distributed run. Every method is collective: all
/// ranks call it, in the same order, from the thread that steps.
pub trait Exchange: Sync {
    /// This rank's rows and halo, and every rank's rows.
    fn plan(&self) -> &RankPlan;
    /// This rank, from 0.
    fn rank(&self) -> usize {
        self.plan().rank
    }
    /// Number of ranks.
    fn size(&self) -> usize {
        self.plan().partition.ranks()
    }
    /// The body rows this rank owns.
    fn rows(&self) -> Range<usize> {
        self.plan().partition.range(self.plan().rank)
    }
    /// Sets this rank's ghost body entries of `field` (every node, model numbering) to the
    /// values their owners hold.
    fn halo(&self, field: &mut [f64]);
    /// Sets every entry of `field` (every node, model numbering) on every rank to the value
    /// its owner holds (body nodes) or its publisher (fictitious nodes,
    /// [`crate::partition::Halo::publish`]).
    fn all_gather(&self, field: &mut [f64]);
    /// `x` combined over the ranks by `op`, the same on every rank.
    fn reduce(&self, x: f64, op: Reduce) -> f64;
    /// Time spent in [`Exchange::halo`] so far on this rank, s.
    fn exchange_seconds(&self) -> f64;
}

/// The body rows and halo of one rank of a partition: what a rank needs to take part.
#[derive(Debug, Clone)]
pub struct RankPlan {
    /// This rank.
    pub rank: usize,
    /// Every rank's rows.
    pub partition: Partition,
    /// This rank's ghosts and the values it sends.
    pub halo: Halo,
}

/// [`Exchange`] between threads of one process: rank r of `n` in-process ranks. The owners
/// publish their rows in a shared array and the readers copy from it between barriers.
pub struct InProcess {
    plan: RankPlan,
    shared: Arc<Shared>,
}

/// The state the in-process ranks share.
struct Shared {
    barrier: Barrier,
    /// θ of every node as f64 bits, written by its owner or publisher.
    field: Vec<AtomicU64>,
    /// One slot per rank for reductions.
    slots: Vec<AtomicU64>,
}

impl InProcess {
    /// One [`InProcess`] per rank of `plans` (all of the same partition) over `n_nodes` nodes
    /// (body and fictitious), to be moved into one thread each.
    pub fn group(plans: Vec<RankPlan>, n_nodes: usize) -> Vec<InProcess> {
        let shared = Arc::new(Shared {
            barrier: Barrier::new(plans.len()),
            field: (0..n_nodes).map(|_| AtomicU64::new(0)).collect(),
            slots: (0..plans.len()).map(|_| AtomicU64::new(0)).collect(),
        });
        plans
            .into_iter()
            .map(|plan| InProcess {
                plan,
                shared: shared.clone(),
            })
            .collect()
    }

    /// Publishes the entries `nodes` of `field` this rank holds current.
    fn publish(&self, field: &[f64], nodes: impl Iterator<Item = usize>) {
        for i in nodes {
            self.shared.field[i].store(field[i].to_bits(), Ordering::Relaxed);
        }
        self.shared.barrier.wait();
    }

    fn read(&self, field: &mut [f64], nodes: impl Iterator<Item = usize>) {
        for j in nodes {
            field[j] = f64::from_bits(self.shared.field[j].load(Ordering::Relaxed));
        }
        // nobody publishes again before everyone has read
        self.shared.barrier.wait();
    }
}

impl Exchange for InProcess {
    fn plan(&self) -> &RankPlan {
        &self.plan
    }
    fn halo(&self, field: &mut [f64]) {
        self.publish(field, self.rows());
        let ghosts = self.plan.halo.recv.iter().flat_map(|(_, n)| n.iter());
        self.read(field, ghosts.map(|&j: &NodeId| j as usize));
    }
    fn all_gather(&self, field: &mut [f64]) {
        self.publish(field, self.plan.gathered());
        // every node has exactly one publisher (its own entries come back unchanged)
        self.read(field, 0..self.shared.field.len());
    }
    fn reduce(&self, x: f64, op: Reduce) -> f64 {
        self.shared.slots[self.rank()].store(x.to_bits(), Ordering::Relaxed);
        self.shared.barrier.wait();
        let load = |r: usize| f64::from_bits(self.shared.slots[r].load(Ordering::Relaxed));
        let v = (1..self.size()).fold(load(0), |a, r| op.apply(a, load(r)));
        self.shared.barrier.wait();
        v
    }
    fn exchange_seconds(&self) -> f64 {
        0.0
    }
}

impl RankPlan {
    /// The plans of all `ranks` ranks of `model`: rows cut by work ([`Partition::by_work`]),
    /// halos closed under the boundary's rules ([`crate::partition::halos`]).
    pub fn all(model: &crate::model::Model, ranks: usize) -> Vec<RankPlan> {
        let k = &model.conductance;
        let partition = Partition::by_work(k, ranks);
        let rules = model.boundary.linear_rules();
        let sources = crate::partition::rule_sources(model.cloud.len(), &rules);
        crate::partition::halos(k, &sources, model.cloud.n_body, &partition)
            .into_iter()
            .enumerate()
            .map(|(rank, halo)| RankPlan {
                rank,
                partition: partition.clone(),
                halo,
            })
            .collect()
    }

    /// The nodes this rank gives the others when the whole field is gathered: its rows, then
    /// the fictitious nodes it publishes ([`Halo::publish`]).
    pub fn gathered(&self) -> impl Iterator<Item = usize> + '_ {
        let publish = self.halo.publish.iter().map(|&j| j as usize);
        self.partition.range(self.rank).chain(publish)
    }
}
