//! Node clouds from meshes: one node per element at its centroid, with the element's measure
//! as volume and its characteristic size as spacing; boundary sets from physical groups and
//! fictitious layers made by mirroring body nodes across the nearest boundary facet.

use super::facets::{Facet, FacetSet};
use super::fictitious::{Fictitious, Reflection};
use super::order::morton_order;
use super::{Cloud, HorizonRule, MeshSides, Sides};
use crate::error::{Error, Result};
use crate::math::{NodeId, Point, Vector};
use crate::mesh::{contains, measure_and_centroid, Element, ElementKind, Mesh};
use crate::spatial::PointIndex;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::sync::Arc;

/// Name of the boundary set made of the facets that no physical group names (always the last).
pub const UNNAMED: &str = "(no group)";

/// A region of a mesh geometry: a physical group of the body's dimension.
#[derive(Debug, Clone)]
pub struct MeshRegion {
    /// The group's name.
    pub name: String,
    /// Index of the group in [`Mesh::groups`].
    pub group: usize,
    /// Horizon rule (δ = n·Δ_i or an explicit δ).
    pub horizon: HorizonRule,
    /// Material index.
    pub material: u16,
}

/// A geometry given by a mesh.
#[derive(Debug, Clone)]
pub struct MeshGeometry {
    /// The mesh, in file units.
    pub mesh: Arc<Mesh>,
    /// Metres per file unit.
    pub scale: f64,
    /// Out-of-plane measure τ (see [`Cloud::tau`]).
    pub tau: f64,
    /// Regions: every element of the body's dimension belongs to one of them.
    pub regions: Vec<MeshRegion>,
    /// Largest ratio of horizons between nearby nodes; larger horizons are reduced to it.
    pub horizon_ratio: Option<f64>,
}

type FaceKey = [u32; 4];

fn key_of(nodes: &[u32]) -> FaceKey {
    let mut k = [u32::MAX; 4];
    k[..nodes.len()].copy_from_slice(nodes);
    k.sort_unstable();
    k
}

fn facet_kind(n: usize) -> ElementKind {
    match n {
        1 => ElementKind::Point,
        2 => ElementKind::Line,
        3 => ElementKind::Triangle,
        _ => ElementKind::Quad,
    }
}

impl MeshGeometry {
    /// Dimension of the body.
    pub fn dim(&self) -> usize {
        self.mesh.dim()
    }

    /// Mesh group indices of the boundary sets (groups one dimension below the body), in order.
    pub fn set_groups(&self) -> Vec<usize> {
        let d = self.dim();
        (0..self.mesh.groups.len())
            .filter(|&g| d > 0 && self.mesh.groups[g].dim == d - 1)
            .collect()
    }

    /// Index of the set of boundary facets that no group names (after the groups' sets).
    pub fn unnamed_set(&self) -> usize {
        self.set_groups().len()
    }

    /// Names of the boundary sets of the groups, by set index.
    pub fn set_names(&self) -> Vec<String> {
        self.set_groups()
            .iter()
            .map(|&g| self.mesh.groups[g].name.clone())
            .collect()
    }

    /// True when boundary set `s` has no element in the mesh.
    pub fn set_is_empty(&self, s: usize) -> bool {
        let g = self.set_groups()[s] as u16;
        !self.mesh.elements.iter().any(|e| e.groups.contains(&g))
    }

    fn region_of(&self, e: &Element) -> Result<usize> {
        e.groups
            .iter()
            .find_map(|&g| self.regions.iter().position(|r| r.group == g as usize))
            .ok_or_else(|| {
                let name = e
                    .groups
                    .first()
                    .map(|&g| self.mesh.groups[g as usize].name.clone())
                    .unwrap_or_default();
                Error::model(
                    "region",
                    format!("physical group `{name}` has elements but no [[region]]: add one named `{name}`"),
                )
            })
    }

