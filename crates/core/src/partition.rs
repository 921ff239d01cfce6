//! Distributing a model over ranks: contiguous ranges of the body's node order balanced by
//! work ([`Partition`]), and the ghost values each range needs from the others ([`Halo`]).
//!
//! A rank owns the rows `range` of K and computes only those; the rows read the temperatures
//! of their columns, and the boundary's rules ([`crate::bc::Boundary::linear_rules`]) set
//! fictitious and driven nodes from other nodes. The nodes a rank needs are therefore the
//! closure of its rows' columns under those rules: with them current, every value the rank
//! computes has the same bits as in a serial run, because each row keeps its summation order.
//! Nothing here talks to other processes; [`crate::solve::exchange`] does.

use crate::cloud::Cloud;
use crate::horizons::Horizons;
use crate::kernel::Kernel;
use crate::math::NodeId;
use crate::operator::Conductance;
use rayon::prelude::*;
use std::collections::HashSet;
use std::ops::Range;

/// Work of one row besides its pairs, in pairs (the update, the boundary, the halo copy).
pub const ROW_WORK: usize = 4;

/// Contiguous ranges of the body nodes, one per rank, in the node order of the model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    /// `ranks + 1` row bounds: rank r owns rows `bounds[r]..bounds[r + 1]`.
    pub bounds: Vec<usize>,
}

impl Partition {
    /// Cuts the body rows of `cloud` into `ranks` contiguous ranges of nearly equal estimated
    /// work, before any bond exists: the pairs of row i taken as the nodes of spacing Δ_i in
    /// a ball of radius δ_i + Δ_i/2 (exact in the bulk of a lattice; dual-horizon transitions
    /// and free surfaces differ by a few per cent), plus [`ROW_WORK`]. Every rank computes
    /// the same cut from the cloud alone.
    pub fn by_estimate(cloud: &Cloud, ranks: usize) -> Self {
        let ball = match cloud.dim {
            1 => 2.0,
            2 => std::f64::consts::PI,
            _ => 4.0 / 3.0 * std::f64::consts::PI,
        };
        let mut cumulative = Vec::with_capacity(cloud.n_body + 1);
        cumulative.push(0usize);
        for i in 0..cloud.n_body {
            let (d, h) = (cloud.horizon[i], cloud.spacing[i]);
            let pairs = ball * ((d + 0.5 * h) / h).powi(cloud.dim as i32);
            let work = pairs.ceil().min(1e9) as usize + ROW_WORK;
            cumulative.push(cumulative[i] + work);
        }
        Self::by_cumulative(cloud.n_body, ranks, |i| cumulative[i])
    }

    /// Cuts `rows` rows into `ranks` ranges given the work of rows `0..i` as `work(i)`
    /// (non-decreasing, `work(0) = 0`): rank r starts at the first row whose cumulative work
    /// reaches r/ranks of the total.
    pub fn by_cumulative(rows: usize, ranks: usize, work: impl Fn(usize) -> usize) -> Self {
        let ranks = ranks.max(1);
        let total = work(rows) as u128;
        let mut bounds = Vec::with_capacity(ranks + 1);
        bounds.push(0);
        for r in 1..ranks {
            let target = total * r as u128 / ranks as u128;
            let (mut lo, mut hi) = (*bounds.last().expect("bound"), rows);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if (work(mid) as u128) < target {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            bounds.push(lo);
        }
        bounds.push(rows);
        Partition { bounds }
    }

    /// Number of ranks.
    pub fn ranks(&self) -> usize {
        self.bounds.len() - 1
    }

    /// The rows of rank `r`.
    pub fn range(&self, r: usize) -> Range<usize> {
        self.bounds[r]..self.bounds[r + 1]
    }

    /// The rank that owns body node `i` (the last of several ranks whose range is empty
    /// there never owns it).
    pub fn owner(&self, i: usize) -> usize {
        self.bounds.partition_point(|&b| b <= i) - 1
    }
}

/// The values a rank receives from each other rank before it applies the boundary, and the
/// values it sends them (body nodes, in increasing order); the fictitious nodes it publishes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Halo {
    /// `(rank, nodes)`: the ghost nodes this rank receives from `rank`.
    pub recv: Vec<(usize, Vec<NodeId>)>,
    /// `(rank, nodes)`: the owned nodes this rank sends to `rank`.
    pub send: Vec<(usize, Vec<NodeId>)>,
    /// The nodes past the body (fictitious) whose values this rank gives the others when the
    /// whole field is gathered, in increasing order.
    pub publish: Vec<NodeId>,
}

