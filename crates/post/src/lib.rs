//! peritherm-post: the post-processing layer of peritherm — the measures that compare a run
//! with a classical solution and the report pages that show them ([`report`]), and the plots
//! ([`plot`]: line, convergence and map plots, PNG and SVG). It reads what a run wrote through
//! `peritherm-io` and evaluates with `peritherm-core`; it must not depend on the command line
//! (`peritherm`: clap, indicatif, ctrlc, anyhow), and nothing below it depends on it.
#![warn(missing_docs)]

pub mod error;
pub mod figures;
pub mod plot;
pub mod report;

pub use error::{Error, Result};
