//! Node clouds: struct-of-arrays storage and the built-in box generators.
//!
//! A cloud holds the body nodes first (`0..n_body`) and the fictitious boundary-layer
//! nodes after them (the fictitious regions of Wang, Oterkus & Oterkus, the mirror/naive layers of
//! PCS2022; their types are in [`fictitious`]). Every node has its own spacing Δ and horizon δ, which is
//! what dual horizon needs (Wang, Oterkus & Oterkus §3).

pub mod facets;
pub mod fictitious;
pub mod mesh;
pub mod order;

use crate::error::{Error, Result};
use crate::math::{Point, Vector, GEOMETRIC_TOLERANCE};
use crate::symmetry::Symmetry;
use facets::FacetSet;

// the fictitious nodes' types under their old paths
pub use fictitious::{Fictitious, Reflection};

/// Faces of an axis-aligned box, in the order x_min, x_max, y_min, y_max, z_min, z_max.
pub const FACE_NAMES: [&str; 6] = ["x_min", "x_max", "y_min", "y_max", "z_min", "z_max"];

/// Index of a face (0..6): axis = face / 2, max side when face is odd.
pub type Face = usize;

/// Direction of the body seen from a face along its axis: +1 for a min face, −1 for a max face.
pub fn inward(face: Face) -> f64 {
    if face.is_multiple_of(2) {
        1.0
    } else {
        -1.0
    }
}

/// Boundary sets of a mesh-based cloud.
#[derive(Debug, Clone)]
pub struct MeshSides {
    /// Set names (physical groups one dimension below the body).
    pub names: Vec<String>,
    /// Facets of each set.
    pub sets: Vec<FacetSet>,
    /// Every boundary facet of the body (by topology), with the set it belongs to.
    pub boundary: FacetSet,
}

/// The body's boundary: the faces of a box, or facet sets of a mesh.
#[derive(Debug, Clone, Default)]
pub enum Sides {
    /// Sets 0..2d are the box faces x_min … z_max.
    #[default]
    Box,
    /// Sets are physical groups of a mesh.
    Mesh(Box<MeshSides>),
}

/// Struct-of-arrays node cloud.
#[derive(Debug, Clone, Default)]
pub struct Cloud {
    /// Spatial dimension d (1, 2 or 3).
    pub dim: usize,
    /// Out-of-plane measure τ: cross-section area (m²) in 1D, thickness (m) in 2D, 1 in 3D.
    pub tau: f64,
    /// Node positions, m.
    pub pos: Vec<Point>,
    /// True node volumes V_i (length × A, area × h, volume; rings and shells when
    /// [`Cloud::symmetry`] is not planar), m³.
    pub volume: Vec<f64>,
    /// Node spacing Δ_i, m.
    pub spacing: Vec<f64>,
    /// Node horizon δ_i, m.
    pub horizon: Vec<f64>,
    /// Material index per node.
    pub material: Vec<u16>,
    /// Region index per node.
    pub region: Vec<u16>,
    /// Number of body nodes; nodes `n_body..` are fictitious.
    pub n_body: usize,
    /// For each fictitious node (index − n_body), where its temperature comes from.
    pub fictitious: Vec<Fictitious>,
    /// Boundary sets.
    pub sides: Sides,
    /// Bounding box of the body: min corner, m.
    pub min: Point,
    /// Bounding box of the body: max corner, m.
    pub max: Point,
    /// Whether nodes sit on the boundary with partial volumes (Bobaru & Duangpanya 2012 §3).
    pub boundary_placement: bool,
    /// Planar, or rings/shells about the axis x = 0 (PCS2022; theory
    /// §7).
    pub symmetry: Symmetry,
}

impl Cloud {
    /// Total number of nodes, body and fictitious.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// True when the cloud has no node.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Number of fictitious nodes.
    pub fn n_fictitious(&self) -> usize {
        self.len() - self.n_body
    }

    /// Signed distance of a point inside the body to a face of the bounding box, m.
    pub fn distance_to_face(&self, p: &Point, face: Face) -> f64 {
        (p[face / 2] - self.face_plane(face)) * inward(face)
    }

    /// Coordinate of a face's plane along its axis, m.
    pub fn face_plane(&self, face: Face) -> f64 {
        let a = face / 2;
        if face.is_multiple_of(2) {
            self.min[a]
        } else {
            self.max[a]
        }
    }