impl Halo {
    /// Number of ghost nodes received per exchange.
    pub fn ghosts(&self) -> usize {
        self.recv.iter().map(|(_, n)| n.len()).sum()
    }

    /// Values sent per exchange.
    pub fn sent(&self) -> usize {
        self.send.iter().map(|(_, n)| n.len()).sum()
    }
}

/// The rules that set constrained and fictitious nodes, indexed by node: `rules[f]` lists the
/// nodes that θ_f is computed from ([`crate::bc::Boundary::linear_rules`]).
pub fn rule_sources(n_nodes: usize, rules: &[(usize, Vec<(usize, f64)>)]) -> Vec<Vec<NodeId>> {
    let mut out = vec![Vec::new(); n_nodes];
    for (node, sources) in rules {
        out[*node].extend(sources.iter().map(|&(s, _)| s as NodeId));
    }
    out
}

/// Every node outside `rows` (body or not) that the rank of `rows` needs current: the
/// columns of its rows and the sources of every rule that sets a node it needs, closed under
/// the rules, with `seeds` besides, in increasing order.
pub fn closure(
    conductance: &Conductance,
    sources: &[Vec<NodeId>],
    rows: Range<usize>,
    seeds: &[NodeId],
) -> Vec<NodeId> {
    let cols = &conductance.cols[conductance.offsets[rows.start]..conductance.offsets[rows.end]];
    close(cols.iter().copied(), sources, rows, seeds)
}

/// [`closure`] of the columns `cols` of the rows `rows`.
pub fn close(
    cols: impl Iterator<Item = NodeId>,
    sources: &[Vec<NodeId>],
    rows: Range<usize>,
    seeds: &[NodeId],
) -> Vec<NodeId> {
    // only the nodes outside the rows are remembered: the work is that of the rows' pairs and
    // the closure, not of the whole cloud (a rank of thousands plans its halo in its share)
    let mut seen: HashSet<NodeId> = HashSet::new();
    let mut stack: Vec<NodeId> = Vec::new();
    let mut visit = |j: NodeId, stack: &mut Vec<NodeId>| {
        if !rows.contains(&(j as usize)) && seen.insert(j) {
            stack.push(j);
        }
    };
    let own_sources = rows.clone().flat_map(|i| sources[i].iter().copied());
    for j in cols.chain(seeds.iter().copied()).chain(own_sources) {
        visit(j, &mut stack);
    }
    while let Some(j) = stack.pop() {
        for &s in &sources[j as usize] {
            visit(s, &mut stack);
        }
    }
    let mut out: Vec<NodeId> = seen.into_iter().collect();
    out.sort_unstable();
    out
}

/// The fictitious nodes each rank of `partition` publishes when the ranks gather the whole
/// field: a node goes to the owner of its anchor, the first body node found by following
/// the first source of its rule ([`rule_sources`]); nodes set from no body node (a value
/// given by an expression) go to rank 0. Every rank computes it alone, from the boundary.
pub fn publishers(
    sources: &[Vec<NodeId>],
    n_body: usize,
    partition: &Partition,
) -> Vec<Vec<NodeId>> {
    let mut out = vec![Vec::new(); partition.ranks()];
    for f in n_body..sources.len() {
        let owner = anchor(sources, n_body, f).map_or(0, |a| partition.owner(a));
        out[owner].push(f as NodeId);
    }
    out
}

/// The body node a fictitious node `f` is anchored to ([`publishers`]), if any.
fn anchor(sources: &[Vec<NodeId>], n_body: usize, f: usize) -> Option<usize> {
    let mut at = f;
    // rules chain a few levels at most (a corner set from an edge set from the body)
    for _ in 0..64 {
        let s = *sources[at].first()? as usize;
        if s < n_body {
            return Some(s);
        }
        at = s;
    }
    None
}

