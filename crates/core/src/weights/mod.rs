//! Consistent bond weights (beyond the papers): the symmetric, positive pair conductances
//! closest to K that integrate linear, or linear and quadratic, fields exactly.
//!
//! On a lattice the calibrated kernel already gives every bulk node the moments of the
//! classical Laplacian. On an unstructured cloud (gmsh triangles, tetrahedra) it does not: the
//! midpoint sum over an irregular horizon misses the second moment by a few per cent and leaves
//! a first moment, and that quadrature bias does not vanish as Δ → 0 at fixed δ/Δ, so the run
//! does not converge to the classical solution. At each selected node i (a complete horizon:
//! no free surface, crack or material interface within reach) we impose
//!
//! ```text
//! Σ_j K'_ij ξ_ij = 0,       Σ_j K'_ij ξ_ij ⊗ ξ_ij = 2 k_i V_i I
//! ```
//!
//! so that Σ_j K'_ij (θ_j − θ_i) = V_i k_i ∇²θ for every quadratic θ (theory §2.1: the
//! 2D thickness and 1D cross-section are in V_i).
//!
//! Of all K' that meet these moments we take the one nearest to K in relative entropy,
//! minimising Σ_pairs K' ln(K'/K) − K' + K. Its Lagrange conditions give
//! `K'_ij = K_ij exp(λ_i·φ(ξ_ij) + λ_j·φ(ξ_ji))` with φ(ξ) = (ξ, ξ ⊗ ξ) and one multiplier
//! vector λ_i per selected node: K' is symmetric bit for bit (the exponent is the same sum in
//! rows i and j), every pair conductance stays positive, so energy is conserved, the operator
//! stays negative semi-definite and the Gershgorin bound on the stable Δt still holds. λ
//! minimises the convex dual `D(λ) = Σ_pairs K'_ij(λ) − Σ_i λ_i·t_i`, whose gradient is the
//! moment residual; we minimise it by Newton's method with a backtracking line search, each
//! Newton system solved by block-Jacobi conjugate gradients.
//!
//! Two short cuts: a cloud already consistent to [`TOLERANCE`] (a lattice without a horizon
//! change) keeps K bit for bit, and the linear order first tries the additive form of one
//! linear solve (`additive`), exact in one step, falling back to the entropy form only where
//! that would make a pair non-positive. The Newton iterations, the parallel sums and hence the
//! weights are the same bits at any thread count.
//!
//! The anchors in the literature: Seleson 2014 (improved one-point quadrature for peridynamics)
//! and Pasetto, Shen, D'Elia, Tian, Trask & Kamensky 2022 (optimization-based quadrature) fit
//! quadrature weights to integrate polynomials; Trask, You, Yu & Parks 2019 (an asymptotically
//! compatible meshfree quadrature, generalized moving least squares) is exact for polynomials
//! but gives up the symmetry of the pair weights, hence exact conservation. Here the weights
//! stay symmetric and positive and the polynomial moments are exact: where no positive
//! symmetric solution exists for a node (too few or one-sided neighbours), the node is left out
//! and reported ([`Consistency::uncorrected`]) rather than the mesh refused.

// CSR loops index several arrays (cols, vals, k0, positions) by one entry index.
#![allow(clippy::needless_range_loop)]

mod additive;
mod coarse;
mod cost;
mod direct;
pub mod store;

pub use cost::{estimate, Estimate, Path};

use crate::cloud::Cloud;
use crate::math::{Real, Vector};
use crate::operator::Conductance;
use crate::progress;
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// Moment components: ξ (x, y, z), then ξ⊗ξ (xx, yy, zz, xy, xz, yz), each scaled by δ_i.
const NC: usize = 9;
/// One node's moment vector or multipliers.
type Mom = SVector<Real, NC>;
/// One node's block of the Newton matrix.
type Block = SMatrix<Real, NC, NC>;

/// Which polynomial fields the corrected operator integrates exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// No correction: the kernel's weights as they are.
    None,
    /// Zero first moments: linear fields are exact steady states.
    Linear,
    /// Zero first moments and the classical second moments: the Laplacian of every quadratic.
    #[default]
    Quadratic,
}

