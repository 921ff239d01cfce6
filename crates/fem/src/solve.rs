//! Time integration and the steady solve with a sparse Cholesky factorisation (faer).
//!
//! With θ the scheme's weight (1 backward Euler, ½ Crank–Nicolson) one step solves
//! (M/Δt + θK) u_{n+1} = (M/Δt − (1 − θ)K) u_n + θ f_{n+1} + (1 − θ) f_n
//! on the free nodes, the held ones eliminated (their columns moved to the right-hand side
//! with their values at t_{n+1}), so the matrix stays symmetric positive definite. The steady
//! solve is K u = f on the free nodes. Each distinct Δt is factorised once and cached.
//!
//! Crank–Nicolson starts the way Rannacher proposed: its first two steps are four backward
//! Euler half steps, whose matrix M/(Δt/2) + K is twice the Crank–Nicolson one (the same
//! factorisation serves). They damp the stiff modes that a jump between the initial field and
//! the held values excites, which Crank–Nicolson alone leaves ringing when Δt ≫ h²/α, and
//! keep the scheme second order.

use crate::assemble::System;
use crate::boundary::Conditions;
use crate::mesh::FemMesh;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Side};
use peritherm_core::error::{Error, Result};

/// A sparse Cholesky factor L Lᵀ with the scratch memory its solves need, so that solving
/// allocates nothing.
struct Factor {
    /// Δt it was made for, s (0: the steady matrix K).
    dt: f64,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    scratch: MemBuffer,
}

impl Factor {
    /// Factorises the lower triangle `a` (SPD), or says why it cannot.
    fn new(dt: f64, a: &SparseColMat<usize, f64>) -> std::result::Result<Factor, String> {
        let par = faer::get_global_parallelism();
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut work =
            MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut work),
                Default::default(),
            )
            .map_err(|e| e.to_string())?;
        let scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, par));
        Ok(Factor {
            dt,
            symbolic,
            values,
            scratch,
        })
    }

    /// Overwrites `rhs` with the solution of L Lᵀ x = rhs.
    fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(rhs, n, 1),
            faer::get_global_parallelism(),
            MemStack::new(&mut self.scratch),
        );
    }
}

/// Time discretisation of the FEM solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Backward Euler: first order in time, L-stable (no oscillations after jumps).
    BackwardEuler,
    /// Crank–Nicolson: second order in time, A-stable; started with four backward-Euler half
    /// steps (Rannacher) so that stiff modes excited at t = 0 are damped.
    CrankNicolson,
    /// The steady state K u = f at every output time (boundary values taken at that time).
    Steady,
}

impl Scheme {
    /// Every scheme, in the order their names are listed to users.
    pub const ALL: [Scheme; 3] = [Scheme::CrankNicolson, Scheme::BackwardEuler, Scheme::Steady];

    /// The scheme of [`Scheme::name`] `name` (`_` read as `-`), if there is one.
    pub fn from_name(name: &str) -> Option<Scheme> {
        let name = name.replace('_', "-");
        Scheme::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The name written to run.json.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::BackwardEuler => "backward-euler",
            Scheme::CrankNicolson => "crank-nicolson",
            Scheme::Steady => "steady",
        }
    }

    /// Weight θ of the new time level (1 for the steady solve).
    fn weight(self) -> f64 {
        match self {
            Scheme::CrankNicolson => 0.5,
            _ => 1.0,
        }
    }
}

/// Crank–Nicolson steps taken as backward-Euler half steps at the start (Rannacher: 2).
const STARTUP: u32 = 2;

/// Steps a FEM system through time; allocates only when it meets a new Δt.
pub struct Stepper<'a> {
    mesh: &'a FemMesh,
    sys: &'a System,
    cond: &'a Conditions,
    scheme: Scheme,
    /// Reduced index of each node, `u32::MAX` for held nodes.
    reduced: Vec<u32>,
    /// Node of each reduced index.
    free: Vec<u32>,
    /// Factorisations by Δt (s); the steady one under Δt = 0.
    factors: Vec<Factor>,
    f_now: Vec<f64>,
    f_next: Vec<f64>,
    f_time: f64,
    rhs: Vec<f64>,
    /// Crank–Nicolson steps still to be taken as two backward-Euler half steps.
    startup: u32,
}

