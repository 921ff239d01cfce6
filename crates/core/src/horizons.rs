//! Directed neighbour lists (CSR): j is listed under i when j lies in i's horizon.
//!
//! The relation is directed because horizons differ from node to node (Wang, Oterkus & Oterkus,
//! eqs. 19–22: the α masks); each entry is the neighbour's index and nothing else: its
//! partial-volume factor β_ij (theory §2.3) and the distance at which Algorithm 1 evaluates the
//! kernel profile are recomputed by [`crate::kernel::Kernel::coverage`] where they are needed
//! ([`partial_volume`]). Built once, in parallel, and dropped by a model once K is assembled.

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
    /// Neighbour index j of each directed bond, sorted within a row (its partial-volume
    /// factor is [`partial_volume`], recomputed where needed rather than stored).
    pub targets: Vec<NodeId>,
}

/// Rows per parallel task of the search.
const SEARCH_CHUNK: usize = 2048;

/// A uniform bucket grid over the cloud's bounding box (cells of half the largest reach),
/// nodes listed cell by cell in increasing index.
struct Grid {
    lo: [f64; 3],
    inv: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<NodeId>,
}

impl Grid {
    /// The grid for `pts`, or None when it would not pay: reaches that vary more than 4×
    /// (a refined mesh) or more cells than 8 per node.
    fn new(pts: &[[f64; 3]], reach: &[f64]) -> Option<Grid> {
        let rmax = reach.iter().cloned().fold(0.0, f64::max);
        let rmin = reach.iter().cloned().fold(f64::INFINITY, f64::min);
        if !(rmin > 0.0 && rmax <= 4.0 * rmin) || pts.len() >= u32::MAX as usize {
            return None;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in pts {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let cell = 0.5 * rmax;
        let inv = 1.0 / cell;
        let mut dims = [1usize; 3];
        let mut cells = 1.0;
        for a in 0..3 {
            let d = ((hi[a] - lo[a]) * inv).floor() + 1.0;
            cells *= d;
            dims[a] = d as usize;
        }
        if cells.is_nan() || cells > 8.0 * pts.len() as f64 + 1024.0 {
            return None;
        }
        let mut g = Grid {
            lo,
            inv,
            dims,
            start: Vec::new(),
            items: vec![0; pts.len()],
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let of: Vec<u32> = pts.iter().map(|p| g.cell_of(p) as u32).collect();
        let mut start = vec![0u32; ncell + 1];
        for &c in &of {
            start[c as usize + 1] += 1;
        }
        for c in 0..ncell {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        for (i, &c) in of.iter().enumerate() {
            g.items[fill[c as usize] as usize] = i as NodeId;
            fill[c as usize] += 1;
        }
        g.start = start;
        Some(g)
    }

    /// Marks the rows `rows` and every node in a cell within `rmax` of a cell holding one of
    /// them: a superset of the nodes within `rmax` of the rows, found cell by cell (no
    /// distance is computed).
    fn near(&self, pts: &[[f64; 3]], rows: std::ops::Range<usize>, rmax: f64) -> Vec<bool> {
        let ncell = self.dims[0] * self.dims[1] * self.dims[2];
        let mut held = vec![false; ncell];
        for p in &pts[rows.clone()] {
            held[self.cell_of(p)] = true;
        }
        // cells within rmax of a held one: k cells each way (the cells are rmax/2 wide)
        let k = (rmax * self.inv).ceil() as usize + 1;
        let mut near = vec![false; ncell];
        let [dx, dy, dz] = self.dims;
        for c in (0..ncell).filter(|&c| held[c]) {
            let (x, y, z) = (c % dx, (c / dx) % dy, c / (dx * dy));
            let span = |v: usize, d: usize| v.saturating_sub(k)..=(v + k).min(d - 1);
            for zz in span(z, dz) {
                for yy in span(y, dy) {
                    let row = (zz * dy + yy) * dx;
                    near[row + x.saturating_sub(k)..=row + (x + k).min(dx - 1)].fill(true);
                }
            }
        }
        let mut wanted = vec![false; pts.len()];
        wanted[rows].fill(true);
        for c in (0..ncell).filter(|&c| near[c]) {
            for &j in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                wanted[j as usize] = true;
            }
        }
        wanted
    }

    fn coord(&self, x: f64, a: usize) -> usize {
        (((x - self.lo[a]) * self.inv).floor().max(0.0) as usize).min(self.dims[a] - 1)
    }

    fn cell_of(&self, p: &[f64; 3]) -> usize {
        (self.coord(p[2], 2) * self.dims[1] + self.coord(p[1], 1)) * self.dims[0]
            + self.coord(p[0], 0)
    }

    /// Pushes every node q with |q − p|² ≤ r2 onto `out` (unsorted).
    fn within(&self, pts: &[[f64; 3]], p: &[f64; 3], r2: f64, out: &mut Vec<NodeId>) {
        // a slightly larger box: |q − p|² ≤ r2 may hold a hair outside p ± √r2 by rounding
        let r = r2.sqrt() * (1.0 + 1e-9);
        let lo: [usize; 3] = std::array::from_fn(|a| self.coord(p[a] - r, a));
        let hi: [usize; 3] = std::array::from_fn(|a| self.coord(p[a] + r, a));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = (z * self.dims[1] + y) * self.dims[0];
                let (a, b) = (
                    self.start[row + lo[0]] as usize,
                    self.start[row + hi[0] + 1] as usize,
                );
                for &j in &self.items[a..b] {
                    let q = &pts[j as usize];
                    let (dx, dy, dz) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
                    if dx * dx + dy * dy + dz * dz <= r2 {
                        out.push(j);
                    }
                }
            }
        }
    }
}

/// Fixed-radius search: the bucket grid for near-uniform clouds, else a k-d tree (kiddo).
enum Finder {
    Grid(Grid),
    Tree(ImmutableKdTree<f64, 3>),
}

impl Finder {
    /// The bucket grid when `grid` and it pays ([`Grid::new`]), else a k-d tree; `pts` is
    /// not empty.
    fn new(pts: &[[f64; 3]], reach: &[f64], grid: bool) -> Finder {
        match grid.then(|| Grid::new(pts, reach)).flatten() {
            Some(g) => Finder::Grid(g),
            None => Finder::Tree(
                ImmutableKdTree::new_from_slice(pts).expect("a non-empty cloud builds a k-d tree"),
            ),
        }
    }