/// What the correction achieved.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Consistency {
    /// Newton iterations (over all rounds).
    pub newton: usize,
    /// Conjugate-gradient iterations (over all Newton iterations).
    pub iterations: usize,
    /// Nodes corrected (complete horizon, moments met to the tolerance).
    pub corrected: usize,
    /// Nodes with a complete horizon for which no positive symmetric solution was found.
    pub uncorrected: usize,
    /// Largest relative moment error over the corrected nodes, before.
    pub before: Real,
    /// The same after the correction.
    pub after: Real,
    /// Largest relative moment error left at an uncorrected node (0 when there is none).
    pub worst_uncorrected: Real,
    /// Smallest ratio K'_ij / K_ij over all stored pairs (always > 0).
    pub min_ratio: Real,
    /// Largest ratio K'_ij / K_ij over all stored pairs.
    pub max_ratio: Real,
    /// Whether the weights were loaded from a store of earlier solves ([`store`]) instead
    /// of computed (the other fields are those of the solve that computed them).
    #[serde(default)]
    pub reused: bool,
}

/// faer's parallelism in the factorisations of the correction: sequential, because faer's
/// parallel sparse Cholesky orders its sums by the thread count, and the weights must be the
/// same bits for any thread count (every other sum of the correction has a fixed order).
const FACTOR_PAR: faer::Par = faer::Par::Seq;

/// Relative tolerance on every moment component at every corrected node.
pub const TOLERANCE: Real = 1e-10;
/// Newton iterations per round before the nodes still far off are left out.
const MAX_NEWTON: usize = 40;
/// Rounds of leaving out nodes that admit no solution.
const MAX_ROUNDS: usize = 3;

/// The data of one correction problem.
struct Problem<'a> {
    cloud: &'a Cloud,
    offsets: &'a [usize],
    cols: &'a [u32],
    /// K before the correction, per CSR entry.
    k0: Vec<Real>,
    /// Which body nodes carry constraints.
    sel: Vec<bool>,
    /// Moment components in use (dimension and order).
    used: Mom,
    /// Target moments t_i (scaled), per body node.
    target: Vec<Mom>,
    /// Scale of node i's moments (its diagonal target, or 1), for the relative error.
    unit: Vec<Real>,
    /// Bytes a direct factorisation of the Newton matrix may take (None: no limit known).
    factor_room: Option<Real>,
}

/// φ(ξ) scaled by the node's horizon s: (ξ/s, vech(ξξᵀ)/s²), masked to the used components.
#[inline(always)]
fn phi(xi: &Vector, s: Real, used: &Mom) -> Mom {
    monomials(&(xi / s)).component_mul(used)
}

/// The monomials q(ξ) = (ξ, vech ξξᵀ) of a bond, unscaled and unmasked (φ is q scaled).
#[inline(always)]
fn monomials(x: &Vector) -> Mom {
    Mom::from([
        x.x,
        x.y,
        x.z,
        x.x * x.x,
        x.y * x.y,
        x.z * x.z,
        x.x * x.y,
        x.x * x.z,
        x.y * x.z,
    ])
}

/// The moment components in use for `dim` and `order`.
fn used_components(dim: usize, order: Order) -> Mom {
    let mut used = Mom::zeros();
    for a in 0..dim {
        used[a] = 1.0;
    }
    if order == Order::Quadratic {
        // xx, yy, zz, xy, xz, yz: used when every axis they name exists
        let axes: [&[usize]; 6] = [&[0], &[1], &[2], &[0, 1], &[0, 2], &[1, 2]];
        for (c, ax) in axes.iter().enumerate() {
            if ax.iter().all(|&a| a < dim) {
                used[3 + c] = 1.0;
            }
        }
    }
    used
}

impl<'a> Problem<'a> {
    /// The problem of meeting `order`'s moments at the nodes `sel` of `cloud` for the
    /// conductances `k` and the conductivities `conductivity` (W/(m·K)), with `factor_room`
    /// bytes for a direct factorisation.
    fn new(
        k: &'a Conductance,
        cloud: &'a Cloud,
        sel: &[bool],
        conductivity: &[Real],
        order: Order,
        factor_room: Option<Real>,
    ) -> Problem<'a> {
        let n = k.n_rows();
        let dim = cloud.dim;
        let quad = order == Order::Quadratic;
        let target: Vec<Mom> = (0..n)
            .map(|i| {
                let mut t = Mom::zeros();
                if quad {
                    let s = cloud.horizon[i];
                    for a in 0..dim {
                        t[3 + a] = 2.0 * conductivity[i] * cloud.volume[i] / (s * s);
                    }
                }
                t
            })
            .collect();
        let mut p = Problem {
            cloud,
            offsets: &k.offsets,
            cols: &k.cols,
            k0: k.vals.clone(),
            sel: sel[..n].to_vec(),
            used: used_components(dim, order),
            target,
            unit: Vec::new(),
            factor_room,
        };
        // unit of node i: its diagonal target second moment, or (linear) the present one
        p.unit = (0..n)
            .map(|i| {
                let s2 = cloud.horizon[i] * cloud.horizon[i];
                let present: Real = (k.offsets[i]..k.offsets[i + 1])
                    .map(|e| {
                        p.k0[e] * (cloud.pos[k.cols[e] as usize] - cloud.pos[i]).norm_squared()
                    })
                    .sum::<Real>()
                    / (s2 * dim as Real);
                let u = if quad { p.target[i][3] } else { present };
                if u > 0.0 && p.sel[i] {
                    u
                } else {
                    Real::INFINITY
                }
            })
            .collect();
        p
    }
}

