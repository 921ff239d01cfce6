//! First-order Lagrange shape functions, their reference gradients, quadrature rules and the
//! local facets of every element kind (gmsh node ordering).
//!
//! Reference elements: the line and the quadrangle/hexahedron live on [−1, 1]^d, the
//! triangle and the tetrahedron on the unit simplex. Every rule integrates polynomials of
//! degree 2 exactly, enough for the consistent mass of linear elements and the stiffness of
//! bilinear/trilinear ones on parallelogram cells (Gauss 2 × 2 (× 2) is exact there too).

use crate::math::{Point, Vector};
use crate::mesh::ElementKind;

/// Most nodes of an element (the hexahedron).
pub const MAX_NODES: usize = 8;

/// Values N_a and reference gradients ∂N_a/∂ξ_j of the shape functions at one point.
#[derive(Debug, Clone, Copy, Default)]
pub struct ShapeAt {
    /// N_a (dimensionless), a < the element's node count.
    pub n: [f64; MAX_NODES],
    /// ∂N_a/∂ξ_j (per reference unit), unused axes 0.
    pub dn: [[f64; 3]; MAX_NODES],
}

const G: f64 = 0.577_350_269_189_625_8; // 1/√3
const TA: f64 = 0.585_410_196_624_968_5; // tetrahedron 4-point rule
const TB: f64 = 0.138_196_601_125_010_5;

const POINT_RULE: [([f64; 3], f64); 1] = [([0.0; 3], 1.0)];
const LINE_RULE: [([f64; 3], f64); 2] = [([-G, 0.0, 0.0], 1.0), ([G, 0.0, 0.0], 1.0)];
const TRI_RULE: [([f64; 3], f64); 3] = [
    ([1.0 / 6.0, 1.0 / 6.0, 0.0], 1.0 / 6.0),
    ([2.0 / 3.0, 1.0 / 6.0, 0.0], 1.0 / 6.0),
    ([1.0 / 6.0, 2.0 / 3.0, 0.0], 1.0 / 6.0),
];
const QUAD_RULE: [([f64; 3], f64); 4] = [
    ([-G, -G, 0.0], 1.0),
    ([G, -G, 0.0], 1.0),
    ([G, G, 0.0], 1.0),
    ([-G, G, 0.0], 1.0),
];
const TET_RULE: [([f64; 3], f64); 4] = [
    ([TB, TB, TB], 1.0 / 24.0),
    ([TA, TB, TB], 1.0 / 24.0),
    ([TB, TA, TB], 1.0 / 24.0),
    ([TB, TB, TA], 1.0 / 24.0),
];
const HEX_RULE: [([f64; 3], f64); 8] = [
    ([-G, -G, -G], 1.0),
    ([G, -G, -G], 1.0),
    ([G, G, -G], 1.0),
    ([-G, G, -G], 1.0),
    ([-G, -G, G], 1.0),
    ([G, -G, G], 1.0),
    ([G, G, G], 1.0),
    ([-G, G, G], 1.0),
];

/// Quadrature points (reference coordinates) and weights of an element kind, exact to degree 2.
pub fn quadrature(kind: ElementKind) -> &'static [([f64; 3], f64)] {
    match kind {
        ElementKind::Point => &POINT_RULE,
        ElementKind::Line => &LINE_RULE,
        ElementKind::Triangle => &TRI_RULE,
        ElementKind::Quad => &QUAD_RULE,
        ElementKind::Tet => &TET_RULE,
        ElementKind::Hex => &HEX_RULE,
    }
}

/// Reference coordinates of the element's centre (where recovered gradients are taken).
pub fn centre(kind: ElementKind) -> [f64; 3] {
    match kind {
        ElementKind::Triangle => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        ElementKind::Tet => [0.25; 3],
        _ => [0.0; 3],
    }
}

/// Signs of the corners of [−1, 1]³ in gmsh's hexahedron order (the quadrangle uses the first 4).
const CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Shape functions and reference gradients of `kind` at reference point `xi`.
pub fn shape(kind: ElementKind, xi: [f64; 3]) -> ShapeAt {
    let mut s = ShapeAt::default();
    let [x, y, z] = xi;
    match kind {
        ElementKind::Point => s.n[0] = 1.0,
        ElementKind::Line => {
            s.n[0] = 0.5 * (1.0 - x);
            s.n[1] = 0.5 * (1.0 + x);
            s.dn[0][0] = -0.5;
            s.dn[1][0] = 0.5;
        }
        ElementKind::Triangle => {
            s.n[..3].copy_from_slice(&[1.0 - x - y, x, y]);
            s.dn[0] = [-1.0, -1.0, 0.0];
            s.dn[1] = [1.0, 0.0, 0.0];
            s.dn[2] = [0.0, 1.0, 0.0];
        }
        ElementKind::Tet => {
            s.n[..4].copy_from_slice(&[1.0 - x - y - z, x, y, z]);
            s.dn[0] = [-1.0, -1.0, -1.0];
            s.dn[1] = [1.0, 0.0, 0.0];
            s.dn[2] = [0.0, 1.0, 0.0];
            s.dn[3] = [0.0, 0.0, 1.0];
        }
        ElementKind::Quad => {
            for (a, c) in CORNERS[..4].iter().enumerate() {
                let (fx, fy) = (1.0 + c[0] * x, 1.0 + c[1] * y);
                s.n[a] = 0.25 * fx * fy;
                s.dn[a] = [0.25 * c[0] * fy, 0.25 * c[1] * fx, 0.0];
            }
        }
        ElementKind::Hex => {
            for (a, c) in CORNERS.iter().enumerate() {
                let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                s.n[a] = 0.125 * fx * fy * fz;
                s.dn[a] = [
                    0.125 * c[0] * fy * fz,
                    0.125 * c[1] * fx * fz,
                    0.125 * c[2] * fx * fy,
                ];
            }
        }
    }
    s
}

