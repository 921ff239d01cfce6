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

mod adaptive;
mod dense;
mod distributed;
mod linear;
mod ordering;
mod schemes;
mod steady;
mod system;

pub use adaptive::Adaptive;
pub use distributed::{symmetric_over, DISTRIBUTED_CG_STALL, DISTRIBUTED_CG_TOLERANCE};
pub use linear::{LinearError, Options, Solver};
pub use ordering::{nested_dissection, Ordering};
pub use schemes::Scheme;
pub use system::{System, SYMMETRY_TOLERANCE};

use crate::error::{Error, Result};
use crate::model::Model;
use faer::dyn_stack::MemBuffer;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::linalg::lu::SymbolicLu;
use faer::Par;
use linear::{Factor, Ledger};
use serde::{Deserialize, Serialize};
use std::time::Instant;

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
    /// [`Solver::Auto`]: the work of CG, direct solves and factorisations.
    ledger: Ledger,
    /// A distributed run's halo and block preconditioner ([`Implicit::distribute`]).
    ranks: Option<distributed::Ranks<'a>>,
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
    pub fn new(model: &'a Model, scheme: Scheme, mut options: Options) -> Result<Self> {
        let sys = System::build(model)?;
        let share = sys.held != (0..sys.len());
        if share {
            // a rank's share steps distributed ([`Implicit::distribute`]), which checks the
            // symmetry over the ranks and factorises its own block only
            options.solver = Solver::Cg;
        } else if options.solver == Solver::Cg && !sys.symmetric {
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
        let t = Instant::now();
        let (chol, lu, stack) = linear::symbolic(&sys, model, &options, par)?;
        let stats = ImplicitStats {
            factor_seconds: t.elapsed().as_secs_f64(),
            factor_entries: chol.as_ref().map_or(0, |s| s.len_val()),
            ..Default::default()
        };
        let ledger = Ledger::new(&sys, chol.as_ref());
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
            ledger,
            ranks: None,
            cg_error: 0.0,
            min_mass: sys.mass.iter().fold(f64::INFINITY, |m: f64, &v| m.min(v)),
            stats,
            sys,
            taken: 0,
            h_prev: 0.0,
        })
    }

    /// The model the system was eliminated from.
    pub fn model(&self) -> &'a Model {
        self.model
    }

    /// The eliminated system.
    pub fn system(&self) -> &System {
        &self.sys
    }
}

fn refuse(message: impl Into<String>) -> Error {
    Error::model("time.integrator", message)
}