impl<'a> Problem<'a> {
    fn n(&self) -> usize {
        self.sel.len()
    }

    /// The nodes of `among` whose moments for the weights `vals` miss their targets by more
    /// than [`TOLERANCE`] (relative to the node's unit).
    fn missing(&self, vals: &[Real], among: &[bool]) -> Vec<bool> {
        (0..self.n())
            .into_par_iter()
            .map(|i| {
                among[i]
                    && (self.raw_moment(vals, i) - self.target[i]).amax() / self.unit[i] > TOLERANCE
            })
            .collect()
    }

    /// The problem on the nodes `active` alone: every pair that touches a node of `full`
    /// outside `active` is held at K (its K' is zero here and its moments move into the
    /// targets of the active nodes), so those nodes keep their moments exactly.
    fn restricted(&self, active: &[bool], full: &[bool]) -> Problem<'a> {
        let n = self.n();
        let held = |i: usize| i < n && full[i] && !active[i];
        let mut k0 = self.k0.clone();
        let mut target = self.target.clone();
        for i in 0..n {
            for e in self.offsets[i]..self.offsets[i + 1] {
                let j = self.cols[e] as usize;
                if held(i) || held(j) {
                    if active[i] {
                        target[i] -= self.k0[e] * self.phis(i, j).0;
                    }
                    k0[e] = 0.0;
                }
            }
        }
        Problem {
            cloud: self.cloud,
            offsets: self.offsets,
            cols: self.cols,
            k0,
            sel: active.to_vec(),
            used: self.used,
            target,
            unit: self.unit.clone(),
            factor_room: self.factor_room,
        }
    }

    /// The nodes of `within` at most `hops` neighbour rings (rows of K) from a node of `seeds`.
    fn rings(&self, seeds: &[bool], hops: usize, within: &[bool]) -> Vec<bool> {
        let n = self.n();
        let mut reached = seeds.to_vec();
        let mut front: Vec<usize> = (0..n).filter(|&i| seeds[i]).collect();
        for _ in 0..hops {
            let mut next = Vec::new();
            for &i in &front {
                for e in self.offsets[i]..self.offsets[i + 1] {
                    let j = self.cols[e] as usize;
                    if j < n && !reached[j] {
                        reached[j] = true;
                        next.push(j);
                    }
                }
            }
            if next.is_empty() {
                break;
            }
            front = next;
        }
        reached.iter().zip(within).map(|(r, w)| *r && *w).collect()
    }

    fn lam<'b>(&self, lambda: &'b [Mom], j: usize) -> Option<&'b Mom> {
        (j < self.n() && self.sel[j]).then(|| &lambda[j])
    }

    /// Bond vector ξ_ij and the two scaled moment vectors φ_i(ξ_ij), φ_j(ξ_ji).
    #[inline(always)]
    fn phis(&self, i: usize, j: usize) -> (Mom, Mom) {
        let c = self.cloud;
        let xi = c.pos[j] - c.pos[i];
        (
            phi(&xi, c.horizon[i], &self.used),
            phi(&-xi, c.horizon[j], &self.used),
        )
    }

    /// Exponent of pair (i, j), the same bits in rows i and j (the smaller index first).
    #[inline(always)]
    fn exponent(&self, lambda: &[Mom], i: usize, j: usize) -> Real {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        let (pa, pb) = self.phis(a, b);
        let ga = self.lam(lambda, a).map_or(0.0, |l| l.dot(&pa));
        let gb = self.lam(lambda, b).map_or(0.0, |l| l.dot(&pb));
        ga + gb
    }

    /// K'(λ) into `vals`, rows in parallel.
    fn weights(&self, lambda: &[Mom], vals: &mut [Real]) {
        let off = self.offsets;
        let mut rows: Vec<(usize, &mut [Real])> = Vec::with_capacity(self.n());
        let mut rest = vals;
        for i in 0..self.n() {
            let (a, b) = std::mem::take(&mut rest).split_at_mut(off[i + 1] - off[i]);
            rows.push((i, a));
            rest = b;
        }
        rows.into_par_iter().with_min_len(256).for_each(|(i, row)| {
            for (v, e) in row.iter_mut().zip(off[i]..off[i + 1]) {
                let j = self.cols[e] as usize;
                // a held pair stays 0 (never 0·∞ where λ has run off at a node without a solution)
                *v = if self.k0[e] == 0.0 {
                    0.0
                } else {
                    self.k0[e] * self.exponent(lambda, i, j).exp()
                };
            }
        });
    }

    /// The dual objective D(λ) = Σ_pairs K'_ij − Σ_i λ_i·t_i for the weights `vals`.
    fn dual(&self, lambda: &[Mom], vals: &[Real]) -> Real {
        let n = self.n();
        crate::math::ordered_sum(n, |i| {
            let mut s = 0.0;
            for e in self.offsets[i]..self.offsets[i + 1] {
                // pairs of two body nodes appear in both rows
                let half = if (self.cols[e] as usize) < n {
                    0.5
                } else {
                    1.0
                };
                s += half * vals[e];
            }
            s - self.lam(lambda, i).map_or(0.0, |l| l.dot(&self.target[i]))
        })
    }

    /// Moment residual r_i = Σ_j K'_ij φ_i(ξ_ij) − t_i at the selected nodes (0 elsewhere).
    fn residual(&self, vals: &[Real]) -> Vec<Mom> {
        (0..self.n())
            .into_par_iter()
            .map(|i| {
                if !self.sel[i] {
                    return Mom::zeros();
                }
                self.raw_moment(vals, i) - self.target[i]
            })
            .collect()
    }

    /// Σ_j K_ij φ_i(ξ_ij) for the weights `vals`.
    fn raw_moment(&self, vals: &[Real], i: usize) -> Mom {
        let mut m = Mom::zeros();
        for e in self.offsets[i]..self.offsets[i + 1] {
            let (pi, _) = self.phis(i, self.cols[e] as usize);
            m += vals[e] * pi;
        }
        m
    }

    /// Largest |r_i| component relative to the node's unit, over the selected nodes.
    fn worst(&self, res: &[Mom]) -> Real {
        res.par_iter()
            .zip(&self.unit)
            .map(|(r, u)| r.amax() / u)
            .reduce(|| 0.0, Real::max)
    }

    /// y = H v, the Hessian of D: (H v)_i = Σ_j K'_ij φ_i (φ_i·v_i + φ_j·v_j), with `bare`
    /// scratch of one moment vector per body node.
    ///
    /// φ_i(ξ) is the monomial vector q(ξ) = (ξ, vech ξξᵀ) scaled by node i's horizon, and
    /// φ_j(ξ_ji) is q(−ξ) scaled by node j's, so the scales move onto the nodes: v_j / scale_j
    /// once per node (`bare`), then per pair only q(ξ), two dot products and one update.
    fn hessian(&self, vals: &[Real], v: &[Mom], bare: &mut [Mom], y: &mut [Mom]) {
        let c = self.cloud;
        bare.par_iter_mut().enumerate().for_each(|(j, b)| {
            *b = match self.lam(v, j) {
                Some(vj) => self.unscaled(vj, c.horizon[j]),
                None => Mom::zeros(),
            };
        });
        let bare = &*bare;
        y.par_iter_mut().enumerate().for_each(|(i, yi)| {
            *yi = Mom::zeros();
            if !self.sel[i] {
                return;
            }
            let mut acc = Mom::zeros();
            for e in self.offsets[i]..self.offsets[i + 1] {
                let j = self.cols[e] as usize;
                let q = monomials(&(c.pos[j] - c.pos[i]));
                let mut s = q.dot(&bare[i]);
                if j < self.n() {
                    let bj = &bare[j];
                    s += q.fixed_rows::<6>(3).dot(&bj.fixed_rows::<6>(3))
                        - q.fixed_rows::<3>(0).dot(&bj.fixed_rows::<3>(0));
                }
                acc += (vals[e] * s) * q;
            }
            *yi = self.unscaled(&acc, c.horizon[i]);
        });
    }

    /// `m` with its first-moment part divided by `s` and its second-moment part by s²,
    /// masked to the used components: φ(ξ, s)·v = q(ξ)·unscaled(v, s).
    #[inline(always)]
    fn unscaled(&self, m: &Mom, s: Real) -> Mom {
        let (a, b) = (1.0 / s, 1.0 / (s * s));
        Mom::from_fn(|k, _| m[k] * if k < 3 { a } else { b }).component_mul(&self.used)
    }

    /// Inverse diagonal blocks of H (identity on unused components and unselected nodes).
    fn preconditioner(&self, vals: &[Real]) -> Vec<Block> {
        (0..self.n())
            .into_par_iter()
            .map(|i| {
                let mut b = Block::zeros();
                if self.sel[i] {
                    for e in self.offsets[i]..self.offsets[i + 1] {
                        let (pi, _) = self.phis(i, self.cols[e] as usize);
                        b += vals[e] * pi * pi.transpose();
                    }
                }
                for c in 0..NC {
                    if self.used[c] == 0.0 || !self.sel[i] {
                        b[(c, c)] = 1.0;
                    }
                }
                match b.cholesky() {
                    Some(ch) => ch.inverse(),
                    None => {
                        Block::from_diagonal(&b.diagonal().map(
                            |d| {
                                if d > 0.0 {
                                    1.0 / d
                                } else {
                                    1.0
                                }
                            },
                        ))
                    }
                }
            })
            .collect()
    }
}