    /// Body nodes in the first `layers` node layers next to a face.
    pub fn face_layer(&self, face: Face, layers: f64) -> Vec<usize> {
        (0..self.n_body)
            .filter(|&i| {
                let d = self.distance_to_face(&self.pos[i], face);
                d < (layers - 0.25) * self.spacing[i]
            })
            .collect()
    }

    /// Exposed area of a surface node on a face, m² (cell face area × out-of-plane measure).
    pub fn exposed_area(&self, i: usize) -> f64 {
        let f = if self.boundary_placement { 2.0 } else { 1.0 };
        f * self.volume[i] / self.spacing[i]
    }

    /// Turns planar node measures into ring or shell volumes (× 2πr or 4πr², r = x). Every
    /// node, fictitious ones included, must lie at r > 0: the axis or centre takes no layer.
    pub fn apply_symmetry(&mut self, symmetry: Symmetry) -> Result<()> {
        self.symmetry = symmetry;
        if !symmetry.is_symmetric() {
            return Ok(());
        }
        if let Some(i) = (0..self.len()).find(|&i| self.pos[i].x <= 0.0) {
            let what = if i < self.n_body {
                "a body node"
            } else {
                "a fictitious node"
            };
            return Err(Error::model(
                "symmetry",
                format!(
                "{} model: {what} lies at r = x = {:.6e} ≤ 0; the body must lie at x ≥ 0 and the face at the axis (x = 0) takes no fictitious layer (leave it free: no bonds cross the axis)",
                symmetry.name(),
                self.pos[i].x
            ),
            ));
        }
        for (v, p) in self.volume.iter_mut().zip(&self.pos) {
            *v *= symmetry.volume_factor(p.x);
        }
        Ok(())
    }

    /// Total body volume, m³.
    pub fn body_volume(&self) -> f64 {
        self.volume[..self.n_body].iter().sum()
    }

    /// Number of boundary sets (box faces, or mesh groups one dimension below the body).
    pub fn n_sets(&self) -> usize {
        match &self.sides {
            Sides::Box => 2 * self.dim,
            Sides::Mesh(m) => m.sets.len(),
        }
    }

    /// Distance from `p` to boundary set `s`, m (∞ for an empty set).
    pub fn set_distance(&self, p: &Point, s: usize) -> f64 {
        match &self.sides {
            Sides::Box => self.distance_to_face(p, s),
            Sides::Mesh(m) => m.sets[s].nearest(p).map_or(f64::INFINITY, |(_, d)| d),
        }
    }

    /// Nearest point of set `s` to `p` and the unit normal there pointing into the body.
    pub fn set_foot(&self, p: &Point, s: usize) -> (Point, Vector) {
        match &self.sides {
            Sides::Box => {
                let mut q = *p;
                q[s / 2] = self.face_plane(s);
                let mut n = Vector::zeros();
                n[s / 2] = inward(s);
                (q, n)
            }
            Sides::Mesh(m) => match m.sets[s].nearest(p) {
                Some((k, _)) => {
                    let f = &m.sets[s].facets[k];
                    (f.closest(p), -f.normal)
                }
                None => (*p, Vector::zeros()),
            },
        }
    }

    /// Body nodes in the first `layers` node layers next to set `s`: closer than
    /// (layers − ¼)·Δ_i, and on a mesh also every element with a side on the set.
    pub fn set_layer(&self, s: usize, layers: f64) -> Vec<usize> {
        match &self.sides {
            Sides::Box => self.face_layer(s, layers),
            Sides::Mesh(m) => {
                let mut hit = vec![false; self.n_body];
                for f in &m.sets[s].facets {
                    hit[f.cell as usize] = true;
                }
                (0..self.n_body)
                    .filter(|&i| {
                        hit[i]
                            || self.set_distance(&self.pos[i], s)
                                < (layers - 0.25) * self.spacing[i]
                    })
                    .collect()
            }
        }
    }

    /// Body nodes exposed on set `s` with their exposed area, m².
    pub fn exposed(&self, s: usize) -> Vec<(usize, f64)> {
        match &self.sides {
            Sides::Box => self
                .face_layer(s, 1.0)
                .into_iter()
                .map(|i| {
                    // a face of constant r: the ring or shell area there, not at the node
                    let scale = if s / 2 == 0 {
                        self.symmetry.volume_factor(self.face_plane(s))
                            / self.symmetry.volume_factor(self.pos[i].x)
                    } else {
                        1.0
                    };
                    (i, self.exposed_area(i) * scale)
                })
                .collect(),
            Sides::Mesh(m) => {
                let mut area: std::collections::BTreeMap<usize, f64> = Default::default();
                for f in &m.sets[s].facets {
                    let n = f.corners.len() as f64;
                    let r = f.corners.iter().map(|c| c.x).sum::<f64>() / n;
                    *area.entry(f.cell as usize).or_default() +=
                        f.area * self.symmetry.volume_factor(r);
                }
                area.into_iter().collect()
            }
        }
    }

