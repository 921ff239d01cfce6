//! CLI: the `peritherm` binary as a user meets it. The output contract of each command,
//! plots and reports, one clear line for every bad or hostile input (within time and memory
//! limits), transactional output directories, interruption, and a mutation fuzzer over the
//! bundled cases and a mesh.
//!
//! Run this group with `cargo test --release --test cli`, one file of it with a filter,
//! e.g. `cargo test --release --test cli hostile::`.

#[path = "../common"]
mod common {
    pub mod case;
    pub mod cli;
    pub mod hostile;
    pub mod runs;
}

mod cache;
mod check_run;
mod commands;
mod figures;
mod fuzz;
mod hostile;
mod plot;
