//! Bond cutting: pre-cracks and the boundary of non-convex bodies (theory §5).
//!
//! A bond AB is cut by a crack segment CD when A and B lie strictly on opposite sides of CD's
//! line and C and D on opposite sides of AB's (Bobaru & Duangpanya 2012 §3.4). A bond through an
//! interior vertex of a crack polyline is cut; one that only touches a crack tip is not. In 3D a
//! bond is cut when it passes through a crack triangle. Bonds between body nodes that leave the
//! body (across a hole or a re-entrant corner) are cut by the body's boundary facets, and a
//! fictitious node's bonds may cross only the sets it was mirrored across.

use crate::cloud::fictitious::Fictitious;
use crate::cloud::Cloud;
use crate::horizons::{partial_volume, Horizons};
use crate::kernel::Kernel;
use crate::math::{Point, Vector};
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
    /// For a segment of a growing crack, how its tip advances; None for a standing crack.
    pub growth: Option<Growth>,
}

/// A crack that grows along its polyline from the first point at a constant speed
/// (Bobaru & Duangpanya 2012 Example 5): at time t it covers the path up to arc length
/// `initial + speed (t − start)`, and each bond is cut when the tip passes its crossing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Growth {
    /// Time the tip starts moving, s.
    pub start: f64,
    /// Tip speed along the path, m/s.
    pub speed: f64,
    /// Length cracked from the start, m.
    pub initial: f64,
    /// Arc length of this segment's first corner along the path, m (set by [`growing_path`]).
    pub arc: f64,
}

/// The segments of a crack that grows along `points` from the first one.
pub fn growing_path(points: &[Point], mu: f64, growth: Growth) -> Vec<Cutter> {
    let pairs: Vec<[Point; 2]> = points.windows(2).map(|w| [w[0], w[1]]).collect();
    let mut arc = 0.0;
    let mut out = segments(&pairs, mu);
    for (c, p) in out.iter_mut().zip(&pairs) {
        c.growth = Some(Growth { arc, ..growth });
        arc += (p[1] - p[0]).norm();
    }
    out
}

/// Bond cuts: the fraction μ of every directed bond now, and the later cuts of growing cracks.
#[derive(Debug, Clone, Default)]
pub struct Cuts {
    /// μ per directed bond at t = 0 (1 where nothing cuts it; empty where nothing cuts any).
    pub mu: Vec<f64>,
    /// (directed bond, time it is cut, μ it keeps), for bonds a growing crack reaches later.
    pub later: Vec<(usize, f64, f64)>,
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
            growth: None,
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
        self.crossing(a, b).is_some()
    }

    /// Where the bond from `a` to `b` crosses this facet: the fraction of the way from the
    /// first corner to the second for a segment (0 for points and triangles), or None.
    pub fn crossing(&self, a: &Point, b: &Point) -> Option<f64> {
        let c = &self.corners;
        let hit = match c.len() {
            1 => (a.x - c[0].x) * (b.x - c[0].x) < 0.0,
            2 => {
                let (o3, o4) = (orient2(&c[0], &c[1], a), orient2(&c[0], &c[1], b));
                if o3 * o4 >= 0.0 {
                    return None;
                }
                let (o1, o2) = (orient2(a, b, &c[0]), orient2(a, b, &c[1]));
                if o1 * o2 < 0.0 || (o1 == 0.0 && !self.tips[0]) || (o2 == 0.0 && !self.tips[1]) {
                    return Some(o1 / (o1 - o2));
                }
                false
            }
            _ => {
                let (sa, sb) = (
                    orient3(&c[0], &c[1], &c[2], a),
                    orient3(&c[0], &c[1], &c[2], b),
                );
                if sa * sb >= 0.0 {
                    return None;
                }
                let u = orient3(a, b, &c[0], &c[1]);
                let v = orient3(a, b, &c[1], &c[2]);
                let w = orient3(a, b, &c[2], &c[0]);
                (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
            }
        };
        hit.then_some(0.0)
    }

    /// When this facet cuts the bond from `a` to `b`: −∞ for a standing crack or a part of a
    /// growing one cracked from the start, the moment its tip passes the crossing otherwise
    /// (s); None when the bond does not cross.
    pub fn cut_time(&self, a: &Point, b: &Point) -> Option<f64> {
        let u = self.crossing(a, b)?;
        Some(match self.growth {
            None => f64::NEG_INFINITY,
            Some(g) => {
                let s = g.arc + u * (self.corners[1] - self.corners[0]).norm();
                if s <= g.initial {
                    f64::NEG_INFINITY
                } else {
                    g.start + (s - g.initial) / g.speed
                }
            }
        })
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
            growth: None,
        })
        .collect()
}