    /// Distance of every body node to the nearest boundary without a fictitious layer, m
    /// (`layered[s]` tells which sets have one).
    pub fn distances_to_free(&self, layered: &[bool]) -> Vec<f64> {
        let has = |s: usize| layered.get(s).copied().unwrap_or(false);
        match &self.sides {
            Sides::Box => (0..self.n_body)
                .map(|i| {
                    (0..2 * self.dim)
                        .filter(|&f| !has(f))
                        .map(|f| self.distance_to_face(&self.pos[i], f))
                        .fold(f64::INFINITY, f64::min)
                })
                .collect(),
            Sides::Mesh(m) => {
                let free = m
                    .boundary
                    .filter(|f| !f.set.is_some_and(|s| has(s as usize)));
                (0..self.n_body)
                    .map(|i| free.nearest(&self.pos[i]).map_or(f64::INFINITY, |(_, d)| d))
                    .collect()
            }
        }
    }

    fn push(&mut self, p: Point, v: f64, dx: f64, delta: f64, mat: u16, reg: u16) {
        self.pos.push(p);
        self.volume.push(v);
        self.spacing.push(dx);
        self.horizon.push(delta);
        self.material.push(mat);
        self.region.push(reg);
    }
}

/// How a region's horizon follows from its spacing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HorizonRule {
    /// δ = n·Δ (Wang, Oterkus & Oterkus, eq. 27).
    Factor(f64),
    /// An explicit δ, m.
    Radius(f64),
}

impl HorizonRule {
    /// The horizon for a node of spacing `dx`, m.
    pub fn horizon(&self, dx: f64) -> f64 {
        match *self {
            HorizonRule::Factor(n) => n * dx,
            HorizonRule::Radius(r) => r,
        }
    }
}

/// An axis-aligned box region with its own lattice, horizon rule and material.
#[derive(Debug, Clone)]
pub struct BoxRegion {
    /// Name, for messages and output.
    pub name: String,
    /// Min corner, m (unused coordinates 0).
    pub min: [f64; 3],
    /// Max corner, m.
    pub max: [f64; 3],
    /// Number of cells along each used axis.
    pub cells: [usize; 3],
    /// Horizon rule.
    pub horizon: HorizonRule,
    /// Material index.
    pub material: u16,
}

impl BoxRegion {
    fn h(&self, a: usize) -> f64 {
        (self.max[a] - self.min[a]) / self.cells[a] as f64
    }

    /// Node spacing Δ of the region's lattice (cells are square), m.
    pub fn spacing(&self) -> f64 {
        self.h(0)
    }
}

/// A built-in geometry: a box domain tiled by box regions.
#[derive(Debug, Clone)]
pub struct BoxGeometry {
    /// Dimension, 1..=3.
    pub dim: usize,
    /// Out-of-plane measure τ (see [`Cloud::tau`]).
    pub tau: f64,
    /// Domain min corner, m.
    pub min: [f64; 3],
    /// Domain max corner, m.
    pub max: [f64; 3],
    /// Nodes on the boundary with partial volumes (Bobaru & Duangpanya 2012 §3) instead of cell
    /// centres.
    pub boundary_placement: bool,
    /// The regions; together they tile the domain.
    pub regions: Vec<BoxRegion>,
}