    fn within(&self, pts: &[[f64; 3]], i: usize, r2: f64, out: &mut Vec<NodeId>) {
        match self {
            Finder::Grid(g) => g.within(pts, &pts[i], r2, out),
            Finder::Tree(t) => out.extend(
                t.query(&pts[i])
                    .within::<SquaredEuclidean<f64>>(r2)
                    .unsorted()
                    .execute()
                    .into_iter()
                    .map(|it| it.item as NodeId),
            ),
        }
    }
}

/// β of the bond i → j, None when it is not a bond (j outside H_i, j = i, or both fictitious).
fn bond(cloud: &Cloud, kernel: &Kernel, i: usize, j: usize) -> Option<f64> {
    let nb = cloud.n_body;
    if j == i || (i >= nb && j >= nb) {
        return None;
    }
    let beta = partial_volume(cloud, kernel, i, j);
    (beta > 0.0).then_some(beta)
}

/// Partial-volume factor β_ij ∈ [0, 1] of the directed bond i → j (the fraction of node j's
/// cell inside node i's horizon, [`Kernel::coverage`]); every bond of [`Horizons`] has β > 0.
#[inline]
pub fn partial_volume(cloud: &Cloud, kernel: &Kernel, i: usize, j: usize) -> f64 {
    let r = (cloud.pos[j] - cloud.pos[i]).norm();
    kernel.coverage(r, cloud.horizon[i], cloud.spacing[j]).0
}

/// What the body rows of one range hold, counted by the search alone (nothing stored).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowCensus {
    /// Entries of K in the rows (pairs).
    pub pairs: usize,
    /// Directed bonds of the rows, and from fictitious nodes into them.
    pub bonds: usize,
    /// The columns of the rows outside them (body or fictitious), sorted.
    pub outside: Vec<NodeId>,
}

