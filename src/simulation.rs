//! Stepping a case by hand: a model's temperature, time and integrator in one value, advanced
//! by a number of steps or to a time with the arithmetic of [`crate::run::run_case`] (the
//! same steppers, step lengths and step times), for scripts and notebooks.
//!
//! [`Simulation::advance_to`] takes the steps a run takes between two output times, so
//! advancing through a case's output times gives a run's fields bit for bit;
//! [`Simulation::step`] takes steps of exactly [`Simulation::dt`].

use crate::case::Case;
use crate::error::{CoreError, Error, Result};
use crate::math::Vector;
use crate::model::Model;
use crate::operator::Conductance;
use crate::prepare::{keyed, plan};
use crate::solve::{check_finite, integrate, steps_between, Engine, Schedule};

/// Steps between two calls of the `keep_going` callback of the stepping methods.
pub const CHECK_EVERY: u64 = 64;

/// The fields at one output time of [`Simulation::run`].
#[derive(Debug, Clone)]
pub struct Snapshot {
    /// Time, s.
    pub time: f64,
    /// Temperature of every node (body first), °C.
    pub theta: Vec<f64>,
    /// Heat flux per body node, W/m².
    pub flux: Vec<Vector>,
    /// Damage φ per body node (0 … 1).
    pub damage: Vec<f64>,
    /// Energy of the body, J ([`Simulation::energy`]).
    pub energy: f64,
}

/// A case's model with its temperature, time and integrator.
pub struct Simulation<'a> {
    case: &'a Case,
    model: &'a Model,
    /// How the case's run steps (the step, adaptive steps, the steady solve).
    schedule: Schedule,
    /// The stepper of the plan, as a run has it.
    engine: Engine<'a>,
    theta: Vec<f64>,
    t: f64,
    steps: u64,
    /// Whether the stepper has taken its state from `theta` (implicit and enthalpy steppers).
    started: bool,
}

impl<'a> Simulation<'a> {
    /// Plans the time loop of `case` on `model` as a run does ([`crate::prepare::plan`]:
    /// the step, the steppers) and starts from the model's initial field at t = 0 s.
    pub fn new(case: &'a Case, model: &'a Model) -> Result<Self> {
        let plan = plan(case, model)?;
        Ok(Simulation {
            case,
            model,
            schedule: plan.schedule(),
            engine: plan.engine,
            theta: model.theta0.clone(),
            t: 0.0,
            steps: 0,
            started: false,
        })
    }

    /// The model.
    pub fn model(&self) -> &'a Model {
        self.model
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Steps taken since the start, whatever their length.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The run's fixed step, s (the case's `time.dt` or 0.95 of the stable step; infinite for
    /// the steady solve, the first step or 0 for adaptive steps).
    pub fn dt(&self) -> f64 {
        self.schedule.dt
    }

    /// Temperature of every node (body first, then fictitious), °C.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// Sets the temperature: `theta` holds the body nodes (°C), or every node; the boundary
    /// then sets its nodes at the current time, and the next step starts the integrator
    /// afresh from this field (implicit: a start-up step; phase change: enthalpies from it).
    pub fn set_theta(&mut self, theta: &[f64]) -> Result<()> {
        let (nb, n) = (self.model.cloud.n_body, self.theta.len());
        if theta.len() != nb && theta.len() != n {
            return Err(Error::model(
                "temperature",
                format!(
                    "{} values given; the model has {nb} body nodes ({n} with the fictitious ones)",
                    theta.len()
                ),
            ));
        }
        if let Some(i) = theta.iter().position(|v| !v.is_finite()) {
            return Err(Error::model(
                "temperature",
                format!("value {i} is not finite ({})", theta[i]),
            ));
        }
        self.theta[..theta.len()].copy_from_slice(theta);
        self.model
            .boundary
            .apply(&self.model.cloud, &mut self.theta, self.t);
        self.started = false;
        Ok(())
    }

    /// Refuses stepping by hand when the case's time loop is not a fixed-step one.
    fn fixed(&self) -> Result<()> {
        let why = if self.schedule.adaptive.is_some() {
            "time.tolerance"
        } else if self.schedule.steady {
            "time.integrator"
        } else {
            return Ok(());
        };
        Err(keyed(
            self.case,
            Error::model(
                why,
                "adaptive steps and the steady solve are not stepped by hand; use run(outputs)",
            ),
        ))
    }

    /// Starts the stepper from the current field once ([`crate::solve::Stepper::begin`]).
    fn begin(&mut self) {
        if !self.started {
            self.engine.stepper().begin(&mut self.theta, self.t);
        }
        self.started = true;
    }

    /// Takes `n` steps of length [`Simulation::dt`]; `keep_going(steps)` is asked every
    /// [`CHECK_EVERY`] steps and stops stepping (at a step's end) when it says false.
    /// Returns whether all `n` steps were taken.
    pub fn step(&mut self, n: u64, keep_going: impl FnMut(u64) -> bool) -> Result<bool> {
        self.fixed()?;
        let (t, h) = (self.t, self.schedule.dt);
        self.steps_of(n, t, h, t + n as f64 * h, keep_going)
    }

    /// Advances to `to` (s, not before the current time) with the steps a run takes between
    /// two output times: the fewest no longer than [`Simulation::dt`], of equal length, the
    /// last landing on `to`. `keep_going` as in [`Simulation::step`].
    pub fn advance_to(&mut self, to: f64, keep_going: impl FnMut(u64) -> bool) -> Result<bool> {
        self.fixed()?;
        if !(to.is_finite() && to >= self.t) {
            return Err(Error::model(
                "time",
                format!("cannot advance to {to} s from t = {} s", self.t),
            ));
        }
        let t = self.t;
        let n = steps_between(t, to, self.schedule.dt);
        let h = if n > 0 { (to - t) / n as f64 } else { 0.0 };
        self.steps_of(n, t, h, to, keep_going)
    }

