//! Bond cutting: pre-cracks and the boundary of non-convex bodies (formulation §5).
//!
//! A bond AB is cut by a crack segment CD when A and B lie strictly on opposite sides of CD's
//! line and C and D on opposite sides of AB's (seed 003 §3.4). A bond through an interior
//! vertex of a crack polyline is cut; one that only touches a crack tip is not. In 3D a bond
//! is cut when it passes through a crack triangle. Bonds between body nodes that leave the
//! body (across a hole or a re-entrant corner) are cut by the body's boundary facets, and a
//! fictitious node's bonds may cross only the sets it was mirrored across.

use crate::cloud::{Cloud, Fictitious};
use crate::math::{Point, Vector};
use crate::neighbors::Horizons;
use crate::spatial::PointIndex;
use rayon::prelude::*;
use std::collections::HashMap;

/// One cutting facet: a point (1D), a segment (2D) or a triangle (3D), m.
#[derive(Debug, Clone)]
pub struct Cutter {
    /// Corners.
    pub corners: Vec<Point>,
    /// For a segment, whether each end is a crack tip (a bond touching it is not cut).
    pub tips: [bool; 2],
    /// Conductance fraction μ kept by a bond that crosses it (0 = insulated).
    pub mu: f64,
    /// For a boundary facet, its set (`Some(None)` for a facet in no set); None for a crack.
    pub boundary: Option<Option<u16>>,
}

/// Crack segments of one polyline or facet group, with tips found by vertex degree.
pub fn segments(pairs: &[[Point; 2]], mu: f64) -> Vec<Cutter> {
    let key = |p: &Point| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut degree: HashMap<[u64; 3], usize> = HashMap::new();
    for s in pairs {
        for p in s {
            *degree.entry(key(p)).or_default() += 1;
        }
    }
    pairs
        .iter()
        .map(|s| Cutter {
            corners: s.to_vec(),
            tips: [degree[&key(&s[0])] == 1, degree[&key(&s[1])] == 1],
            mu,
            boundary: None,
        })
        .collect()
}

fn orient2(a: &Point, b: &Point, c: &Point) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

fn orient3(a: &Point, b: &Point, c: &Point, d: &Point) -> f64 {
    (b - a).cross(&(c - a)).dot(&(d - a))
}

