//! Scalar and point types shared by every module (one place to change precision).

/// Floating-point type of every physical quantity.
pub type Real = f64;

/// A position in space, m (or the case's length unit); unused coordinates are 0.
pub type Point = nalgebra::Point3<Real>;

/// A difference of positions (bond vector ξ), same unit as [`Point`].
pub type Vector = nalgebra::Vector3<Real>;

/// Index of a node in a cloud; u32 keeps neighbour lists compact.
pub type NodeId = u32;
