//! Unstructured meshes as read from a file: nodes, elements and named physical groups.
//!
//! This is the neutral form between a mesh reader (`peritherm_io::gmsh`) and the cloud builder
//! ([`crate::cloud::mesh`]); it holds no physics. Element geometry (centroid, measure) lives
//! here because every consumer needs the same formulas; [`integrity`] finds the defects that
//! make a mesh count volume twice.

pub mod integrity;

use crate::math::{Point, Vector};

/// First-order element shapes peritherm accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElementKind {
    /// A point (the boundary of a 1D mesh).
    Point,
    /// A 2-node line.
    Line,
    /// A 3-node triangle.
    Triangle,
    /// A 4-node quadrangle.
    Quad,
    /// A 4-node tetrahedron.
    Tet,
    /// An 8-node hexahedron.
    Hex,
}

impl ElementKind {
    /// Topological dimension of the shape.
    pub fn dim(self) -> usize {
        match self {
            ElementKind::Point => 0,
            ElementKind::Line => 1,
            ElementKind::Triangle | ElementKind::Quad => 2,
            ElementKind::Tet | ElementKind::Hex => 3,
        }
    }

    /// Number of nodes.
    pub fn n_nodes(self) -> usize {
        match self {
            ElementKind::Point => 1,
            ElementKind::Line => 2,
            ElementKind::Triangle => 3,
            ElementKind::Quad | ElementKind::Tet => 4,
            ElementKind::Hex => 8,
        }
    }

    /// Local node indices of each facet (face of dimension d − 1), gmsh ordering.
    pub fn facets(self) -> &'static [&'static [usize]] {
        match self {
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
}

/// A named physical group (gmsh `Physical Curve("name")` and the like).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Group {
    /// Dimension of the group's elements.
    pub dim: usize,
    /// The file's numeric tag.
    pub tag: i32,
    /// Its name (the tag as text when the file gives none).
    pub name: String,
}

/// One element: its shape, node indices into [`Mesh::nodes`] and the groups it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Shape.
    pub kind: ElementKind,
    /// Node indices (0-based, into [`Mesh::nodes`]), in the file's order.
    pub nodes: Vec<u32>,
    /// Indices into [`Mesh::groups`] (groups of the element's own dimension), shared by the
    /// elements of one gmsh entity (one allocation per entity, not per element).
    pub groups: std::sync::Arc<[u16]>,
}

/// A mesh: node coordinates, elements of every dimension and the physical groups.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Node coordinates, in the file's length unit.
    pub nodes: Vec<Point>,
    /// Elements of every dimension that belong to at least one physical group.
    pub elements: Vec<Element>,
    /// Physical groups, in ascending (dimension, tag) order.
    pub groups: Vec<Group>,
}

impl Mesh {
    /// The largest element dimension (the body's dimension), 0 for an empty mesh.
    pub fn dim(&self) -> usize {
        self.elements
            .iter()
            .map(|e| e.kind.dim())
            .max()
            .unwrap_or(0)
    }

    /// Index of the group of dimension `dim` called `name`.
    pub fn group(&self, dim: usize, name: &str) -> Option<usize> {
        self.groups
            .iter()
            .position(|g| g.dim == dim && g.name == name)
    }

    /// A node of an element of dimension `dim` that lies off the z = 0 plane (2D) or the x
    /// axis (1D) by more than 1e-9 of the largest coordinate; `None` when all lie on it.
    pub fn off_plane(&self, dim: usize) -> Option<usize> {
        if dim >= 3 {
            return None;
        }
        let extent = self
            .nodes
            .iter()
            .map(|p| p.coords.amax())
            .fold(0.0, f64::max);
        let off = |p: &Point| p.z.abs() > 1e-9 * extent || (dim < 2 && p.y.abs() > 1e-9 * extent);
        self.elements
            .iter()
            .filter(|e| e.kind.dim() == dim)
            .flat_map(|e| e.nodes.iter().map(|&n| n as usize))
            .find(|&n| off(&self.nodes[n]))
    }

    /// Node positions of an element.
    pub fn corners(&self, e: &Element) -> Vec<Point> {
        e.nodes.iter().map(|&n| self.nodes[n as usize]).collect()
    }
}

fn tri_area(a: &Point, b: &Point, c: &Point) -> f64 {
    0.5 * (b - a).cross(&(c - a)).norm()
}

fn tet_volume(a: &Point, b: &Point, c: &Point, d: &Point) -> f64 {
    ((b - a).cross(&(c - a)).dot(&(d - a)) / 6.0).abs()
}

/// Gmsh's hexahedron split into six tetrahedra around the diagonal 0–6.
pub const HEX_TETS: [[usize; 4]; 6] = [
    [0, 1, 2, 6],
    [0, 2, 3, 6],
    [0, 3, 7, 6],
    [0, 7, 4, 6],
    [0, 4, 5, 6],
    [0, 5, 1, 6],
];

