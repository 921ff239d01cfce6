//! Helpers shared by the integration tests: independent classical reference solvers, and the
//! hostile-input tools (a CLI runner under limits, a seeded mutator).
#![allow(dead_code)]

pub mod fd;
pub mod heat_fd;
pub mod hostile;
