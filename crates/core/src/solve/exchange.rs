//! What the ranks of a distributed run tell one another: ghost temperatures before each
//! boundary application ([`Exchange::halo`]), the whole field at outputs
//! ([`Exchange::all_gather`]), and every global quantity through one reduction
//! ([`Collective::reduce`]), so that none is left per-rank.
//!
//! The MPI implementation lives with the command line (cargo feature `mpi`); [`InProcess`]
//! runs the same protocol between threads of one process, for tests and for machines
//! without MPI. The partition and the halo lists come from [`crate::partition`].

use crate::math::NodeId;
use crate::partition::{Halo, Partition};
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Barrier, Mutex};

/// Node lists by rank, `(rank, nodes)`: what a rank receives from or sends to each other.
pub type NodeLists = Vec<(usize, Vec<NodeId>)>;

/// How [`Collective::reduce`] combines the ranks' values.
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

/// The messages of a distributed run that need no halo: reductions, and the lists the
/// ranks swap while they plan their halos ([`RankPlan::of_share`]). Every method is
/// collective: all ranks call it, in the same order, from the thread that steps.
pub trait Collective: Sync {
    /// This rank, from 0.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// `x` combined over the ranks by `op`, the same on every rank.
    fn reduce(&self, x: f64, op: Reduce) -> f64;
    /// Sends each `(rank, nodes)` of `lists` to that rank (at most one list per rank) and
    /// returns the lists the other ranks sent this one, as `(sender, nodes)` by sender.
    fn swap(&self, lists: &NodeLists) -> NodeLists;
    /// `x` of every rank, in rank order.
    fn gather_counts(&self, x: u64) -> Vec<u64>;
}

/// The communication of one rank of a distributed run once its halo is planned: ghost
/// temperatures, whole fields at outputs, and the [`Collective`] messages.
pub trait Exchange: Collective {
    /// This rank's rows and halo, and every rank's rows.
    fn plan(&self) -> &RankPlan;
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

/// [`Collective`] between threads of one process: rank r of `n` in-process ranks, before
/// their halos are planned ([`InProcessLink::with_plan`] makes it an [`InProcess`]).
pub struct InProcessLink {
    rank: usize,
    shared: Arc<Shared>,
}

/// [`Exchange`] between threads of one process, for tests and for machines without MPI. The
/// owners publish their rows in a shared array and the readers copy from it between barriers.
pub struct InProcess {
    link: InProcessLink,
    plan: RankPlan,
}

/// The state the in-process ranks share.
struct Shared {
    barrier: Barrier,
    /// θ of every node as f64 bits, written by its owner or publisher.
    field: Vec<AtomicU64>,
    /// One slot per rank for reductions.
    slots: Vec<AtomicU64>,
    /// The lists sent to each rank by [`Collective::swap`], as `(sender, nodes)`.
    mail: Mutex<Vec<NodeLists>>,
}

impl InProcessLink {
    /// One link per rank of `ranks` over `n_nodes` nodes (body and fictitious), to be moved
    /// into one thread each.
    pub fn group(ranks: usize, n_nodes: usize) -> Vec<InProcessLink> {
        let shared = Arc::new(Shared {
            barrier: Barrier::new(ranks),
            field: (0..n_nodes).map(|_| AtomicU64::new(0)).collect(),
            slots: (0..ranks).map(|_| AtomicU64::new(0)).collect(),
            mail: Mutex::new(vec![Vec::new(); ranks]),
        });
        (0..ranks)
            .map(|rank| InProcessLink {
                rank,
                shared: shared.clone(),
            })
            .collect()
    }

    /// This link with its rank's plan: an [`Exchange`].
    pub fn with_plan(self, plan: RankPlan) -> InProcess {
        InProcess { link: self, plan }
    }
}

impl Collective for InProcessLink {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.slots.len()
    }
    fn reduce(&self, x: f64, op: Reduce) -> f64 {
        let all = self.gather_counts(x.to_bits());
        let load = |r: usize| f64::from_bits(all[r]);
        (1..all.len()).fold(load(0), |a, r| op.apply(a, load(r)))
    }
    fn swap(&self, lists: &NodeLists) -> NodeLists {
        {
            let mut mail = self.shared.mail.lock().expect("mail");
            for (to, nodes) in lists {
                mail[*to].push((self.rank, nodes.clone()));
            }
        }
        self.shared.barrier.wait();
        let mut got = std::mem::take(&mut self.shared.mail.lock().expect("mail")[self.rank]);
        got.sort_by_key(|(from, _)| *from);
        // nobody sends again before everyone has taken theirs
        self.shared.barrier.wait();
        got
    }
    fn gather_counts(&self, x: u64) -> Vec<u64> {
        self.shared.slots[self.rank].store(x, Ordering::Relaxed);
        self.shared.barrier.wait();
        let all = self
            .shared
            .slots
            .iter()
            .map(|s| s.load(Ordering::Relaxed))
            .collect();
        self.shared.barrier.wait();
        all
    }
}

impl InProcess {
    /// One [`InProcess`] per rank of `plans` (all of the same partition) over `n_nodes` nodes
    /// (body and fictitious), to be moved into one thread each.
    pub fn group(plans: Vec<RankPlan>, n_nodes: usize) -> Vec<InProcess> {
        let links = InProcessLink::group(plans.len(), n_nodes);
        links
            .into_iter()
            .zip(plans)
            .map(|(l, p)| l.with_plan(p))
            .collect()
    }

    /// Publishes the entries `nodes` of `field` this rank holds current.
    fn publish(&self, field: &[f64], nodes: impl Iterator<Item = usize>) {
        let shared = &self.link.shared;
        for i in nodes {
            shared.field[i].store(field[i].to_bits(), Ordering::Relaxed);
        }
        shared.barrier.wait();
    }