/// [`RowCensus`] of the rows `rows`, searching around each at the largest reach `rmax`.
fn census_of(
    cloud: &Cloud,
    kernel: &Kernel,
    finder: &Finder,
    pts: &[[f64; 3]],
    rmax: f64,
    rows: std::ops::Range<usize>,
) -> RowCensus {
    let r2 = rmax * rmax * (1.0 + 1e-12);
    let mut c = RowCensus::default();
    let mut near = Vec::new();
    for i in rows.clone() {
        near.clear();
        finder.within(pts, i, r2, &mut near);
        for &j in &near {
            let ju = j as usize;
            let out = bond(cloud, kernel, i, ju).is_some();
            let into = bond(cloud, kernel, ju, i).is_some();
            if out || into {
                c.pairs += 1;
                if !rows.contains(&ju) {
                    c.outside.push(j);
                }
            }
            c.bonds += out as usize + (into && ju >= cloud.n_body) as usize;
        }
    }
    c.outside.sort_unstable();
    c.outside.dedup();
    c
}

/// Search radius of every node: its horizon plus the partial-volume band of the coarsest spacing.
fn reaches(cloud: &Cloud, kernel: &Kernel) -> Vec<f64> {
    let dmax = cloud.spacing.iter().cloned().fold(0.0, f64::max);
    cloud
        .horizon
        .iter()
        .map(|&d| kernel.reach(d, dmax))
        .collect()
}

/// The sorted bonds of row `i` (`keep(i, j)` is `Some`) into `found`; none for a row that
/// `wanted` leaves out.
#[inline]
fn row_bonds<F>(
    (finder, pts, reach): (&Finder, &[[f64; 3]], &[f64]),
    keep: &F,
    wanted: Option<&[bool]>,
    i: usize,
    found: &mut Vec<NodeId>,
) where
    F: Fn(usize, usize) -> Option<f64> + Sync,
{
    found.clear();
    if wanted.is_some_and(|w| !w[i]) {
        return;
    }
    finder.within(pts, i, reach[i] * reach[i] * (1.0 + 1e-12), found);
    found.retain(|&j| keep(i, j as usize).is_some());
    found.sort_unstable();
}

/// Pass 1 of [`Horizons::build_with`]: the number of bonds of every row, in parallel blocks
/// of [`SEARCH_CHUNK`] rows, into `lens`. Nothing is kept: pass 2 ([`fill_blocks`]) searches
/// again straight into the final array, which costs a second search but never holds the
/// bonds twice (nor leaves the allocator the freed pieces of a first copy).
fn count_rows<F>(
    search: (&Finder, &[[f64; 3]], &[f64]),
    keep: &F,
    wanted: Option<&[bool]>,
    lens: &mut [usize],
) where
    F: Fn(usize, usize) -> Option<f64> + Sync,
{
    lens.par_chunks_mut(SEARCH_CHUNK)
        .enumerate()
        .for_each(|(c, lens)| {
            let mut found = Vec::new();
            for (r, len) in lens.iter_mut().enumerate() {
                row_bonds(search, keep, wanted, c * SEARCH_CHUNK + r, &mut found);
                *len = found.len();
            }
        });
}

