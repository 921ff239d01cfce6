//! The time integrators of `time.integrator` (theory §4): their names, stability bounds and
//! the step a run takes, and the implicit scheme each implicit integrator runs.

use crate::error::{Error, Result};
use crate::model::Model;
use crate::solve::implicit::Scheme;
use serde::{Deserialize, Serialize};

/// Time integrator of `time.integrator`: the explicit ones in [`crate::solve::explicit`] (or,
/// with phase change, [`crate::solve::enthalpy`]), the implicit ones and the steady solve in
/// [`crate::solve::implicit`] (theory §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Forward Euler, stable for Δt ≤ 2/λ_max.
    Euler,
    /// Classical fourth-order Runge–Kutta, stable for Δt ≤ 2.78/λ_max.
    Rk4,
    /// Backward Euler (implicit, first order, no stability bound).
    BackwardEuler,
    /// Crank–Nicolson (implicit, second order, no stability bound).
    CrankNicolson,
    /// BDF2 (implicit, second order, no stability bound).
    Bdf2,
    /// Steady state A θ = f(t) at each output time (no time stepping).
    Steady,
}

/// An explicit integrator, the ones [`crate::solve::explicit::Explicit`] steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExplicitScheme {
    /// Forward Euler.
    Euler,
    /// Classical fourth-order Runge–Kutta.
    Rk4,
}

/// How an integrator steps ([`Integrator::stepping`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stepping {
    /// By [`crate::solve::explicit::Explicit`].
    Explicit(ExplicitScheme),
    /// By [`crate::solve::implicit::Implicit`] with this scheme.
    Implicit(Scheme),
}

impl TryFrom<Integrator> for ExplicitScheme {
    /// The implicit scheme of an integrator that is not explicit.
    type Error = Scheme;
    fn try_from(i: Integrator) -> std::result::Result<ExplicitScheme, Scheme> {
        match i.stepping() {
            Stepping::Explicit(e) => Ok(e),
            Stepping::Implicit(s) => Err(s),
        }
    }
}

impl Integrator {
    /// Every integrator, in the order their names are listed to users.
    pub const ALL: [Integrator; 6] = [
        Integrator::Euler,
        Integrator::Rk4,
        Integrator::BackwardEuler,
        Integrator::CrankNicolson,
        Integrator::Bdf2,
        Integrator::Steady,
    ];

    /// Name for messages (the `time.integrator` value).
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::Rk4 => "rk4",
            Integrator::BackwardEuler => "backward_euler",
            Integrator::CrankNicolson => "crank_nicolson",
            Integrator::Bdf2 => "bdf2",
            Integrator::Steady => "steady",
        }
    }

    /// The integrator of [`Integrator::name`] `name`, if there is one.
    pub fn from_name(name: &str) -> Option<Integrator> {
        Integrator::ALL.into_iter().find(|i| i.name() == name)
    }

    /// True for the implicit schemes and the steady solve ([`crate::solve::implicit`]).
    pub fn is_implicit(&self) -> bool {
        matches!(self.stepping(), Stepping::Implicit(_))
    }

    /// How the integrator steps: its explicit scheme, or the implicit scheme it runs.
    pub fn stepping(&self) -> Stepping {
        match self {
            Integrator::Euler => Stepping::Explicit(ExplicitScheme::Euler),
            Integrator::Rk4 => Stepping::Explicit(ExplicitScheme::Rk4),
            Integrator::BackwardEuler => Stepping::Implicit(Scheme::BackwardEuler),
            Integrator::CrankNicolson => Stepping::Implicit(Scheme::CrankNicolson),
            Integrator::Bdf2 | Integrator::Steady => Stepping::Implicit(Scheme::Bdf2),
        }
    }

    /// The implicit scheme that runs this integrator (the steady solve uses the system and
    /// solvers of BDF2's set-up); None for the explicit integrators. The one place the
    /// implicit [`Scheme`] is derived from the integrator.
    pub fn scheme(&self) -> Option<Scheme> {
        match self.stepping() {
            Stepping::Implicit(scheme) => Some(scheme),
            Stepping::Explicit(_) => None,
        }
    }

    /// Stability-region extent on the negative real axis (theory §4); infinite for the
    /// implicit schemes (A-stable).
    pub fn stability(&self) -> f64 {
        match self {
            Integrator::Euler => 2.0,
            Integrator::Rk4 => 2.78,
            _ => f64::INFINITY,
        }
    }

    /// Largest stable step for a model, s.
    pub fn stable_dt(&self, model: &Model) -> f64 {
        let l = model.lambda_max();
        if l > 0.0 {
            self.stability() / l
        } else {
            f64::INFINITY
        }
    }
}

/// Chooses the step, s: the user's (checked against the bound) or 0.95 of the bound; implicit
/// integrators need the user's step (no bound), the steady solve none (infinite).
pub fn choose_dt(model: &Model, integrator: Integrator, user: Option<f64>) -> Result<f64> {
    if integrator == Integrator::Steady {
        return Ok(f64::INFINITY);
    }
    if integrator.is_implicit() {
        return match user {
            Some(dt) => Ok(dt),
            None => Err(Error::model(
                "time.dt",
                format!(
                    "is required for the implicit integrator {} (no stability bound to default to), unless time.tolerance asks for adaptive steps",
                    integrator.name()
                ),
            )),
        };
    }
    let bound = integrator.stable_dt(model);
    match user {
        Some(dt) if dt > bound => Err(Error::UnstableDt {
            dt,
            bound,
            integrator: integrator.name(),
        }),
        Some(dt) => Ok(dt),
        None if bound.is_finite() => Ok(0.95 * bound),
        None => Err(Error::model(
            "time.dt",
            "every node is driven; give time.dt explicitly",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(Integrator::from_name(i.name()), Some(i));
        }
        assert_eq!(Integrator::from_name("rk2"), None);
        assert_eq!(Integrator::Steady.scheme(), Some(Scheme::Bdf2));
        assert_eq!(Integrator::Rk4.scheme(), None);
    }
}