impl BoxGeometry {
    /// Checks the tiling and the lattices; errors name the region.
    pub fn validate(&self) -> Result<()> {
        let measure = |min: &[f64; 3], max: &[f64; 3]| -> f64 {
            (0..self.dim).map(|a| max[a] - min[a]).product()
        };
        let total = measure(&self.min, &self.max);
        if total <= 0.0 {
            return Err(Error::model("domain", "max must exceed min on every axis"));
        }
        let scale = (0..self.dim)
            .map(|a| self.max[a] - self.min[a])
            .fold(0.0, f64::max);
        let mut sum = 0.0;
        for (r, reg) in self.regions.iter().enumerate() {
            let key = format!("region.{}", reg.name);
            for a in 0..self.dim {
                if reg.max[a] <= reg.min[a] {
                    return Err(Error::model(&key, "max must exceed min on every axis"));
                }
                if reg.min[a] < self.min[a] - GEOMETRIC_TOLERANCE * scale
                    || reg.max[a] > self.max[a] + GEOMETRIC_TOLERANCE * scale
                {
                    return Err(Error::model(&key, "region extends outside the domain"));
                }
                if reg.cells[a] == 0 {
                    return Err(Error::model(&key, "needs at least one cell per axis"));
                }
            }
            let h0 = reg.h(0);
            for a in 1..self.dim {
                if (reg.h(a) - h0).abs() > 1e-6 * h0 {
                    return Err(Error::model(
                        &key,
                        format!(
                            "cells must be square: spacing {} on x but {} on axis {a}",
                            h0,
                            reg.h(a)
                        ),
                    ));
                }
            }
            sum += measure(&reg.min, &reg.max);
            for other in &self.regions[..r] {
                let overlap: f64 = (0..self.dim)
                    .map(|a| (reg.max[a].min(other.max[a]) - reg.min[a].max(other.min[a])).max(0.0))
                    .product();
                if overlap > GEOMETRIC_TOLERANCE * total {
                    return Err(Error::model(
                        &key,
                        format!("overlaps region {}", other.name),
                    ));
                }
            }
        }
        if (sum - total).abs() > 1e-6 * total {
            return Err(Error::model(
                "region",
                format!("regions cover {sum:e} of the domain's {total:e}: they must tile it"),
            ));
        }
        if self.boundary_placement && self.regions.len() != 1 {
            return Err(Error::model(
                "domain.placement",
                "`boundary` placement supports a single region; use `cell` for several regions",
            ));
        }
        Ok(())
    }

