//! What the consistent weights' set-up will cost, told before it runs (`peritherm check`).
//!
//! The Newton solve's iteration counts are not known before it runs, so the time is a power
//! law in the stored pairs fitted, per solver path, to two measured set-ups of this
//! implementation on the gmsh convergence meshes (2 threads of an AMD EPYC machine with 2
//! cores, `peritherm run --cache off`):
//!
//! | path | mesh, pairs, set-up | mesh, pairs, set-up | exponent |
//! |---|---|---|---|
//! | 2D, one sparse Cholesky factor | conv_rect_tri_L2, 2.78·10⁵, 2.63 s | conv_rect_tri_L4, 4.32·10⁶, 186.7 s | 1.55 |
//! | 2D, two-level CG | conv_rect_tri_L2, 2.78·10⁵, 7.7 s | conv_rect_tri_L3, 1.10·10⁶, 94 s | 1.82 |
//! | 3D, two-level CG | conv_cube_tet_L3, 7.11·10⁶, 48.3 s | conv_cube_tet_L4, 5.39·10⁷, 1 082.6 s | 1.54 |
//!
//! The 2D CG path is taken only above the direct factor's limit, so its law is extrapolated
//! from a forced run far below it. An estimate, not a measurement: expect it within a factor of
//! about 2 on meshes like these, less sure on other machines and far outside the fitted range.
//! The exponents above 1 are the set-up's growth that issue 33 of the project is about.

use super::Order;
use crate::limits::{CORRECTION_BYTES_PER_ENTRY, MAX_DIRECT_ENTRIES};
use crate::math::Real;

/// How the Newton systems of a set-up are solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    /// One sparse Cholesky factor of the Newton matrix (2D and 1D, up to its size limit).
    Direct,
    /// Conjugate gradients with the two-level preconditioner.
    TwoLevel,
}

/// The estimated cost of a set-up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The solver path the set-up will take.
    pub path: Path,
    /// Wall time on 2 threads, s.
    pub seconds: Real,
    /// Memory of the direct factor (0 on the CG path, whose vectors are per node), bytes.
    pub bytes: Real,
}

/// Fitted law (pairs at the anchor, seconds there, exponent) of a path in `dim` dimensions.
fn law(dim: usize, path: Path) -> (Real, Real, Real) {
    match (dim, path) {
        (3, _) => (5.39e7, 1082.6, 1.54),
        (_, Path::Direct) => (4.32e6, 186.7, 1.55),
        (_, Path::TwoLevel) => (2.78e5, 7.7, 1.82),
    }
}

/// The estimated set-up of the weights of `order` for `nodes` corrected nodes and `pairs`
/// stored pairs (CSR entries of K) in `dim` dimensions, every node taking part (a mesh; on a
/// lattice only the band around a change of horizon does, and this is an upper bound). The
/// counts are reals: the memory budget estimates them for hostile cases whose counts overflow
/// integers.
pub fn estimate(dim: usize, order: Order, nodes: Real, pairs: Real) -> Estimate {
    let nu = match order {
        Order::None => 0.0,
        Order::Linear => dim as Real,
        Order::Quadratic => (dim + dim * (dim + 1) / 2) as Real,
    };
    // the lower triangle of the Newton matrix: half the pairs' blocks and the diagonal ones
    let entries = 0.5 * pairs * nu * nu + nodes * nu * (nu + 1.0) / 2.0;
    let path = if dim < 3 && entries <= MAX_DIRECT_ENTRIES {
        Path::Direct
    } else {
        Path::TwoLevel
    };
    let (anchor, seconds, exponent) = law(dim, path);
    Estimate {
        path,
        seconds: if order == Order::None || pairs == 0.0 {
            0.0
        } else {
            seconds * (pairs / anchor).powf(exponent)
        },
        bytes: match path {
            Path::Direct => entries * CORRECTION_BYTES_PER_ENTRY,
            Path::TwoLevel => 0.0,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The law returns its anchors, and the path switches at the direct factor's limit.
    #[test]
    fn estimates_meet_their_anchors() {
        let e = estimate(2, Order::Quadratic, 118_600.0, 4_320_000.0);
        assert_eq!(e.path, Path::Direct);
        assert!((e.seconds - 186.7).abs() < 1e-9 * 186.7, "{e:?}");
        let big = estimate(2, Order::Quadratic, 1_027_614.0, 37_135_828.0);
        assert_eq!(big.path, Path::TwoLevel);
        assert!(big.seconds > 3600.0, "{big:?}");
        let cube = estimate(3, Order::Quadratic, 287_757.0, 53_900_000.0);
        assert!((cube.seconds - 1082.6).abs() < 1e-9 * 1082.6, "{cube:?}");
        assert_eq!(estimate(2, Order::None, 10.0, 100.0).seconds, 0.0);
    }
}
