//! The coarse level of the two-level preconditioner for the consistent-weights Newton systems.
//!
//! The pair exponent `g_ij = (ℓ_i − ℓ_j)·ξ + ξᵀ(L_i + L_j)ξ` does not change when the
//! multipliers follow a "null mode": ℓ_i = b + (A + W)(x_i − x_a), L_i = A/2 with b a vector,
//! A symmetric and W antisymmetric, and more generally ℓ quadratic in x with L = ½ sym ∇ℓ
//! ([`modes`]). The Newton matrix is therefore singular in the interior of
//! the selected nodes and only the boundary of the selection fixes those modes; their smooth
//! versions have tiny eigenvalues, which stalls plain block-Jacobi CG (thousands of iterations
//! at 10⁴ nodes). As in smoothed-aggregation multigrid for elasticity with its rigid-body
//! modes, we cut the selected nodes into aggregates (contiguous runs of the space-filling-curve
//! order), span each aggregate's null modes, and solve the Galerkin coarse system
//! `E = Zᵀ H Z` exactly by sparse Cholesky (faer).

use super::{Mom, Problem};
use crate::math::{Point, Real, Vector};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Side};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// Largest number of null modes per aggregate ([`modes`]).
const MAX_MODES: usize = 12;
/// Coarse vector of one node or aggregate.
type Modes = SVector<Real, MAX_MODES>;
/// One block of the coarse matrix.
type CoarseBlock = SMatrix<Real, MAX_MODES, MAX_MODES>;
/// The null modes of one node's aggregate at the node, one column per mode.
type NodeModes = SMatrix<Real, { super::NC }, MAX_MODES>;

/// Null modes per aggregate, by dimension: the affine multipliers ℓ (b, A, W) and, in 1D and
/// 2D, the quadratic ones. An interior pair's exponent vanishes for every quadratic ℓ with
/// L = ½ sym ∇ℓ (the trapezoid rule is exact on the linear ∇ℓ), so these modes are in the null
/// space too; in 2D they cut the CG iterations of the tutorial rectangle (7 394 nodes) from
/// 6 871 to 2 385. In 3D there would be 30 of them, and at the sizes measured (the unit cube
/// of 4 594 tetrahedral nodes: 280 against 474 CG iterations) the assembly of the larger
/// coarse matrix cost more than the iterations saved (8.1 against 6.2 s).
fn modes(dim: usize) -> usize {
    // 1D: 1 + 1 + 1; 2D: 2 + 3 + 1 affine and 6 quadratic; 3D: 3 + 6 + 3 affine
    match dim {
        1 => 3,
        _ => 12,
    }
}

/// Selected nodes per aggregate, by dimension.
fn aggregate_size(dim: usize) -> usize {
    match dim {
        1 => 8,
        2 => 48,
        _ => 96,
    }
}

/// The aggregates of the selected nodes and their null modes.
struct Aggregates {
    /// Aggregate of each body node (u32::MAX: not selected).
    agg: Vec<u32>,
    /// Node ranges of the aggregates, in the selected nodes' order.
    members: Vec<Vec<u32>>,
    /// Centre and length scale of each aggregate.
    centre: Vec<(Point, Real)>,
    /// Modes per aggregate.
    m: usize,
    /// The modes at each body node (zero at unselected nodes), computed once.
    z: Vec<NodeModes>,
}

/// Aggregates and the factorised coarse matrix.
pub(super) struct Coarse {
    aggs: Aggregates,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<Real>,
    scratch: MemBuffer,
}