impl Cutter {
    /// True when the bond from `a` to `b` crosses this facet.
    pub fn cuts(&self, a: &Point, b: &Point) -> bool {
        let c = &self.corners;
        match c.len() {
            1 => (a.x - c[0].x) * (b.x - c[0].x) < 0.0,
            2 => {
                let (o3, o4) = (orient2(&c[0], &c[1], a), orient2(&c[0], &c[1], b));
                if o3 * o4 >= 0.0 {
                    return false;
                }
                let (o1, o2) = (orient2(a, b, &c[0]), orient2(a, b, &c[1]));
                o1 * o2 < 0.0 || (o1 == 0.0 && !self.tips[0]) || (o2 == 0.0 && !self.tips[1])
            }
            _ => {
                let (sa, sb) = (
                    orient3(&c[0], &c[1], &c[2], a),
                    orient3(&c[0], &c[1], &c[2], b),
                );
                if sa * sb >= 0.0 {
                    return false;
                }
                let u = orient3(a, b, &c[0], &c[1]);
                let v = orient3(a, b, &c[1], &c[2]);
                let w = orient3(a, b, &c[2], &c[0]);
                (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
            }
        }
    }

    fn centre(&self) -> Point {
        let mut s = Vector::zeros();
        for p in &self.corners {
            s += p.coords;
        }
        Point::from(s / self.corners.len() as f64)
    }
}

/// Cutters of one planar facet: a point, a segment or a triangle as is, a quadrangle split
/// in two triangles. Segment ends count as interior vertices (a boundary has no tips).
pub fn facet_cutters(corners: &[Point], mu: f64, boundary: Option<Option<u16>>) -> Vec<Cutter> {
    let parts = match corners.len() {
        4 => vec![
            vec![corners[0], corners[1], corners[2]],
            vec![corners[0], corners[2], corners[3]],
        ],
        _ => vec![corners.to_vec()],
    };
    parts
        .into_iter()
        .map(|corners| Cutter {
            corners,
            tips: [false; 2],
            mu,
            boundary,
        })
        .collect()
}

/// The conductance fraction μ of every directed bond of `horizons` (1 where nothing cuts it).
/// Each pair is tested with its ends in index order, so μ_ij = μ_ji bit for bit.
pub fn bond_factors(cloud: &Cloud, horizons: &Horizons, cutters: &[Cutter]) -> Vec<f64> {
    let mut mu = vec![1.0; horizons.n_bonds()];
    if cutters.is_empty() {
        return mu;
    }
    let centres: Vec<Point> = cutters.iter().map(Cutter::centre).collect();
    let radius = cutters
        .iter()
        .zip(&centres)
        .flat_map(|(c, m)| c.corners.iter().map(move |p| (p - m).norm()))
        .fold(0.0, f64::max);
    let index = PointIndex::new(&centres);
    let nb = cloud.n_body;
    let mirrored_across = |g: usize, set: u16| -> bool {
        match &cloud.fictitious[g - nb] {
            Fictitious::Mirror { chain, .. } => chain.iter().any(|r| r.set == set as usize),
            Fictitious::Lattice { .. } => true,
        }
    };
    let mut rows: Vec<(usize, &mut [f64])> = Vec::with_capacity(horizons.len());
    let mut rest = mu.as_mut_slice();
    for i in 0..horizons.len() {
        let (a, b) = rest.split_at_mut(horizons.row(i).len());
        rows.push((i, a));
        rest = b;
    }
    rows.into_par_iter().with_min_len(64).for_each(|(i, slot)| {
        let range = horizons.row(i);
        let reach = range
            .clone()
            .map(|b| (cloud.pos[horizons.targets[b] as usize] - cloud.pos[i]).norm())
            .fold(0.0, f64::max);
        let near = index.within(&cloud.pos[i], reach + radius);
        if near.is_empty() {
            return;
        }
        for (m, b) in slot.iter_mut().zip(range) {
            let j = horizons.targets[b] as usize;
            let (lo, hi) = (i.min(j), i.max(j));
            let (a, z) = (&cloud.pos[lo], &cloud.pos[hi]);
            for &k in &near {
                let c = &cutters[k];
                if !c.cuts(a, z) {
                    continue;
                }
                *m = match c.boundary {
                    None => m.min(c.mu),
                    // a body-body bond that leaves the body, or a ghost's bond across a
                    // set it was not mirrored across
                    Some(set) => {
                        let allowed = hi >= nb && set.is_some_and(|s| mirrored_across(hi, s));
                        if allowed {
                            *m
                        } else {
                            0.0
                        }
                    }
                };
            }
        }
    });
    mu
}

/// Damage of every body node (formulation §5): φ_i = 1 − Σ_j μ_ij β_ij V_j / Σ_j β_ij V_j over
/// the directed bonds of i (0 intact, 1 with every bond cut).
pub fn damage(cloud: &Cloud, horizons: &Horizons, mu: &[f64]) -> Vec<f64> {
    (0..cloud.n_body)
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            let (mut kept, mut all) = (0.0, 0.0);
            for b in horizons.row(i) {
                let v = horizons.beta[b] * cloud.volume[horizons.targets[b] as usize];
                kept += mu[b] * v;
                all += v;
            }
            if all > 0.0 {
                1.0 - kept / all
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y, 0.0)
    }

    /// A bond crossing a segment is cut; one touching only its tip is not; one through an
    /// interior vertex of a polyline is (seed 003 §3.4).
    #[test]
    fn crossing_tips_and_vertices() {
        let crack = segments(
            &[[p(-1.0, 0.0), p(0.0, 0.0)], [p(0.0, 0.0), p(1.0, 0.0)]],
            0.0,
        );
        let cut = |a: Point, b: Point| crack.iter().any(|c| c.cuts(&a, &b));
        assert!(cut(p(-0.5, -0.1), p(-0.4, 0.2)));
        assert!(
            cut(p(-0.1, -0.1), p(0.1, 0.1)),
            "through the interior vertex"
        );
        assert!(!cut(p(1.0, -0.1), p(1.0, 0.1)), "touching a tip");
        assert!(!cut(p(1.5, -0.1), p(1.5, 0.1)), "beyond the tip");
        assert!(!cut(p(-0.5, 0.1), p(0.5, 0.2)), "same side");
        // both orders of the ends agree
        assert_eq!(
            cut(p(0.3, 0.4), p(0.2, -0.3)),
            cut(p(0.2, -0.3), p(0.3, 0.4))
        );
    }

    /// A bond through a 3D triangle is cut; one passing beside it is not.
    #[test]
    fn through_a_triangle() {
        let t = Cutter {
            corners: vec![
                Point::new(0.0, 0.0, 0.0),
                Point::new(1.0, 0.0, 0.0),
                Point::new(0.0, 1.0, 0.0),
            ],
            tips: [false; 2],
            mu: 0.0,
            boundary: None,
        };
        assert!(t.cuts(&Point::new(0.2, 0.2, -1.0), &Point::new(0.2, 0.2, 1.0)));
        assert!(!t.cuts(&Point::new(0.8, 0.8, -1.0), &Point::new(0.8, 0.8, 1.0)));
        assert!(!t.cuts(&Point::new(0.2, 0.2, 0.1), &Point::new(0.2, 0.2, 1.0)));
    }
}
