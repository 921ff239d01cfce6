//! Distributed runs through MPI (cargo feature `mpi`: the `mpi` crate, rsmpi, over MPICH or
//! Open MPI): `mpiexec -n N peritherm run CASE --out DIR` runs the case file unchanged.
//!
//! Every rank reads the case and builds the cloud, cuts the body rows into contiguous ranges
//! by estimated work (the same cut on every rank, no messages), and then, when the case
//! allows it, builds only the bonds and K of its own rows with the margin their assembly
//! reads ([`crate::prepare::build_rank`]); otherwise (consistent weights, cracks, phase
//! change, implicit or adaptive steps) every rank builds the whole model. Each rank plans its
//! halo, swaps the lists with the others, and steps its own rows, exchanging ghost
//! temperatures before each boundary application ([`Mpi`] implements [`Exchange`]). Rank 0
//! writes the outputs, bit for bit those of a serial run ([`crate::run::run_ranked`]).

use crate::case::Case;
use crate::error::Result;
use crate::math::NodeId;
use crate::output::RunSummary;
use crate::prepare::Options;
use crate::run::run_ranked;
use crate::solve::exchange::{publishers_of, Collective, Exchange, NodeLists, RankPlan, Reduce};
use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The MPI environment of a process: initialised once, finalised when dropped.
pub struct Environment {
    /// The universe (MPI_Init_thread, funneled: only the main thread calls MPI).
    universe: mpi::environment::Universe,
}

impl Environment {
    /// Initialises MPI (a singleton when not started by `mpiexec`); None if it was already.
    pub fn init() -> Option<Environment> {
        let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)?;
        Some(Environment { universe })
    }

    /// This process's rank in the world communicator.
    pub fn rank(&self) -> usize {
        self.universe.world().rank() as usize
    }

    /// Number of ranks in the world communicator.
    pub fn size(&self) -> usize {
        self.universe.world().size() as usize
    }

    /// Worker threads per rank that share this node's cores evenly (at least 1).
    pub fn threads_per_rank(&self) -> usize {
        let on_node = self.universe.world().split_shared(0).size().max(1) as usize;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        (cores / on_node).max(1)
    }

    /// Runs `case` as this rank: builds its share of the model, or the whole model, and its
    /// plan ([`crate::prepare::build_rank`]), then runs ([`run_ranked`]); rank 0 writes `out`
    /// and returns the summary.
    pub fn run(
        &self,
        case: &Case,
        out: &Path,
        options: &Options,
        progress: impl FnMut(u64, u64),
    ) -> Result<Option<RunSummary>> {
        let started = Instant::now();
        let comm = Comm(World(self.universe.world()));
        let (model, plan) = crate::prepare::build_rank(case, options, &comm)?;
        let publish = publishers_of(&model, &plan.partition);
        let exchange = Mpi::new(comm, plan, &publish);
        run_ranked(case, &model, out, started, &exchange, progress)
    }
}

/// A communicator that may be shared with the threads of a rank. MPI is initialised
/// funneled: only the thread that steps calls it, and the handle itself is an identifier
/// (an integer in MPICH, a pointer to a table entry in Open MPI, whose binding is not `Sync`).
struct World(SimpleCommunicator);

// SAFETY: the rank's worker threads never call MPI (only the stepping thread does, through
// `Exchange`); sharing the handle lets `Explicit` stay `Send` for the thread pools.
unsafe impl Send for World {}
unsafe impl Sync for World {}

/// [`Collective`] over an MPI communicator.
pub struct Comm(World);

impl Collective for Comm {
    fn rank(&self) -> usize {
        self.0 .0.rank() as usize
    }

    fn size(&self) -> usize {
        self.0 .0.size() as usize
    }

    fn reduce(&self, x: f64, op: Reduce) -> f64 {
        let mut y = 0.0;
        let op = match op {
            Reduce::Sum => SystemOperation::sum(),
            Reduce::Min => SystemOperation::min(),
            Reduce::Max => SystemOperation::max(),
        };
        self.0 .0.all_reduce_into(&x, &mut y, op);
        y
    }

    fn swap(&self, lists: &NodeLists) -> NodeLists {
        let world = &self.0 .0;
        let n = self.size();
        let mut counts = vec![0 as Count; n];
        for (to, nodes) in lists {
            counts[*to] = nodes.len() as Count;
        }
        let mut incoming = vec![0 as Count; n];
        world.all_to_all_into(&counts[..], &mut incoming[..]);
        let displs = |c: &[Count]| -> Vec<Count> {
            c.iter()
                .scan(0, |at, &k| {
                    let d = *at;
                    *at += k;
                    Some(d)
                })
                .collect()
        };
        let mut send: Vec<NodeId> = Vec::with_capacity(counts.iter().sum::<Count>() as usize);
        let mut by_rank: Vec<&[NodeId]> = vec![&[]; n];
        for (to, nodes) in lists {
            by_rank[*to] = nodes;
        }
        by_rank
            .iter()
            .for_each(|nodes| send.extend_from_slice(nodes));
        let mut recv = vec![0 as NodeId; incoming.iter().sum::<Count>() as usize];
        let (sd, rd) = (displs(&counts), displs(&incoming));
        let sent = Partition::new(&send[..], &counts[..], &sd[..]);
        let mut got = PartitionMut::new(&mut recv[..], &incoming[..], &rd[..]);
        world.all_to_all_varcount_into(&sent, &mut got);
        (0..n)
            .filter(|&r| incoming[r] > 0)
            .map(|r| {
                let at = rd[r] as usize;
                (r, recv[at..at + incoming[r] as usize].to_vec())
            })
            .collect()
    }

