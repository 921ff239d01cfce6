//! The steady solve `A θ = f(t)` at each output time (theory §4).

use super::linear::Guess;
use super::{refuse, Implicit};
use crate::error::{Error, Result};
use crate::operator::Conductance;
use crate::solve::exchange::Reduce;
use crate::solve::stepper::RunStats;

impl Implicit<'_> {
    /// Refuses a steady problem whose boundary conditions leave the temperature level free
    /// (every face insulated, free or a flux): its steady state is not unique. Reduced over
    /// the ranks when distributed.
    pub fn level_fixed(&self) -> Result<()> {
        let floating = match &self.ranks {
            Some(r) => {
                let here = if self.sys.is_floating() { 1.0 } else { 0.0 };
                r.exchange().reduce(here, Reduce::Min) == 1.0
            }
            None => self.sys.is_floating(),
        };
        if floating {
            return Err(refuse(
                "steady: no boundary condition fixes the temperature level (every face insulated or free, no temperature or convection condition); the steady state is not unique",
            ));
        }
        Ok(())
    }

    /// Steady state `A θ = f(t)` with each output time's boundary data and loads, calling
    /// `on_output(k, t, θ, K)` for each (theory §4).
    pub fn steady<E: From<Error>>(
        &mut self,
        theta: &mut [f64],
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> std::result::Result<(), E>,
    ) -> std::result::Result<RunStats, E> {
        self.level_fixed()?;
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
