//! Distributing a model over ranks: contiguous ranges of the body's node order balanced by
//! work ([`Partition`]), and the ghost values each range needs from the others ([`Halo`]).
//!
//! A rank owns the rows `range` of K and computes only those; the rows read the temperatures
//! of their columns, and the boundary's rules ([`crate::bc::Boundary::linear_rules`]) set
//! fictitious and driven nodes from other nodes. The nodes a rank needs are therefore the
//! closure of its rows' columns under those rules: with them current, every value the rank
//! computes has the same bits as in a serial run, because each row keeps its summation order.
//! Nothing here talks to other processes; [`crate::solve::exchange`] does.

use crate::math::NodeId;
use crate::operator::Conductance;
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
    /// Cuts the rows of K into `ranks` contiguous ranges of nearly equal work: pairs plus
    /// [`ROW_WORK`] per row (variable-resolution clouds have rows of very different length,
    /// so equal node counts would not balance). `ranks` of 0 is taken as 1.
    pub fn by_work(conductance: &Conductance, ranks: usize) -> Self {
        let offsets = &conductance.offsets;
        Self::by_cumulative(offsets.len() - 1, ranks, |i| offsets[i] + ROW_WORK * i)
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
    // only the nodes outside the rows are remembered: the work is that of the rows' pairs and
    // the closure, not of the whole cloud (a rank of thousands plans its halo in its share)
    let mut seen: HashSet<NodeId> = HashSet::new();
    let mut stack: Vec<NodeId> = Vec::new();
    let mut visit = |j: NodeId, stack: &mut Vec<NodeId>| {
        if !rows.contains(&(j as usize)) && seen.insert(j) {
            stack.push(j);
        }
    };
    let cols = &conductance.cols[conductance.offsets[rows.start]..conductance.offsets[rows.end]];
    let own_sources = rows.clone().flat_map(|i| sources[i].iter());
    for &j in cols.iter().chain(seeds).chain(own_sources) {
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

/// The halo of every rank of `partition`: who receives which body nodes from whom, and which
/// rank publishes each node past the body (fictitious nodes) when the ranks gather the whole
/// field: the first rank that keeps it current; rank 0 takes on the nodes no rank reads, with
/// their sources. Every rank can compute it alone from the model (no messages at set-up):
/// one pass over K, O(pairs) in all, plus O(ranks · nodes) to list the results.
pub fn halos(
    conductance: &Conductance,
    sources: &[Vec<NodeId>],
    n_body: usize,
    partition: &Partition,
) -> Vec<Halo> {
    let ranks = partition.ranks();
    let n = sources.len();
    let mut closures: Vec<Vec<NodeId>> = (0..ranks)
        .map(|r| closure(conductance, sources, partition.range(r), &[]))
        .collect();
    let mut held = vec![false; n];
    for c in &closures {
        for &j in c {
            held[j as usize] = true;
        }
    }
    let orphans: Vec<NodeId> = (n_body..n)
        .filter(|&j| !held[j])
        .map(|j| j as NodeId)
        .collect();
    if !orphans.is_empty() && ranks > 0 {
        closures[0] = closure(conductance, sources, partition.range(0), &orphans);
    }
    let mut out = vec![Halo::default(); ranks];
    let mut published = vec![false; n];
    for (r, c) in closures.into_iter().enumerate() {
        // sorted ghosts: those of one owner are consecutive (owners hold contiguous rows)
        let mut groups: Vec<(usize, Vec<NodeId>)> = Vec::new();
        for g in c {
            let gu = g as usize;
            if gu < n_body {
                let owner = partition.owner(gu);
                match groups.last_mut() {
                    Some((o, nodes)) if *o == owner => nodes.push(g),
                    _ => groups.push((owner, vec![g])),
                }
            } else if !std::mem::replace(&mut published[gu], true) {
                out[r].publish.push(g);
            }
        }
        for (s, nodes) in groups {
            out[s].send.push((r, nodes.clone()));
            out[r].recv.push((s, nodes));
        }
    }
    for h in &mut out {
        h.send.sort_by_key(|(r, _)| *r);
    }
    out
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
            let p = Partition::by_work(&k, ranks);
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
        // nodes 0..6 body, 6 and 7 fictitious: 6 is read by row 0 and set from node 1; 7 is
        // read by no row and set from node 5, so rank 0 keeps it (and node 5) current
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
            (vec![6, 7], vec![])
        );
        assert_eq!(h[0].recv, vec![(1, vec![3, 5])]);
    }
}
