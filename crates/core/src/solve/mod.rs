//! Time integration of theory §2, eq. 1: one [`Integrator`] enum, one [`Stepper`] interface
//! implemented by the explicit, enthalpy and implicit steppers, and the loops over the output
//! times ([`march`], [`integrate`]).

pub mod engine;
pub mod enthalpy;
pub mod exchange;
pub mod explicit;
pub mod implicit;
pub mod integrator;
pub mod stepper;
pub mod steps;

pub use engine::{integrate, Engine, Schedule};
pub use integrator::{choose_dt, Integrator};
pub use stepper::{check_finite, march, RunStats, Stepper};
pub use steps::{count_steps, steps_between};
