//! peritherm-io: the inputs and outputs layer of peritherm — the case file's schema and its
//! validation ([`case`]), the gmsh reader ([`gmsh`]), reference tables ([`reference`](mod@reference)), the
//! output files (CSV, VTU and `run.json`: [`output`], [`history`]), transactional run
//! directories ([`staging`], [`atomic`]), the cache of consistent weights ([`weights_cache`]) and where a run came from ([`provenance`]). It
//! builds on the numerics of `peritherm-core` and names the FEM reference's options of
//! `peritherm-fem`; it must not depend on the post-processing (`peritherm-post`: plots,
//! reports) or the command line (`peritherm`: clap, indicatif, ctrlc, anyhow).
#![warn(missing_docs)]

pub mod atomic;
pub mod case;
pub mod error;
pub mod gmsh;
pub mod history;
pub mod output;
pub mod provenance;
pub mod reference;
pub mod series;
pub mod staging;
pub mod weights_cache;

pub use error::{Error, Result};
