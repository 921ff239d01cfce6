//! peritherm-fem: the classical finite-element reference layer of peritherm (`peritherm
//! fem`): transient heat conduction with first-order elements on a gmsh mesh or on a
//! structured mesh of a box, backward Euler or Crank–Nicolson (or the steady state), and a
//! sparse Cholesky factorisation (faer) made once per Δt. It takes a model description
//! ([`FemProblem`], built from `peritherm-core` types) and depends on `peritherm-core` only:
//! it must not know the case file (`peritherm-io`) nor read or write files; the driver that
//! runs a case and writes its outputs is `peritherm::fem::run`.
//!
//! Flow: [`grid`] or [`mesh`] → [`split`] (cracks) → [`assemble`] (K, M) → [`boundary`]
//! (held nodes, loads, convection) → [`solve`] → [`field`] (output cloud, flux) — set up by
//! [`problem`].
#![warn(missing_docs)]

pub mod assemble;
pub mod boundary;
pub mod field;
pub mod grid;
pub mod mesh;
pub mod problem;
pub mod shape;
pub mod solve;
pub mod split;

pub use problem::{build_mesh, FemModel, FemOptions, FemProblem};
pub use solve::Scheme;