fn dot(a: &[Mom], b: &[Mom]) -> Real {
    crate::math::ordered_sum(a.len(), |i| a[i].dot(&b[i]))
}

/// The preconditioner of the Newton systems.
enum Precond<'a> {
    /// A Cholesky factor of H at earlier weights.
    Direct(&'a mut direct::Direct),
    /// Block Jacobi plus the aggregates' null modes.
    TwoLevel(Vec<Block>, Box<Option<coarse::Coarse>>),
}

impl Precond<'_> {
    /// z = M⁻¹ r.
    fn apply(&mut self, r: &[Mom], z: &mut [Mom]) {
        match self {
            Precond::Direct(d) => d.solve(r, z),
            Precond::TwoLevel(m, coarse) => {
                z.par_iter_mut()
                    .zip(r)
                    .zip(&*m)
                    .for_each(|((z, r), m)| *z = m * r);
                if let Some(c) = coarse.as_mut() {
                    c.apply(r, z);
                }
            }
        }
    }
}

/// CG iterations preconditioned by an old factor of H beyond which it is factorised anew.
const REFACTOR_AFTER: usize = 25;

/// Solves H x = b by preconditioned CG to `rel` of |b|; returns the iterations.
fn solve(
    p: &Problem,
    vals: &[Real],
    b: &[Mom],
    x: &mut [Mom],
    pre: &mut Precond,
    rel: Real,
) -> usize {
    // a factor of H at earlier weights that needs more than this is refreshed by the caller
    let cap = match pre {
        Precond::Direct(_) => 2 * REFACTOR_AFTER,
        Precond::TwoLevel(..) => 20_000,
    };
    let precondition = |r: &[Mom], z: &mut Vec<Mom>, pre: &mut Precond| pre.apply(r, z);
    x.iter_mut().for_each(|v| *v = Mom::zeros());
    let norm_b = dot(b, b).sqrt();
    if norm_b == 0.0 {
        return 0;
    }
    let mut r = b.to_vec();
    let mut z = vec![Mom::zeros(); b.len()];
    precondition(&r, &mut z, pre);
    let mut d = z.clone();
    let mut hd = vec![Mom::zeros(); b.len()];
    let mut bare = vec![Mom::zeros(); b.len()];
    let mut rz = dot(&r, &z);
    let mut it = 0;
    while it < cap && dot(&r, &r).sqrt() > rel * norm_b {
        p.hessian(vals, &d, &mut bare, &mut hd);
        let dhd = dot(&d, &hd);
        if dhd.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            break;
        }
        let alpha = rz / dhd;
        x.par_iter_mut().zip(&d).for_each(|(x, d)| *x += alpha * d);
        r.par_iter_mut().zip(&hd).for_each(|(r, h)| *r -= alpha * h);
        precondition(&r, &mut z, pre);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        d.par_iter_mut()
            .zip(&z)
            .for_each(|(d, z)| *d = z + beta * *d);
        it += 1;
    }
    it
}

