//! Cases: the bundled case files and the physics they exercise end to end. Every bundled
//! case builds and starts; cracks (bond cutting, damage, the crack plates against finite
//! differences), phase change (the enthalpy form, freezing fronts), the implicit and steady
//! solvers, and the axisymmetric and spherical bodies.
//!
//! Run this group with `cargo test --release --test cases`, one file of it with a filter,
//! e.g. `cargo test --release --test cases cracks:: -- --nocapture`.

#[path = "../common"]
mod common {
    pub mod case;
    pub mod fd;
    pub mod figures;
    pub mod runs;
    pub mod tables;
}

mod bundled;
mod cracks;
mod distributed;
mod figures;
mod implicit;
mod phase;
mod symmetry;