/// Pass 2 of [`Horizons::build_with`]: each block's rows searched again into its part of the
/// targets (`parts`, from [`block_parts`]).
fn fill_blocks<F>(
    search: (&Finder, &[[f64; 3]], &[f64]),
    keep: &F,
    wanted: Option<&[bool]>,
    n: usize,
    parts: Vec<&mut [NodeId]>,
) where
    F: Fn(usize, usize) -> Option<f64> + Sync,
{
    parts.into_par_iter().enumerate().for_each(|(c, t)| {
        let mut found = Vec::new();
        let mut at = 0;
        for i in c * SEARCH_CHUNK..((c + 1) * SEARCH_CHUNK).min(n) {
            row_bonds(search, keep, wanted, i, &mut found);
            t[at..at + found.len()].copy_from_slice(&found);
            at += found.len();
        }
    });
}

/// Marks the rows `rows` and every node j with a bond j → i into one of them (`keep(j, i)`),
/// found by searching around each i at the largest reach of the cloud.
fn reaching<F>(
    finder: &Finder,
    pts: &[[f64; 3]],
    reach: &[f64],
    keep: &F,
    rows: std::ops::Range<usize>,
) -> Vec<bool>
where
    F: Fn(usize, usize) -> Option<f64> + Sync,
{
    let rmax = reach.iter().cloned().fold(0.0, f64::max);
    let r2 = rmax * rmax * (1.0 + 1e-12);
    let found: Vec<Vec<NodeId>> = rows
        .clone()
        .into_par_iter()
        .chunks(SEARCH_CHUNK)
        .map(|chunk| {
            let (mut near, mut out) = (Vec::new(), Vec::new());
            for i in chunk {
                near.clear();
                finder.within(pts, i, r2, &mut near);
                out.extend(near.iter().filter(|&&j| keep(j as usize, i).is_some()));
            }
            out.sort_unstable();
            out.dedup();
            out
        })
        .collect();
    let mut wanted = vec![false; pts.len()];
    wanted[rows].iter_mut().for_each(|w| *w = true);
    for j in found.into_iter().flatten() {
        wanted[j as usize] = true;
    }
    wanted
}

/// The targets of each of `n_blocks` blocks of [`SEARCH_CHUNK`] rows, as disjoint
/// mutable slices of the final arrays (CSR row starts `offsets`), for pass 2.
fn block_parts<'a>(
    offsets: &[usize],
    n_blocks: usize,
    targets: &'a mut [NodeId],
) -> Vec<&'a mut [NodeId]> {
    let total = targets.len();
    let starts: Vec<usize> = (0..n_blocks)
        .map(|c| offsets[c * SEARCH_CHUNK])
        .chain(std::iter::once(total))
        .collect();
    let mut t_rest = targets;
    let mut parts = Vec::with_capacity(n_blocks);
    for w in starts.windows(2) {
        let (t, tr) = std::mem::take(&mut t_rest).split_at_mut(w[1] - w[0]);
        parts.push(t);
        t_rest = tr;
    }
    parts
}

impl Horizons {
    /// Finds, for every node, the neighbours inside its horizon (fixed-radius search, radius
    /// δ_i plus the partial-volume band). Bonds between two fictitious nodes are dropped.
    /// Two parallel passes over blocks of rows: the sorted neighbours of each block, then β
    /// and the evaluation distance written straight into the final arrays.
    pub fn build(cloud: &Cloud, kernel: &Kernel) -> Self {
        Self::build_with(cloud, kernel, true)
    }

    /// True when [`Horizons::build`] searches with the bucket grid (near-uniform reaches),
    /// false when it uses the k-d tree.
    pub fn grid_applies(cloud: &Cloud, kernel: &Kernel) -> bool {
        let pts: Vec<[f64; 3]> = cloud.pos.iter().map(|p| [p.x, p.y, p.z]).collect();
        !pts.is_empty() && Grid::new(&pts, &reaches(cloud, kernel)).is_some()
    }

