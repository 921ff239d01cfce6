//! peritherm: transient heat conduction with dual-horizon peridynamics.
//!
//! The numerics follow `docs/theory.md` (the model in one notation), which reconciles four
//! papers: Bobaru & Duangpanya 2010 (1D), Bobaru & Duangpanya 2012 (2D, cracks), the
//! axisymmetric phase-change paper (doi:10.1007/s42102-022-00092-3) and Wang, Oterkus &
//! Oterkus's dual-horizon thermal diffusion; the full references are at the end of
//! `docs/theory.md`.
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
pub mod simulation;
pub mod solve;
pub mod spatial;
pub mod staging;
pub mod stencil;
pub mod sweep;
pub mod symmetry;
pub mod weights;

pub use error::{Error, Result};
