//! The finite-element mesh: nodes, first-order cells with their region and material, and
//! the boundary sets as lists of cell facets.
//!
//! Boundary facets are stored as (cell, local facet) rather than as node lists, so that
//! splitting the mesh along a crack ([`crate::split`]) renumbers them for free.

use crate::shape::{facet_kind, facets, MAX_NODES};
use peritherm_core::cloud::mesh::MeshGeometry;
use peritherm_core::error::{Error, Result};
use peritherm_core::math::Point;
use peritherm_core::mesh::ElementKind;
use peritherm_core::spatial::PointIndex;
use peritherm_core::symmetry::Symmetry;
use std::collections::HashMap;

/// One cell: its kind, node indices (the first `kind.n_nodes()` are used), region and material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Shape.
    pub kind: ElementKind,
    /// Node indices into [`FemMesh::nodes`] (gmsh ordering).
    pub nodes: [u32; MAX_NODES],
    /// Region index (the case's `[[region]]` order).
    pub region: u16,
    /// Material index.
    pub material: u16,
}

impl Cell {
    /// The used node indices.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes[..self.kind.n_nodes()]
    }
}

/// A facet of a cell: (cell index, local facet index).
pub type FacetRef = (u32, u8);

/// Sorted node indices of a facet, padded with `u32::MAX`: equal for the two cells sharing it.
pub type FacetKey = [u32; 4];

/// A mesh ready for assembly.
#[derive(Debug, Clone)]
pub struct FemMesh {
    /// Spatial dimension d.
    pub dim: usize,
    /// Out-of-plane measure τ: cross-section (m²) in 1D, thickness (m) in 2D, 1 in 3D.
    pub tau: f64,
    /// Node positions, m.
    pub nodes: Vec<Point>,
    /// Cells of dimension d.
    pub cells: Vec<Cell>,
    /// Boundary facets of each boundary set (box faces x_min … z_max, or the mesh's groups).
    pub sets: Vec<Vec<FacetRef>>,
    /// Planar, or axisymmetric / spherical about x = 0 (x = r): every volume and facet
    /// integral is weighted by [`Symmetry::volume_factor`] (1, 2πr or 4πr², m⁰/m/m²).
    pub symmetry: Symmetry,
}