/// Newton iterations over which the worst residual must halve once it is below
/// [`STALL_LEVEL`], or the round ends (a node without a positive solution drives its λ to
/// infinity and the residual stalls, where Newton otherwise converges quadratically).
const STALL_WINDOW: usize = 8;
/// Worst relative residual below which Newton is in its fast phase (far from the solution
/// the residual may grow for a few damped steps).
const STALL_LEVEL: Real = 1e-3;

/// Whether the last [`STALL_WINDOW`] Newton iterations failed to halve the worst residual.
fn stalled(history: &[Real]) -> bool {
    let n = history.len();
    n > STALL_WINDOW
        && history[n - 1] < STALL_LEVEL
        && history[n - 1] > 0.5 * history[n - 1 - STALL_WINDOW]
}

/// The relative residual to which a Newton system is solved at worst moment residual `worst`
/// (inexact Newton): only as accurate as the step can use, 0.1·worst far from the solution
/// (at most 1e-2), and near it no tighter than a step needs to bring the residual, about
/// forcing × worst, to a tenth of [`TOLERANCE`]. A fixed floor of 1e-6 there cost about a
/// quarter of the CG iterations on the unit cube of 36 447 tetrahedral nodes.
fn forcing(worst: Real) -> Real {
    let enough = 0.1 * TOLERANCE / worst;
    (0.1 * worst).clamp(1e-6, 1e-2).max(enough.min(1e-2))
}