impl Aggregates {
    /// The k-th null mode of aggregate `a` at node `i`, as scaled multipliers (see [`super::phi`]).
    fn mode(&self, p: &Problem, a: usize, i: usize, k: usize) -> Mom {
        let (c, s) = self.centre[a];
        let dim = p.cloud.dim;
        let r: Vector = (p.cloud.pos[i] - c) / s;
        let si = p.cloud.horizon[i] / s;
        // unscaled ℓ (times s) and L (times s²), then scaled by the node's horizon
        let mut l = Vector::zeros();
        let mut big = [[0.0; 3]; 3];
        if k < dim {
            l[k] = 1.0;
        } else if k < dim + dim * (dim + 1) / 2 {
            let (a1, a2) = sym_pair(dim, k - dim);
            let mut e = [[0.0; 3]; 3];
            e[a1][a2] = 1.0;
            e[a2][a1] = 1.0;
            for (x, row) in e.iter().enumerate() {
                for (y, v) in row.iter().enumerate() {
                    l[x] += v * r[y];
                    big[x][y] = 0.5 * v;
                }
            }
        } else if k < dim + dim * dim {
            let (a1, a2) = anti_pair(k - dim - dim * (dim + 1) / 2);
            l[a1] += r[a2];
            l[a2] -= r[a1];
        } else {
            // ℓ_c = r_a r_b, L = ½ sym ∇ℓ
            let q = k - dim - dim * dim;
            let npairs = dim * (dim + 1) / 2;
            let (c0, (a1, a2)) = (q / npairs, sym_pair(dim, q % npairs));
            l[c0] = r[a1] * r[a2];
            let mut g = [[0.0; 3]; 3];
            g[c0][a1] += r[a2];
            g[c0][a2] += r[a1];
            for x in 0..3 {
                for y in 0..3 {
                    big[x][y] = 0.25 * (g[x][y] + g[y][x]);
                }
            }
        }
        let f = si;
        let f2 = si * si;
        Mom::from([
            l.x * f,
            l.y * f,
            l.z * f,
            big[0][0] * f2,
            big[1][1] * f2,
            big[2][2] * f2,
            2.0 * big[0][1] * f2,
            2.0 * big[0][2] * f2,
            2.0 * big[1][2] * f2,
        ])
        .component_mul(&p.used)
    }

    /// u_i = (φ·mode_k(i))_k for the scaled moment vector `ph` of node i.
    fn project(&self, i: usize, ph: &Mom) -> Modes {
        self.z[i].tr_mul(ph)
    }

    /// Cuts the selected nodes of `p` into aggregates.
    fn new(p: &Problem) -> Option<Aggregates> {
        let dim = p.cloud.dim;
        let selected: Vec<u32> = (0..p.n() as u32).filter(|&i| p.sel[i as usize]).collect();
        if selected.is_empty() {
            return None;
        }
        let members: Vec<Vec<u32>> = selected
            .chunks(aggregate_size(dim))
            .map(<[u32]>::to_vec)
            .collect();
        let mut agg = vec![u32::MAX; p.n()];
        let centre = members
            .iter()
            .enumerate()
            .map(|(a, list)| {
                let mut c = Vector::zeros();
                let mut s = 0.0;
                for &i in list {
                    agg[i as usize] = a as u32;
                    c += p.cloud.pos[i as usize].coords;
                    s += p.cloud.horizon[i as usize];
                }
                let n = list.len() as Real;
                (Point::from(c / n), s / n)
            })
            .collect();
        let mut aggs = Aggregates {
            agg,
            members,
            centre,
            m: modes(dim),
            z: Vec::new(),
        };
        aggs.z = (0..p.n())
            .into_par_iter()
            .map(|i| {
                let mut z = NodeModes::zeros();
                if let Some(a) = (aggs.agg[i] != u32::MAX).then_some(aggs.agg[i] as usize) {
                    for k in 0..aggs.m {
                        z.set_column(k, &aggs.mode(p, a, i, k));
                    }
                }
                z
            })
            .collect();
        Some(aggs)
    }

    /// The lower triangle of E = Σ_pairs K' (u_i + u_j)(u_i + u_j)ᵀ for the weights `vals`.
    fn matrix(&self, p: &Problem, vals: &[Real]) -> Option<SparseColMat<usize, Real>> {
        let m = self.m;
        let rows: Vec<Vec<(usize, CoarseBlock)>> = (0..self.members.len())
            .into_par_iter()
            .map(|a| self.aggregate_rows(p, vals, a))
            .collect();
        let mut trip = Vec::new();
        for (a, blocks) in rows.iter().enumerate() {
            for (b, blk) in blocks.iter().filter(|(b, _)| *b <= a) {
                for r in 0..m {
                    for c in 0..m {
                        if *b == a && c > r {
                            continue;
                        }
                        let mut v = blk[(r, c)];
                        if *b == a && r == c {
                            // modes that vanish on a tiny aggregate: keep E definite
                            v = if v > 0.0 { v * (1.0 + 1e-10) } else { 1.0 };
                        }
                        trip.push(Triplet::new(a * m + r, *b * m + c, v));
                    }
                }
            }
        }
        let nc = self.members.len() * m;
        SparseColMat::<usize, Real>::try_new_from_triplets(nc, nc, &trip).ok()
    }

