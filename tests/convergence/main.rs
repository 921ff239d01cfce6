//! Convergence: the solvers against analytical series and independent references. The
//! examples of the papers (Bobaru & Duangpanya 2010 and 2012; Wang, Oterkus & Oterkus's
//! dual-horizon paper) against their classical solutions, δ- and h-convergence on gmsh
//! meshes, the series themselves against finite differences, references from tables and
//! other meshes, and the built-in FEM solver. Each test states its tolerance and where it
//! comes from; several print measured figures with `--nocapture`.
//!
//! Run this group with `cargo test --release --test convergence`, one file of it with a
//! filter, e.g. `cargo test --release --test convergence fem:: -- --nocapture`.

#[path = "../common"]
mod common {
    pub mod case;
    pub mod cli;
    pub mod fd;
    pub mod figures;
    pub mod heat_fd;
    pub mod tables;
}

mod fem;
mod laser_split;
mod mesh_convergence;
mod papers;
mod references;
mod series;
