//! peritherm: transient heat conduction with dual-horizon peridynamics.
//!
//! The numerics follow `docs/theory.md` (the model in one notation), which reconciles four
//! papers: Bobaru & Duangpanya 2010 (1D), Bobaru & Duangpanya 2012 (2D, cracks), PCS2022
//! (doi:10.1007/s42102-022-00092-3) and Wang, Oterkus &
//! Oterkus's dual-horizon thermal diffusion; the full references are at the end of
//! `docs/theory.md`.
//!
//! This package is the command line (`peritherm`, with `bench`) and the drivers that run a
//! case ([`run`], [`sweep`], [`prepare`], [`bench`](mod@bench), [`fem::run`]); it re-exports the
//! modules of the layers below it under their old paths (`peritherm::cloud`,
//! `peritherm::case`, …): the numerics (`peritherm-core`), the classical FEM reference
//! (`peritherm-fem`), the inputs and outputs (`peritherm-io`) and the post-processing
//! (`peritherm-post`); `docs/architecture.md` describes the layers.
//!
//! Flow: [`case`] (TOML) → [`model::ModelSpec`] → [`cloud`] → [`horizons`] →
//! [`operator`] → [`bc`] → [`solve::explicit`] → [`output`]. Numerics never read files.
#![warn(missing_docs)]

pub use peritherm_analytic as analytic;
pub use peritherm_core::{
    bc, budget, cloud, crack, expr, gather, horizons, kernel, limits, material, math, mesh, model,
    operator, packed, partition, progress, solve, spatial, stencil, symmetry, weights,
};
pub use peritherm_io::{
    atomic, case, gmsh, history, output, provenance, reference, series, staging, weights_cache,
};
pub use peritherm_post::{error, plot, report};

pub mod bench;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod fem;
pub mod figures;
pub mod planner;
pub mod prepare;
pub mod run;
pub mod simulation;
pub mod sweep;

/// The drivers' error: post's, which wraps io's and core's ([`error::IoError`],
/// [`error::CoreError`]).
pub use error::{Error, Result};