    /// Builds the cloud; sets with `layered[s]` get a mirrored fictitious layer as thick as
    /// the horizons next to them (plus `band` spacings for partial volumes).
    pub fn generate(&self, layered: &[bool], band: f64) -> Result<Cloud> {
        let mesh = &*self.mesh;
        let dim = self.dim();
        if !(1..=3).contains(&dim) {
            return Err(Error::model(
                "mesh",
                "has no line, surface or volume elements",
            ));
        }
        let cells: Vec<&Element> = mesh
            .elements
            .iter()
            .filter(|e| e.kind.dim() == dim)
            .collect();
        check_flat(mesh, dim)?;
        let raw = self.body_nodes(&cells, dim)?;
        // body nodes at centroids, in Morton order
        let perm = morton_order(&raw.iter().map(|r| r.1).collect::<Vec<_>>());
        let mut new_of = vec![0u32; cells.len()];
        for (new, &old) in perm.iter().enumerate() {
            new_of[old] = new as u32;
        }
        let mut c = self.body_cloud(&raw, &perm, dim);
        let index = PointIndex::new(&c.pos);
        if let Some(ratio) = self.horizon_ratio {
            grade_horizons(&mut c, &index, ratio);
        }
        let body: Vec<&Element> = perm.iter().map(|&old| cells[old]).collect();
        let locate = Locator {
            mesh,
            scale: self.scale,
            cells: &body,
            index: &index,
        };
        let sides = self.sides(&cells, &new_of, &locate)?;
        mirror_layers(&mut c, &sides, &locate, layered, band);
        c.sides = Sides::Mesh(Box::new(sides));
        Ok(c)
    }

    /// (measure in m^dim, centroid in m, region) of every cell, in the cells' order.
    fn body_nodes(&self, cells: &[&Element], dim: usize) -> Result<Vec<(f64, Point, usize)>> {
        let s = self.scale;
        let mut raw = Vec::with_capacity(cells.len());
        for e in cells {
            let (m, c) = measure_and_centroid(e.kind, &self.mesh.corners(e));
            if m.is_nan() || m <= 0.0 {
                return Err(Error::model(
                    "mesh",
                    format!(
                        "an element has zero measure near ({}, {}, {})",
                        c.x, c.y, c.z
                    ),
                ));
            }
            raw.push((
                m * s.powi(dim as i32),
                Point::from(c.coords * s),
                self.region_of(e)?,
            ));
        }
        Ok(raw)
    }

    /// The body nodes of the cells `raw` (from [`MeshGeometry::body_nodes`]) in the order
    /// `perm`, with their bounding box.
    fn body_cloud(&self, raw: &[(f64, Point, usize)], perm: &[usize], dim: usize) -> Cloud {
        let mut c = Cloud {
            dim,
            tau: self.tau,
            ..Default::default()
        };
        for &old in perm {
            let (m, p, r) = raw[old];
            let reg = &self.regions[r];
            let dx = m.powf(1.0 / dim as f64);
            c.push(
                p,
                m * self.tau,
                dx,
                reg.horizon.horizon(dx),
                reg.material,
                r as u16,
            );
        }
        c.n_body = c.len();
        c.min = c.pos[0];
        c.max = c.pos[0];
        for p in &c.pos {
            for a in 0..3 {
                c.min[a] = c.min[a].min(p[a]);
                c.max[a] = c.max[a].max(p[a]);
            }
        }
        c
    }

    /// Boundary facets (by topology) and the facets of every set, in metres.
    fn sides(&self, cells: &[&Element], new_of: &[u32], locate: &Locator) -> Result<MeshSides> {
        let mesh = &*self.mesh;
        let faces = facet_counts(cells, new_of);
        let mut cell_centre = vec![Point::origin(); cells.len()];
        for (k, e) in cells.iter().enumerate() {
            cell_centre[new_of[k] as usize] = measure_and_centroid(e.kind, &mesh.corners(e)).1;
        }
        let maker = FacetMaker {
            geometry: self,
            dim: self.dim(),
            cell_centre: &cell_centre,
        };
        let (mut sets, owner) = self.group_sets(&faces, &maker)?;
        let s = self.scale;
        let mut boundary: Vec<Facet> = faces
            .iter()
            .filter(|(_, v)| v.2 == 1)
            .map(|(k, (cell, nodes, _))| maker.make(nodes, *cell, owner.get(k).copied()))
            // a side facing another element is a non-conforming interface, not boundary
            .filter(|f| {
                let inner = Point::from(cell_centre[f.cell as usize].coords * s);
                let step = 0.02 * (f.centre() - inner).norm();
                !locate.inside(&(f.centre() + f.normal * step))
            })
            .collect();
        // a deterministic order, whatever the hash map's
        boundary.sort_by_cached_key(|f| {
            let c = f.centre();
            (f.cell, [c.x, c.y, c.z].map(f64::to_bits))
        });
        // the facets that no group names form one more set, after the groups
        let unnamed = sets.len() as u16;
        for f in boundary.iter_mut().filter(|f| f.set.is_none()) {
            f.set = Some(unnamed);
        }
        sets.push(FacetSet::new(
            boundary
                .iter()
                .filter(|f| f.set == Some(unnamed))
                .cloned()
                .collect(),
        ));
        let mut names = self.set_names();
        names.push(UNNAMED.to_string());
        Ok(MeshSides {
            names,
            sets,
            boundary: FacetSet::new(boundary),
        })
    }

