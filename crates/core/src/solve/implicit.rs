//! Implicit time integration (backward Euler, Crank–Nicolson, BDF2) and the steady-state solve
//! of theory §4 (beyond the papers) for linear materials.
//!
//! **The system on the body's free nodes.** Theory §2, eq. 1, for the free body nodes is
//! `M_i dθ_i/dt = Σ_j K_ij (θ_j − θ_i) + M_i s_i`, M_i = V_i ρc_i. Every other node is
//! constrained by the boundary (theory §3): a fictitious node by its affine rule
//! θ_f = σ·Σ w θ(mirror stencil) + Σ coef·g(t), a nodal-Dirichlet node by θ_b(t), a flux-relation
//! node by an affine rule over body nodes. [`crate::bc::Boundary::linear_rules`] gives the linear
//! part of those rules in the order the explicit solvers apply them; each is expanded
//! recursively over the free nodes (θ_c = Σ S_ck θ_k + g_c(t)), and the time-dependent part
//! g(t) is what `Boundary::apply` writes on a field whose free entries are 0. Substituting gives
//!
//! `M dθ/dt = −A θ + f(t)`, `A = D − K_FF − K_FC S + diag(M·h_conv)`, `f = K_FC g(t) + M·loads(t)`
//!
//! with D the row sums of K: the implicit path solves exactly the explicit path's
//! semi-discrete system. A is symmetric when every mirror stencil is one-to-one and the
//! reflection maps pairs onto pairs (lattice boxes with mirrored layers: measured asymmetry
//! ~1e-16 of the diagonal), and nonsymmetric when images are interpolated (mesh clouds,
//! inverse-distance stencils) or for flux relations. Symmetry is checked to 1e-10 of the
//! largest diagonal entry.
//!
//! **Solver.** Symmetric A: sparse Cholesky (faer, supernodal) of `cM + A` with a geometric
//! nested-dissection ordering ([`nested_dissection`]), factorised once per distinct
//! coefficient c (so once per Δt); nonsymmetric A: sparse LU with partial pivoting (faer,
//! COLAMD) of the same matrix. Jacobi-preconditioned conjugate gradients ([`Solver::Cg`],
//! symmetric A only) are kept for comparison. Measured per solve (`cargo test --release --test
//! cases implicit:: -- --ignored --nocapture`, Crank–Nicolson; 2 cores shared with other jobs, load
//! average 5–7, so ±30 %): crack plate (40 000 unknowns, Δt = 0.01 s) 71 ms direct against
//! 505 ms CG (83 iterations to 1e-11), factorisation 0.98 s; thermal shock (250 000 unknowns,
//! Δt = 0.05 s) 0.43 s direct against 6.0 s CG (100 iterations), factorisation 6.9 s with
//! nested dissection (nnz(L) = 95 M) against 12.2 s with AMD (127 M). A factorisation costs
//! about 15 solves and is amortised after a few steps, so the direct solver is the default.
//!
//! **Schemes** (fixed Δt, no stability bound; steps shrink to land on output times):
//! backward Euler `(M/h + A)θ⁺ = M/h θ + f⁺`; Crank–Nicolson `(2M/h + A)θ⁺ = (2M/h − A)θ + f + f⁺`,
//! whose first step is two backward-Euler half steps (Rannacher start-up: the same matrix,
//! and it damps the stiff modes that a discontinuous start, e.g. a boundary jump, excites);
//! BDF2 with variable-step coefficients (ω = h_n/h_{n−1}), started by one backward-Euler step.
//! Steady: `A θ = f(t)` at each output time's boundary data.
//!
//! **Adaptive Δt** ([`Implicit::run_adaptive`], case key `time.tolerance`): a local error
//! estimate per step (backward Euler from θ', Crank–Nicolson TR–AB2, BDF2 Milne; see
//! `Implicit::attempt`), steps on a ladder h_max·2^(−k) so that each matrix is factorised
//! once, [`Solver::Auto`] (CG on a rung until factorising pays) and cubic Hermite output.

use crate::error::{Error, Result};
use crate::model::Model;
use crate::operator::Conductance;
use crate::solve::explicit::{steps_between, RunStats};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Implicit time-stepping scheme (theory §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Backward Euler, first order, L-stable.
    BackwardEuler,
    /// Crank–Nicolson (trapezoidal rule), second order, A-stable; Rannacher start-up.
    CrankNicolson,
    /// Two-step backward differentiation, second order, L-stable; backward-Euler start-up.
    Bdf2,
}

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

/// Fill-reducing ordering of the sparse Cholesky factorisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ordering {
    /// Geometric nested dissection on the node positions ([`nested_dissection`]).
    NestedDissection,
    /// faer's approximate minimum degree.
    Amd,
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

/// Relative asymmetry below which A is treated as symmetric (of the largest diagonal entry).
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// The semi-discrete system `M dθ/dt = −A θ + f(t)` on the free body nodes (theory §4).
#[derive(Debug, Clone)]
pub struct System {
    /// Body node of each unknown.
    pub free: Vec<usize>,
    /// Row offsets of A (CSR), length n + 1.
    pub offsets: Vec<usize>,
    /// Column (unknown) indices of A, sorted within each row.
    pub cols: Vec<usize>,
    /// Entries of A, W/K.
    pub vals: Vec<f64>,
    /// Position of A_ii in `vals` for each row.
    pub diag_pos: Vec<usize>,
    /// Heat capacity M_i = V_i ρc_i of each unknown, J/K.
    pub mass: Vec<f64>,
    /// Largest |A_ij − A_ji| over the largest diagonal entry (dimensionless).
    pub asymmetry: f64,
    /// True when `asymmetry` ≤ [`SYMMETRY_TOLERANCE`].
    pub symmetric: bool,
    /// Row offsets of the coupling to constrained nodes (CSR over the unknowns).
    c_offsets: Vec<usize>,
    /// Constrained node of each coupling entry.
    c_cols: Vec<u32>,
    /// K_ic of each coupling entry, W/K.
    c_vals: Vec<f64>,
}

fn refuse(message: impl Into<String>) -> Error {
    Error::model("time.integrator", message)
}

