//! Implicit steps over ranks ([`Implicit::distribute`]): each rank steps the unknowns of its
//! own rows, and every linear system is solved by conjugate gradients whose matrix–vector
//! products read the ghosts' values through the halo, preconditioned by block Jacobi (each
//! rank's diagonal block of cM + A factorised by sparse Cholesky, one factor per c), with
//! every dot product and norm reduced over the ranks ([`Collective::reduce`]).
//!
//! A distributed solve needs a symmetric A: the pairs between ranks are compared by
//! [`cross_asymmetry`] at set-up. It is iterated to [`DISTRIBUTED_CG_TOLERANCE`], close to
//! round-off, so that the fields agree with a serial direct solve to about 1e-12 relative.

use super::linear::{keep, llt_values, shifted_into, slot_of, Guess, LinearError};
use super::{Implicit, System};
use crate::error::Result;
use crate::model::Model;
use crate::solve::exchange::{swap_values, Collective, Exchange, Reduce};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::{Conj, MatMut, Par, Side};
use std::ops::Range;

/// Relative residual ‖b − Bx‖₂/‖b‖₂ at which a distributed CG solve stops: round-off, so that
/// a distributed run agrees with a serial direct solve to about 1e-12 relative. Where
/// round-off keeps the residual above it, the solve stops once the residual has not fallen
/// for [`DISTRIBUTED_CG_STALL`] iterations.
pub const DISTRIBUTED_CG_TOLERANCE: f64 = 1e-15;

/// Iterations without a smaller residual after which a distributed CG solve has reached
/// round-off and stops.
pub const DISTRIBUTED_CG_STALL: u64 = 8;

/// Iterations after which a distributed CG solve that has not reached its tolerance is
/// refused ([`LinearError::CgDiverged`]).
const MAX_ITERATIONS: u64 = 20_000;

/// What one rank of a distributed implicit run holds beyond the serial stepper.
pub(super) struct Ranks<'a> {
    /// The other ranks.
    exchange: &'a dyn Exchange,
    /// Every node's value as last sent or received (model numbering).
    field: Vec<f64>,
    /// Unknowns read from other ranks, with their nodes.
    ghosts: Vec<(usize, usize)>,
    /// This rank's diagonal block of A (CSR over the own unknowns, from 0).
    block: System,
    /// Symbolic Cholesky of the block (AMD ordering).
    symbolic: SymbolicCholesky<usize>,
    /// Factors of cM + A on the block by coefficient c (at most two).
    factors: Vec<(f64, Vec<f64>)>,
    /// Scratch of the block's factorisations and solves.
    stack: MemBuffer,
}

