//! The built-in classical finite-element reference (`peritherm fem`): the numerics of
//! `peritherm-fem` (re-exported here: [`problem`], [`solve`], …) and the driver that runs a
//! case with them ([`run`]: the case mapped to a [`FemProblem`], its errors keyed to the
//! case's keys, the output files written).

pub use peritherm_fem::*;

pub mod run;

pub use run::run_fem;
