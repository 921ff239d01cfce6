//! peritherm-core: the numerics layer of peritherm — node clouds ([`cloud`]), horizons
//! ([`horizons`]), kernels ([`kernel`]), the dual-horizon operator ([`operator`],
//! [`weights`], [`stencil`]), boundary conditions ([`bc`]), cracks ([`crack`]), materials
//! ([`material`]), the model ([`model::ModelSpec`]) and the time integrators ([`solve`]),
//! following `docs/theory.md` (the analytic references are the crate `peritherm-analytic`).
//! It reads and writes no file and must not depend on file formats, plotting or the command
//! line (no toml, serde_json, mshio, plotters, clap, indicatif, ctrlc or anyhow): the layers
//! above it (`peritherm-fem`, `peritherm-analytic`, `peritherm-io`, `peritherm-post`,
//! `peritherm`) depend on it, never the other way round. Its [`Error`] holds the numerics'
//! errors only; the layers above raise their own and wrap it.
#![warn(missing_docs)]

pub mod bc;
pub mod budget;
pub mod cloud;
pub mod crack;
pub mod error;
pub mod expr;
pub mod gather;
pub mod horizons;
pub mod kernel;
pub mod limits;
pub mod machine;
pub mod material;
pub mod math;
pub mod mesh;
pub mod model;
pub mod operator;
pub mod packed;
pub mod partition;
pub mod progress;
pub mod solve;
pub mod spatial;
pub mod stencil;
pub mod symmetry;
pub mod weights;

pub use error::{Error, Result};
