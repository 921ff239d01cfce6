//! Properties: exact invariants that hold to round-off whatever the resolution. Energy
//! conservation, symmetry of K, linear (and, with consistent weights, quadratic) fields
//! kept steady, serial == parallel bit for bit, the explicit stability bound, the boundary
//! rules, and the clouds built from gmsh meshes (volumes, neighbours, bonds cut at cracks
//! and corners) with the reader's refusals; and of the repository, that no module imports
//! one that imports it back and that git tracks no generated file.
//!
//! Run this group with `cargo test --release --test properties`, one file of it with a
//! filter, e.g. `cargo test --release --test properties weights::`.

#[path = "../common"]
mod common {
    pub mod case;
    pub mod figures;
}

mod boundary;
mod gmsh;
mod mesh;
mod modules;
mod operator;
mod tracked;
mod weights;