    /// The facet set of every boundary group (in [`MeshGeometry::set_groups`] order) and the
    /// first set that owns each facet.
    fn group_sets(
        &self,
        faces: &FacetCounts,
        maker: &FacetMaker,
    ) -> Result<(Vec<FacetSet>, HashMap<FaceKey, u16>)> {
        let mesh = &*self.mesh;
        let groups = self.set_groups();
        let mut owner: HashMap<FaceKey, u16> = HashMap::new();
        let mut sets = Vec::with_capacity(groups.len());
        for (si, &g) in groups.iter().enumerate() {
            let mut list = Vec::new();
            for e in mesh
                .elements
                .iter()
                .filter(|e| e.groups.contains(&(g as u16)))
            {
                let key = key_of(&e.nodes);
                let Some((cell, _, _)) = faces.get(&key) else {
                    return Err(Error::model(
                        format!("mesh group {}", mesh.groups[g].name),
                        "has an element that is not a side of any body element: re-mesh with the curve (surface) embedded in the body",
                    ));
                };
                owner.entry(key).or_insert(si as u16);
                list.push(maker.make(&e.nodes, *cell, Some(si as u16)));
            }
            sets.push(FacetSet::new(list));
        }
        Ok((sets, owner))
    }
}

/// Makes the facets of a mesh geometry (the body's dimension found once: [`Mesh::dim`]
/// scans the elements).
struct FacetMaker<'a> {
    geometry: &'a MeshGeometry,
    dim: usize,
    /// The centroid of every body cell by its body node index, file units.
    cell_centre: &'a [Point],
}

impl FacetMaker<'_> {
    /// A facet of `nodes` (file units) next to body cell `cell`, in metres, with its outward
    /// normal (away from the cell's centre) and its area times τ.
    fn make(&self, nodes: &[u32], cell: u32, set: Option<u16>) -> Facet {
        let g = self.geometry;
        let s = g.scale;
        let q: Vec<Point> = nodes.iter().map(|&n| g.mesh.nodes[n as usize]).collect();
        let inside = self.cell_centre[cell as usize];
        let mut n = match q.len() {
            1 => Vector::x(),
            2 => {
                let t = q[1] - q[0];
                Vector::new(t.y, -t.x, 0.0)
            }
            3 => (q[1] - q[0]).cross(&(q[2] - q[0])),
            _ => (q[2] - q[0]).cross(&(q[3] - q[1])),
        }
        .normalize();
        if (inside - q[0]).dot(&n) > 0.0 {
            n = -n;
        }
        let (m, _) = measure_and_centroid(facet_kind(q.len()), &q);
        let tau_area = match self.dim {
            1 => g.tau,
            2 => m * s * g.tau,
            _ => m * s * s,
        };
        Facet {
            corners: q.iter().map(|p| Point::from(p.coords * s)).collect(),
            normal: n,
            area: tau_area,
            cell,
            set,
        }
    }
}

/// Every facet of the cells by its sorted nodes: (the new index of the first cell that has
/// it, its nodes as that cell lists them, how many cells have it).
type FacetCounts = HashMap<FaceKey, (u32, Vec<u32>, u8)>;

/// The [`FacetCounts`] of `cells`; `new_of` maps a cell's index to its body node.
fn facet_counts(cells: &[&Element], new_of: &[u32]) -> FacetCounts {
    let mut faces: FacetCounts = HashMap::new();
    for (k, e) in cells.iter().enumerate() {
        for f in e.kind.facets() {
            let nodes: Vec<u32> = f.iter().map(|&i| e.nodes[i]).collect();
            faces
                .entry(key_of(&nodes))
                .and_modify(|v| v.2 += 1)
                .or_insert((new_of[k], nodes, 1));
        }
    }
    faces
}

/// Checks that a 2D mesh lies in the z = 0 plane and a 1D mesh on the x axis
/// ([`Mesh::off_plane`]).
fn check_flat(mesh: &Mesh, dim: usize) -> Result<()> {
    let Some(n) = mesh.off_plane(dim) else {
        return Ok(());
    };
    let p = mesh.nodes[n];
    Err(Error::model(
        "mesh",
        format!(
            "a {dim}D mesh must lie in the {} (node at {}, {}, {})",
            if dim == 2 { "z = 0 plane" } else { "x axis" },
            p.x,
            p.y,
            p.z
        ),
    ))
}