    /// Generates the cloud with fictitious layers outside the faces in `fictitious` (bit mask),
    /// each at least `layer` m thick (one horizon plus the partial-volume band).
    pub fn generate(&self, fictitious: u8, layer: f64) -> Result<Cloud> {
        self.validate()?;
        let mut c = Cloud {
            dim: self.dim,
            tau: self.tau,
            min: Point::new(self.min[0], self.min[1], self.min[2]),
            max: Point::new(self.max[0], self.max[1], self.max[2]),
            boundary_placement: self.boundary_placement,
            ..Default::default()
        };
        let mut fict: Vec<(Point, f64, f64, f64, u16, u16, u8)> = Vec::new();
        for (r, reg) in self.regions.iter().enumerate() {
            let h = reg.h(0);
            let delta = reg.horizon.horizon(h);
            let (lo, hi) = self.index_range(reg, fictitious, layer);
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
                    for i in lo[0]..hi[0] {
                        let (pt, v, out) = self.lattice_node(reg, [i, j, k], h);
                        if out == 0 {
                            c.push(pt, v, h, delta, reg.material, r as u16);
                        } else {
                            fict.push((pt, v, h, delta, reg.material, r as u16, out));
                        }
                    }
                }
            }
        }
        c.n_body = c.len();
        for (p, v, h, d, m, r, out) in fict {
            c.push(p, v, h, d, m, r);
            c.fictitious.push(Fictitious::Lattice { outside: out });
        }
        Ok(c)
    }

    /// The lattice index range [lo, hi) of a region per axis, extended by the layer
    /// (`layer` m, whole spacings) beyond the domain faces in the `fictitious` bit mask.
    fn index_range(&self, reg: &BoxRegion, fictitious: u8, layer: f64) -> ([i64; 3], [i64; 3]) {
        let scale = (0..self.dim)
            .map(|a| self.max[a] - self.min[a])
            .fold(0.0, f64::max);
        let eps = GEOMETRIC_TOLERANCE * scale;
        // whether the region reaches the domain's face
        let on_face = |face: Face| {
            let a = face / 2;
            if face.is_multiple_of(2) {
                (reg.min[a] - self.min[a]).abs() < eps
            } else {
                (reg.max[a] - self.max[a]).abs() < eps
            }
        };
        let h = reg.h(0);
        let ext = (layer / h - 1e-9).ceil().max(0.0) as i64;
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3]; // exclusive
        for a in 0..3 {
            if a >= self.dim {
                hi[a] = 1;
                continue;
            }
            let n = reg.cells[a] as i64;
            hi[a] = if self.boundary_placement { n + 1 } else { n };
            if fictitious & (1 << (2 * a)) != 0 && on_face(2 * a) {
                lo[a] = -ext;
            }
            if fictitious & (1 << (2 * a + 1)) != 0 && on_face(2 * a + 1) {
                hi[a] += ext;
            }
        }
        (lo, hi)
    }

    /// The node of lattice index `idx` of a region of spacing `h` m: its position, its volume
    /// (halved on the faces with boundary placement), m^dim·τ, and the bit mask of the domain
    /// faces it lies beyond (0 for a body node).
    fn lattice_node(&self, reg: &BoxRegion, idx: [i64; 3], h: f64) -> (Point, f64, u8) {
        let bp = self.boundary_placement;
        let mut p = [0.0; 3];
        let mut v = self.tau;
        let mut out = 0u8;
        for a in 0..self.dim {
            let n = reg.cells[a] as i64;
            let off = if bp { 0.0 } else { 0.5 };
            p[a] = reg.min[a] + (idx[a] as f64 + off) * h;
            let mut frac = 1.0;
            if bp && (idx[a] == 0 || idx[a] == n) {
                frac = 0.5;
            }
            if idx[a] < 0 {
                out |= 1 << (2 * a);
                frac = 1.0;
            }
            let last = if bp { n } else { n - 1 };
            if idx[a] > last {
                out |= 1 << (2 * a + 1);
                frac = 1.0;
            }
            v *= h * frac;
        }
        (Point::new(p[0], p[1], p[2]), v, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plate(bp: bool, k: f64) -> BoxGeometry {
        let left = BoxRegion {
            name: "r1".into(),
            min: [-0.5, -0.5, 0.0],
            max: [0.0, 0.5, 0.0],
            cells: [10, 20, 1],
            horizon: HorizonRule::Factor(3.0),
            material: 0,
        };
        let n2 = (10.0 * k) as usize;
        let right = BoxRegion {
            name: "r2".into(),
            min: [0.0, -0.5, 0.0],
            max: [0.5, 0.5, 0.0],
            cells: [n2, 2 * n2, 1],
            horizon: HorizonRule::Factor(3.0),
            material: 0,
        };
        BoxGeometry {
            dim: 2,
            tau: 0.1,
            min: [-0.5, -0.5, 0.0],
            max: [0.5, 0.5, 0.0],
            boundary_placement: bp,
            regions: if bp {
                vec![BoxRegion {
                    min: [-0.5, -0.5, 0.0],
                    max: [0.5, 0.5, 0.0],
                    cells: [20, 20, 1],
                    ..left
                }]
            } else {
                vec![left, right]
            },
        }
    }

    /// Body volumes sum to the domain measure × τ (tolerance: round-off).
    #[test]
    fn volumes_sum_to_domain() {
        for (bp, k) in [(false, 1.0), (false, 0.5), (true, 1.0)] {
            let c = plate(bp, k).generate(0b1111, 0.2).unwrap();
            assert!((c.body_volume() - 0.1).abs() < 1e-14, "{}", c.body_volume());
            assert!(c.n_fictitious() > 0);
        }
    }

    #[test]
    fn boundary_placement_has_partial_areas() {
        let c = plate(true, 1.0).generate(0, 0.0).unwrap();
        assert_eq!(c.n_body, 21 * 21);
        let h2 = 0.05 * 0.05 * 0.1;
        let corner = c
            .pos
            .iter()
            .position(|p| p.x == -0.5 && p.y == -0.5)
            .unwrap();
        assert!((c.volume[corner] - h2 / 4.0).abs() < 1e-18);
        let edge = c
            .pos
            .iter()
            .position(|p| p.x == -0.5 && (p.y - 0.0).abs() < 1e-12)
            .unwrap();
        assert!((c.volume[edge] - h2 / 2.0).abs() < 1e-18);
    }

    #[test]
    fn fictitious_layer_is_thick_enough_and_marked() {
        let c = plate(false, 0.5).generate(0b0001, 0.16).unwrap();
        for f in 0..c.n_fictitious() {
            let p = c.pos[c.n_body + f];
            assert_eq!(c.fictitious[f], Fictitious::Lattice { outside: 1 });
            assert!(p.x < -0.5 && p.x > -0.5 - 0.16 - 0.05);
        }
        // 4 columns of 20 nodes (0.16 / 0.05 rounded up)
        assert_eq!(c.n_fictitious(), 80);
    }

    #[test]
    fn rejects_gaps_and_overlaps() {
        let mut g = plate(false, 1.0);
        g.regions[1].min[0] = 0.1;
        g.regions[1].cells[0] = 8;
        assert!(g.validate().unwrap_err().to_string().contains("tile"));
        let mut g = plate(false, 1.0);
        g.regions[1].min[0] = -0.1;
        assert!(g.validate().is_err());
    }
}
