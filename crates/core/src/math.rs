//! Scalar and point types shared by every module (one place to change precision).

/// Floating-point type of every physical quantity.
pub type Real = f64;

/// A position in space, m (or the case's length unit); unused coordinates are 0.
pub type Point = nalgebra::Point3<Real>;

/// A difference of positions (bond vector ξ), same unit as [`Point`].
pub type Vector = nalgebra::Vector3<Real>;

/// Relative tolerance of geometric coincidence (breakpoints, region extents, crack ends), as a
/// fraction of the domain's size: two coordinates closer than this are the same.
pub const GEOMETRIC_TOLERANCE: Real = 1e-9;

/// Index of a node in a cloud; u32 keeps neighbour lists compact.
pub type NodeId = u32;

/// Σ_{i<n} f(i) in parallel with a summation order that does not depend on the thread count
/// (fixed chunks, partial sums added in order), so a result is the same bits on any machine.
pub fn ordered_sum(n: usize, f: impl Fn(usize) -> Real + Sync) -> Real {
    use rayon::prelude::*;
    /// Terms per partial sum.
    const CHUNK: usize = 4096;
    let partial: Vec<Real> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).map(&f).sum())
        .collect();
    partial.iter().sum()
}