impl<'a> Implicit<'a> {
    /// Makes this stepper one rank of a distributed run over `exchange`: it steps the unknowns
    /// of the rank's rows and solves by distributed block-Jacobi CG. Returns false when there
    /// is one rank, and when A is not symmetric over the ranks (its asymmetry is then the one
    /// measured over all ranks; every rank must step the whole model, which needs the whole
    /// model: see [`crate::model::Model::rows`]). Collective.
    pub fn distribute(&mut self, exchange: &'a dyn Exchange) -> Result<bool> {
        if exchange.size() == 1 {
            // one rank holds the whole model: the serial solvers serve it best
            return Ok(false);
        }
        let rows = exchange.rows();
        let free = &self.sys.free;
        let own =
            free.partition_point(|&i| i < rows.start)..free.partition_point(|&i| i < rows.end);
        // a whole model's system measured every pair already; a share's compares with the
        // other ranks' rows
        let whole = self.sys.held == (0..self.sys.len());
        let asymmetry = match whole {
            true => self.sys.asymmetry,
            false => cross_asymmetry(&self.sys, &own, exchange),
        };
        if asymmetry > super::SYMMETRY_TOLERANCE {
            self.sys.asymmetry = asymmetry;
            self.sys.symmetric = false;
            return Ok(false);
        }
        let ghosts = ghosts_of(&self.sys, &own);
        let block = block_of(&self.sys, &own);
        let symbolic = factorize_symbolic_cholesky(
            block.pattern(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| LinearError::SymbolicCholesky(format!("{e:?}")))?;
        let stack = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, self.par));
        self.sys.held = own;
        self.chol = None;
        self.lu = None;
        self.factors.clear();
        self.stats.factor_entries = symbolic.len_val();
        self.ranks = Some(Ranks {
            exchange,
            field: vec![0.0; self.model.cloud.len()],
            ghosts,
            block,
            symbolic,
            factors: Vec::new(),
            stack,
        });
        Ok(true)
    }

    /// The unknowns this stepper computes: all, or a rank's.
    pub(super) fn own(&self) -> Range<usize> {
        self.sys.held.clone()
    }

    /// Sets the ghost entries of `x` (one of the unknown vectors) from their owners.
    pub(super) fn halo_of(ranks: &mut Option<Ranks>, sys: &System, x: &mut [f64]) {
        let Some(r) = ranks else {
            return;
        };
        for k in sys.held.clone() {
            r.field[sys.free[k]] = x[k];
        }
        r.exchange.halo(&mut r.field);
        for &(k, node) in &r.ghosts {
            x[k] = r.field[node];
        }
    }

    /// `Σ a·b` over this stepper's unknowns, summed over the ranks.
    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let own = self.own();
        let s: f64 = a[own.clone()].iter().zip(&b[own]).map(|(x, y)| x * y).sum();
        match &self.ranks {
            Some(r) => r.exchange.reduce(s, Reduce::Sum),
            None => s,
        }
    }

    /// Solves `(cM + A) x = rhs` over the ranks by block-Jacobi CG; x replaces the own entries
    /// of `rhs`. Returns the iterations.
    pub(super) fn distributed_pcg(&mut self, c: f64, guess: Guess) -> Result<u64> {
        let mut cg = std::mem::take(&mut self.cg);
        let mut rhs = std::mem::take(&mut self.rhs);
        let done = self.pcg_with(c, guess, &mut cg, &mut rhs);
        let own = self.own();
        if done.is_ok() {
            rhs[own.clone()].copy_from_slice(&cg[0][own]);
        }
        self.cg = cg;
        self.rhs = rhs;
        done
    }

    /// The iterations of [`Implicit::distributed_pcg`] on the buffers `[x, r, z, p]` and
    /// `b` (overwritten as the product buffer once r is formed).
    fn pcg_with(
        &mut self,
        c: f64,
        guess: Guess,
        cg: &mut [Vec<f64>; 4],
        b: &mut [f64],
    ) -> Result<u64> {
        let own = self.own();
        let [x, r, z, p] = cg;
        match guess {
            Guess::U => x[own.clone()].copy_from_slice(&self.u[own.clone()]),
            Guess::Zero => x[own.clone()].fill(0.0),
            Guess::Preset => {}
        }
        Self::halo_of(&mut self.ranks, &self.sys, x);
        // r = b − (cM + A) x, combine giving −(cM + A) x
        self.sys.combine(-c, 1.0, x, r, self.options.parallel);
        for k in own.clone() {
            r[k] += b[k];
        }
        let tol = DISTRIBUTED_CG_TOLERANCE * self.dot(b, b).sqrt();
        self.precondition(c, r, z)?;
        p[own.clone()].copy_from_slice(&z[own.clone()]);
        let mut rz = self.dot(r, z);
        let q = b;
        let mut its = 0u64;
        let (mut best, mut best_at) = (f64::INFINITY, 0);
        loop {
            let rr = self.dot(r, r).sqrt();
            if rr < best {
                (best, best_at) = (rr, its);
            }
            if rr <= tol || its - best_at >= DISTRIBUTED_CG_STALL {
                return Ok(its);
            }
            if its >= MAX_ITERATIONS || !rr.is_finite() {
                return Err(LinearError::CgDiverged { iterations: its }.into());
            }
            Self::halo_of(&mut self.ranks, &self.sys, p);
            self.sys.combine(-c, 1.0, p, q, self.options.parallel);
            for v in &mut q[own.clone()] {
                *v = -*v;
            }
            let alpha = rz / self.dot(p, q);
            for k in own.clone() {
                x[k] += alpha * p[k];
                r[k] -= alpha * q[k];
            }
            self.precondition(c, r, z)?;
            let rz_new = self.dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            for k in own.clone() {
                p[k] = z[k] + beta * p[k];
            }
            its += 1;
        }
    }

    /// `z = B⁻¹ r` on this rank's unknowns, B the rank's diagonal block of cM + A.
    fn precondition(&mut self, c: f64, r: &[f64], z: &mut [f64]) -> Result<()> {
        let own = self.own();
        let par = self.par;
        let ranks = self.ranks.as_mut().expect("a distributed stepper");
        let started = std::time::Instant::now();
        let (slot, new) = ranks.factor(c, par)?;
        if new {
            self.stats.factorisations += 1;
            self.stats.factor_seconds += started.elapsed().as_secs_f64();
        }
        let z = &mut z[own.clone()];
        z.copy_from_slice(&r[own]);
        let n = z.len();
        LltRef::new(&ranks.symbolic, &ranks.factors[slot].1).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(z, n, 1),
            par,
            MemStack::new(&mut ranks.stack),
        );
        Ok(())
    }
}