/// Measure (length, area or volume, file units) and centroid of an element with corners `p`.
/// Quadrangles and hexahedra are split into triangles and tetrahedra (exact for planar faces).
pub fn measure_and_centroid(kind: ElementKind, p: &[Point]) -> (f64, Point) {
    let weighted = |parts: &[(f64, Point)]| -> (f64, Point) {
        let total: f64 = parts.iter().map(|(m, _)| m).sum();
        let mut c = Vector::zeros();
        for (m, q) in parts {
            c += q.coords * *m;
        }
        (total, Point::from(c / total))
    };
    let mean = |q: &[Point]| -> Point {
        let mut c = Vector::zeros();
        for x in q {
            c += x.coords;
        }
        Point::from(c / q.len() as f64)
    };
    match kind {
        ElementKind::Point => (1.0, p[0]),
        ElementKind::Line => ((p[1] - p[0]).norm(), mean(p)),
        ElementKind::Triangle => (tri_area(&p[0], &p[1], &p[2]), mean(p)),
        ElementKind::Quad => weighted(&[
            (tri_area(&p[0], &p[1], &p[2]), mean(&[p[0], p[1], p[2]])),
            (tri_area(&p[0], &p[2], &p[3]), mean(&[p[0], p[2], p[3]])),
        ]),
        ElementKind::Tet => (tet_volume(&p[0], &p[1], &p[2], &p[3]), mean(p)),
        ElementKind::Hex => {
            let parts: Vec<(f64, Point)> = HEX_TETS
                .iter()
                .map(|t| {
                    let q = [p[t[0]], p[t[1]], p[t[2]], p[t[3]]];
                    (tet_volume(&q[0], &q[1], &q[2], &q[3]), mean(&q))
                })
                .collect();
            weighted(&parts)
        }
    }
}

/// True when `p` lies in the element of shape `kind` with corners `c` (boundary included,
/// round-off tolerant; 2D elements in the z = 0 plane, 1D ones on the x axis).
pub fn contains(kind: ElementKind, c: &[Point], p: &Point) -> bool {
    let eps = 1e-12;
    let tri = |a: &Point, b: &Point, d: &Point| -> bool {
        let area = (b - a).cross(&(d - a)).z;
        let s = area.signum();
        let w = [
            (b - p).cross(&(d - p)).z * s,
            (d - p).cross(&(a - p)).z * s,
            (a - p).cross(&(b - p)).z * s,
        ];
        w.iter().all(|&x| x >= -eps * area.abs())
    };
    let tet = |a: &Point, b: &Point, d: &Point, e: &Point| -> bool {
        let vol =
            |w: &Point, x: &Point, y: &Point, z: &Point| (x - w).cross(&(y - w)).dot(&(z - w));
        let v = vol(a, b, d, e);
        let s = v.signum();
        [
            vol(p, b, d, e),
            vol(a, p, d, e),
            vol(a, b, p, e),
            vol(a, b, d, p),
        ]
        .iter()
        .all(|&x| x * s >= -eps * v.abs())
    };
    match kind {
        ElementKind::Point => false,
        ElementKind::Line => {
            let (lo, hi) = (c[0].x.min(c[1].x), c[0].x.max(c[1].x));
            p.x >= lo && p.x <= hi
        }
        ElementKind::Triangle => tri(&c[0], &c[1], &c[2]),
        ElementKind::Quad => tri(&c[0], &c[1], &c[2]) || tri(&c[0], &c[2], &c[3]),
        ElementKind::Tet => tet(&c[0], &c[1], &c[2], &c[3]),
        ElementKind::Hex => HEX_TETS
            .iter()
            .any(|t| tet(&c[t[0]], &c[t[1]], &c[t[2]], &c[t[3]])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(x: f64, y: f64, z: f64) -> Point {
        Point::new(x, y, z)
    }

    /// Measures and centroids of simple shapes (tolerance: round-off).
    #[test]
    fn measures_of_unit_shapes() {
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-14, "{a} vs {b}");
        let (m, c) = measure_and_centroid(
            ElementKind::Triangle,
            &[pt(0., 0., 0.), pt(1., 0., 0.), pt(0., 1., 0.)],
        );
        close(m, 0.5);
        close(c.x, 1.0 / 3.0);
        // a trapezoid: area 1.5, centroid x = 7/9 (by the first moment)
        let (m, c) = measure_and_centroid(
            ElementKind::Quad,
            &[
                pt(0., 0., 0.),
                pt(2., 0., 0.),
                pt(1., 1., 0.),
                pt(0., 1., 0.),
            ],
        );
        close(m, 1.5);
        close(c.x, 7.0 / 9.0);
        close(c.y, 4.0 / 9.0);
        let cube: Vec<Point> = [
            (0., 0., 0.),
            (1., 0., 0.),
            (1., 1., 0.),
            (0., 1., 0.),
            (0., 0., 1.),
            (1., 0., 1.),
            (1., 1., 1.),
            (0., 1., 1.),
        ]
        .iter()
        .map(|&(x, y, z)| pt(2. * x, y, z))
        .collect();
        let (m, c) = measure_and_centroid(ElementKind::Hex, &cube);
        close(m, 2.0);
        close(c.x, 1.0);
        close(c.z, 0.5);
        let (m, _) = measure_and_centroid(
            ElementKind::Tet,
            &[
                pt(0., 0., 0.),
                pt(1., 0., 0.),
                pt(0., 1., 0.),
                pt(0., 0., 1.),
            ],
        );
        close(m, 1.0 / 6.0);
    }
}
