//! Time integration of theory §2, eq. 1.

pub mod enthalpy;
pub mod explicit;
pub mod implicit;
