//! Linear solvers of `(cM + A) x = b`: sparse Cholesky or LU (faer), Jacobi-preconditioned
//! conjugate gradients, and the ski-rental choice between them ([`Solver::Auto`]).

use super::Implicit;
use super::{nested_dissection, Ordering, System};
use crate::error::{Error, Result};
use crate::model::Model;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::LltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, SymbolicLu};
use faer::sparse::linalg::lu::{LuRef, NumericLu};
use faer::sparse::SparseColMatRef;
use faer::Par;
use faer::{Conj, MatMut, Side};
use std::time::Instant;

/// Linear solver for the implicit systems.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    /// Sparse Cholesky (symmetric A) or sparse LU (nonsymmetric A), factorised once per Δt.
    Direct,
    /// Jacobi-preconditioned conjugate gradients (symmetric A only), warm-started.
    Cg,
    /// Direct, but a coefficient c not factorised yet is solved by Jacobi-PCG until the CG time
    /// spent on it exceeds one factorisation (ski rental; symmetric A, else as `Direct`).
    Auto,
}

/// Settings of the implicit solvers.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Linear solver.
    pub solver: Solver,
    /// Use rayon (products) and faer's parallel kernels; false runs everything serially.
    pub parallel: bool,
    /// Relative residual at which conjugate gradients stop (dimensionless).
    pub cg_tolerance: f64,
    /// Fill-reducing ordering for the Cholesky factor.
    pub ordering: Ordering,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            solver: Solver::Direct,
            parallel: true,
            cg_tolerance: 1e-11,
            ordering: Ordering::NestedDissection,
        }
    }
}

/// A failure of the linear solvers of the implicit and steady schemes (reported as
/// [`Error::Solver`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearError {
    /// The symbolic Cholesky factorisation (ordering, elimination tree) failed.
    #[error("symbolic Cholesky: {0}")]
    SymbolicCholesky(String),
    /// The symbolic LU factorisation failed.
    #[error("symbolic LU: {0}")]
    SymbolicLu(String),
    /// The numeric Cholesky factorisation of `cM + A` failed (c in 1/s).
    #[error("Cholesky factorisation of cM + A (c = {c:e} 1/s) failed ({detail}); the system is singular (steady state of a body no boundary holds?) or not positive definite")]
    Cholesky {
        /// Coefficient c of M, 1/s.
        c: f64,
        /// faer's report.
        detail: String,
    },
    /// The numeric LU factorisation of `cM + A` failed (c in 1/s).
    #[error("LU factorisation of cM + A (c = {c:e} 1/s) failed ({detail}); the system is singular (steady state of a body no boundary holds?)")]
    Lu {
        /// Coefficient c of M, 1/s.
        c: f64,
        /// faer's report.
        detail: String,
    },
    /// A direct solve was asked for without a symbolic factorisation (internal).
    #[error("no symbolic factorisation for the direct solver")]
    NoSymbolic,
    /// Conjugate gradients did not reach their tolerance.
    #[error("conjugate gradients did not converge in {iterations} iterations")]
    CgDiverged {
        /// Iterations taken.
        iterations: u64,
    },
}

impl From<LinearError> for Error {
    fn from(e: LinearError) -> Error {
        Error::Solver {
            message: e.to_string(),
        }
    }
}

/// The symbolic factorisation a solver needs and the scratch memory of its solves: Cholesky
/// for symmetric A (nested dissection or AMD), LU for nonsymmetric A, none for CG.
pub(super) type Symbolic = (
    Option<SymbolicCholesky<usize>>,
    Option<SymbolicLu<usize>>,
    MemBuffer,
);

/// Builds the [`Symbolic`] factorisation of the pattern of A for `options.solver`.
pub(super) fn symbolic(
    sys: &System,
    model: &Model,
    options: &Options,
    par: Par,
) -> Result<Symbolic> {
    let n = sys.len();
    let symbolic = sys.pattern();
    Ok(match options.solver {
        Solver::Cg => (None, None, MemBuffer::new(faer::dyn_stack::StackReq::EMPTY)),
        Solver::Direct | Solver::Auto if sys.symmetric => {
            let (fwd, inv) = match options.ordering {
                Ordering::NestedDissection => nested_dissection(sys, model),
                Ordering::Amd => (Vec::new(), Vec::new()),
            };
            let ordering = match options.ordering {
                Ordering::NestedDissection => {
                    SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n))
                }
                Ordering::Amd => SymmetricOrdering::Amd,
            };
            let s =
                factorize_symbolic_cholesky(symbolic, Side::Lower, ordering, Default::default())
                    .map_err(|e| LinearError::SymbolicCholesky(format!("{e:?}")))?;
            let req = s.solve_in_place_scratch::<f64>(1, par);
            (Some(s), None, MemBuffer::new(req))
        }
        Solver::Direct | Solver::Auto => {
            let s = factorize_symbolic_lu(symbolic, Default::default())
                .map_err(|e| LinearError::SymbolicLu(format!("{e:?}")))?;
            let req = s
                .solve_in_place_scratch::<f64>(1, par)
                .or(s.solve_transpose_in_place_scratch::<f64>(1, par));
            (None, Some(s), MemBuffer::new(req))
        }
    })
}