impl<'a> Stepper<'a> {
    /// A stepper for `sys` with the conditions `cond` on `mesh`.
    pub fn new(mesh: &'a FemMesh, sys: &'a System, cond: &'a Conditions, scheme: Scheme) -> Self {
        let n = sys.len();
        let mut reduced = vec![u32::MAX; n];
        let mut free = Vec::new();
        for (i, r) in reduced.iter_mut().enumerate() {
            if !cond.is_held(i) {
                *r = free.len() as u32;
                free.push(i as u32);
            }
        }
        let nf = free.len();
        Stepper {
            mesh,
            sys,
            cond,
            scheme,
            reduced,
            free,
            factors: Vec::new(),
            f_now: vec![0.0; n],
            f_next: vec![0.0; n],
            f_time: f64::NAN,
            rhs: vec![0.0; nf],
            startup: STARTUP * u32::from(scheme == Scheme::CrankNicolson),
        }
    }

    /// Number of free (unknown) nodes.
    pub fn n_free(&self) -> usize {
        self.free.len()
    }

    /// Number of distinct factorisations made so far.
    pub fn n_factorisations(&self) -> usize {
        self.factors.len()
    }

    /// Index of the factorisation of M/Δt + θK (K alone for Δt = 0), made if missing.
    fn factor(&mut self, dt: f64) -> Result<usize> {
        if let Some(k) = self
            .factors
            .iter()
            .position(|f| (f.dt - dt).abs() <= 1e-12 * dt.abs())
        {
            return Ok(k);
        }
        if dt == 0.0 && !self.cond.anchored() {
            return Err(Error::model(
                "boundary",
                "fem: the steady temperature is not determined (the system matrix is not positive definite): give a held temperature or a convection boundary",
            ));
        }
        let (sys, w) = (self.sys, self.scheme.weight());
        let inv_dt = if dt > 0.0 { 1.0 / dt } else { 0.0 };
        let mut trip = Vec::with_capacity(sys.cols.len() / 2 + self.free.len());
        for (r, &i) in self.free.iter().enumerate() {
            let i = i as usize;
            for p in sys.offsets[i]..sys.offsets[i + 1] {
                let c = self.reduced[sys.cols[p] as usize];
                if c != u32::MAX && c as usize <= r {
                    let v = sys.mass[p] * inv_dt + w * sys.stiffness[p];
                    trip.push(Triplet::new(r, c as usize, v));
                }
            }
        }
        let nf = self.free.len();
        let not_spd = |what: String| {
            Error::model(
                "boundary",
                format!("fem: the system matrix is not positive definite ({what}); a steady problem needs a held temperature or a convection boundary"),
            )
        };
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(nf, nf, &trip)
            .map_err(|e| not_spd(format!("{e:?}")))?;
        self.factors.push(Factor::new(dt, &a).map_err(not_spd)?);
        Ok(self.factors.len() - 1)
    }