    /// [`Horizons::build`] with the bucket grid allowed or not (the k-d tree always works;
    /// both give the same lists).
    pub fn build_with(cloud: &Cloud, kernel: &Kernel, grid: bool) -> Self {
        Self::search(cloud, kernel, grid, None)
    }

    /// The rows a rank needs to assemble the body rows `rows` of K bit for bit as a whole
    /// model would (dual horizon: the margin comes from the other side's δ): those rows, and
    /// every node j (body or fictitious) whose horizon holds one of them, for w_ji (on the
    /// bucket grid, every node of the cells within the largest reach of theirs: a few more).
    /// Every other row is left empty. The search is that of [`Horizons::build`] over those
    /// rows.
    pub fn build_rows(cloud: &Cloud, kernel: &Kernel, rows: std::ops::Range<usize>) -> Self {
        Self::build_rows_with(cloud, kernel, rows, true)
    }

    /// [`Horizons::build_rows`] with the bucket grid allowed or not (the k-d tree finds the
    /// margin by a search at the largest reach).
    pub fn build_rows_with(
        cloud: &Cloud,
        kernel: &Kernel,
        rows: std::ops::Range<usize>,
        grid: bool,
    ) -> Self {
        Self::search(cloud, kernel, grid, Some(rows))
    }

    /// The search of [`Horizons::build_with`]; with `rows`, that of [`Horizons::build_rows`].
    fn search(
        cloud: &Cloud,
        kernel: &Kernel,
        grid: bool,
        rows: Option<std::ops::Range<usize>>,
    ) -> Self {
        let pts: Vec<[f64; 3]> = cloud.pos.iter().map(|p| [p.x, p.y, p.z]).collect();
        let n = pts.len();
        if n == 0 {
            return Horizons {
                offsets: vec![0],
                ..Default::default()
            };
        }
        let reach = reaches(cloud, kernel);
        let finder = Finder::new(&pts, &reach, grid);
        let keep = |i: usize, j: usize| bond(cloud, kernel, i, j);
        let wanted = rows.map(|rows| match &finder {
            // a margin of whole cells: a few more rows than needed, no distance computed
            Finder::Grid(g) => g.near(&pts, rows, reach.iter().cloned().fold(0.0, f64::max)),
            Finder::Tree(_) => reaching(&finder, &pts, &reach, &keep, rows),
        });
        // pass 1: the row lengths; pass 2: the same search into place
        let search = (&finder, &pts[..], &reach[..]);
        let mut lens = vec![0usize; n];
        count_rows(search, &keep, wanted.as_deref(), &mut lens);
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0usize);
        for (i, len) in lens.iter().enumerate() {
            offsets.push(offsets[i] + len);
        }
        drop(lens);
        let total = offsets[n];
        let mut h = Horizons {
            offsets,
            targets: vec![0; total],
        };
        let blocks = n.div_ceil(SEARCH_CHUNK);
        let parts = block_parts(&h.offsets, blocks, &mut h.targets);
        fill_blocks(search, &keep, wanted.as_deref(), n, parts);
        h
    }

    /// [`RowCensus`] of each range of body rows in `ranges` (one rank's each, say), from
    /// one search structure, the ranges in parallel: what [`Horizons::build_rows`] and the
    /// assembly would give each, without holding any bond.
    pub fn census(
        cloud: &Cloud,
        kernel: &Kernel,
        ranges: &[std::ops::Range<usize>],
    ) -> Vec<RowCensus> {
        let pts: Vec<[f64; 3]> = cloud.pos.iter().map(|p| [p.x, p.y, p.z]).collect();
        if pts.is_empty() {
            return vec![RowCensus::default(); ranges.len()];
        }
        let reach = reaches(cloud, kernel);
        let rmax = reach.iter().cloned().fold(0.0, f64::max);
        let finder = Finder::new(&pts, &reach, true);
        ranges
            .par_iter()
            .map(|r| census_of(cloud, kernel, &finder, &pts, rmax, r.clone()))
            .collect()
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