    fn read(&self, field: &mut [f64], nodes: impl Iterator<Item = usize>) {
        let shared = &self.link.shared;
        for j in nodes {
            field[j] = f64::from_bits(shared.field[j].load(Ordering::Relaxed));
        }
        // nobody publishes again before everyone has read
        shared.barrier.wait();
    }
}

impl Collective for InProcess {
    fn rank(&self) -> usize {
        self.link.rank()
    }
    fn size(&self) -> usize {
        self.link.size()
    }
    fn reduce(&self, x: f64, op: Reduce) -> f64 {
        self.link.reduce(x, op)
    }
    fn swap(&self, lists: &NodeLists) -> NodeLists {
        self.link.swap(lists)
    }
    fn gather_counts(&self, x: u64) -> Vec<u64> {
        self.link.gather_counts(x)
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
        self.read(field, 0..self.link.shared.field.len());
    }
    fn exchange_seconds(&self) -> f64 {
        0.0
    }
}

impl RankPlan {
    /// The plans of all `ranks` ranks of a whole `model`: rows cut by estimated work
    /// ([`Partition::by_estimate`]), halos closed under the boundary's rules
    /// ([`crate::partition::halos`]); no messages.
    pub fn all(model: &crate::model::Model, ranks: usize) -> Vec<RankPlan> {
        let partition = Partition::by_estimate(&model.cloud, ranks);
        let sources = rule_sources_of(model);
        crate::partition::halos(&model.conductance, &sources, model.cloud.n_body, &partition)
            .into_iter()
            .enumerate()
            .map(|(rank, halo)| RankPlan {
                rank,
                partition: partition.clone(),
                halo,
            })
            .collect()
    }

    /// The plan of this rank from its share of the model ([`crate::model::Model::build_share`]
    /// over `partition`): its own halo, and what it sends, swapped with the others. The same
    /// plan as [`RankPlan::all`] gives this rank.
    pub fn of_share(
        model: &crate::model::Model,
        partition: Partition,
        link: &dyn Collective,
    ) -> RankPlan {
        let rank = link.rank();
        let sources = rule_sources_of(model);
        let nb = model.cloud.n_body;
        let publish = crate::partition::publishers(&sources, nb, &partition).swap_remove(rank);
        let k = &model.conductance;
        let mut halo = crate::partition::own_halo(k, &sources, nb, &partition, rank, publish);
        halo.send = link.swap(&halo.recv);
        RankPlan {
            rank,
            partition,
            halo,
        }
    }

    /// The nodes this rank gives the others when the whole field is gathered: its rows, then
    /// the fictitious nodes it publishes ([`Halo::publish`]).
    pub fn gathered(&self) -> impl Iterator<Item = usize> + '_ {
        let publish = self.halo.publish.iter().map(|&j| j as usize);
        self.partition.range(self.rank).chain(publish)
    }
}

/// The fictitious nodes each rank of `partition` publishes at a gather, by rank
/// ([`crate::partition::publishers`]).
pub fn publishers_of(model: &crate::model::Model, partition: &Partition) -> Vec<Vec<NodeId>> {
    let sources = rule_sources_of(model);
    crate::partition::publishers(&sources, model.cloud.n_body, partition)
}

/// Sends each `(rank, values)` of `lists` to that rank (at most one list per rank) and returns
/// what the others sent this one, by sender: [`Collective::swap`] carrying each f64 as the two
/// halves of its bits. Collective.
pub fn swap_values(link: &dyn Collective, lists: &[(usize, Vec<f64>)]) -> Vec<(usize, Vec<f64>)> {
    let packed: NodeLists = lists
        .iter()
        .map(|(to, v)| {
            let halves = v.iter().flat_map(|x| {
                let b = x.to_bits();
                [(b >> 32) as NodeId, b as NodeId]
            });
            (*to, halves.collect())
        })
        .collect();
    link.swap(&packed)
        .into_iter()
        .map(|(from, h)| {
            let v = h
                .chunks_exact(2)
                .map(|p| f64::from_bits((u64::from(p[0]) << 32) | u64::from(p[1])));
            (from, v.collect())
        })
        .collect()
}

/// The sources of each node's boundary rule ([`crate::partition::rule_sources`]).
fn rule_sources_of(model: &crate::model::Model) -> Vec<Vec<NodeId>> {
    let rules = model.boundary.linear_rules();
    crate::partition::rule_sources(model.cloud.len(), &rules)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every value reaches its rank with all its bits (signs, subnormals, NaN payloads and
    /// infinities included), by sender, and ranks that get nothing get no list.
    #[test]
    fn values_are_swapped_bit_for_bit() {
        let odd = [
            -0.0,
            5e-324,
            f64::INFINITY,
            f64::from_bits(0x7ff8_0000_dead_beef),
            1.0 / 3.0,
        ];
        let links = InProcessLink::group(3, 0);
        let got: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = links
                .iter()
                .map(|link| {
                    s.spawn(move || {
                        let me = link.rank();
                        // rank r sends odd[r..] to rank (r + 1) % 3, rank 2 sends nothing
                        let lists = match me {
                            2 => Vec::new(),
                            _ => vec![((me + 1) % 3, odd[me..].to_vec())],
                        };
                        swap_values(link, &lists)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(got[0].is_empty());
        assert_eq!(got[1].len(), 1);
        assert_eq!((got[1][0].0, bits(&got[1][0].1)), (0, bits(&odd)));
        assert_eq!((got[2][0].0, bits(&got[2][0].1)), (1, bits(&odd[1..])));
    }
}
