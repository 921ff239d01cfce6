//! Fictitious boundary layers (theory §3): nodes outside the body that carry the boundary
//! temperatures, naive or mirrored (Wang, Oterkus & Oterkus's fictitious regions; PCS2022).

use crate::math::{NodeId, Point};

/// How a fictitious layer takes its temperature from the body (theory §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// θ_f = θ_b(t).
    Naive,
    /// Reflection of the body field across the face (Dirichlet, insulated or flux rule).
    Mirror,
}

/// One reflection of a mirrored fictitious node: across which set, where, and how far.
#[derive(Debug, Clone, PartialEq)]
pub struct Reflection {
    /// Boundary set crossed.
    pub set: usize,
    /// Foot of the reflection on the set (where boundary values are evaluated), m.
    pub foot: Point,
    /// Distance between the point and its mirror image, m.
    pub distance: f64,
}

/// Where a fictitious node takes its temperature from (theory §3).
#[derive(Debug, Clone, PartialEq)]
pub enum Fictitious {
    /// A lattice node of a box geometry, outside the faces in the bit mask (bit f = face f).
    Lattice {
        /// Faces the node lies outside of.
        outside: u8,
    },
    /// The image of body node `of` through `chain` (outermost reflection first).
    Mirror {
        /// The body node mirrored.
        of: NodeId,
        /// Reflections from the fictitious node back to `of`.
        chain: Vec<Reflection>,
    },
}
