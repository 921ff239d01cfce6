//! [`Engine`], the stepper a case's integrator and model call for (explicit, enthalpy or
//! implicit), and [`integrate`], the loop over the output times for every [`Schedule`] (fixed
//! steps through [`march`], adaptive ones through the implicit stepper's own control).

use crate::error::{Error, Result};
use crate::model::Model;
use crate::operator::Conductance;
use crate::solve::enthalpy::Enthalpic;
use crate::solve::explicit::Explicit;
use crate::solve::implicit::{self, Adaptive, Implicit, Solver};
use crate::solve::integrator::{Integrator, Stepping};
use crate::solve::stepper::{march, RunStats, Stepper};

/// The stepper of a case: the one that its integrator and model call for.
pub enum Engine<'a> {
    /// Forward Euler or RK4 on a linear model.
    Explicit(Explicit<'a>),
    /// Forward Euler in enthalpy form (phase change).
    Enthalpic(Enthalpic<'a>),
    /// Backward Euler, Crank–Nicolson, BDF2 or the steady solve.
    Implicit(Box<Implicit<'a>>),
}

impl<'a> Engine<'a> {
    /// Chooses and sets up the stepper of `integrator` on `model`: the enthalpy form of
    /// forward Euler for phase change (PCS2022,
    /// doi:10.1007/s42102-022-00092-3, refusing other integrators), the implicit stepper
    /// (system eliminated and factorised symbolically; `adaptive` steps visit several Δt, so
    /// CG until a factorisation pays, [`Solver::Auto`]) or the explicit one.
    pub fn new(model: &'a Model, integrator: Integrator, adaptive: bool) -> Result<Self> {
        if model.enthalpy.is_some() {
            return Ok(Engine::Enthalpic(Enthalpic::new(model, integrator)?));
        }
        let scheme = match integrator.stepping() {
            Stepping::Explicit(explicit) => {
                return Ok(Engine::Explicit(Explicit::new(model, explicit)))
            }
            Stepping::Implicit(scheme) => scheme,
        };
        let options = implicit::Options {
            solver: if adaptive {
                Solver::Auto
            } else {
                Solver::Direct
            },
            ..implicit::Options::default()
        };
        let stepper = Implicit::new(model, scheme, options)?;
        Ok(Engine::Implicit(Box::new(stepper)))
    }

    /// The stepper.
    pub fn stepper(&mut self) -> &mut (dyn Stepper + 'a) {
        match self {
            Engine::Explicit(s) => s,
            Engine::Enthalpic(s) => s,
            Engine::Implicit(s) => s.as_mut(),
        }
    }

    /// The stepper, read only.
    pub fn stepper_ref(&self) -> &(dyn Stepper + 'a) {
        match self {
            Engine::Explicit(s) => s,
            Engine::Enthalpic(s) => s,
            Engine::Implicit(s) => s.as_ref(),
        }
    }

    /// The implicit stepper, if this is one (its counters, adaptive steps, the steady solve).
    pub fn implicit(&self) -> Option<&Implicit<'a>> {
        match self {
            Engine::Implicit(s) => Some(s),
            _ => None,
        }
    }
}

/// How a run steps through its output times.
#[derive(Debug, Clone, Copy)]
pub struct Schedule {
    /// The fixed step, s (infinite for the steady solve; adaptive: the first step or 0).
    pub dt: f64,
    /// Adaptive steps of the implicit schemes (`time.tolerance`), if asked for.
    pub adaptive: Option<Adaptive>,
    /// The steady solve at each output time instead of steps.
    pub steady: bool,
}

impl Schedule {
    /// True for fixed steps of [`Schedule::dt`] (neither adaptive steps nor the steady solve).
    pub fn is_fixed(&self) -> bool {
        self.adaptive.is_none() && !self.steady
    }
}

/// The time loop of a run from `theta` (every node, °C) at `t0` (s) through `outputs` (s):
/// fixed steps through [`march`], or the implicit stepper's steady solve or adaptive steps.
/// Calls `on_output(k, t, θ, K, E)` at each output (K in W/K, E the body's energy in J) and
/// `progress(steps, t)` now and then (t in s). `on_output` may fail with the error of a
/// layer above (`E`, which holds this crate's [`Error`]); the loop then stops with it.
pub fn integrate<E: From<Error>>(
    engine: &mut Engine<'_>,
    schedule: &Schedule,
    theta: &mut [f64],
    t0: f64,
    outputs: &[f64],
    mut on_output: impl FnMut(usize, f64, &[f64], &Conductance, f64) -> std::result::Result<(), E>,
    mut progress: impl FnMut(u64, f64),
) -> std::result::Result<RunStats, E> {
    if let Engine::Implicit(im) = engine {
        let model = im.model();
        let mut linear = |k: usize, t: f64, th: &[f64], c: &Conductance| {
            on_output(k, t, th, c, model.energy(th))
        };
        if schedule.steady {
            return im.steady(theta, outputs, linear);
        }
        if let Some(a) = &schedule.adaptive {
            return im.run_adaptive(theta, t0, a, outputs, &mut linear, progress);
        }
    }
    let dt = schedule.dt;
    let stepper = engine.stepper();
    stepper.begin(theta, t0);
    march(
        stepper,
        theta,
        t0,
        dt,
        outputs,
        |s, k, t, th| {
            let e = s.energy_now(th);
            on_output(k, t, th, s.conductance_now(), e)
        },
        |steps| progress(steps, steps as f64 * dt),
    )
}
