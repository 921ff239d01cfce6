//! The built-in classical finite-element reference (`peritherm fem`): transient heat
//! conduction with first-order elements on the case's gmsh mesh or on a structured mesh of
//! its box, backward Euler or Crank–Nicolson (or the steady state), and a sparse Cholesky
//! factorisation (faer) made once per Δt.
//!
//! Flow: [`grid`] or [`mesh`] → [`split`] (cracks) → [`assemble`] (K, M) → [`boundary`]
//! (held nodes, loads, convection) → [`solve`] → [`field`] (output cloud, flux) — driven
//! by [`run`].

pub mod assemble;
pub mod boundary;
pub mod field;
pub mod grid;
pub mod mesh;
pub mod run;
pub mod shape;
pub mod solve;
pub mod split;

pub use run::{build_mesh, run_fem, FemOptions};
pub use solve::Scheme;