/// Local node indices of each facet (face of dimension d − 1) of an element, gmsh ordering.
pub fn facets(kind: ElementKind) -> &'static [&'static [usize]] {
    match kind {
        ElementKind::Point => &[],
        ElementKind::Line => &[&[0], &[1]],
        ElementKind::Triangle => &[&[0, 1], &[1, 2], &[2, 0]],
        ElementKind::Quad => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
        ElementKind::Tet => &[&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]],
        ElementKind::Hex => &[
            &[0, 3, 2, 1],
            &[0, 1, 5, 4],
            &[0, 4, 7, 3],
            &[1, 2, 6, 5],
            &[2, 3, 7, 6],
            &[4, 5, 6, 7],
        ],
    }
}

/// The element kind of a facet with `n` corners in a body of dimension `dim`.
pub fn facet_kind(dim: usize, n: usize) -> ElementKind {
    match (dim, n) {
        (1, _) => ElementKind::Point,
        (2, _) => ElementKind::Line,
        (_, 3) => ElementKind::Triangle,
        _ => ElementKind::Quad,
    }
}

/// Physical gradients ∂N_a/∂x (1/m) and |det J| (m^d per reference unit) of an element of
/// dimension `dim` with corners `x`, at the point where `s` was evaluated. Unused axes of the
/// Jacobian are padded with the identity, so one 3 × 3 inverse serves every dimension.
pub fn physical(
    kind: ElementKind,
    s: &ShapeAt,
    x: &[Point],
    dim: usize,
) -> ([[f64; 3]; MAX_NODES], f64) {
    let n = kind.n_nodes();
    let mut j = nalgebra::Matrix3::<f64>::identity();
    for r in 0..dim {
        for c in 0..dim {
            j[(r, c)] = (0..n).map(|a| x[a][r] * s.dn[a][c]).sum();
        }
    }
    let det = j.determinant();
    let inv = j.try_inverse().unwrap_or_else(nalgebra::Matrix3::zeros);
    let mut g = [[0.0; 3]; MAX_NODES];
    for (ga, dn) in g.iter_mut().zip(&s.dn).take(n) {
        // ∇N = J^{-T} ∂N/∂ξ
        for (r, v) in ga.iter_mut().enumerate().take(dim) {
            *v = (0..dim).map(|c| inv[(c, r)] * dn[c]).sum();
        }
    }
    (g, det.abs())
}

/// Measure density of a facet (dimension d − 1, corners `x`) at the point where `s` was
/// evaluated: 1 for a point, |∂x/∂ξ| for a segment, |∂x/∂ξ × ∂x/∂η| for a surface.
pub fn facet_density(kind: ElementKind, s: &ShapeAt, x: &[Point]) -> f64 {
    let n = kind.n_nodes();
    let tangent = |c: usize| -> Vector { (0..n).map(|a| x[a].coords * s.dn[a][c]).sum() };
    match kind.dim() {
        0 => 1.0,
        1 => tangent(0).norm(),
        _ => tangent(0).cross(&tangent(1)).norm(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shape functions sum to 1 and their gradients to 0 at every quadrature point, and the
    /// weights sum to the reference measure (tolerance: round-off).
    #[test]
    fn partition_of_unity_and_weights() {
        for (kind, measure) in [
            (ElementKind::Line, 2.0),
            (ElementKind::Triangle, 0.5),
            (ElementKind::Quad, 4.0),
            (ElementKind::Tet, 1.0 / 6.0),
            (ElementKind::Hex, 8.0),
        ] {
            let w: f64 = quadrature(kind).iter().map(|q| q.1).sum();
            assert!((w - measure).abs() < 1e-14, "{kind:?}");
            for (xi, _) in quadrature(kind) {
                let s = shape(kind, *xi);
                let n = kind.n_nodes();
                assert!((s.n[..n].iter().sum::<f64>() - 1.0).abs() < 1e-14);
                for j in 0..3 {
                    assert!(s.dn[..n].iter().map(|d| d[j]).sum::<f64>().abs() < 1e-14);
                }
            }
        }
    }
}