    /// `n` steps of `h` from `t` (step s from t + s·h), the last ending at `end`.
    ///
    /// Not [`crate::solve::march`] (which [`Simulation::run`] reaches through
    /// [`integrate`] for adaptive steps and the steady solve), though its step times are the
    /// same: `march` divides each span between output times into equal steps
    /// `(to − t)/n`, which may differ from [`Simulation::step`]'s exact `dt` in the last bit
    /// and so change the fields; it cannot stop between steps when `keep_going` says so; and
    /// it counts steps (the NaN check every 4096, the implicit stepper's `accepted` at
    /// [`crate::solve::Stepper::finish`]) per call, where a simulation counts from its start.
    fn steps_of(
        &mut self,
        n: u64,
        t: f64,
        h: f64,
        end: f64,
        mut keep_going: impl FnMut(u64) -> bool,
    ) -> Result<bool> {
        self.begin();
        let mut done = 0;
        let mut stopped = false;
        while done < n {
            let tn = t + done as f64 * h;
            let t1 = if done + 1 == n {
                end
            } else {
                t + (done + 1) as f64 * h
            };
            let stepper = self.engine.stepper();
            stepper
                .advance(&mut self.theta, tn, t1, h)
                .map_err(|e| keyed(self.case, e))?;
            done += 1;
            self.steps += 1;
            self.t = t1;
            if self.steps.is_multiple_of(4096) {
                stepper.check(&self.theta, self.t)?;
            }
            if done < n && done.is_multiple_of(CHECK_EVERY) && !keep_going(self.steps) {
                stopped = true;
                break;
            }
        }
        self.settle()?;
        Ok(!stopped)
    }

    /// Brings θ and K up to the current time after stepping: the implicit state into θ (the
    /// constrained nodes set), growing cracks cut, and a finite check.
    fn settle(&mut self) -> Result<()> {
        let t = self.t;
        self.engine.stepper().settle(&mut self.theta, t)?;
        Ok(check_finite(&self.theta, self.model.cloud.n_body, t)?)
    }

    /// K as it is now (growing cracks cut; with phase change, the current conductivities),
    /// W/K.
    pub fn conductance(&mut self) -> &Conductance {
        // phase change: the conductivities need the enthalpies; set them now as the first
        // step would (growing cracks: the bonds cut by now)
        self.begin();
        self.engine.stepper().conductance_now()
    }

    /// Peridynamic heat flux of every body node now (theory §8), W/m².
    pub fn flux(&mut self) -> Vec<Vector> {
        let model = self.model;
        let theta = std::mem::take(&mut self.theta);
        let q = self.conductance().flux(&model.cloud, &theta);
        self.theta = theta;
        q
    }

    /// Damage φ of every body node now (theory §5).
    pub fn damage(&self) -> Vec<f64> {
        self.model.damage_at(self.t)
    }

    /// Energy of the body now, J, as a run's `energy`: Σ V_i ρc_i θ_i, or with phase change
    /// Σ V_i H_i of the stepper (before the first step, [`Model::energy`]).
    pub fn energy(&self) -> f64 {
        if self.started {
            self.engine.stepper_ref().energy_now(&self.theta)
        } else {
            self.model.energy(&self.theta)
        }
    }

    /// The fields now.
    pub fn snapshot(&mut self) -> Snapshot {
        Snapshot {
            time: self.t,
            flux: self.flux(),
            damage: self.damage(),
            energy: self.energy(),
            theta: self.theta.clone(),
        }
    }

    /// Advances through `outputs` (s, increasing, after the current time) and takes a
    /// [`Snapshot`] at each, as a run from this state would: fixed steps through
    /// [`Simulation::advance_to`], adaptive steps and the steady solve through the implicit
    /// stepper's own loops. `keep_going` as in [`Simulation::step`] (fixed steps only);
    /// returns the snapshots taken and whether all outputs were reached.
    pub fn run(
        &mut self,
        outputs: &[f64],
        mut keep_going: impl FnMut(u64) -> bool,
    ) -> Result<(Vec<Snapshot>, bool)> {
        let mut prev = self.t;
        for &t in outputs {
            if !(t.is_finite() && t >= prev) {
                return Err(Error::model(
                    "outputs",
                    format!("must be increasing times from t = {} s, got {t} s", self.t),
                ));
            }
            prev = t;
        }
        let mut snapshots = Vec::new();
        if self.fixed().is_ok() {
            for &t in outputs {
                if !self.advance_to(t, &mut keep_going)? {
                    return Ok((snapshots, false));
                }
                snapshots.push(self.snapshot());
            }
            return Ok((snapshots, true));
        }
        let model = self.model;
        let mut theta = std::mem::take(&mut self.theta);
        let collect = |_: usize, t: f64, th: &[f64], k: &Conductance, energy: f64| {
            snapshots.push(Snapshot {
                time: t,
                theta: th.to_vec(),
                flux: k.flux(&model.cloud, th),
                damage: model.damage_at(t),
                energy,
            });
            Ok::<(), CoreError>(())
        };
        // adaptive steps or the steady solve: the implicit stepper's own loops
        let result = integrate(
            &mut self.engine,
            &self.schedule,
            &mut theta,
            self.t,
            outputs,
            collect,
            |_, _| {},
        );
        self.theta = theta;
        let stats = result.map_err(|e| keyed(self.case, e))?;
        self.steps += stats.steps;
        if let Some(&t) = outputs.last() {
            self.t = t;
        }
        self.started = false;
        Ok((snapshots, true))
    }
}
