//! Helpers shared by the integration tests: independent classical reference solvers.
#![allow(dead_code)]

pub mod fd;
pub mod heat_fd;