impl<'a> Ranks<'a> {
    /// The other ranks.
    pub(super) fn exchange(&self) -> &'a dyn Exchange {
        self.exchange
    }

    /// The slot of the block's factor of cM + A, and whether it was factorised now (not
    /// cached).
    fn factor(&mut self, c: f64, par: Par) -> Result<(usize, bool)> {
        if let Some(p) = slot_of(&self.factors, c) {
            return Ok((p, false));
        }
        let mut vals = vec![0.0; self.block.vals.len()];
        shifted_into(&self.block, c, &mut vals);
        let values = llt_values(&self.symbolic, &self.block, &vals, c, par)?;
        Ok((keep(&mut self.factors, c, values), true))
    }
}

/// Whether the implicit system of `model`, one rank's share of `link`'s ranks, is symmetric
/// over all ranks (each rank's entries towards another's compared with that rank's
/// transposed ones), so that [`Implicit::distribute`] can solve it.
/// Collective.
pub fn symmetric_over(model: &Model, link: &dyn Collective) -> Result<bool> {
    let sys = System::build(model)?;
    let own = sys.held.clone();
    Ok(cross_asymmetry(&sys, &own, link) <= super::SYMMETRY_TOLERANCE)
}

/// The largest |A_rc − A_cr| over the pairs of this rank's rows `own` with other ranks'
/// rows and the pairs within `own`, over the largest diagonal entry, the same on every rank:
/// each rank sends its entries towards every other rank's unknowns to that rank, which
/// compares them with its own transposed entries. Collective.
pub(super) fn cross_asymmetry(sys: &System, own: &Range<usize>, link: &dyn Collective) -> f64 {
    let partition = &rank_ends(own, link);
    let owner = |k: usize| partition.partition_point(|&end| end <= k);
    let mut lists: Vec<(usize, Vec<f64>)> = Vec::new();
    let mut asym: f64 = 0.0;
    for r in own.clone() {
        for e in sys.offsets[r]..sys.offsets[r + 1] {
            let c = sys.cols[e];
            if own.contains(&c) {
                asym = asym.max((sys.vals[e] - sys.get(c, r)).abs());
                continue;
            }
            let to = owner(c);
            match lists.iter_mut().find(|(q, _)| *q == to) {
                Some((_, l)) => l.extend([r as f64, c as f64, sys.vals[e]]),
                None => lists.push((to, vec![r as f64, c as f64, sys.vals[e]])),
            }
        }
    }
    for (_, got) in swap_values(link, &lists) {
        for t in got.chunks_exact(3) {
            let (r, c) = (t[0] as usize, t[1] as usize);
            asym = asym.max((t[2] - sys.get(c, r)).abs());
        }
    }
    let scale = sys.diagonal_max(own);
    let asym = link.reduce(asym, Reduce::Max);
    let scale = link.reduce(scale, Reduce::Max);
    if scale > 0.0 {
        asym / scale
    } else {
        0.0
    }
}

/// The end of every rank's unknowns, in rank order (each rank's `own.end`, gathered).
fn rank_ends(own: &Range<usize>, link: &dyn Collective) -> Vec<usize> {
    let ends = link.gather_counts(own.end as u64);
    ends.into_iter().map(|e| e as usize).collect()
}

/// The unknowns outside `own` that the rows of `own` read, with their nodes.
fn ghosts_of(sys: &System, own: &Range<usize>) -> Vec<(usize, usize)> {
    let mut ghosts: Vec<usize> = (sys.offsets[own.start]..sys.offsets[own.end])
        .map(|e| sys.cols[e])
        .filter(|c| !own.contains(c))
        .collect();
    ghosts.sort_unstable();
    ghosts.dedup();
    ghosts.into_iter().map(|k| (k, sys.free[k])).collect()
}

/// The diagonal block of `sys` on `own` as a system of its own (unknowns from 0).
fn block_of(sys: &System, own: &Range<usize>) -> System {
    let mut block = System::empty();
    block.free = sys.free[own.clone()].to_vec();
    block.mass = sys.mass[own.clone()].to_vec();
    block.offsets.push(0);
    for r in own.clone() {
        for e in sys.offsets[r]..sys.offsets[r + 1] {
            let c = sys.cols[e];
            if own.contains(&c) {
                if c == r {
                    block.diag_pos.push(block.cols.len());
                }
                block.cols.push(c - own.start);
                block.vals.push(sys.vals[e]);
            }
        }
        block.offsets.push(block.cols.len());
    }
    block.held = 0..block.free.len();
    block
}
