//! The fixed-step schemes: backward Euler, Crank–Nicolson (Rannacher start-up) and
//! variable-step BDF2 (theory §4).

use super::linear::Guess;
use super::Implicit;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::operator::Conductance;
use crate::solve::stepper::{check_finite, march, RunStats, Stepper};

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

impl Implicit<'_> {
    pub(super) fn forcing_into_next(&mut self, t: f64) {
        self.sys.forcing(
            self.model,
            t,
            &mut self.scratch,
            &mut self.rate,
            &mut self.f_next,
        );
    }

    /// Backward Euler from the current `u` over `h` to time `t1` with coefficient c = 1/h.
    pub(super) fn be_step(&mut self, t1: f64, h: f64) -> Result<()> {
        let c = 1.0 / h;
        self.forcing_into_next(t1);
        for r in self.own() {
            self.rhs[r] = c * self.sys.mass[r] * self.u[r] + self.f_next[r];
        }
        self.solve(c, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        Ok(())
    }

    /// Crank–Nicolson from `u` (with f at t in `f_now`) over h to `t1`.
    pub(super) fn cn_step(&mut self, t1: f64, h: f64) -> Result<()> {
        let c = 2.0 / h;
        self.forcing_into_next(t1);
        Self::halo_of(&mut self.ranks, &self.sys, &mut self.u);
        self.sys
            .combine(c, 1.0, &self.u, &mut self.rhs, self.options.parallel);
        for r in self.own() {
            self.rhs[r] += self.f_now[r] + self.f_next[r];
        }
        self.solve(c, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        std::mem::swap(&mut self.f_now, &mut self.f_next);
        Ok(())
    }

    /// Variable-step BDF2 from (u_prev, u) with step ratio ω = h / h_prev to `t1`.
    pub(super) fn bdf2_step(&mut self, t1: f64, h: f64, omega: f64) -> Result<()> {
        let a0 = (1.0 + 2.0 * omega) / (1.0 + omega);
        let a1 = 1.0 + omega;
        let a2 = omega * omega / (1.0 + omega);
        self.forcing_into_next(t1);
        for r in self.own() {
            self.rhs[r] =
                self.sys.mass[r] / h * (a1 * self.u[r] - a2 * self.u_prev[r]) + self.f_next[r];
        }
        self.solve(a0 / h, Guess::U)?;
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.rhs);
        Ok(())
    }

    /// Takes the unknowns from `theta` (every node, °C) and the forcing f at `t` (s) into
    /// `f_now`: where fixed steps ([`Implicit::start`]) and adaptive ones start.
    pub(super) fn take_state(&mut self, theta: &[f64], t: f64) {
        for (u, &i) in self.u.iter_mut().zip(&self.sys.free) {
            *u = theta[i];
        }
        self.sys.forcing(
            self.model,
            t,
            &mut self.scratch,
            &mut self.rate,
            &mut self.f_now,
        );
    }

    /// Writes the unknowns into `theta` and sets every constrained node at time t; a
    /// distributed run's ranks then gather the whole field.
    pub(super) fn scatter(&self, theta: &mut [f64], t: f64) -> Result<()> {
        for k in self.own() {
            theta[self.sys.free[k]] = self.u[k];
        }
        let ranks = self.ranks.as_ref().map(|r| r.exchange());
        if let Some(ex) = ranks {
            ex.halo(theta);
        }
        self.model.boundary.apply(&self.model.cloud, theta, t);
        if let Some(ex) = ranks {
            ex.all_gather(theta);
        }
        check_finite(theta, self.model.cloud.n_body, t)
    }

    /// Starts fixed-step stepping ([`Implicit::step`]) from `theta` (every node, °C) at
    /// `t0`, s: the unknowns and the forcing are taken there, and the next step is a start-up
    /// step (Crank–Nicolson: two backward-Euler half steps; BDF2: backward Euler).
    pub fn start(&mut self, theta: &[f64], t0: f64) {
        self.take_state(theta, t0);
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
    /// `progress(steps)` after every step and at the end.
    pub fn run(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        dt: f64,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> Result<()>,
        progress: impl FnMut(u64),
    ) -> Result<RunStats> {
        self.check_dt(dt)?;
        self.start(theta, t0);
        march(
            self,
            theta,
            t0,
            dt,
            outputs,
            |me, k, t, theta| on_output(k, t, theta, &me.model.conductance),
            progress,
        )
    }
}

impl Stepper for Implicit<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn check_dt(&self, dt: f64) -> Result<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::model(
                "time.dt",
                format!("must be a positive number for an implicit integrator, got {dt}"),
            ));
        }
        Ok(())
    }
    fn begin(&mut self, theta: &mut [f64], t: f64) {
        self.start(theta, t);
    }
    fn advance(&mut self, _theta: &mut [f64], t: f64, t1: f64, h: f64) -> Result<()> {
        self.step(t, t1, h)
    }
    fn report_every(&self) -> u64 {
        1
    }
    fn check(&self, _theta: &[f64], _t: f64) -> Result<()> {
        Ok(())
    }
    fn settle(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        self.scatter(theta, t)
    }
    fn finish(&mut self, stats: &RunStats) {
        self.stats.accepted = stats.steps;
    }
}
