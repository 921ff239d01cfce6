//! Time integration of formulation eq (1).

pub mod enthalpy;
pub mod explicit;
pub mod implicit;