    /// Solves the reduced system in `self.rhs` with factorisation `k` and scatters into `theta`.
    fn solve_into(&mut self, k: usize, theta: &mut [f64], t: f64) -> Result<()> {
        let nf = self.free.len();
        if nf > 0 {
            self.factors[k].solve(&mut self.rhs);
        }
        for (r, &i) in self.free.iter().enumerate() {
            let v = self.rhs[r];
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    node: i as usize,
                    time: t,
                });
            }
            theta[i as usize] = v;
        }
        Ok(())
    }

    /// One step of length `dt` (s) from time `t`: `theta` (°C, every node) goes to t + dt.
    pub fn step(&mut self, theta: &mut [f64], t: f64, dt: f64) -> Result<()> {
        let k = self.factor(dt)?;
        if self.startup > 0 {
            self.startup -= 1;
            self.half_step(theta, t, dt, k)?;
            return self.half_step(theta, t + 0.5 * dt, dt, k);
        }
        let (sys, w) = (self.sys, self.scheme.weight());
        let inv_dt = 1.0 / dt;
        if w < 1.0 && self.f_time != t {
            self.cond.load(t, &mut self.f_now);
        }
        self.cond.load(t + dt, &mut self.f_next);
        // (M/Δt − (1 − θ)K) u_n + θ f_{n+1} + (1 − θ) f_n, gathered row by row
        for (r, &i) in self.free.iter().enumerate() {
            let i = i as usize;
            let mut s = w * self.f_next[i];
            if w < 1.0 {
                s += (1.0 - w) * self.f_now[i];
            }
            for p in sys.offsets[i]..sys.offsets[i + 1] {
                let j = sys.cols[p] as usize;
                s += (sys.mass[p] * inv_dt - (1.0 - w) * sys.stiffness[p]) * theta[j];
            }
            self.rhs[r] = s;
        }
        // held values at t + dt, their columns moved to the right-hand side
        self.cond.impose(self.mesh, t + dt, theta);
        self.lift(theta, inv_dt, w);
        std::mem::swap(&mut self.f_now, &mut self.f_next);
        self.f_time = t + dt;
        self.solve_into(k, theta, t + dt)
    }

    /// A backward-Euler step of Δt/2 from `t` with the Crank–Nicolson factorisation `k` of Δt:
    /// (M/Δt + K/2) u = M/Δt u_n + f(t + Δt/2)/2.
    fn half_step(&mut self, theta: &mut [f64], t: f64, dt: f64, k: usize) -> Result<()> {
        let sys = self.sys;
        let (inv_dt, to) = (1.0 / dt, t + 0.5 * dt);
        self.cond.load(to, &mut self.f_next);
        for (r, &i) in self.free.iter().enumerate() {
            let i = i as usize;
            let mut s = 0.5 * self.f_next[i];
            for p in sys.offsets[i]..sys.offsets[i + 1] {
                s += sys.mass[p] * inv_dt * theta[sys.cols[p] as usize];
            }
            self.rhs[r] = s;
        }
        self.cond.impose(self.mesh, to, theta);
        self.lift(theta, inv_dt, 0.5);
        std::mem::swap(&mut self.f_now, &mut self.f_next);
        self.f_time = to;
        self.solve_into(k, theta, to)
    }

    /// Subtracts (M/Δt + θK)_{F,held} u_held from the reduced right-hand side.
    fn lift(&mut self, theta: &[f64], inv_dt: f64, w: f64) {
        let sys = self.sys;
        for (r, &i) in self.free.iter().enumerate() {
            let i = i as usize;
            let mut s = 0.0;
            for p in sys.offsets[i]..sys.offsets[i + 1] {
                let j = sys.cols[p] as usize;
                if self.reduced[j] == u32::MAX {
                    s += (sys.mass[p] * inv_dt + w * sys.stiffness[p]) * theta[j];
                }
            }
            self.rhs[r] -= s;
        }
    }

    /// The steady state with the loads and held values of time `t`, into `theta` (°C).
    pub fn steady(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        let k = self.factor(0.0)?;
        self.cond.load(t, &mut self.f_next);
        for (r, &i) in self.free.iter().enumerate() {
            self.rhs[r] = self.f_next[i as usize];
        }
        self.cond.impose(self.mesh, t, theta);
        self.lift(theta, 0.0, 1.0);
        self.solve_into(k, theta, t)
    }
}

#[cfg(test)]
mod tests {
    use super::Scheme;

    /// Every scheme is found again from its run.json name (and with `_` for `-`); other names
    /// are not.
    #[test]
    fn schemes_are_found_by_name() {
        for s in Scheme::ALL {
            assert_eq!(Scheme::from_name(s.name()), Some(s));
            assert_eq!(Scheme::from_name(&s.name().replace('-', "_")), Some(s));
        }
        assert_eq!(Scheme::from_name("bdf2"), None);
    }
}