    fn gather_counts(&self, x: u64) -> Vec<u64> {
        let mut all = vec![0u64; self.size()];
        self.0 .0.all_gather_into(&x, &mut all[..]);
        all
    }
}

/// [`Exchange`] over an MPI communicator.
pub struct Mpi {
    comm: Comm,
    plan: RankPlan,
    /// The nodes of the gathered field in the order the ranks send them: each rank's rows,
    /// then the fictitious nodes it publishes.
    gathered: Vec<usize>,
    /// Values per rank in the gathered field, and where each rank's start.
    counts: Vec<Count>,
    displs: Vec<Count>,
    buffers: Mutex<Buffers>,
    /// Time spent in halo exchanges, s (f64 bits).
    seconds: AtomicU64,
}

/// Send and receive buffers, allocated once.
#[derive(Default)]
struct Buffers {
    send: Vec<f64>,
    recv: Vec<f64>,
    gather: Vec<f64>,
}

impl Mpi {
    /// The exchange of this rank of `comm` with its `plan`, given the fictitious nodes every
    /// rank publishes (`publish`, by rank: [`crate::partition::publishers`]).
    pub fn new(comm: Comm, plan: RankPlan, publish: &[Vec<NodeId>]) -> Mpi {
        let mut gathered = Vec::new();
        let mut counts = Vec::with_capacity(publish.len());
        for (r, p) in publish.iter().enumerate() {
            let before = gathered.len();
            gathered.extend(plan.partition.range(r));
            gathered.extend(p.iter().map(|&j| j as usize));
            counts.push((gathered.len() - before) as Count);
        }
        let displs = counts
            .iter()
            .scan(0, |at, &c| {
                let d = *at;
                *at += c;
                Some(d)
            })
            .collect();
        let buffers = Buffers {
            send: vec![0.0; plan.halo.sent().max(counts[plan.rank] as usize)],
            recv: vec![0.0; plan.halo.ghosts()],
            gather: vec![0.0; gathered.len()],
        };
        Mpi {
            comm,
            plan,
            gathered,
            counts,
            displs,
            buffers: Mutex::new(buffers),
            seconds: AtomicU64::new(0),
        }
    }

    fn world(&self) -> &SimpleCommunicator {
        &self.comm.0 .0
    }
}

impl Collective for Mpi {
    fn rank(&self) -> usize {
        self.comm.rank()
    }
    fn size(&self) -> usize {
        self.comm.size()
    }
    fn reduce(&self, x: f64, op: Reduce) -> f64 {
        self.comm.reduce(x, op)
    }
    fn swap(&self, lists: &NodeLists) -> NodeLists {
        self.comm.swap(lists)
    }
    fn gather_counts(&self, x: u64) -> Vec<u64> {
        self.comm.gather_counts(x)
    }
}

impl Exchange for Mpi {
    fn plan(&self) -> &RankPlan {
        &self.plan
    }

    fn halo(&self, field: &mut [f64]) {
        let started = Instant::now();
        let mut b = self.buffers.lock().expect("buffers");
        let Buffers { send, recv, .. } = &mut *b;
        let halo = &self.plan.halo;
        let packed = halo.send.iter().flat_map(|(_, n)| n.iter());
        for (s, &j) in send.iter_mut().zip(packed) {
            *s = field[j as usize];
        }
        mpi::request::scope(|scope| {
            // every receive is posted before any send, so the blocking sends cannot deadlock
            let mut pending = Vec::with_capacity(halo.recv.len());
            let mut rest = &mut recv[..];
            for (r, nodes) in &halo.recv {
                let (mine, tail) = std::mem::take(&mut rest).split_at_mut(nodes.len());
                rest = tail;
                let from = self.world().process_at_rank(*r as i32);
                pending.push(from.immediate_receive_into(scope, mine));
            }
            let mut at = 0;
            for (r, nodes) in &halo.send {
                let to = self.world().process_at_rank(*r as i32);
                to.send(&send[at..at + nodes.len()]);
                at += nodes.len();
            }
            for p in pending {
                p.wait_without_status();
            }
        });
        let ghosts = halo.recv.iter().flat_map(|(_, n)| n.iter());
        for (&v, &j) in recv.iter().zip(ghosts) {
            field[j as usize] = v;
        }
        let spent = self.exchange_seconds() + started.elapsed().as_secs_f64();
        self.seconds.store(spent.to_bits(), Ordering::Relaxed);
    }

    fn all_gather(&self, field: &mut [f64]) {
        let mut b = self.buffers.lock().expect("buffers");
        let Buffers { send, gather, .. } = &mut *b;
        let at = self.displs[self.plan.rank] as usize;
        let mine = &self.gathered[at..at + self.counts[self.plan.rank] as usize];
        for (s, &j) in send.iter_mut().zip(mine) {
            *s = field[j];
        }
        let mut parts = PartitionMut::new(&mut gather[..], &self.counts[..], &self.displs[..]);
        self.world()
            .all_gather_varcount_into(&send[..mine.len()], &mut parts);
        for (&v, &j) in gather.iter().zip(&self.gathered) {
            field[j] = v;
        }
    }

    fn exchange_seconds(&self) -> f64 {
        f64::from_bits(self.seconds.load(Ordering::Relaxed))
    }
}
