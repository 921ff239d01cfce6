//! Boundary facets of a mesh-based cloud: points (1D), segments (2D), triangles and
//! quadrangles (3D), grouped into named sets, with nearest-facet queries.

use crate::math::{Point, Vector};
use crate::spatial::PointIndex;

/// One boundary facet, in metres.
#[derive(Debug, Clone)]
pub struct Facet {
    /// Corners (1 to 4).
    pub corners: Vec<Point>,
    /// Unit normal pointing out of the adjacent body cell.
    pub normal: Vector,
    /// True exposed area (× thickness in 2D, × cross-section in 1D), m².
    pub area: f64,
    /// Body node of the adjacent cell.
    pub cell: u32,
    /// Set (physical group) the facet belongs to, if any.
    pub set: Option<u16>,
}

impl Facet {
    /// Centroid of the corners.
    pub fn centre(&self) -> Point {
        let mut c = Vector::zeros();
        for p in &self.corners {
            c += p.coords;
        }
        Point::from(c / self.corners.len() as f64)
    }

    /// Largest distance from the centre to a corner, m.
    pub fn radius(&self) -> f64 {
        let c = self.centre();
        self.corners
            .iter()
            .map(|p| (p - c).norm())
            .fold(0.0, f64::max)
    }

    /// Closest point of the facet to `p`.
    pub fn closest(&self, p: &Point) -> Point {
        let c = &self.corners;
        match c.len() {
            1 => c[0],
            2 => closest_on_segment(p, &c[0], &c[1]),
            3 => closest_on_triangle(p, &c[0], &c[1], &c[2]),
            _ => {
                let a = closest_on_triangle(p, &c[0], &c[1], &c[2]);
                let b = closest_on_triangle(p, &c[0], &c[2], &c[3]);
                if (a - p).norm_squared() <= (b - p).norm_squared() {
                    a
                } else {
                    b
                }
            }
        }
    }

    /// Reflection of `p` across the facet's plane (line in 2D, point in 1D).
    pub fn reflect(&self, p: &Point) -> Point {
        p - self.normal * (2.0 * (p - self.corners[0]).dot(&self.normal))
    }

    /// Signed distance of `p` from the facet's plane, positive outside the body, m.
    pub fn outward_distance(&self, p: &Point) -> f64 {
        (p - self.corners[0]).dot(&self.normal)
    }
}

fn closest_on_segment(p: &Point, a: &Point, b: &Point) -> Point {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    a + ab * t
}

/// Closest point on a triangle (Ericson, Real-Time Collision Detection, §5.1.5).
fn closest_on_triangle(p: &Point, a: &Point, b: &Point, c: &Point) -> Point {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// A collection of facets with a nearest-facet index.
pub struct FacetSet {
    /// The facets.
    pub facets: Vec<Facet>,
    index: PointIndex,
    max_radius: f64,
}

impl std::fmt::Debug for FacetSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FacetSet({} facets)", self.facets.len())
    }
}

impl Clone for FacetSet {
    fn clone(&self) -> Self {
        FacetSet::new(self.facets.clone())
    }
}

impl FacetSet {
    /// Indexes `facets` by their centres.
    pub fn new(facets: Vec<Facet>) -> Self {
        let centres: Vec<Point> = facets.iter().map(Facet::centre).collect();
        let max_radius = facets.iter().map(Facet::radius).fold(0.0, f64::max);
        FacetSet {
            index: PointIndex::new(&centres),
            facets,
            max_radius,
        }
    }

    /// The facets of this collection that satisfy `keep`, as a new set.
    pub fn filter(&self, keep: impl Fn(&Facet) -> bool) -> FacetSet {
        FacetSet::new(self.facets.iter().filter(|f| keep(f)).cloned().collect())
    }

    /// Number of facets.
    pub fn len(&self) -> usize {
        self.facets.len()
    }

    /// True when there is no facet.
    pub fn is_empty(&self) -> bool {
        self.facets.is_empty()
    }

    /// The facet nearest to `p` and the distance to it (exact), or None for an empty set.
    pub fn nearest(&self, p: &Point) -> Option<(usize, f64)> {
        let (_, d0) = *self.index.nearest(p, 1).first()?;
        // any closer facet has its centre within d0 + max_radius of p
        self.index
            .within(p, d0 + self.max_radius)
            .into_iter()
            .map(|k| (k, (self.facets[k].closest(p) - p).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
    }

    /// Indices of facets that may come within `r` of `p` (a superset).
    pub fn candidates(&self, p: &Point, r: f64) -> Vec<usize> {
        self.index.within(p, r + self.max_radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: (f64, f64), b: (f64, f64), n: (f64, f64)) -> Facet {
        Facet {
            corners: vec![Point::new(a.0, a.1, 0.0), Point::new(b.0, b.1, 0.0)],
            normal: Vector::new(n.0, n.1, 0.0),
            area: 1.0,
            cell: 0,
            set: None,
        }
    }

    /// Nearest facet, distances and reflections on the unit square's bottom and right edges.
    #[test]
    fn nearest_and_reflection() {
        let s = FacetSet::new(vec![
            seg((0.0, 0.0), (1.0, 0.0), (0.0, -1.0)),
            seg((1.0, 0.0), (1.0, 1.0), (1.0, 0.0)),
        ]);
        let p = Point::new(0.9, 0.2, 0.0);
        let (k, d) = s.nearest(&p).unwrap();
        assert_eq!(k, 1);
        assert!((d - 0.1).abs() < 1e-15);
        let q = s.facets[k].reflect(&p);
        assert!((q.x - 1.1).abs() < 1e-15 && (q.y - 0.2).abs() < 1e-15);
        assert!((s.facets[k].outward_distance(&q) - 0.1).abs() < 1e-15);
        // beyond the segment's end the distance is to the corner
        let (_, d) = s.nearest(&Point::new(1.3, -0.4, 0.0)).unwrap();
        assert!((d - 0.5).abs() < 1e-15);
    }

    /// Closest point on a triangle in each Voronoi region (tolerance: round-off).
    #[test]
    fn closest_on_a_triangle() {
        let f = Facet {
            corners: vec![
                Point::new(0.0, 0.0, 0.0),
                Point::new(1.0, 0.0, 0.0),
                Point::new(0.0, 1.0, 0.0),
            ],
            normal: Vector::z(),
            area: 0.5,
            cell: 0,
            set: None,
        };
        let c = f.closest(&Point::new(0.2, 0.2, 3.0));
        assert!((c - Point::new(0.2, 0.2, 0.0)).norm() < 1e-15);
        let c = f.closest(&Point::new(2.0, -1.0, 0.5));
        assert!((c - Point::new(1.0, 0.0, 0.0)).norm() < 1e-15);
        let c = f.closest(&Point::new(1.0, 1.0, 0.0));
        assert!((c - Point::new(0.5, 0.5, 0.0)).norm() < 1e-15);
    }
}