/// Finds whether a point lies in the body, from the cells next to it.
struct Locator<'a> {
    mesh: &'a Mesh,
    scale: f64,
    cells: &'a [&'a Element],
    index: &'a PointIndex,
}

impl Locator<'_> {
    /// True when `p` (m) lies inside or on one of the body elements nearest to it.
    fn inside(&self, p: &Point) -> bool {
        let q = Point::from(p.coords / self.scale);
        self.index.nearest(p, 12).into_iter().any(|(k, _)| {
            let e = self.cells[k];
            contains(e.kind, &self.mesh.corners(e), &q)
        })
    }
}

/// Mirrors body nodes across the nearest facet of each layered set, then mirrors those
/// images across later layered sets near corners (up to one reflection per set, so corner
/// quadrants and octants are filled); images inside the body are dropped.
fn mirror_layers(c: &mut Cloud, sides: &MeshSides, locate: &Locator, layered: &[bool], band: f64) {
    let nb = c.n_body;
    let reach = |i: usize| 1.25 * (c.horizon[i] + band * c.spacing[i]);
    let is_layered = |s: usize| layered.get(s).copied().unwrap_or(false);
    let mut ghosts: Vec<(usize, Point, Vec<Reflection>)> = Vec::new();
    for (si, set) in sides.sets.iter().enumerate() {
        if !is_layered(si) {
            continue;
        }
        for i in 0..nb {
            let p = c.pos[i];
            let Some((k, d)) = set.nearest(&p) else {
                continue;
            };
            if d > reach(i) {
                continue;
            }
            let f = &set.facets[k];
            let q = f.reflect(&p);
            if f.outward_distance(&q) <= 0.0 || locate.inside(&q) {
                continue;
            }
            let first = Reflection {
                set: si,
                foot: f.closest(&p),
                distance: (q - p).norm(),
            };
            // images of images across later sets, while the image is still within reach
            // of them on their inner side (the region beyond a corner)
            let mut pending = vec![(q, vec![first])];
            while let Some((q, chain)) = pending.pop() {
                let last = chain[0].set;
                for (sj, other) in sides.sets.iter().enumerate().skip(last + 1) {
                    if !is_layered(sj) {
                        continue;
                    }
                    let Some((k2, _)) = other.nearest(&q) else {
                        continue;
                    };
                    let f2 = &other.facets[k2];
                    let d2 = -f2.outward_distance(&q);
                    if d2 <= 0.0 || d2 > reach(i) {
                        continue;
                    }
                    let q2 = f2.reflect(&q);
                    if locate.inside(&q2) {
                        continue;
                    }
                    let mut longer = vec![Reflection {
                        set: sj,
                        foot: f2.closest(&q),
                        distance: (q2 - q).norm(),
                    }];
                    longer.extend(chain.iter().cloned());
                    pending.push((q2, longer));
                }
                ghosts.push((i, q, chain));
            }
        }
    }
    for (i, q, chain) in ghosts {
        let (v, dx, d) = (c.volume[i], c.spacing[i], c.horizon[i]);
        let (m, r) = (c.material[i], c.region[i]);
        c.push(q, v, dx, d, m, r);
        c.fictitious.push(Fictitious::Mirror {
            of: i as NodeId,
            chain,
        });
    }
}

/// Limits horizons so that no node's δ exceeds `ratio` times a nearby node's (Dijkstra order).
fn grade_horizons(c: &mut Cloud, index: &PointIndex, ratio: f64) {
    let nb = c.n_body;
    let k = 3usize.pow(c.dim as u32);
    let nbrs: Vec<Vec<usize>> = (0..nb)
        .map(|i| {
            index
                .nearest(&c.pos[i], k)
                .into_iter()
                .map(|(j, _)| j)
                .collect()
        })
        .collect();
    let mut heap: BinaryHeap<Reverse<(u64, usize)>> = (0..nb)
        .map(|i| Reverse((c.horizon[i].to_bits(), i)))
        .collect();
    while let Some(Reverse((bits, i))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > c.horizon[i] {
            continue;
        }
        for &j in &nbrs[i] {
            let cap = ratio * d;
            if cap < c.horizon[j] {
                c.horizon[j] = cap;
                heap.push(Reverse((cap.to_bits(), j)));
            }
        }
    }
}
