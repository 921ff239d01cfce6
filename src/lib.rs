//! peritherm: transient heat conduction with dual-horizon peridynamics.
//!
//! The numerics follow `formulation.md` (the project's contract), which reconciles
//! Bobaru & Duangpanya 2010 (seed 000), 2012 (seed 003), the axisymmetric/phase-change
//! paper (seed 001) and Wang, Oterkus & Oterkus's dual-horizon thermal diffusion (seed 004).
//!
//! Flow: [`case`] (TOML) → [`model::ModelSpec`] → [`cloud`] → [`neighbors`] →
//! [`operator`] → [`bc`] → [`solve::explicit`] → [`output`]. Numerics never read files.
#![warn(missing_docs)]

pub mod analytic;
pub mod bc;
pub mod bench;
pub mod budget;
pub mod case;
pub mod cloud;
pub mod crack;
pub mod error;
pub mod expr;
pub mod fem;
pub mod gmsh;
pub mod history;
pub mod kernel;
pub mod limits;
pub mod material;
pub mod math;
pub mod mesh;
pub mod model;
pub mod neighbors;
pub mod operator;
pub mod output;
pub mod plot;
pub mod prepare;
pub mod provenance;
pub mod reference;
pub mod report;
pub mod run;
pub mod solve;
pub mod spatial;
pub mod staging;
pub mod stencil;
pub mod sweep;
pub mod symmetry;
pub mod weights;

pub use error::{Error, Result};