/// One factorisation of `cM + A`.
pub(super) enum Factor {
    Llt(Vec<f64>),
    Lu(Box<NumericLu<usize, f64>>),
}

/// Initial guess of a conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Guess {
    Zero,
    U,
    /// Already in the first CG buffer.
    Preset,
}

/// Coefficients whose CG work is remembered by [`Solver::Auto`].
pub(super) const RENT_SLOTS: usize = 64;
/// Multiply-adds of a numeric factorisation done in the time of one CG work unit (one stored
/// entry of A read and multiplied): the dense kernels of a supernodal factorisation run at
/// several times the rate of the memory-bound CG loop. Measured on 2 threads: 1.0–1.4e-10 s
/// per multiply-add against 0.9–1.05e-9 s per CG unit on the two bundled adaptive cases
/// (crack plate, thermal shock), a ratio of 7–9.
pub(super) const FACTOR_FLOPS_PER_UNIT: f64 = 8.0;

/// [`Solver::Auto`]'s ledger, counted in work units rather than seconds so that the choice
/// depends on the system alone: the same case takes the same path, and gives the same bits,
/// on any machine, thread count, load or rank.
pub(super) struct Ledger {
    /// Work of one CG iteration: nnz(A) + 6n (product and vector updates).
    iteration: f64,
    /// Work of one direct solve: a forward and a backward sweep over L.
    direct: f64,
    /// Work of one numeric factorisation: its multiply-adds / [`FACTOR_FLOPS_PER_UNIT`].
    factor: f64,
    /// CG work beyond a direct solve's, spent per coefficient c not factorised.
    spent: Vec<(f64, f64)>,
}

impl Ledger {
    /// The costs of CG, direct solves and factorisations of `sys` with the symbolic `chol`.
    pub(super) fn new(sys: &System, chol: Option<&SymbolicCholesky<usize>>) -> Self {
        let n = sys.len() as f64;
        Ledger {
            iteration: sys.vals.len() as f64 + 6.0 * n,
            direct: chol.map_or(0.0, |s| 2.0 * s.len_val() as f64),
            factor: chol.map_or(f64::INFINITY, |s| {
                factor_multiply_adds(s) / FACTOR_FLOPS_PER_UNIT
            }),
            spent: Vec::with_capacity(RENT_SLOTS),
        }
    }

    /// True while the CG work spent on `c` is below one factorisation's (the ski-rental rule:
    /// at most twice the cheaper choice's cost).
    fn rent_cg(&self, c: f64) -> bool {
        let spent = self
            .spent
            .iter()
            .find(|(k, _)| Implicit::same(*k, c))
            .map_or(0.0, |r| r.1);
        spent < self.factor
    }

    /// Adds what `iterations` of CG on coefficient c cost beyond a direct solve.
    fn pay(&mut self, c: f64, iterations: u64) {
        let work = (iterations as f64 * self.iteration - self.direct).max(0.0);
        if let Some(r) = self.spent.iter_mut().find(|(k, _)| Implicit::same(*k, c)) {
            r.1 += work;
            return;
        }
        if self.spent.len() == RENT_SLOTS {
            self.spent.remove(0);
        }
        self.spent.push((c, work));
    }
}

/// Multiply-adds of one numeric Cholesky factorisation with the symbolic structure `s`: per
/// supernode of w columns and h rows below it, w³/6 (its diagonal block) + h·w²/2 (the
/// panel's triangular solve) + h²·w/2 (its update of the rest); per simplicial column of h
/// entries below the diagonal, h²/2 + h.
pub(super) fn factor_multiply_adds(s: &SymbolicCholesky<usize>) -> f64 {
    match s.raw() {
        SymbolicCholeskyRaw::Supernodal(sn) => (0..sn.n_supernodes())
            .map(|k| {
                let w = (sn.supernode_end()[k] - sn.supernode_begin()[k]) as f64;
                let h = sn.supernode(k).pattern().len() as f64;
                w * w * w / 6.0 + h * w * w / 2.0 + h * h * w / 2.0
            })
            .sum(),
        SymbolicCholeskyRaw::Simplicial(sp) => sp
            .col_ptr()
            .windows(2)
            .map(|c| {
                let h = (c[1] - c[0]).saturating_sub(1) as f64;
                h * h / 2.0 + h
            })
            .sum(),
    }
}