/// The halo of rank `rank` without its send lists ([`Halo::recv`] and [`Halo::publish`]):
/// the [`closure`] of its rows seeded with the fictitious nodes it publishes, its ghosts
/// grouped by owner. The rows of K it reads are its own, so a rank's share of the model
/// ([`crate::model::Model::build_share`]) plans its own halo.
pub fn own_halo(
    conductance: &Conductance,
    sources: &[Vec<NodeId>],
    n_body: usize,
    partition: &Partition,
    rank: usize,
    publish: Vec<NodeId>,
) -> Halo {
    let needed = closure(conductance, sources, partition.range(rank), &publish);
    // sorted ghosts: those of one owner are consecutive (owners hold contiguous rows)
    let mut recv: Vec<(usize, Vec<NodeId>)> = Vec::new();
    for g in needed.into_iter().filter(|&g| (g as usize) < n_body) {
        let owner = partition.owner(g as usize);
        match recv.last_mut() {
            Some((o, nodes)) if *o == owner => nodes.push(g),
            _ => recv.push((owner, vec![g])),
        }
    }
    Halo {
        recv,
        send: Vec::new(),
        publish,
    }
}

/// The send lists of every rank from all ranks' receive lists: what r receives from s, s
/// sends to r.
pub fn fill_sends(halos: &mut [Halo]) {
    for r in 0..halos.len() {
        for (s, nodes) in halos[r].recv.clone() {
            halos[s].send.push((r, nodes));
        }
    }
    for h in halos.iter_mut() {
        h.send.sort_by_key(|(r, _)| *r);
    }
}

/// The halo of every rank of `partition` from a whole model ([`own_halo`] of each, then
/// [`fill_sends`]): no messages at set-up.
pub fn halos(
    conductance: &Conductance,
    sources: &[Vec<NodeId>],
    n_body: usize,
    partition: &Partition,
) -> Vec<Halo> {
    let publish = publishers(sources, n_body, partition);
    let mut out: Vec<Halo> = publish
        .into_iter()
        .enumerate()
        .map(|(r, p)| own_halo(conductance, sources, n_body, partition, r, p))
        .collect();
    fill_sends(&mut out);
    out
}

/// What one rank of a partition would hold and exchange, counted without building the model
/// ([`loads`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RankLoad {
    /// Body nodes (rows).
    pub nodes: usize,
    /// Pairs of K in its rows.
    pub pairs: usize,
    /// Directed bonds of its rows, and from fictitious nodes into them.
    pub bonds: usize,
    /// Ghost body nodes it receives per halo exchange.
    pub ghosts: usize,
    /// Ranks it receives ghosts from.
    pub sources: usize,
    /// Fictitious nodes it publishes at a gather.
    pub publish: usize,
}

