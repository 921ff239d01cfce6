//! The one stepping interface of the time integrators ([`Stepper`]), implemented by the
//! explicit, enthalpy and implicit steppers (`solve::explicit`, `solve::enthalpy`,
//! `solve::implicit`), and the loop over the output times at a fixed step ([`march`]). Which
//! stepper a case gets, and the loop for every schedule, are `solve::engine`'s: this module
//! imports none of the steppers.

use crate::error::{Error, Result};
use crate::model::Model;
use crate::operator::Conductance;
use crate::solve::steps::steps_between;

/// Summary of a run.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunStats {
    /// Time steps taken.
    pub steps: u64,
}

/// A fixed-step time integrator: the state of every node in θ (°C), advanced step by step.
///
/// The explicit steppers keep θ current; the implicit one keeps its state in the unknowns and
/// writes it into θ at [`Stepper::settle`].
pub trait Stepper {
    /// The model the stepper integrates.
    fn model(&self) -> &Model;

    /// Number of body nodes (the entries of θ that are checked for NaN).
    fn n_body(&self) -> usize {
        self.model().cloud.n_body
    }

    /// Refuses a fixed step `dt` (s) the stepper cannot take (implicit: not positive and
    /// finite); the explicit steppers take any step the plan chose.
    fn check_dt(&self, dt: f64) -> Result<()> {
        let _ = dt;
        Ok(())
    }

    /// Takes the state from `theta` (every node, °C) at time `t` (s): the next step starts
    /// afresh (implicit: a start-up step; phase change: enthalpies from θ; growing cracks:
    /// the bonds cut by `t`).
    fn begin(&mut self, theta: &mut [f64], t: f64);

    /// One step of length `h` (s) from `t` to `t1` (s; `t + h` up to the round-off the caller
    /// chooses, e.g. exactly an output time).
    fn advance(&mut self, theta: &mut [f64], t: f64, t1: f64, h: f64) -> Result<()>;

    /// Steps between two progress reports of [`march`] (implicit steps are slow: every one).
    fn report_every(&self) -> u64 {
        256
    }

    /// Fails with [`Error::NonFinite`] if θ holds a non-finite body temperature at `t` (s);
    /// checked every 4096 steps. The implicit state is checked at [`Stepper::settle`] instead.
    fn check(&self, theta: &[f64], t: f64) -> Result<()> {
        check_finite(theta, self.n_body(), t)
    }

    /// Brings θ up to time `t` (s) after steps (implicit: the state into θ, constrained nodes
    /// set; growing cracks: K cut) and fails if a body temperature is not finite; by default
    /// only the check, θ being current.
    fn settle(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        check_finite(theta, self.n_body(), t)
    }

    /// K as it is after [`Stepper::settle`] (growing cracks cut; with phase change, the
    /// current conductivities), W/K; by default the model's.
    fn conductance_now(&mut self) -> &Conductance {
        &self.model().conductance
    }

    /// Energy of the body in the state `theta`, J: Σ V_i ρc_i θ_i ([`Model::energy`], the
    /// default), or with phase change Σ V_i H_i of the stepper once it has begun.
    fn energy_now(&self, theta: &[f64]) -> f64 {
        self.model().energy(theta)
    }

    /// Called by [`march`] at the end of a run with its counters.
    fn finish(&mut self, stats: &RunStats) {
        let _ = stats;
    }
}

/// Fails with [`Error::NonFinite`] at the first body node of `theta` (of `nb`) that is not finite at time `t`, s.
pub fn check_finite(theta: &[f64], nb: usize, t: f64) -> Result<()> {
    match theta[..nb].iter().position(|v| !v.is_finite()) {
        Some(node) => Err(Error::NonFinite { node, time: t }),
        None => Ok(()),
    }
}

/// [`check_finite`] of a stepper that computes the body rows `rows`: a distributed run's
/// (`exchange`) checks its own rows and finds the first non-finite node over all ranks, so
/// that every rank stops together.
pub fn first_non_finite(
    theta: &[f64],
    rows: std::ops::Range<usize>,
    exchange: Option<&dyn crate::solve::exchange::Exchange>,
    t: f64,
) -> Result<()> {
    let Some(ex) = exchange else {
        return check_finite(theta, rows.end, t);
    };
    let local = theta[rows.clone()]
        .iter()
        .position(|v| !v.is_finite())
        .map_or(f64::INFINITY, |p| (rows.start + p) as f64);
    match ex.reduce(local, crate::solve::exchange::Reduce::Min) {
        node if node.is_finite() => Err(Error::NonFinite {
            node: node as usize,
            time: t,
        }),
        _ => Ok(()),
    }
}

/// The fixed-step time loop of every stepper: steps no longer than `dt` (s) that land on each
/// output time (s), a NaN check every 4096 steps and at every output, where
/// `at_output(stepper, k, t, θ)` is called; `progress(steps)` every
/// [`Stepper::report_every`] steps and at the end. The caller has begun the stepper.
pub fn march<S: Stepper + ?Sized, E: From<Error>>(
    stepper: &mut S,
    theta: &mut [f64],
    t0: f64,
    dt: f64,
    outputs: &[f64],
    mut at_output: impl FnMut(&mut S, usize, f64, &[f64]) -> std::result::Result<(), E>,
    mut progress: impl FnMut(u64),
) -> std::result::Result<RunStats, E> {
    stepper.check_dt(dt)?;
    let every = stepper.report_every();
    let mut t = t0;
    let mut stats = RunStats::default();
    for (k, &to) in outputs.iter().enumerate() {
        let n = steps_between(t, to, dt);
        let h = if n > 0 { (to - t) / n as f64 } else { 0.0 };
        for s in 0..n {
            let tn = t + s as f64 * h;
            let t1 = if s + 1 == n {
                to
            } else {
                t + (s + 1) as f64 * h
            };
            stepper.advance(theta, tn, t1, h)?;
            stats.steps += 1;
            if stats.steps % every == 0 {
                progress(stats.steps);
            }
            if stats.steps % 4096 == 0 {
                stepper.check(theta, tn + h)?;
            }
        }
        t = to;
        stepper.settle(theta, t)?;
        at_output(stepper, k, t, theta)?;
    }
    progress(stats.steps);
    stepper.finish(&stats);
    Ok(stats)
}