impl System {
    /// Eliminates fictitious and constrained nodes from the model's equations.
    pub fn build(model: &Model) -> Result<System> {
        if !model.growth.is_empty() {
            return Err(refuse(
                "implicit and steady solvers do not handle growing cracks (crack[].speed): K changes as the tips pass; use euler or rk4",
            ));
        }
        let cloud = &model.cloud;
        let (nb, nn) = (cloud.n_body, cloud.len());
        let rules = model.boundary.linear_rules();
        let mut constrained = vec![false; nn];
        for c in constrained.iter_mut().skip(nb) {
            *c = true;
        }
        for (node, _) in &rules {
            constrained[*node] = true;
        }
        const NONE: u32 = u32::MAX;
        let mut index = vec![NONE; nn];
        let mut free = Vec::new();
        for i in 0..nb {
            if !constrained[i] {
                index[i] = free.len() as u32;
                free.push(i);
            }
        }
        let n = free.len();
        if n == 0 {
            return Err(refuse(
                "every body node is constrained: nothing to integrate",
            ));
        }
        // expand each rule over the free nodes, in the order the boundary applies them
        let mut expanded: Vec<Option<Vec<(u32, f64)>>> = vec![None; nn];
        for (node, terms) in &rules {
            let mut row: Vec<(u32, f64)> = Vec::new();
            for &(src, w) in terms {
                if index[src] != NONE {
                    row.push((index[src], w));
                } else if let Some(e) = &expanded[src] {
                    row.extend(e.iter().map(|&(k, v)| (k, v * w)));
                } else {
                    return Err(refuse(format!(
                        "the boundary rule of node {node} reads node {src} before it is set (chained nodal flux relations); the implicit solvers cannot eliminate it: use euler or rk4"
                    )));
                }
            }
            row.sort_by_key(|e| e.0);
            let mut merged: Vec<(u32, f64)> = Vec::with_capacity(row.len());
            for (k, v) in row {
                match merged.last_mut() {
                    Some(l) if l.0 == k => l.1 += v,
                    _ => merged.push((k, v)),
                }
            }
            expanded[*node] = Some(merged);
        }
        let k = &model.conductance;
        let loads = model.boundary.load_diagonal(nb);
        let mass: Vec<f64> = free
            .iter()
            .map(|&i| cloud.volume[i] * model.capacity[i])
            .collect();
        let mut sys = System {
            free,
            offsets: Vec::with_capacity(n + 1),
            cols: Vec::with_capacity(k.nnz()),
            vals: Vec::with_capacity(k.nnz()),
            diag_pos: Vec::with_capacity(n),
            mass,
            asymmetry: 0.0,
            symmetric: true,
            c_offsets: Vec::with_capacity(n + 1),
            c_cols: Vec::new(),
            c_vals: Vec::new(),
        };
        sys.offsets.push(0);
        sys.c_offsets.push(0);
        let mut acc = vec![0.0; n];
        let mut touched = vec![false; n];
        let mut list: Vec<usize> = Vec::new();
        fn touch(c: usize, v: f64, acc: &mut [f64], list: &mut Vec<usize>, touched: &mut [bool]) {
            if !touched[c] {
                touched[c] = true;
                list.push(c);
            }
            acc[c] += v;
        }
        for r in 0..n {
            let i = sys.free[r];
            touch(
                r,
                k.diag[i] + sys.mass[r] * loads[i],
                &mut acc,
                &mut list,
                &mut touched,
            );
            for e in k.offsets[i]..k.offsets[i + 1] {
                let (j, kij) = (k.cols[e] as usize, k.vals[e]);
                if index[j] != NONE {
                    touch(index[j] as usize, -kij, &mut acc, &mut list, &mut touched);
                } else {
                    sys.c_cols.push(j as u32);
                    sys.c_vals.push(kij);
                    if let Some(ex) = &expanded[j] {
                        for &(c, w) in ex {
                            touch(c as usize, -kij * w, &mut acc, &mut list, &mut touched);
                        }
                    }
                }
            }
            list.sort_unstable();
            for &c in &list {
                if c == r {
                    sys.diag_pos.push(sys.cols.len());
                }
                sys.cols.push(c);
                sys.vals.push(acc[c]);
                acc[c] = 0.0;
            }
            for &c in &list {
                touched[c] = false;
            }
            list.clear();
            sys.offsets.push(sys.cols.len());
            sys.c_offsets.push(sys.c_cols.len());
        }
        // symmetry of A, relative to its largest diagonal entry
        let scale = sys
            .diag_pos
            .iter()
            .map(|&p| sys.vals[p].abs())
            .fold(0.0, f64::max);
        let mut asym: f64 = 0.0;
        for r in 0..n {
            for e in sys.offsets[r]..sys.offsets[r + 1] {
                let c = sys.cols[e];
                asym = asym.max((sys.vals[e] - sys.get(c, r)).abs());
            }
        }
        sys.asymmetry = if scale > 0.0 { asym / scale } else { 0.0 };
        sys.symmetric = sys.asymmetry <= SYMMETRY_TOLERANCE;
        Ok(sys)
    }

    /// Number of unknowns (free body nodes).
    pub fn len(&self) -> usize {
        self.free.len()
    }

    /// True when there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.free.is_empty()
    }

    /// The entry A_rc if stored, else 0, W/K.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let range = self.offsets[r]..self.offsets[r + 1];
        match self.cols[range.clone()].binary_search(&c) {
            Ok(p) => self.vals[range.start + p],
            Err(_) => 0.0,
        }
    }

    /// True when the constant field is in the null space of A (no boundary fixes the level):
    /// every row sum below 1e-9 of its diagonal entry.
    pub fn is_floating(&self) -> bool {
        (0..self.len()).all(|r| {
            let s: f64 = self.vals[self.offsets[r]..self.offsets[r + 1]].iter().sum();
            s.abs() <= 1e-9 * self.vals[self.diag_pos[r]].abs()
        })
    }

    /// `out = c·M·u − a·A·u` (W), in parallel when asked.
    fn combine(&self, c: f64, a: f64, u: &[f64], out: &mut [f64], parallel: bool) {
        let row = |r: usize| {
            let mut s = 0.0;
            for e in self.offsets[r]..self.offsets[r + 1] {
                s += self.vals[e] * u[self.cols[e]];
            }
            c * self.mass[r] * u[r] - a * s
        };
        if parallel {
            out.par_iter_mut()
                .with_min_len(1024)
                .enumerate()
                .for_each(|(r, o)| *o = row(r));
        } else {
            for (r, o) in out.iter_mut().enumerate() {
                *o = row(r);
            }
        }
    }

    /// The forcing f(t) (W) into `out`; `scratch` is a whole-cloud field whose free entries are
    /// 0 (only constrained entries are written), `rate` a body-sized buffer.
    fn forcing(
        &self,
        model: &Model,
        t: f64,
        scratch: &mut [f64],
        rate: &mut [f64],
        out: &mut [f64],
    ) {
        model.boundary.apply(&model.cloud, scratch, t);
        for (r, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for e in self.c_offsets[r]..self.c_offsets[r + 1] {
                s += self.c_vals[e] * scratch[self.c_cols[e] as usize];
            }
            *o = s;
        }
        if model.boundary.has_loads() {
            rate.fill(0.0);
            model
                .boundary
                .add_loads(&model.cloud, &model.capacity, scratch, t, rate);
            for (r, o) in out.iter_mut().enumerate() {
                *o += self.mass[r] * rate[self.free[r]];
            }
        }
    }
}