/// The [`RankLoad`] of every rank of `partition` over `cloud` (bonds by `kernel`, boundary
/// rules `sources`, [`rule_sources`]): a neighbour search counted per rank
/// ([`Horizons::census`]), the halo closed as [`own_halo`] closes it.
pub fn loads(
    cloud: &Cloud,
    kernel: &Kernel,
    sources: &[Vec<NodeId>],
    partition: &Partition,
) -> Vec<RankLoad> {
    let ranges: Vec<Range<usize>> = (0..partition.ranks()).map(|r| partition.range(r)).collect();
    let census = Horizons::census(cloud, kernel, &ranges);
    let publish = publishers(sources, cloud.n_body, partition);
    census
        .into_par_iter()
        .zip(publish)
        .enumerate()
        .map(|(r, (c, publish))| {
            let needed = close(c.outside.into_iter(), sources, partition.range(r), &publish);
            let ghosts: Vec<NodeId> = needed
                .into_iter()
                .filter(|&g| (g as usize) < cloud.n_body)
                .collect();
            let mut owners: Vec<usize> = ghosts
                .iter()
                .map(|&g| partition.owner(g as usize))
                .collect();
            owners.dedup();
            RankLoad {
                nodes: partition.range(r).len(),
                pairs: c.pairs,
                bonds: c.bonds,
                ghosts: ghosts.len(),
                sources: owners.len(),
                publish: publish.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path graph 0 – 1 – … – (n−1): each row holds its left and right neighbour.
    fn chain(n: usize) -> Conductance {
        let mut k = Conductance {
            offsets: vec![0],
            ..Default::default()
        };
        for i in 0..n {
            for j in [i.wrapping_sub(1), i + 1] {
                if j < n {
                    k.cols.push(j as NodeId);
                    k.vals.push(1.0);
                }
            }
            k.offsets.push(k.cols.len());
        }
        k
    }

    #[test]
    fn ranges_cover_the_rows_once_and_balance_the_work() {
        let k = chain(1000);
        for ranks in [1, 2, 3, 7, 1000, 1500] {
            // the work of rows 0..i: their pairs plus ROW_WORK each
            let p = Partition::by_cumulative(1000, ranks, |i| k.offsets[i] + ROW_WORK * i);
            assert_eq!(p.ranks(), ranks);
            assert_eq!((p.bounds[0], p.bounds[ranks]), (0, 1000));
            assert!(p.bounds.windows(2).all(|w| w[0] <= w[1]));
            for i in [0, 1, 499, 999] {
                assert!(p.range(p.owner(i)).contains(&i), "{ranks} ranks, node {i}");
            }
            if ranks <= 1000 {
                // uniform rows: sizes differ by at most one row
                let sizes: Vec<usize> = (0..ranks).map(|r| p.range(r).len()).collect();
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{ranks} ranks: {sizes:?}");
            }
        }
    }

    #[test]
    fn heavy_rows_get_fewer_per_rank() {
        // the first half of the rows carry 9 times the work of the second half
        let rows = 1000;
        let work = |i: usize| if i <= 500 { 9 * i } else { 4500 + (i - 500) };
        let p = Partition::by_cumulative(rows, 2, work);
        assert_eq!(p.bounds, vec![0, 278, 1000]);
    }

    #[test]
    fn the_halo_of_a_chain_is_its_neighbours_and_rules_close_it() {
        let k = chain(10);
        let p = Partition {
            bounds: vec![0, 4, 10],
        };
        let none = vec![Vec::new(); 10];
        let h = halos(&k, &none, 10, &p);
        assert!(h[0].publish.is_empty() && h[1].publish.is_empty());
        assert_eq!(h[0].recv, vec![(1, vec![4])]);
        assert_eq!(h[1].recv, vec![(0, vec![3])]);
        assert_eq!(h[0].send, vec![(1, vec![3])]);
        // node 5 is set from node 9 (a rule): rank 0 reads 4, not 5, so nothing changes
        // for it; make node 4 a rule of node 8 and rank 0 needs 8 as well
        let mut rules = none.clone();
        rules[4] = vec![8];
        let h = halos(&k, &rules, 10, &p);
        assert_eq!(h[0].recv, vec![(1, vec![4, 8])]);
        assert_eq!(h[1].send, vec![(0, vec![4, 8])]);
    }

    #[test]
    fn each_fictitious_node_is_published_once() {
        // nodes 0..6 body, 6 and 7 fictitious: 6 is read by row 0 and set from node 1, so
        // rank 0 publishes it; 7 is read by no row and set from node 5, so rank 1 does
        let mut k = chain(6);
        k.cols.insert(0, 6);
        k.vals.insert(0, 1.0);
        for o in &mut k.offsets[1..] {
            *o += 1;
        }
        let mut rules = vec![Vec::new(); 8];
        rules[6] = vec![1];
        rules[7] = vec![5];
        let p = Partition {
            bounds: vec![0, 3, 6],
        };
        let h = halos(&k, &rules, 6, &p);
        assert_eq!(
            (h[0].publish.clone(), h[1].publish.clone()),
            (vec![6], vec![7])
        );
        assert_eq!(h[0].recv, vec![(1, vec![3])]);
        // a node set from another fictitious node follows it to its body anchor; one set
        // from none (an expression) goes to rank 0
        let mut rules = vec![Vec::new(); 9];
        rules[6] = vec![7];
        rules[7] = vec![5];
        let p = publishers(&rules, 6, &p);
        assert_eq!(p, vec![vec![8], vec![6, 7]]);
    }
}