    /// The blocks E[a, b] from the rows of aggregate a's nodes.
    fn aggregate_rows(&self, p: &Problem, vals: &[Real], a: usize) -> Vec<(usize, CoarseBlock)> {
        let mut out: Vec<(usize, CoarseBlock)> = vec![(a, CoarseBlock::zeros())];
        for &i in &self.members[a] {
            let i = i as usize;
            for e in p.offsets[i]..p.offsets[i + 1] {
                let j = p.cols[e] as usize;
                let (pi, pj) = p.phis(i, j);
                let pu = self.project(i, &pi);
                out[0].1 += (pu * vals[e]) * pu.transpose();
                let ui = pu * vals[e];
                if j < p.n() && p.sel[j] {
                    let b = self.agg[j] as usize;
                    let uj = self.project(j, &pj);
                    let slot = match out.iter().position(|(x, _)| *x == b) {
                        Some(s) => s,
                        None => {
                            out.push((b, CoarseBlock::zeros()));
                            out.len() - 1
                        }
                    };
                    out[slot].1 += ui * uj.transpose();
                }
            }
        }
        out
    }

    /// Zᵀ r, aggregate by aggregate.
    fn restrict(&self, r: &[Mom]) -> Vec<Real> {
        let m = self.m;
        self.members
            .par_iter()
            .flat_map_iter(|list| {
                let mut s = Modes::zeros();
                for &i in list {
                    s += self.project(i as usize, &r[i as usize]);
                }
                (0..m).map(move |k| s[k])
            })
            .collect()
    }

    /// z += Z c.
    fn prolong(&self, c: &[Real], z: &mut [Mom]) {
        let m = self.m;
        z.par_iter_mut().enumerate().for_each(|(i, zi)| {
            let a = self.agg[i];
            if a == u32::MAX {
                return;
            }
            let a = a as usize;
            let ca = Modes::from_fn(|k, _| if k < m { c[a * m + k] } else { 0.0 });
            *zi += self.z[i] * ca;
        });
    }
}

impl Coarse {
    /// Builds the aggregates and factorises E for the weights `vals`; None if it fails.
    pub(super) fn new(p: &Problem, vals: &[Real]) -> Option<Coarse> {
        let aggs = Aggregates::new(p)?;
        let e = aggs.matrix(p, vals)?;
        let par = super::FACTOR_PAR;
        let symbolic = factorize_symbolic_cholesky(
            e.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .ok()?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut work =
            MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<Real>(par, Default::default()));
        symbolic
            .factorize_numeric_llt(
                &mut values,
                e.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut work),
                Default::default(),
            )
            .ok()?;
        let scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<Real>(1, par));
        Some(Coarse {
            aggs,
            symbolic,
            values,
            scratch,
        })
    }

    /// z += Z E⁻¹ Zᵀ r.
    pub(super) fn apply(&mut self, r: &[Mom], z: &mut [Mom]) {
        let mut c = self.aggs.restrict(r);
        let n = c.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut c, n, 1),
            super::FACTOR_PAR,
            MemStack::new(&mut self.scratch),
        );
        self.aggs.prolong(&c, z);
    }
}

/// Axes of the q-th symmetric basis matrix: the diagonal ones first, then xy, xz, yz.
fn sym_pair(dim: usize, q: usize) -> (usize, usize) {
    if q < dim {
        return (q, q);
    }
    [(0, 1), (0, 2), (1, 2)][q - dim]
}

/// Axes of the q-th antisymmetric basis matrix: xy, xz, yz.
fn anti_pair(q: usize) -> (usize, usize) {
    [(0, 1), (0, 2), (1, 2)][q]
}