/// Elimination order by geometric nested dissection (George 1973): split the unknowns at the
/// median of the longer axis of their bounding box, order each half recursively and the
/// separator (the second half's nodes bonded to the first half) last. On 2D lattices with
/// wide horizons this gives less fill than minimum degree. Returns (new → old, old → new).
pub fn nested_dissection(sys: &System, model: &Model) -> (Vec<usize>, Vec<usize>) {
    let n = sys.len();
    let pos: Vec<[f64; 3]> = sys
        .free
        .iter()
        .map(|&i| {
            let p = model.cloud.pos[i];
            [p.x, p.y, p.z]
        })
        .collect();
    let mut stamp = vec![0u64; n];
    let mut next = 1u64;
    let mut order = Vec::with_capacity(n);
    let mut nodes: Vec<usize> = (0..n).collect();
    // explicit stack: (nodes, separator to emit after both halves)
    enum Job {
        Split(Vec<usize>),
        Emit(Vec<usize>),
    }
    let mut jobs = vec![Job::Split(std::mem::take(&mut nodes))];
    while let Some(job) = jobs.pop() {
        let mut set = match job {
            Job::Emit(sep) => {
                order.extend(sep);
                continue;
            }
            Job::Split(set) => set,
        };
        if set.len() <= 128 {
            order.extend(set);
            continue;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &k in &set {
            for a in 0..3 {
                lo[a] = lo[a].min(pos[k][a]);
                hi[a] = hi[a].max(pos[k][a]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = set.len() / 2;
        set.select_nth_unstable_by(mid, |&a, &b| pos[a][axis].total_cmp(&pos[b][axis]));
        let (first, second) = (next, next + 1);
        next += 2;
        for &k in &set[..mid] {
            stamp[k] = first;
        }
        for &k in &set[mid..] {
            stamp[k] = second;
        }
        let (mut b, mut sep) = (Vec::new(), Vec::new());
        for &k in &set[mid..] {
            let touches = sys.cols[sys.offsets[k]..sys.offsets[k + 1]]
                .iter()
                .any(|&c| stamp[c] == first);
            if touches {
                sep.push(k);
            } else {
                b.push(k);
            }
        }
        set.truncate(mid);
        jobs.push(Job::Emit(sep));
        jobs.push(Job::Split(b));
        jobs.push(Job::Split(set));
    }
    let mut inverse = vec![0usize; n];
    for (new, &old) in order.iter().enumerate() {
        inverse[old] = new;
    }
    (order, inverse)
}

/// One factorisation of `cM + A`.
enum Factor {
    Llt(Vec<f64>),
    Lu(Box<NumericLu<usize, f64>>),
}

/// Counters and timings of an implicit run (run.json `implicit`).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct ImplicitStats {
    /// Numeric factorisations performed.
    pub factorisations: u64,
    /// Linear solves performed (direct and CG).
    pub solves: u64,
    /// Linear solves done by conjugate gradients.
    #[serde(default)]
    pub cg_solves: u64,
    /// Conjugate-gradient iterations in all (0 for the direct solver).
    pub cg_iterations: u64,
    /// Seconds spent in symbolic and numeric factorisation, s.
    pub factor_seconds: f64,
    /// Seconds spent in linear solves, s.
    pub solve_seconds: f64,
    /// Stored entries of the Cholesky factor L (0 for LU and CG).
    pub factor_entries: usize,
    /// Adaptive runs: local error allowed per step, K (0 for fixed Δt).
    #[serde(default)]
    pub tolerance: f64,
    /// Steps accepted (all steps for fixed Δt).
    #[serde(default)]
    pub accepted: u64,
    /// Adaptive steps rejected by the error estimate and retried shorter.
    #[serde(default)]
    pub rejected: u64,
    /// First accepted step, s.
    #[serde(default)]
    pub first_step: f64,
    /// Shortest accepted step, s.
    #[serde(default)]
    pub min_step: f64,
    /// Longest accepted step, s.
    #[serde(default)]
    pub max_step: f64,
}

/// Adaptive Δt of [`Implicit::run_adaptive`].
#[derive(Debug, Clone, Copy)]
pub struct Adaptive {
    /// Local error estimate allowed per step, max over the unknowns, K.
    pub tolerance: f64,
    /// First step, s (None: tolerance over the largest initial rate |θ'(0)|, or a
    /// ten-thousandth of the last output time if nothing moves at t0).
    pub first: Option<f64>,
    /// Largest step, the top of the ladder, s (None: a tenth of the last output time).
    pub max: Option<f64>,
}

/// Initial guess of a conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Guess {
    Zero,
    U,
    /// Already in the first CG buffer.
    Preset,
}

/// Share of the tolerance allowed to the error of a CG solution in adaptive runs.
const CG_SHARE: f64 = 1e-3;
/// Safety factor of the step controller (dimensionless).
const SAFETY: f64 = 0.9;
/// Accepted steps on a rung before the step may grow to the next (hysteresis).
const HYSTERESIS: u32 = 3;
/// Most rungs one accepted step may climb (growth cap 2² = 4).
const GROWTH_RUNGS: u32 = 2;
/// Most rungs one rejection may go down (factor 2^−5).
const MAX_CUT: u32 = 5;
/// Most halvings of the ladder's top step before the run gives up.
const MAX_RUNG: u32 = 60;
/// Coefficients whose CG time is remembered by [`Solver::Auto`].
const RENT_SLOTS: usize = 64;
/// Before any factorisation is timed, [`Solver::Auto`] estimates one as this many CG
/// iterations times nnz(L)/nnz(A) (measured: crack plate 1.0 s ≈ 17, thermal shock 6.9 s ≈ 9).
const FACTOR_PER_FILL: f64 = 15.0;

/// Implicit integrator state with preallocated buffers.
pub struct Implicit<'a> {
    model: &'a Model,
    sys: System,
    scheme: Scheme,
    options: Options,
    par: Par,
    chol: Option<SymbolicCholesky<usize>>,
    lu: Option<SymbolicLu<usize>>,
    /// Factorisations by coefficient c (at most two kept).
    factors: Vec<(f64, Factor)>,
    b_vals: Vec<f64>,
    stack: MemBuffer,
    u: Vec<f64>,
    u_prev: Vec<f64>,
    rhs: Vec<f64>,
    f_now: Vec<f64>,
    f_next: Vec<f64>,
    scratch: Vec<f64>,
    rate: Vec<f64>,
    cg: [Vec<f64>; 4],
    /// Adaptive runs: θ two steps back, the next solution, θ' now / one step back / next
    /// (K/s), the predictor and the BDF2 history value.
    u_prev2: Vec<f64>,
    next: Vec<f64>,
    d_now: Vec<f64>,
    d_prev: Vec<f64>,
    d_next: Vec<f64>,
    pred: Vec<f64>,
    hist: Vec<f64>,
    /// [`Solver::Auto`]: CG seconds spent per coefficient c not factorised.
    rent: Vec<(f64, f64)>,
    /// Seconds of the last numeric factorisation (0 before the first).
    last_factor_seconds: f64,
    /// Seconds of all CG solves.
    cg_seconds: f64,
    /// Seconds of the last direct solve (0 before the first).
    direct_seconds: f64,
    /// Error allowed to a CG solution, K (adaptive runs: [`CG_SHARE`] of the tolerance).
    cg_error: f64,
    /// Smallest heat capacity M_i, J/K.
    min_mass: f64,
    /// Counters and timings.
    pub stats: ImplicitStats,
    /// Fixed steps taken since [`Implicit::start`] (0: the next is a start-up step).
    taken: u64,
    /// Length of the last fixed step, s.
    h_prev: f64,
}

impl<'a> Implicit<'a> {
    /// Builds the system (refusing what it cannot handle) and allocates the buffers.
    pub fn new(model: &'a Model, scheme: Scheme, options: Options) -> Result<Self> {
        let sys = System::build(model)?;
        if options.solver == Solver::Cg && !sys.symmetric {
            return Err(refuse(format!(
                "conjugate gradients need a symmetric system; A is asymmetric to {:.1e} (interpolated mirror stencils or flux relations): use the direct solver",
                sys.asymmetry
            )));
        }
        let n = sys.len();
        let par = if options.parallel {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        let symbolic = SymbolicSparseColMatRef::new_checked(n, n, &sys.offsets, None, &sys.cols);
        let t = Instant::now();
        let (chol, lu, stack) = match options.solver {
            Solver::Cg => (None, None, MemBuffer::new(faer::dyn_stack::StackReq::EMPTY)),
            Solver::Direct | Solver::Auto if sys.symmetric => {
                let (fwd, inv) = match options.ordering {
                    Ordering::NestedDissection => nested_dissection(&sys, model),
                    Ordering::Amd => (Vec::new(), Vec::new()),
                };
                let ordering = match options.ordering {
                    Ordering::NestedDissection => {
                        SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n))
                    }
                    Ordering::Amd => SymmetricOrdering::Amd,
                };
                let s = factorize_symbolic_cholesky(
                    symbolic,
                    Side::Lower,
                    ordering,
                    Default::default(),
                )
                .map_err(|e| Error::Solver {
                    message: format!("symbolic Cholesky: {e:?}"),
                })?;
                let req = s.solve_in_place_scratch::<f64>(1, par);
                (Some(s), None, MemBuffer::new(req))
            }
            Solver::Direct | Solver::Auto => {
                let s = factorize_symbolic_lu(symbolic, Default::default()).map_err(|e| {
                    Error::Solver {
                        message: format!("symbolic LU: {e:?}"),
                    }
                })?;
                let req = s
                    .solve_in_place_scratch::<f64>(1, par)
                    .or(s.solve_transpose_in_place_scratch::<f64>(1, par));
                (None, Some(s), MemBuffer::new(req))
            }
        };
        let stats = ImplicitStats {
            factor_seconds: t.elapsed().as_secs_f64(),
            factor_entries: chol.as_ref().map_or(0, |s| s.len_val()),
            ..Default::default()
        };
        let mut scratch = vec![0.0; model.cloud.len()];
        for &i in &sys.free {
            scratch[i] = 0.0;
        }
        Ok(Implicit {
            model,
            scheme,
            options,
            par,
            chol,
            lu,
            factors: Vec::new(),
            b_vals: sys.vals.clone(),
            stack,
            u: vec![0.0; n],
            u_prev: vec![0.0; n],
            rhs: vec![0.0; n],
            f_now: vec![0.0; n],
            f_next: vec![0.0; n],
            scratch,
            rate: vec![0.0; model.cloud.n_body],
            cg: std::array::from_fn(|_| vec![0.0; n]),
            u_prev2: Vec::new(),
            next: Vec::new(),
            d_now: Vec::new(),
            d_prev: Vec::new(),
            d_next: Vec::new(),
            pred: Vec::new(),
            hist: Vec::new(),
            rent: Vec::with_capacity(RENT_SLOTS),
            last_factor_seconds: 0.0,
            cg_seconds: 0.0,
            direct_seconds: 0.0,
            cg_error: 0.0,
            min_mass: sys.mass.iter().fold(f64::INFINITY, |m: f64, &v| m.min(v)),
            stats,
            sys,
            taken: 0,
            h_prev: 0.0,
        })
    }

    /// The eliminated system.
    pub fn system(&self) -> &System {
        &self.sys
    }

    /// Makes sure a factorisation of `cM + A` is cached; returns its slot.
    fn factor(&mut self, c: f64) -> Result<usize> {
        if let Some(p) = self.factors.iter().position(|(k, _)| Self::same(*k, c)) {
            return Ok(p);
        }
        let started = Instant::now();
        let sys = &self.sys;
        self.b_vals.copy_from_slice(&sys.vals);
        for (r, &p) in sys.diag_pos.iter().enumerate() {
            self.b_vals[p] += c * sys.mass[r];
        }
        let n = sys.len();
        let symbolic = SymbolicSparseColMatRef::new_checked(n, n, &sys.offsets, None, &sys.cols);
        let b = SparseColMatRef::new(symbolic, &self.b_vals);
        let factor = if let Some(s) = &self.chol {
            let mut values = vec![0.0; s.len_val()];
            let req = s.factorize_numeric_llt_scratch::<f64>(self.par, Default::default());
            let mut mem = MemBuffer::new(req);
            s.factorize_numeric_llt(
                &mut values,
                b,
                Side::Lower,
                LltRegularization::default(),
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| Error::Solver {
                message: format!(
                    "Cholesky factorisation of cM + A (c = {c:e} 1/s) failed ({e:?}); the system is singular (steady state of a body no boundary holds?) or not positive definite"
                ),
            })?;
            Factor::Llt(values)
        } else if let Some(s) = &self.lu {
            let mut numeric = NumericLu::<usize, f64>::new();
            let req = s.factorize_numeric_lu_scratch::<f64>(self.par, Default::default());
            let mut mem = MemBuffer::new(req);
            s.factorize_numeric_lu(
                &mut numeric,
                b,
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| Error::Solver {
                message: format!(
                    "LU factorisation of cM + A (c = {c:e} 1/s) failed ({e:?}); the system is singular (steady state of a body no boundary holds?)"
                ),
            })?;
            Factor::Lu(Box::new(numeric))
        } else {
            return Err(Error::Solver {
                message: "no symbolic factorisation for the direct solver".into(),
            });
        };
        if self.factors.len() == 2 {
            self.factors.remove(0);
        }
        self.factors.push((c, factor));
        self.stats.factorisations += 1;
        self.last_factor_seconds = started.elapsed().as_secs_f64();
        self.stats.factor_seconds += self.last_factor_seconds;
        Ok(self.factors.len() - 1)
    }

    /// True when `c` matches `k` to 1e-12 relative.
    fn same(k: f64, c: f64) -> bool {
        (k - c).abs() <= 1e-12 * c.abs().max(f64::MIN_POSITIVE)
    }

    /// [`Solver::Auto`]: solve with CG while the seconds its solves on `c` took beyond a direct
    /// solve (the last one timed; 0 before any) are below the cost of one factorisation, then
    /// factorise (the ski-rental rule: at most twice the cheaper choice's cost). The cost is
    /// the last factorisation's time; before any, CG iterations scaled by the factor's fill
    /// ([`FACTOR_PER_FILL`]). So CG stays wherever it is cheaper per solve than the factor.
    fn use_cg(&self, c: f64) -> bool {
        match self.options.solver {
            Solver::Cg => true,
            Solver::Direct => false,
            Solver::Auto => {
                let Some(chol) = &self.chol else {
                    return false;
                };
                if self.factors.iter().any(|(k, _)| Self::same(*k, c)) {
                    return false;
                }
                let spent = self
                    .rent
                    .iter()
                    .find(|(k, _)| Self::same(*k, c))
                    .map_or(0.0, |r| r.1);
                let cost = if self.last_factor_seconds > 0.0 {
                    self.last_factor_seconds
                } else if self.stats.cg_iterations > 0 {
                    let per_iteration = self.cg_seconds / self.stats.cg_iterations as f64;
                    let fill = chol.len_val() as f64 / self.sys.vals.len() as f64;
                    FACTOR_PER_FILL * fill * per_iteration
                } else {
                    f64::INFINITY
                };
                spent < cost
            }
        }
    }

    /// Adds what a CG solve on coefficient c cost beyond a direct solve ([`Solver::Auto`]).
    fn pay_rent(&mut self, c: f64, seconds: f64) {
        self.cg_seconds += seconds;
        let seconds = (seconds - self.direct_seconds).max(0.0);
        if let Some(r) = self.rent.iter_mut().find(|(k, _)| Self::same(*k, c)) {
            r.1 += seconds;
            return;
        }
        if self.rent.len() == RENT_SLOTS {
            self.rent.remove(0);
        }
        self.rent.push((c, seconds));
    }

    /// Solves `(cM + A) x = rhs`: the answer replaces `rhs`; `guess` starts CG.
    fn solve(&mut self, c: f64, guess: Guess) -> Result<()> {
        if self.use_cg(c) {
            let started = Instant::now();
            let its = self.pcg(c, guess)?;
            let seconds = started.elapsed().as_secs_f64();
            self.pay_rent(c, seconds);
            self.stats.cg_iterations += its;
            self.stats.cg_solves += 1;
            self.stats.solves += 1;
            self.stats.solve_seconds += seconds;
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
        self.direct_seconds = started.elapsed().as_secs_f64();
        self.stats.solve_seconds += self.direct_seconds;
        Ok(())
    }

    /// Jacobi-preconditioned CG on `(cM + A) x = rhs`; x replaces `rhs`. Returns iterations.
    fn pcg(&mut self, c: f64, guess: Guess) -> Result<u64> {
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
                return Err(Error::Solver {
                    message: format!("conjugate gradients did not converge in {its} iterations"),
                });
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

    fn forcing_into_next(&mut self, t: f64) {
        self.sys.forcing(
            self.model,
            t,
            &mut self.scratch,
            &mut self.rate,
            &mut self.f_next,
        );
    }

    /// Backward Euler from the current `u` over `h` to time `t1` with coefficient c = 1/h.
    fn be_step(&mut self, t1: f64, h: f64) -> Result<()> {
        let c = 1.0 / h;
        self.forcing_into_next(t1);
        for r in 0..self.u.len() {
            self.rhs[r] = c * self.sys.mass[r] * self.u[r] + self.f_next[r];
        }
        self.solve(c, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        Ok(())
    }

    /// Crank–Nicolson from `u` (with f at t in `f_now`) over h to `t1`.
    fn cn_step(&mut self, t1: f64, h: f64) -> Result<()> {
        let c = 2.0 / h;
        self.forcing_into_next(t1);
        self.sys
            .combine(c, 1.0, &self.u, &mut self.rhs, self.options.parallel);
        for r in 0..self.u.len() {
            self.rhs[r] += self.f_now[r] + self.f_next[r];
        }
        self.solve(c, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        std::mem::swap(&mut self.f_now, &mut self.f_next);
        Ok(())
    }

    /// Variable-step BDF2 from (u_prev, u) with step ratio ω = h / h_prev to `t1`.
    fn bdf2_step(&mut self, t1: f64, h: f64, omega: f64) -> Result<()> {
        let a0 = (1.0 + 2.0 * omega) / (1.0 + omega);
        let a1 = 1.0 + omega;
        let a2 = omega * omega / (1.0 + omega);
        self.forcing_into_next(t1);
        for r in 0..self.u.len() {
            self.rhs[r] =
                self.sys.mass[r] / h * (a1 * self.u[r] - a2 * self.u_prev[r]) + self.f_next[r];
        }
        self.solve(a0 / h, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        Ok(())
    }

    fn gather(&mut self, theta: &[f64]) {
        for (u, &i) in self.u.iter_mut().zip(&self.sys.free) {
            *u = theta[i];
        }
    }

    /// Writes the unknowns into `theta` and sets every constrained node at time t.
    fn scatter(&self, theta: &mut [f64], t: f64) -> Result<()> {
        for (&u, &i) in self.u.iter().zip(&self.sys.free) {
            theta[i] = u;
        }
        self.model.boundary.apply(&self.model.cloud, theta, t);
        match theta[..self.model.cloud.n_body]
            .iter()
            .position(|v| !v.is_finite())
        {
            Some(node) => Err(Error::NonFinite { node, time: t }),
            None => Ok(()),
        }
    }

    /// Starts fixed-step stepping ([`Implicit::step`]) from `theta` (every node, °C) at
    /// `t0`, s: the unknowns and the forcing are taken there, and the next step is a start-up
    /// step (Crank–Nicolson: two backward-Euler half steps; BDF2: backward Euler).
    pub fn start(&mut self, theta: &[f64], t0: f64) {
        self.gather(theta);
        self.sys.forcing(
            self.model,
            t0,
            &mut self.scratch,
            &mut self.rate,
            &mut self.f_now,
        );
        self.taken = 0;
        self.h_prev = 0.0;
    }

    /// One fixed step of length `h` (s) from `tn` to `t1` (s; `t1` is `tn + h` up to the
    /// round-off the caller chooses, e.g. exactly an output time), after [`Implicit::start`].
    /// The state stays in the unknowns until [`Implicit::state_into`].
    pub fn step(&mut self, tn: f64, t1: f64, h: f64) -> Result<()> {
        match self.scheme {
            Scheme::BackwardEuler => self.be_step(t1, h)?,
            Scheme::CrankNicolson if self.taken == 0 => {
                // Rannacher start-up: two BE half steps, the matrix of CN
                self.be_step(tn + 0.5 * h, 0.5 * h)?;
                self.be_step(t1, 0.5 * h)?;
                std::mem::swap(&mut self.f_now, &mut self.f_next);
            }
            Scheme::CrankNicolson => self.cn_step(t1, h)?,
            Scheme::Bdf2 if self.taken == 0 => self.be_step(t1, h)?,
            Scheme::Bdf2 => self.bdf2_step(t1, h, h / self.h_prev)?,
        }
        self.h_prev = h;
        self.taken += 1;
        if self.taken == 1 {
            self.stats.first_step = h;
            self.stats.min_step = h;
        }
        self.stats.min_step = self.stats.min_step.min(h);
        self.stats.max_step = self.stats.max_step.max(h);
        Ok(())
    }

    /// Writes the state of the fixed steps into `theta` (every node, °C) with the constrained
    /// nodes set at time `t`, s; an error if a body temperature is not finite.
    pub fn state_into(&self, theta: &mut [f64], t: f64) -> Result<()> {
        self.scatter(theta, t)
    }

    /// Integrates from `t0` through each output time with steps no longer than `dt` that land
    /// on the output times, calling `on_output(k, t, θ, K)` there (θ: every node) and
    /// `progress(steps)` after every step.
    pub fn run(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        dt: f64,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> Result<()>,
        mut progress: impl FnMut(u64),
    ) -> Result<RunStats> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::model(
                "time.dt",
                format!("must be a positive number for an implicit integrator, got {dt}"),
            ));
        }
        self.start(theta, t0);
        let mut stats = RunStats::default();
        let mut t = t0;
        for (k, &to) in outputs.iter().enumerate() {
            let n = steps_between(t, to, dt);
            let h = if n > 0 { (to - t) / n as f64 } else { 0.0 };
            for s in 0..n {
                let t1 = if s + 1 == n {
                    to
                } else {
                    t + (s + 1) as f64 * h
                };
                self.step(t + s as f64 * h, t1, h)?;
                stats.steps += 1;
                progress(stats.steps);
            }
            t = to;
            self.scatter(theta, t)?;
            on_output(k, t, theta, &self.model.conductance)?;
        }
        self.stats.accepted = stats.steps;
        Ok(stats)
    }

    /// θ' = M⁻¹(f − A v) into `out` (K/s).
    fn derivative(sys: &System, v: &[f64], f: &[f64], out: &mut [f64], parallel: bool) {
        sys.combine(0.0, 1.0, v, out, parallel);
        for ((o, fr), m) in out.iter_mut().zip(f).zip(&sys.mass) {
            *o = (*o + fr) / m;
        }
    }

    /// Cubic Hermite interpolant at s ∈ [0, 1] of a step of length h from (a, a') to (b, b').
    fn hermite(a: &[f64], da: &[f64], b: &[f64], db: &[f64], h: f64, s: f64, out: &mut [f64]) {
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10) = (2.0 * s3 - 3.0 * s2 + 1.0, (s3 - 2.0 * s2 + s) * h);
        let (h01, h11) = (3.0 * s2 - 2.0 * s3, (s3 - s2) * h);
        for r in 0..out.len() {
            out[r] = h00 * a[r] + h10 * da[r] + h01 * b[r] + h11 * db[r];
        }
    }

    /// One backward-Euler solve `(cM + A)θ = cM·v + f(t1)` into `next`, from v = `next` (which
    /// also starts CG) or else `u`; f(t1) is left in `f_next`.
    fn be_into_next(&mut self, t1: f64, c: f64, from_next: bool) -> Result<()> {
        self.forcing_into_next(t1);
        self.rhs_mass(c, from_next);
        let guess = if from_next {
            self.cg[0].copy_from_slice(&self.next);
            Guess::Preset
        } else {
            Guess::U
        };
        self.solve(c, guess)?;
        std::mem::swap(&mut self.next, &mut self.rhs);
        Ok(())
    }

    /// `rhs = c·M·v + f_next` (W) with v = `next` or `u`.
    fn rhs_mass(&mut self, c: f64, from_next: bool) {
        let v = if from_next { &self.next } else { &self.u };
        for (((o, vr), m), f) in self
            .rhs
            .iter_mut()
            .zip(v)
            .zip(&self.sys.mass)
            .zip(&self.f_next)
        {
            *o = c * m * vr + f;
        }
    }

    /// One attempted step of length h from (t, u) to t + h; the result goes to `next` and
    /// `d_next` (θ' there), f(t + h) to `f_next`. Returns the local error estimate (K, max
    /// over the unknowns) and the order p it scales with (est ∝ h^(p+1)).
    ///
    /// Estimates: backward Euler `(h/2)·‖θ'ₙ₊₁ − θ'ₙ‖` (its local error h²θ''/2, θ'' by the
    /// difference of the directly evaluated derivatives; Hairer & Wanner, *Solving ODEs II*,
    /// §IV.8); Crank–Nicolson's Rannacher start (two backward-Euler half steps) the same at
    /// half the weight, `(h/4)·‖θ'₁ − θ'₀‖`; Crank–Nicolson the TR–AB2 estimate of Gresho &
    /// Sani (*Incompressible Flow and the FEM*, vol. 1, §3.16.4; Gresho, Griffiths & Silvester,
    /// SIAM J. Sci. Comput. 30, 2008): AB2 predictor θᵖ = θₙ + (hₙ/2)[(2 + hₙ/hₙ₋₁)θ'ₙ −
    /// (hₙ/hₙ₋₁)θ'ₙ₋₁] and dₙ₊₁ = (θₙ₊₁ − θᵖ)/(3(1 + hₙ₋₁/hₙ)), θ' = M⁻¹(f − Aθ) evaluated
    /// directly; BDF2 Milne's device (Hairer, Nørsett & Wanner, *Solving ODEs I*, §III.7;
    /// Brenan, Campbell & Petzold, *DAEs*, §5.2): the quadratic through the last three
    /// accepted values extrapolated to tₙ₊₁ errs by C_p h³θ''', BDF2 by −(2/9)h³θ''', so the
    /// local error is (2/9)/(C_p + 2/9)·‖θₙ₊₁ − θᵖ‖ (2/11 for equal steps).
    ///
    /// BDF2 here has a fixed leading coefficient, `(3/2)θₙ₊₁ − 2θₙ + (1/2)θ(tₙ − h) =
    /// h M⁻¹(f − Aθₙ₊₁)`, with θ(tₙ − h) an accepted value or the Hermite interpolant of the
    /// last step when the step changed (the interpolation strategy of Brenan, Campbell &
    /// Petzold §5.2): its matrix 1.5M/h + A depends on h alone, so each rung of the ladder
    /// has one factorisation.
    #[allow(clippy::too_many_arguments)]
    fn attempt(
        &mut self,
        accepted: u64,
        t: f64,
        h: f64,
        h_prev: f64,
        t_prev: f64,
        t_prev2: f64,
    ) -> Result<(f64, u32)> {
        let par = self.options.parallel;
        let n = self.u.len();
        let t1 = t + h;
        let first = accepted == 0;
        match self.scheme {
            Scheme::BackwardEuler | Scheme::Bdf2
                if first || self.scheme == Scheme::BackwardEuler =>
            {
                self.be_into_next(t1, 1.0 / h, false)?;
                Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
                for r in 0..n {
                    self.pred[r] = 0.5 * h * (self.d_next[r] - self.d_now[r]);
                }
                Ok((self.estimate(), 1))
            }
            Scheme::CrankNicolson if first => {
                // Rannacher start-up: two backward-Euler half steps, the matrix of CN
                self.be_into_next(t + 0.5 * h, 2.0 / h, false)?;
                self.be_into_next(t1, 2.0 / h, true)?;
                Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
                for r in 0..n {
                    self.pred[r] = 0.25 * h * (self.d_next[r] - self.d_now[r]);
                }
                Ok((self.estimate(), 1))
            }
            Scheme::CrankNicolson => {
                let w = h / h_prev;
                for r in 0..n {
                    self.pred[r] =
                        self.u[r] + 0.5 * h * ((2.0 + w) * self.d_now[r] - w * self.d_prev[r]);
                }
                self.forcing_into_next(t1);
                // (2M/h + A)θₙ₊₁ = (2M/h − A)θₙ + fₙ + fₙ₊₁ = 2M/h θₙ + M θ'ₙ + fₙ₊₁
                for r in 0..n {
                    let m = self.sys.mass[r];
                    self.rhs[r] = m * (2.0 / h * self.u[r] + self.d_now[r]) + self.f_next[r];
                }
                self.cg[0].copy_from_slice(&self.pred);
                self.solve(2.0 / h, Guess::Preset)?;
                std::mem::swap(&mut self.next, &mut self.rhs);
                Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
                let w = 1.0 / (3.0 * (1.0 + h_prev / h));
                for r in 0..n {
                    self.pred[r] = w * (self.next[r] - self.pred[r]);
                }
                Ok((self.estimate(), 2))
            }
            Scheme::BackwardEuler | Scheme::Bdf2 => {
                // BDF2 (backward Euler took the first arm); θ(t − h): an accepted value or the
                // Hermite interpolant of the last step
                let back = t - h;
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * h;
                if close(back, t_prev) {
                    self.hist.copy_from_slice(&self.u_prev);
                } else if accepted >= 2 && close(back, t_prev2) {
                    self.hist.copy_from_slice(&self.u_prev2);
                } else if back > t_prev {
                    Self::hermite(
                        &self.u_prev,
                        &self.d_prev,
                        &self.u,
                        &self.d_now,
                        t - t_prev,
                        (back - t_prev) / (t - t_prev),
                        &mut self.hist,
                    );
                } else {
                    return Err(Error::Solver {
                        message: format!(
                            "BDF2 step {h:e} s at t = {t:e} s reaches behind the stored history (internal)"
                        ),
                    });
                }
                // predictor: quadratic through the last three accepted values (or, after the
                // start, through θ₀, θ'₀ and θ₁), extrapolated to t + h; cp its error constant
                let cp = if accepted >= 2 {
                    let (t1r, t2r) = ((t_prev - t) / h, (t_prev2 - t) / h);
                    let l0 = (1.0 - t1r) * (1.0 - t2r) / (t1r * t2r);
                    let l1 = (1.0 - t2r) / (t1r * (t1r - t2r));
                    let l2 = (1.0 - t1r) / (t2r * (t2r - t1r));
                    for r in 0..n {
                        self.pred[r] = l0 * self.u[r] + l1 * self.u_prev[r] + l2 * self.u_prev2[r];
                    }
                    (1.0 - t1r) * (1.0 - t2r) / 6.0
                } else {
                    let h0 = t - t_prev;
                    let x = t1 - t_prev;
                    for r in 0..n {
                        let a = (self.u[r] - self.u_prev[r] - self.d_prev[r] * h0) / (h0 * h0);
                        self.pred[r] = self.u_prev[r] + self.d_prev[r] * x + a * x * x;
                    }
                    let t0r = (t_prev - t) / h;
                    (1.0 - t0r) * (1.0 - t0r) / 6.0
                };
                self.forcing_into_next(t1);
                for r in 0..n {
                    let m = self.sys.mass[r];
                    self.rhs[r] = m / h * (2.0 * self.u[r] - 0.5 * self.hist[r]) + self.f_next[r];
                }
                self.cg[0].copy_from_slice(&self.pred);
                self.solve(1.5 / h, Guess::Preset)?;
                std::mem::swap(&mut self.next, &mut self.rhs);
                Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
                let cc = 2.0 / 9.0;
                let w = cc / (cp + cc);
                for r in 0..n {
                    self.pred[r] = w * (self.next[r] - self.pred[r]);
                }
                Ok((self.estimate(), 2))
            }
        }
    }

    /// Max norm of the error estimate in `pred` (K).
    fn estimate(&self) -> f64 {
        self.pred.iter().fold(0.0, |m: f64, v| m.max(v.abs()))
    }

    /// Integrates from `t0` with steps chosen from a local error estimate (see
    /// `Implicit::attempt`) and calls `on_output(k, t, θ, K)` at each output time with θ there
    /// from the cubic Hermite interpolant of the step that covers it (θ and θ' at both ends:
    /// fourth-order accurate, so the steps need not land on the outputs); `progress(accepted,
    /// t)` after each accepted step.
    ///
    /// **Step control.** Steps are rungs h_k = h_max·2^(−k) of a ladder so that each distinct
    /// matrix cM + A is factorised once and reused (two factorisations cached). A step is
    /// accepted when est ≤ tol; the ideal next step is h·0.9·(tol/est)^(1/(p+1)). On
    /// acceptance the step climbs one rung when that ideal is at least twice the step and 3
    /// steps were accepted on the rung (two rungs after one step when it is 4× or more; BDF2
    /// one rung after two steps); on rejection it drops as many rungs as the ideal asks (at
    /// least one, at most five) and retries from the same state. The first step is the
    /// largest rung not above `first`. The last step may pass the last output time.
    pub fn run_adaptive(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        adaptive: &Adaptive,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> Result<()>,
        mut progress: impl FnMut(u64, f64),
    ) -> Result<RunStats> {
        let tol = adaptive.tolerance;
        if !(tol.is_finite() && tol > 0.0) {
            return Err(Error::model(
                "time.tolerance",
                format!("must be a positive number, got {tol}"),
            ));
        }
        let Some(&t_last) = outputs.last() else {
            return Ok(RunStats::default());
        };
        let top = adaptive.max.unwrap_or((t_last - t0) / 10.0);
        if !(top.is_finite() && top > 0.0) {
            return Err(Error::model(
                "time.dt_max",
                format!("must be a positive number, got {top}"),
            ));
        }
        let n = self.sys.len();
        self.cg_error = CG_SHARE * tol;
        for v in [
            &mut self.u_prev2,
            &mut self.next,
            &mut self.d_now,
            &mut self.d_prev,
            &mut self.d_next,
            &mut self.pred,
            &mut self.hist,
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
        let par = self.options.parallel;
        self.gather(theta);
        self.sys.forcing(
            self.model,
            t0,
            &mut self.scratch,
            &mut self.rate,
            &mut self.f_now,
        );
        Self::derivative(&self.sys, &self.u, &self.f_now, &mut self.d_now, par);
        let first = match adaptive.first {
            Some(h) if h.is_finite() && h > 0.0 => h,
            Some(h) => {
                return Err(Error::model(
                    "time.dt",
                    format!("must be a positive number, got {h}"),
                ))
            }
            None => {
                let rate = self.d_now.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
                if rate > 0.0 {
                    tol / rate
                } else {
                    (t_last - t0) * 1e-4
                }
            }
        };
        // the largest rung not above the first step
        let mut k = ((top / first).log2() - 1e-9).ceil().max(0.0) as u32;
        let rung = |k: u32| top * 0.5f64.powi(k as i32);
        let mut stats = RunStats::default();
        self.stats.tolerance = tol;
        self.stats.min_step = f64::INFINITY;
        let (mut t, mut t_prev, mut t_prev2, mut h_prev) = (t0, t0, t0, 0.0);
        let mut on_rung = 0u32;
        let mut next_output = 0;
        while next_output < outputs.len() {
            if k > MAX_RUNG {
                return Err(Error::Solver {
                    message: format!(
                        "adaptive step fell below {:e} s at t = {t:e} s without meeting time.tolerance = {tol:e} K",
                        rung(MAX_RUNG)
                    ),
                });
            }
            let h = rung(k);
            let (est, p) = self.attempt(stats.steps, t, h, h_prev, t_prev, t_prev2)?;
            let ideal = if est > 0.0 {
                SAFETY * (tol / est).powf(1.0 / (p as f64 + 1.0))
            } else {
                f64::INFINITY
            };
            let accepted = est <= tol;
            if !accepted {
                // rejected (or non-finite): drop rungs and retry from the same state
                self.stats.rejected += 1;
                on_rung = 0;
                let cut = if ideal.is_finite() && ideal > 0.0 {
                    (-ideal.log2()).ceil().clamp(1.0, MAX_CUT as f64) as u32
                } else {
                    MAX_CUT
                };
                k += cut;
                continue;
            }
            // accept: shift the history
            std::mem::swap(&mut self.u_prev2, &mut self.u_prev);
            std::mem::swap(&mut self.u_prev, &mut self.u);
            std::mem::swap(&mut self.u, &mut self.next);
            std::mem::swap(&mut self.d_prev, &mut self.d_now);
            std::mem::swap(&mut self.d_now, &mut self.d_next);
            std::mem::swap(&mut self.f_now, &mut self.f_next);
            (t_prev2, t_prev) = (t_prev, t);
            t += h;
            h_prev = h;
            stats.steps += 1;
            on_rung += 1;
            if stats.steps == 1 {
                self.stats.first_step = h;
            }
            self.stats.min_step = self.stats.min_step.min(h);
            self.stats.max_step = self.stats.max_step.max(h);
            while next_output < outputs.len() && outputs[next_output] <= t + 1e-12 * h {
                let to = outputs[next_output];
                let s = ((to - t_prev) / h).clamp(0.0, 1.0);
                Self::hermite(
                    &self.u_prev,
                    &self.d_prev,
                    &self.u,
                    &self.d_now,
                    h,
                    s,
                    &mut self.next,
                );
                self.scatter_from_next(theta, to)?;
                on_output(next_output, to, theta, &self.model.conductance)?;
                next_output += 1;
            }
            progress(stats.steps, t);
            // climb whole rungs: one when the ideal step is twice this one and HYSTERESIS
            // steps were accepted here, up to GROWTH_RUNGS at once when it is 4× or more
            // (BDF2 one at a time, needing two steps on the rung: θ(t − 2h) is then stored)
            let (cap, wait) = match self.scheme {
                Scheme::Bdf2 => (1, if ideal >= 4.0 { 2 } else { HYSTERESIS }),
                _ => (GROWTH_RUNGS, if ideal >= 4.0 { 1 } else { HYSTERESIS }),
            };
            if ideal >= 2.0 && on_rung >= wait && k > 0 {
                let up = (ideal.log2().floor() as u32).min(cap).min(k);
                k -= up;
                on_rung = 0;
            }
        }
        self.stats.accepted = stats.steps;
        Ok(stats)
    }

    /// Writes `next` (the interpolated unknowns) into `theta` and sets the constrained nodes
    /// at time t.
    fn scatter_from_next(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        std::mem::swap(&mut self.u, &mut self.next);
        let done = self.scatter(theta, t);
        std::mem::swap(&mut self.u, &mut self.next);
        done
    }

    /// Steady state `A θ = f(t)` with each output time's boundary data and loads, calling
    /// `on_output(k, t, θ, K)` for each (theory §4).
    pub fn steady(
        &mut self,
        theta: &mut [f64],
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> Result<()>,
    ) -> Result<RunStats> {
        if self.sys.is_floating() {
            return Err(refuse(
                "steady: no boundary condition fixes the temperature level (every face insulated or free, no temperature or convection condition); the steady state is not unique",
            ));
        }
        for (k, &t) in outputs.iter().enumerate() {
            self.sys.forcing(
                self.model,
                t,
                &mut self.scratch,
                &mut self.rate,
                &mut self.rhs,
            );
            self.solve(0.0, Guess::Zero)?;
            std::mem::swap(&mut self.u, &mut self.rhs);
            self.scatter(theta, t)?;
            on_output(k, t, theta, &self.model.conductance)?;
        }
        Ok(RunStats::default())
    }
}