/// The conductance fraction μ of every directed bond of `horizons` (1 where nothing cuts it)
/// and the later cuts of growing cracks; where nothing is cut, no factor at all (`mu` empty:
/// every bond whole). Each pair is tested with its ends in index order, so μ_ij = μ_ji bit for bit.
pub fn bond_factors(cloud: &Cloud, horizons: &Horizons, cutters: &[Cutter]) -> Cuts {
    if cutters.is_empty() {
        return Cuts::default();
    }
    // filled in parallel: at 10⁷ nodes this is gigabytes of fresh pages
    let mut mu: Vec<f64> = Vec::with_capacity(horizons.n_bonds());
    mu.par_extend(rayon::iter::repeat_n(1.0, horizons.n_bonds()));
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
    let later: Vec<(usize, f64, f64)> = horizons
        .rows_mut(&mut mu)
        .into_par_iter()
        .with_min_len(64)
        .flat_map_iter(|(i, slot)| {
            let range = horizons.row(i);
            let reach = range
                .clone()
                .map(|b| (cloud.pos[horizons.targets[b] as usize] - cloud.pos[i]).norm())
                .fold(0.0, f64::max);
            let near = index.within(&cloud.pos[i], reach + radius);
            let mut later = Vec::new();
            if near.is_empty() {
                return later;
            }
            for (m, b) in slot.iter_mut().zip(range) {
                let j = horizons.targets[b] as usize;
                let (lo, hi) = (i.min(j), i.max(j));
                let (a, z) = (&cloud.pos[lo], &cloud.pos[hi]);
                // the earliest cut of a growing crack, and the μ it leaves
                let mut first: Option<(f64, f64)> = None;
                for &k in &near {
                    let c = &cutters[k];
                    let Some(t) = c.cut_time(a, z) else {
                        continue;
                    };
                    match c.boundary {
                        None if t == f64::NEG_INFINITY => *m = m.min(c.mu),
                        None => {
                            if first.is_none_or(|f| t < f.0) {
                                first = Some((t, c.mu));
                            }
                        }
                        // a body-body bond that leaves the body, or a ghost's bond across a
                        // set it was not mirrored across
                        Some(set) => {
                            if !(hi >= nb && set.is_some_and(|s| mirrored_across(hi, s))) {
                                *m = 0.0;
                            }
                        }
                    }
                }
                if let Some((t, keep)) = first {
                    if keep < 1.0 && *m > 0.0 {
                        later.push((b, t, keep));
                    }
                }
            }
            later
        })
        .collect();
    if later.is_empty() && mu.par_iter().all(|&m| m == 1.0) {
        // nothing cut (a convex body without cracks): hold no factor
        return Cuts::default();
    }
    Cuts { mu, later }
}

/// Skin correction at cracks (beyond the papers): a node whose bonds a crack cuts loses
/// part of its horizon's second moment Σ_j w_ij |ξ_ij|², so the conductivity along the crack
/// face drops (the skin effect Bobaru & Duangpanya 2012 accept). This scales the node's own
/// directed weights by the moment of all its bonds over the moment of the bonds the crack leaves
/// (`mu` = the cracks' μ per directed bond), restoring the moment; K stays symmetric since
/// K_ij = V_i V_j (w_ij + w_ji).
pub fn restore_moment(cloud: &Cloud, horizons: &Horizons, mu: &[f64], weights: &mut [f64]) {
    if mu.is_empty() {
        return;
    }
    horizons
        .rows_mut(weights)
        .into_par_iter()
        .with_min_len(256)
        .for_each(|(i, slot)| {
            let range = horizons.row(i);
            if range.clone().all(|b| mu[b] == 1.0) {
                return;
            }
            let (mut all, mut kept) = (0.0, 0.0);
            for (w, b) in slot.iter().zip(range.clone()) {
                let r2 = (cloud.pos[horizons.targets[b] as usize] - cloud.pos[i]).norm_squared();
                all += w * r2;
                kept += w * r2 * mu[b];
            }
            if kept > 0.0 {
                let f = all / kept;
                for w in slot.iter_mut() {
                    *w *= f;
                }
            }
        });
}

/// What the damage of the body nodes needs of their directed bonds (theory §5), held by a
/// model with cracks in place of its neighbour lists: each body row's β_ij V_j and the cracks'
/// cuts.
#[derive(Debug, Clone, Default)]
pub struct DamageBonds {
    /// Start of each body row's directed bonds, length n_body + 1.
    offsets: Vec<usize>,
    /// β_ij V_j of every directed bond of the body rows, m³ (m² in 2D, m in 1D).
    volume: Vec<f64>,
    /// The cracks' factors μ of every directed bond ([`bond_factors`] of the cracks alone).
    pub cuts: Cuts,
}

