//! First-order Lagrange shape functions, their reference gradients, quadrature rules and the
//! local facets of every element kind (gmsh node ordering).
//!
//! Reference elements: the line and the quadrangle/hexahedron live on [−1, 1]^d, the
//! triangle and the tetrahedron on the unit simplex. Every rule integrates polynomials of
//! degree 2 exactly, enough for the consistent mass of linear elements and the stiffness of
//! bilinear/trilinear ones on parallelogram cells (Gauss 2 × 2 (× 2) is exact there too).

use peritherm_core::math::{Point, Vector};
use peritherm_core::mesh::ElementKind;
use peritherm_core::symmetry::Symmetry;

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

/// Gauss 3-point rule on [−1, 1], exact to degree 5.
const LINE_RULE_3: [([f64; 3], f64); 3] = [
    ([-0.774_596_669_241_483_4, 0.0, 0.0], 5.0 / 9.0),
    ([0.0, 0.0, 0.0], 8.0 / 9.0),
    ([0.774_596_669_241_483_4, 0.0, 0.0], 5.0 / 9.0),
];
const DA: f64 = 0.445_948_490_915_965; // Dunavant degree-4 6-point triangle rule
const DB: f64 = 0.091_576_213_509_771;
const WA: f64 = 0.223_381_589_678_011 / 2.0;
const WB: f64 = 0.109_951_743_655_322 / 2.0;
const TRI_RULE_4: [([f64; 3], f64); 6] = [
    ([DA, DA, 0.0], WA),
    ([1.0 - 2.0 * DA, DA, 0.0], WA),
    ([DA, 1.0 - 2.0 * DA, 0.0], WA),
    ([DB, DB, 0.0], WB),
    ([1.0 - 2.0 * DB, DB, 0.0], WB),
    ([DB, 1.0 - 2.0 * DB, 0.0], WB),
];

/// The rule for the integrals of a body with `symmetry`: [`quadrature`], except where the
/// ring or shell weight raises the degree beyond it — spherical lines (4πr² N_a N_b, degree
/// 4: Gauss 3-point) and axisymmetric triangles (2πr N_a N_b, degree 3: Dunavant's 6-point
/// rule of degree 4). Exact integration keeps the O(1) relative quadrature error out of the
/// cells at the axis or centre, where the weight varies from 0 across one cell.
pub fn quadrature_for(kind: ElementKind, symmetry: Symmetry) -> &'static [([f64; 3], f64)] {
    match (kind, symmetry) {
        (ElementKind::Line, Symmetry::Spherical) => &LINE_RULE_3,
        (ElementKind::Triangle, Symmetry::Axisymmetric) => &TRI_RULE_4,
        _ => quadrature(kind),
    }
}

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

/// Local node indices of each facet of an element, gmsh ordering ([`ElementKind::facets`]).
pub fn facets(kind: ElementKind) -> &'static [&'static [usize]] {
    kind.facets()
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

    /// The rules of symmetric bodies integrate every monomial up to their degree exactly
    /// (line: x^k on [−1, 1], k ≤ 5; triangle: x^i y^j on the unit simplex, i + j ≤ 4, exact
    /// value i! j!/(i + j + 2)!), to round-off (1e-14).
    #[test]
    fn symmetric_rules_are_exact_to_their_degree() {
        let line = quadrature_for(ElementKind::Line, Symmetry::Spherical);
        for k in 0..=5 {
            let q: f64 = line.iter().map(|(x, w)| w * x[0].powi(k)).sum();
            let exact = if k % 2 == 0 {
                2.0 / (k + 1) as f64
            } else {
                0.0
            };
            assert!((q - exact).abs() < 1e-14, "x^{k}: {q} vs {exact}");
        }
        let fact = |n: i32| (1..=n).map(f64::from).product::<f64>();
        let tri = quadrature_for(ElementKind::Triangle, Symmetry::Axisymmetric);
        for i in 0..=4 {
            for j in 0..=(4 - i) {
                let q: f64 = tri
                    .iter()
                    .map(|(x, w)| w * x[0].powi(i) * x[1].powi(j))
                    .sum();
                let exact = fact(i) * fact(j) / fact(i + j + 2);
                assert!((q - exact).abs() < 1e-14, "x^{i} y^{j}: {q} vs {exact}");
            }
        }
        // planar bodies keep the degree-2 rules
        assert_eq!(quadrature_for(ElementKind::Line, Symmetry::Planar).len(), 2);
        assert_eq!(
            quadrature_for(ElementKind::Quad, Symmetry::Axisymmetric).len(),
            4
        );
    }
}