/// The values of `cM + A` of `sys` into `vals`: A's entries with c·M_i added on the
/// diagonal, W/K.
pub(super) fn shifted_into(sys: &System, c: f64, vals: &mut [f64]) {
    vals.copy_from_slice(&sys.vals);
    for (r, &p) in sys.diag_pos.iter().enumerate() {
        vals[p] += c * sys.mass[r];
    }
}

/// The numeric Cholesky factor, with the symbolic structure `s`, of the matrix with the CSR
/// arrays of `sys` (symmetric: they are its CSC arrays too) and the values `vals` = cM + A.
pub(super) fn llt_values(
    s: &SymbolicCholesky<usize>,
    sys: &System,
    vals: &[f64],
    c: f64,
    par: Par,
) -> Result<Vec<f64>> {
    let mut values = vec![0.0; s.len_val()];
    let req = s.factorize_numeric_llt_scratch::<f64>(par, Default::default());
    let mut mem = MemBuffer::new(req);
    s.factorize_numeric_llt(
        &mut values,
        SparseColMatRef::new(sys.pattern(), vals),
        Side::Lower,
        LltRegularization::default(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|e| LinearError::Cholesky {
        c,
        detail: format!("{e:?}"),
    })?;
    Ok(values)
}

/// The slot of the factor of coefficient `c` among `slots`, if cached.
pub(super) fn slot_of<T>(slots: &[(f64, T)], c: f64) -> Option<usize> {
    slots.iter().position(|(k, _)| Implicit::same(*k, c))
}

/// Caches `factor` of coefficient `c` in `slots`, which keep the two latest; returns its slot.
pub(super) fn keep<T>(slots: &mut Vec<(f64, T)>, c: f64, factor: T) -> usize {
    if slots.len() == 2 {
        slots.remove(0);
    }
    slots.push((c, factor));
    slots.len() - 1
}

impl Implicit<'_> {
    /// Makes sure a factorisation of `cM + A` is cached; returns its slot.
    pub(super) fn factor(&mut self, c: f64) -> Result<usize> {
        if let Some(p) = slot_of(&self.factors, c) {
            return Ok(p);
        }
        let started = Instant::now();
        let sys = &self.sys;
        shifted_into(sys, c, &mut self.b_vals);
        let factor = if let Some(s) = &self.chol {
            Factor::Llt(llt_values(s, sys, &self.b_vals, c, self.par)?)
        } else if let Some(s) = &self.lu {
            let mut numeric = NumericLu::<usize, f64>::new();
            let req = s.factorize_numeric_lu_scratch::<f64>(self.par, Default::default());
            let mut mem = MemBuffer::new(req);
            s.factorize_numeric_lu(
                &mut numeric,
                SparseColMatRef::new(sys.pattern(), &self.b_vals),
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| LinearError::Lu {
                c,
                detail: format!("{e:?}"),
            })?;
            Factor::Lu(Box::new(numeric))
        } else {
            return Err(LinearError::NoSymbolic.into());
        };
        let slot = keep(&mut self.factors, c, factor);
        self.stats.factorisations += 1;
        self.stats.factor_seconds += started.elapsed().as_secs_f64();
        Ok(slot)
    }

    /// True when `c` matches `k` to 1e-12 relative.
    pub(super) fn same(k: f64, c: f64) -> bool {
        (k - c).abs() <= 1e-12 * c.abs().max(f64::MIN_POSITIVE)
    }

    /// [`Solver::Auto`]: solve with CG while its work on `c` beyond direct solves is below one
    /// factorisation's ([`Ledger`]); a coefficient already factorised is solved directly.
    pub(super) fn use_cg(&self, c: f64) -> bool {
        match self.options.solver {
            Solver::Cg => true,
            Solver::Direct => false,
            Solver::Auto => {
                self.chol.is_some()
                    && !self.factors.iter().any(|(k, _)| Self::same(*k, c))
                    && self.ledger.rent_cg(c)
            }
        }
    }

    /// Solves `(cM + A) x = rhs`: the answer replaces `rhs`; `guess` starts CG.
    pub(super) fn solve(&mut self, c: f64, guess: Guess) -> Result<()> {
        let distributed = self.ranks.is_some();
        if distributed || self.use_cg(c) {
            let started = Instant::now();
            let its = if distributed {
                self.distributed_pcg(c, guess)?
            } else {
                let its = self.pcg(c, guess)?;
                self.ledger.pay(c, its);
                its
            };
            self.stats.cg_iterations += its;
            self.stats.cg_solves += 1;
            self.stats.solves += 1;
            self.stats.solve_seconds += started.elapsed().as_secs_f64();
            return Ok(());
        }
        let slot = self.factor(c)?;
        let started = Instant::now();
        let n = self.sys.len();
        match &self.factors[slot].1 {
            Factor::Llt(values) => {
                let s = self
                    .chol
                    .as_ref()
                    .expect("Cholesky symbolic with its factor");
                LltRef::new(s, values).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut self.rhs, n, 1),
                    self.par,
                    MemStack::new(&mut self.stack),
                );
            }
            Factor::Lu(numeric) => {
                let s = self.lu.as_ref().expect("LU symbolic with its factor");
                // the CSR arrays of A are the CSC arrays of Aᵀ: solve with the transpose
                LuRef::new_unchecked(s, numeric).solve_transpose_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(&mut self.rhs, n, 1),
                    self.par,
                    MemStack::new(&mut self.stack),
                );
            }
        }
        self.stats.solves += 1;
        self.stats.solve_seconds += started.elapsed().as_secs_f64();
        Ok(())
    }

    /// Jacobi-preconditioned CG on `(cM + A) x = rhs`; x replaces `rhs`. Returns iterations.
    pub(super) fn pcg(&mut self, c: f64, guess: Guess) -> Result<u64> {
        let sys = &self.sys;
        let par = self.options.parallel;
        let [x, r, z, p] = &mut self.cg;
        match guess {
            Guess::U => x.copy_from_slice(&self.u),
            Guess::Zero => x.fill(0.0),
            Guess::Preset => {}
        }
        // r = b − B x, with B = cM + A = −(−c M − A)
        sys.combine(-c, 1.0, x, r, par);
        for (ri, bi) in r.iter_mut().zip(&self.rhs) {
            *ri += bi;
        }
        let bnorm = self.rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        // relative residual, or (adaptive runs) ‖r‖₂ ≤ e·c·min M, which bounds the error
        // ‖x − x*‖₂ ≤ ‖r‖₂/λ_min(cM + A) ≤ e since A is positive semi-definite
        let tol = (self.options.cg_tolerance * bnorm.max(f64::MIN_POSITIVE))
            .max(self.cg_error * c * self.min_mass);
        let diag = |k: usize| sys.vals[sys.diag_pos[k]] + c * sys.mass[k];
        for (k, (zi, ri)) in z.iter_mut().zip(r.iter()).enumerate() {
            *zi = ri / diag(k);
        }
        p.copy_from_slice(z);
        let mut rz: f64 = r.iter().zip(z.iter()).map(|(a, b)| a * b).sum();
        let mut its = 0u64;
        let q = &mut self.rhs;
        while r.iter().map(|v| v * v).sum::<f64>().sqrt() > tol {
            if its >= 20_000 {
                return Err(LinearError::CgDiverged { iterations: its }.into());
            }
            sys.combine(-c, 1.0, p, q, par);
            for v in q.iter_mut() {
                *v = -*v;
            }
            let pq: f64 = p.iter().zip(q.iter()).map(|(a, b)| a * b).sum();
            let alpha = rz / pq;
            for k in 0..x.len() {
                x[k] += alpha * p[k];
                r[k] -= alpha * q[k];
                z[k] = r[k] / diag(k);
            }
            let rz_new: f64 = r.iter().zip(z.iter()).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for k in 0..p.len() {
                p[k] = z[k] + beta * p[k];
            }
            its += 1;
        }
        self.rhs.copy_from_slice(x);
        Ok(its)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::SymbolicSparseColMatRef;

    /// A dense SPD pattern of n unknowns factorises in n³/6 + O(n²) multiply-adds, whichever
    /// structure (supernodal or simplicial) faer chooses.
    #[test]
    fn a_dense_factor_costs_a_sixth_of_n_cubed() {
        let n = 60;
        let offsets: Vec<usize> = (0..=n).map(|c| c * n).collect();
        let rows: Vec<usize> = (0..n * n).map(|e| e % n).collect();
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &offsets, None, &rows);
        let s = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Identity,
            Default::default(),
        )
        .unwrap();
        let cube = (n * n * n) as f64 / 6.0;
        let got = factor_multiply_adds(&s);
        // the O(n²) terms are n²/2 + n: within 10 % of n³/6 at n = 60
        assert!((got - cube).abs() <= 0.1 * cube, "{got} against {cube}");
    }
}