impl DamageBonds {
    /// The body rows of `horizons` with their cracks' `cuts`.
    pub fn new(cloud: &Cloud, horizons: &Horizons, kernel: &Kernel, cuts: Cuts) -> Self {
        let offsets = horizons.offsets[..=cloud.n_body].to_vec();
        let volume = (0..cloud.n_body)
            .into_par_iter()
            .with_min_len(1024)
            .flat_map_iter(|i| {
                horizons.row(i).map(move |b| {
                    let j = horizons.targets[b] as usize;
                    partial_volume(cloud, kernel, i, j) * cloud.volume[j]
                })
            })
            .collect();
        DamageBonds {
            offsets,
            volume,
            cuts,
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.offsets.capacity() * 8
            + self.volume.capacity() * 8
            + self.cuts.mu.capacity() * 8
            + self.cuts.later.capacity() * 24
    }

    /// Damage of every body node at time `t` (theory §5), growing cracks included:
    /// φ_i = 1 − Σ_j μ_ij β_ij V_j / Σ_j β_ij V_j over the directed bonds of i (0 intact, 1
    /// with every bond cut).
    pub fn at(&self, t: f64) -> Vec<f64> {
        let c = &self.cuts;
        let n = self.offsets.len() - 1;
        if c.mu.is_empty() {
            return vec![0.0; n];
        }
        let mut mu = c.mu.clone();
        for &(b, tc, m) in &c.later {
            if tc <= t {
                mu[b] = mu[b].min(m);
            }
        }
        (0..n)
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let (mut kept, mut all) = (0.0, 0.0);
                let row = self.offsets[i]..self.offsets[i + 1];
                for (m, v) in mu[row.clone()].iter().zip(&self.volume[row]) {
                    kept += m * v;
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
}

/// The 2D crack segments present at time `t` (growing cracks up to their tips), m.
pub fn segments_at(cutters: &[Cutter], t: f64) -> Vec<[Point; 2]> {
    present(cutters, t).map(|(s, _)| s).collect()
}

/// The 2D crack tips at time `t` (the free ends of standing cracks and the moving ends of
/// growing ones), m.
pub fn tips_at(cutters: &[Cutter], t: f64) -> Vec<Point> {
    present(cutters, t)
        .flat_map(|(s, tip)| (0..2).filter(move |&k| tip[k]).map(move |k| s[k]))
        .collect()
}

/// Each 2D crack segment present at time `t`, with whether each of its ends is a tip.
fn present(cutters: &[Cutter], t: f64) -> impl Iterator<Item = ([Point; 2], [bool; 2])> + '_ {
    cutters
        .iter()
        .filter(|c| c.corners.len() == 2 && c.boundary.is_none())
        .filter_map(move |c| {
            let (a, b) = (c.corners[0], c.corners[1]);
            let Some(g) = c.growth else {
                return Some(([a, b], c.tips));
            };
            let covered = g.initial + g.speed * (t - g.start).max(0.0) - g.arc;
            let len = (b - a).norm();
            (covered > 0.0).then(|| {
                let end = (covered / len).min(1.0);
                ([a, a + (b - a) * end], [c.tips[0], c.tips[1] || end < 1.0])
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y, 0.0)
    }

    /// A standing crack has its two ends as tips; a growing crack's tip moves along its
    /// path at its speed (exact arithmetic on these numbers, so compared to 1e-15).
    #[test]
    fn tips_of_standing_and_growing_cracks() {
        let standing = segments(&[[p(0.0, 0.0), p(1.0, 0.0)]], 0.0);
        assert_eq!(tips_at(&standing, 0.0), vec![p(0.0, 0.0), p(1.0, 0.0)]);
        let growth = Growth {
            start: 1.0,
            speed: 0.5,
            initial: 0.25,
            arc: 0.0,
        };
        let path = growing_path(&[p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)], 0.0, growth);
        for (t, tip) in [
            (0.0, p(0.25, 0.0)),
            (2.0, p(0.75, 0.0)),
            (3.0, p(1.0, 0.25)),
        ] {
            let tips = tips_at(&path, t);
            let last = tips.last().unwrap();
            assert!((last - tip).norm() < 1e-15, "t = {t}: {tips:?}");
        }
    }

    /// A bond crossing a segment is cut; one touching only its tip is not; one through an
    /// interior vertex of a polyline is (Bobaru & Duangpanya 2012 §3.4).
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
            growth: None,
        };
        assert!(t.cuts(&Point::new(0.2, 0.2, -1.0), &Point::new(0.2, 0.2, 1.0)));
        assert!(!t.cuts(&Point::new(0.8, 0.8, -1.0), &Point::new(0.8, 0.8, 1.0)));
        assert!(!t.cuts(&Point::new(0.2, 0.2, 0.1), &Point::new(0.2, 0.2, 1.0)));
    }
}