/// One round of Newton's method on the dual from `lambda`; returns (Newton, CG) iterations.
fn newton(p: &Problem, lambda: &mut [Mom], vals: &mut [Real]) -> (usize, usize) {
    let n = p.n();
    let (mut newton, mut cg) = (0, 0);
    let mut step = vec![Mom::zeros(); n];
    let mut trial = vec![Mom::zeros(); n];
    let mut trial_vals = vec![0.0; vals.len()];
    let mut direct = direct::Direct::new(p);
    p.weights(lambda, vals);
    let mut d0 = p.dual(lambda, vals);
    let mut history = Vec::with_capacity(MAX_NEWTON);
    for _ in 0..MAX_NEWTON {
        let res = p.residual(vals);
        let worst = p.worst(&res);
        history.push(worst);
        if worst <= TOLERANCE || stalled(&history) {
            break;
        }
        progress::report(progress::Event::Newton {
            step: newton + 1,
            residual: worst,
            iterations: cg,
        });
        let rhs: Vec<Mom> = res.iter().map(|r| -r).collect();
        let forcing = forcing(worst);
        // a factor of H at earlier weights preconditions CG until CG needs many iterations
        let mut it = usize::MAX;
        if let Some(d) = direct.as_mut().filter(|_| newton > 0) {
            it = solve(p, vals, &rhs, &mut step, &mut Precond::Direct(d), forcing);
        }
        if it > REFACTOR_AFTER {
            it = 0;
            let factored = direct.as_mut().is_some_and(|d| d.factorise(p, vals));
            if factored {
                direct.as_mut().expect("factored").solve(&rhs, &mut step);
            } else {
                direct = None;
                let mut pre = Precond::TwoLevel(
                    p.preconditioner(vals),
                    Box::new(coarse::Coarse::new(p, vals)),
                );
                it = solve(p, vals, &rhs, &mut step, &mut pre, forcing);
            }
        }
        cg += it;
        newton += 1;
        // backtracking (Armijo) on the dual along the Newton direction
        let slope = dot(&res, &step);
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            for ((t, l), s) in trial.iter_mut().zip(lambda.iter()).zip(&step) {
                *t = l + alpha * s;
            }
            p.weights(&trial, &mut trial_vals);
            let d1 = p.dual(&trial, &trial_vals);
            // near the optimum the decrease of D is below its round-off: a step that halves
            // the worst moment residual is then taken on that evidence
            let armijo = d1.is_finite() && d1 <= d0 + 1e-4 * alpha * slope;
            if armijo || (d1.is_finite() && p.worst(&p.residual(&trial_vals)) < 0.5 * worst) {
                lambda.copy_from_slice(&trial);
                vals.copy_from_slice(&trial_vals);
                d0 = d1;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    (newton, cg)
}

/// Neighbour rings around the nodes that miss their moments in the first local solve.
const FIRST_HOPS: usize = 3;

/// Directed pairs (entries of K) up to which the whole cloud is solved in one piece instead of
/// locally. A local solve holds every pair outside its band at K, so the band carries the whole
/// correction: on the dual-horizon plate with δ halved across the middle (6 250 nodes,
/// 194 308 pairs) that doubled the largest error at 1 ms against the reference (1.07e-3 against
/// 5.57e-4 °C). Above it the local solve is kept for its cost: on the thermal-shock plate with
/// the horizon doubled (2.2·10⁷ pairs) the whole solve took 253 s and 10.7 GB against 19 s and
/// 1.9 GB.
pub const WHOLE_PAIRS: usize = 1_000_000;

/// Corrects `k` in place so that the body nodes with `sel[i]` meet the moments of `order`
/// (see the module documentation); `conductivity[i]` is the k_i of node i's target, W/(m·K).
/// Returns what was achieved and which body nodes now meet their moments.
///
/// On a cloud of at most [`WHOLE_PAIRS`] pairs every selected node takes part. On a larger one
/// the solve is local: only the pairs among the nodes that miss their moments and a few
/// rings of neighbours around them change (on a lattice with a change of horizon, a band
/// along the change; on a mesh, every node). Every pair that touches a selected node outside
/// that set keeps K, so those nodes keep their exact moments; where the band is too narrow
/// for a solution, it grows (twice the rings) and the solve starts again from K.
pub fn correct(
    k: &mut Conductance,
    cloud: &Cloud,
    sel: &[bool],
    conductivity: &[Real],
    order: Order,
) -> (Consistency, Vec<bool>) {
    let room = direct::machine_room();
    correct_within(k, cloud, sel, conductivity, order, room)
}

/// [`correct`], first looking in `store` for the weights of the same problem ([`store::key`])
/// and keeping them there once solved; the weights are the same bits either way.
pub fn correct_reusing(
    k: &mut Conductance,
    cloud: &Cloud,
    sel: &[bool],
    conductivity: &[Real],
    order: Order,
    store: Option<&dyn store::Store>,
) -> (Consistency, Vec<bool>) {
    let Some(store) = store else {
        return correct(k, cloud, sel, conductivity, order);
    };
    let key = store::key(k, cloud, sel, conductivity, order);
    if let Some(found) = load(k, &key, store) {
        return found;
    }
    let (summary, met) = correct(k, cloud, sel, conductivity, order);
    let solved = store::SolvedRef {
        vals: &k.vals,
        met: &met,
        summary: &summary,
    };
    store.save(&key, solved);
    (summary, met)
}

/// The weights of the problem of [`correct`] loaded from `store` into `k`, or None (`k`
/// unchanged, nothing solved) when the store does not hold them: what `peritherm check` does.
pub fn correct_stored(
    k: &mut Conductance,
    cloud: &Cloud,
    sel: &[bool],
    conductivity: &[Real],
    order: Order,
    store: &dyn store::Store,
) -> Option<(Consistency, Vec<bool>)> {
    load(k, &store::key(k, cloud, sel, conductivity, order), store)
}

/// The weights kept under `key` loaded into `k`, with their summary (marked reused).
fn load(
    k: &mut Conductance,
    key: &store::Key,
    store: &dyn store::Store,
) -> Option<(Consistency, Vec<bool>)> {
    let found = store.load(key, k.vals.len(), k.n_rows())?;
    progress::report(progress::Event::WeightsLoaded);
    store_vals(k, found.vals);
    let summary = Consistency {
        reused: true,
        ..found.summary
    };
    Some((summary, found.met))
}

/// [`correct`] with `factor_room` bytes for a direct factorisation of the Newton matrix
/// (None: no limit); a factor that would not fit is left to CG, which reaches the same
/// weights more slowly.
pub fn correct_within(
    k: &mut Conductance,
    cloud: &Cloud,
    sel: &[bool],
    conductivity: &[Real],
    order: Order,
    factor_room: Option<Real>,
) -> (Consistency, Vec<bool>) {
    let whole_cloud = k.vals.len() <= WHOLE_PAIRS;
    let mut p = Problem::new(k, cloud, sel, conductivity, order, factor_room);
    let mut out = Consistency {
        before: p.worst(&p.residual(&p.k0)),
        min_ratio: 1.0,
        max_ratio: 1.0,
        ..Default::default()
    };
    if out.before <= TOLERANCE {
        // already consistent (a lattice without a horizon change): K stays as it is, bit for bit
        let vals = p.k0.clone();
        summarise(&p, &vals, &[], &mut out);
        return (out, p.sel);
    }
    let full = p.sel.clone();
    progress::report(progress::Event::WeightsStart {
        nodes: full.iter().filter(|&&s| s).count(),
        pairs: k.vals.len(),
    });
    let seeds = p.missing(&p.k0, &full);
    let mut hops = FIRST_HOPS;
    let (vals, left_out) = loop {
        let active = if whole_cloud {
            full.clone()
        } else {
            p.rings(&seeds, hops, &full)
        };
        let whole = active == full;
        let (vals, left_out) = solve_piece(&p, &active, &full, order, &mut out);
        if whole || !left_out.contains(&true) {
            break (vals, left_out);
        }
        hops *= 2;
    };
    for i in 0..full.len() {
        p.sel[i] = full[i] && !left_out[i];
    }
    summarise(&p, &vals, &left_out, &mut out);
    let sel = p.sel;
    store_vals(k, vals);
    (out, sel)
}

/// The weights with the pairs among `active` solved for in one piece (the others keep
/// theirs), and the nodes left out.
fn solve_piece(
    p: &Problem,
    active: &[bool],
    full: &[bool],
    order: Order,
    out: &mut Consistency,
) -> (Vec<Real>, Vec<bool>) {
    let mut local = p.restricted(active, full);
    let (mut vals, left_out) = solve_selection(&mut local, order, out);
    // the pairs held fixed come back
    for (v, (k0, l)) in vals.iter_mut().zip(p.k0.iter().zip(&local.k0)) {
        if *l == 0.0 {
            *v = *k0;
        }
    }
    (vals, left_out)
}

/// The corrected weights for the nodes `p.sel` (the additive form first for the linear order,
/// else rounds of Newton that leave out nodes without a solution), and the nodes left out.
fn solve_selection(p: &mut Problem, order: Order, out: &mut Consistency) -> (Vec<Real>, Vec<bool>) {
    let n = p.n();
    if order == Order::Linear {
        if let Some((vals, it)) = additive::linear(p) {
            if p.worst(&p.residual(&vals)) <= TOLERANCE {
                out.iterations += it;
                return (vals, vec![false; n]);
            }
        }
    }
    let mut lambda = vec![Mom::zeros(); n];
    let mut vals = p.k0.clone();
    let mut left_out = vec![false; n];
    for round in 0..MAX_ROUNDS {
        let (nw, cg) = newton(p, &mut lambda, &mut vals);
        out.newton += nw;
        out.iterations += cg;
        let res = p.residual(&vals);
        let bad: Vec<usize> = (0..n)
            .filter(|&i| p.sel[i] && res[i].amax() / p.unit[i] > TOLERANCE)
            .collect();
        if bad.is_empty() || round + 1 == MAX_ROUNDS {
            break;
        }
        // nodes that admit no positive symmetric solution drive their λ to infinity: leave
        // out the ones still far from their moments and start again from λ = 0
        let cut = bad
            .iter()
            .map(|&i| res[i].amax() / p.unit[i])
            .fold(0.0, Real::max)
            * 1e-3;
        for &i in &bad {
            if res[i].amax() / p.unit[i] >= cut.max(TOLERANCE) {
                p.sel[i] = false;
                left_out[i] = true;
            }
        }
        lambda.iter_mut().for_each(|l| *l = Mom::zeros());
    }
    (vals, left_out)
}

/// Stores the pair conductances `vals` in `k` with their row sums.
fn store_vals(k: &mut Conductance, vals: Vec<Real>) {
    k.vals = vals;
    for i in 0..k.n_rows() {
        k.diag[i] = k.vals[k.offsets[i]..k.offsets[i + 1]].iter().sum();
    }
}

/// Fills the counts, errors and ratios of `out` from the final weights.
fn summarise(p: &Problem, vals: &[Real], left_out: &[bool], out: &mut Consistency) {
    let res = p.residual(vals);
    out.after = p.worst(&res);
    out.corrected = p.sel.iter().filter(|&&s| s).count();
    let mut worst = 0.0;
    for (i, &l) in left_out.iter().enumerate() {
        if l {
            out.uncorrected += 1;
            let m = p.raw_moment(vals, i) - p.target[i];
            worst = Real::max(worst, m.amax() / p.unit[i]);
        }
    }
    out.worst_uncorrected = worst;
    for (v, k0) in vals.iter().zip(&p.k0) {
        if *k0 > 0.0 {
            out.min_ratio = out.min_ratio.min(v / k0);
            out.max_ratio = out.max_ratio.max(v / k0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Far from the solution a tenth of the residual (at most 1e-2); near it just enough for one
    /// step to bring the residual to a tenth of [`TOLERANCE`].
    #[test]
    fn forcing_is_as_tight_as_the_step_needs() {
        assert_eq!(forcing(1.0), 1e-2);
        assert!((forcing(1e-3) - 1e-4).abs() <= 1e-4 * 1e-12);
        for worst in [1e-6, 3.5e-9] {
            let next = forcing(worst) * worst;
            assert!(
                (next - 0.1 * TOLERANCE).abs() <= 1e-12 * TOLERANCE,
                "{worst}: {next}"
            );
        }
        assert_eq!(forcing(0.5 * TOLERANCE), 1e-2);
    }
}