impl FemMesh {
    /// Node indices of a facet, in the cell's local order.
    pub fn facet_nodes(&self, f: FacetRef) -> impl Iterator<Item = u32> + '_ {
        let c = &self.cells[f.0 as usize];
        facets(c.kind)[f.1 as usize]
            .iter()
            .map(move |&a| c.nodes[a])
    }

    /// Kind of a facet.
    pub fn facet_kind(&self, f: FacetRef) -> ElementKind {
        let c = &self.cells[f.0 as usize];
        facet_kind(self.dim, facets(c.kind)[f.1 as usize].len())
    }

    /// Every facet of every cell by key: interior facets appear twice, boundary ones once.
    pub fn facet_map(&self) -> HashMap<FacetKey, Vec<FacetRef>> {
        let mut map: HashMap<FacetKey, Vec<FacetRef>> = HashMap::new();
        for (e, c) in self.cells.iter().enumerate() {
            for (k, f) in facets(c.kind).iter().enumerate() {
                let key = key_of(f.iter().map(|&a| c.nodes[a]));
                map.entry(key).or_default().push((e as u32, k as u8));
            }
        }
        map
    }

    /// For every node, the cells that use it (CSR: offsets, then (cell, local index) pairs).
    pub fn node_cells(&self) -> (Vec<usize>, Vec<(u32, u8)>) {
        let mut count = vec![0usize; self.nodes.len() + 1];
        for c in &self.cells {
            for &n in c.nodes() {
                count[n as usize + 1] += 1;
            }
        }
        for i in 0..self.nodes.len() {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut out = vec![(0u32, 0u8); count[self.nodes.len()]];
        for (e, c) in self.cells.iter().enumerate() {
            for (a, &n) in c.nodes().iter().enumerate() {
                out[fill[n as usize]] = (e as u32, a as u8);
                fill[n as usize] += 1;
            }
        }
        (count, out)
    }

    /// Weight of a quadrature point at `p` from the body's symmetry: 1 (planar), 2πr or 4πr²
    /// with r = x (the ring and shell measures of PCS2022,
    /// doi:10.1007/s42102-022-00092-3), m⁰, m or m².
    #[inline]
    pub fn symmetry_weight(&self, p: &Point) -> f64 {
        self.symmetry.volume_factor(p.x)
    }

    /// Corner positions of a cell.
    pub fn corners(&self, c: &Cell) -> [Point; MAX_NODES] {
        let mut p = [Point::origin(); MAX_NODES];
        for (a, &n) in c.nodes().iter().enumerate() {
            p[a] = self.nodes[n as usize];
        }
        p
    }

    /// Builds the mesh from a gmsh geometry: its cells of the body's dimension (regions by
    /// physical group), coordinates scaled to metres, unused nodes dropped, and each boundary
    /// set's facets matched to the cell facets they cover.
    pub fn from_gmsh(g: &MeshGeometry) -> Result<FemMesh> {
        let mesh = &*g.mesh;
        let dim = g.dim();
        let mut renumber = vec![u32::MAX; mesh.nodes.len()];
        let mut nodes = Vec::new();
        let mut cells = Vec::new();
        for e in mesh.elements.iter().filter(|e| e.kind.dim() == dim) {
            let r = e
                .groups
                .iter()
                .find_map(|&gr| g.regions.iter().position(|r| r.group == gr as usize))
                .ok_or_else(|| {
                    Error::model(
                        "region",
                        "a body element belongs to no [[region]] (name its physical group)",
                    )
                })?;
            let mut c = Cell {
                kind: e.kind,
                nodes: [0; MAX_NODES],
                region: r as u16,
                material: g.regions[r].material,
            };
            for (a, &n) in e.nodes.iter().enumerate() {
                if renumber[n as usize] == u32::MAX {
                    renumber[n as usize] = nodes.len() as u32;
                    nodes.push(Point::from(mesh.nodes[n as usize].coords * g.scale));
                }
                c.nodes[a] = renumber[n as usize];
            }
            cells.push(c);
        }
        let mut m = FemMesh {
            dim,
            tau: g.tau,
            nodes,
            cells,
            sets: Vec::new(),
            symmetry: Symmetry::Planar,
        };
        let map = m.facet_map();
        for gr in g.set_groups() {
            let mut set = Vec::new();
            for e in mesh
                .elements
                .iter()
                .filter(|e| e.groups.contains(&(gr as u16)))
            {
                let key = key_of(e.nodes.iter().map(|&n| renumber[n as usize]));
                if let Some(f) = map.get(&key) {
                    set.push(f[0]);
                }
            }
            m.sets.push(set);
        }
        Ok(m)
    }

    /// An error when a node lies inside a boundary facet of another cell (a hanging node:
    /// regions meshed with different sizes that do not share their interface nodes). Probes
    /// the centre of every facet that belongs to one cell only, and in 3D its edge midpoints.
    pub fn check_conforming(&self) -> Result<()> {
        let map = self.facet_map();
        let boundary: Vec<FacetRef> = map
            .values()
            .filter(|v| v.len() == 1)
            .map(|v| v[0])
            .collect();
        let mut on_boundary = vec![false; self.nodes.len()];
        for &f in &boundary {
            for n in self.facet_nodes(f) {
                on_boundary[n as usize] = true;
            }
        }
        let ids: Vec<usize> = (0..self.nodes.len()).filter(|&i| on_boundary[i]).collect();
        let pts: Vec<Point> = ids.iter().map(|&i| self.nodes[i]).collect();
        let index = PointIndex::new(&pts);
        for &f in &boundary {
            let nodes: Vec<u32> = self.facet_nodes(f).collect();
            let corners: Vec<Point> = nodes.iter().map(|&n| self.nodes[n as usize]).collect();
            let size = corners
                .iter()
                .map(|p| (p - corners[0]).norm())
                .fold(0.0, f64::max);
            let mut probes = vec![Point::from(
                corners
                    .iter()
                    .map(|p| p.coords)
                    .sum::<peritherm_core::math::Vector>()
                    / corners.len() as f64,
            )];
            if corners.len() > 2 {
                for k in 0..corners.len() {
                    let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
                    probes.push(Point::from((a.coords + b.coords) * 0.5));
                }
            }
            for p in probes {
                if let Some(&j) = index
                    .within(&p, 1e-6 * size)
                    .iter()
                    .find(|&&j| !nodes.contains(&(ids[j] as u32)))
                {
                    let q = pts[j];
                    return Err(Error::model(
                        "mesh",
                        format!(
                            "fem: the mesh is not conforming: node ({:e}, {:e}, {:e}) lies inside an element side it does not belong to (regions meshed with different sizes that do not share their interface nodes); the FEM reference needs a conforming mesh",
                            q.x, q.y, q.z
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Facet keys of the gmsh boundary set `s` (e.g. a crack group), in this mesh's numbering.
    pub fn set_keys(&self, s: usize) -> Vec<FacetKey> {
        self.sets[s]
            .iter()
            .map(|&f| key_of(self.facet_nodes(f)))
            .collect()
    }
}

/// The key of a facet with these nodes.
pub fn key_of(nodes: impl Iterator<Item = u32>) -> FacetKey {
    let mut k = [u32::MAX; 4];
    for (slot, n) in k.iter_mut().zip(nodes) {
        *slot = n;
    }
    k.sort_unstable();
    k
}
