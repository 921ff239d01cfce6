//! Output of FEM fields in the node-cloud contract: the mesh nodes as a [`Cloud`] (so the
//! field CSV/VTU writers and the reference comparison of `peritherm run` serve unchanged) and
//! the recovered heat flux.
//!
//! At a FEM node: `spacing` = mean size (measure^(1/d)) of the cells around it, `horizon` = 0,
//! `volume` = lumped nodal measure ∫N_i dV (ring or shell volume when the mesh is
//! axisymmetric or spherical), `damage` = 0, `region` = the region of the first
//! cell around it, and q = −k∇θ taken at the centre of every cell around the node and averaged
//! with the cells' measures as weights, W/m².
//!
//! The copies of a node split along a crack share a position; each is written 1e-9 × its
//! spacing off it, towards the centre of the cells it belongs to, so that readers that tell
//! the crack's sides apart by position (`peritherm compare`, `plot`) put it on its own side.

use crate::assemble::System;
use crate::mesh::FemMesh;
use crate::shape::{centre, physical, shape, MAX_NODES};
use peritherm_core::cloud::Cloud;
use peritherm_core::material::Material;
use peritherm_core::math::{Point, Vector};
use peritherm_core::mesh::measure_and_centroid;

/// Flux recovery data: per cell, k∇N_a at its centre; per node, the cells around it with weights.
#[derive(Debug, Clone)]
pub struct Recovery {
    /// k ∂N_a/∂x at the centre of each cell, W/(m·K) per m, 8 × 3 per cell.
    grads: Vec<[[f64; 3]; MAX_NODES]>,
    /// CSR offsets of each node's cells.
    offsets: Vec<usize>,
    /// (cell, weight) with weights summing to 1 per node.
    around: Vec<(u32, f64)>,
}

/// The output cloud of `mesh` (body nodes only) and the flux recovery.
pub fn output_cloud(mesh: &FemMesh, sys: &System, materials: &[Material]) -> (Cloud, Recovery) {
    let d = mesh.dim;
    let measures: Vec<f64> = mesh
        .cells
        .iter()
        .map(|c| measure_and_centroid(c.kind, &mesh.corners(c)[..c.kind.n_nodes()]).0)
        .collect();
    let grads = centre_gradients(mesh, materials);
    let (offsets, cells) = mesh.node_cells();
    let nn = mesh.nodes.len();
    let mut around = Vec::with_capacity(cells.len());
    let mut spacing = vec![0.0; nn];
    let mut region = vec![0u16; nn];
    let mut material = vec![0u16; nn];
    for i in 0..nn {
        let ring = &cells[offsets[i]..offsets[i + 1]];
        let total: f64 = ring.iter().map(|&(e, _)| measures[e as usize]).sum();
        for &(e, _) in ring {
            around.push((e, measures[e as usize] / total));
            spacing[i] += measures[e as usize].powf(1.0 / d as f64) / ring.len() as f64;
        }
        if let Some(&(e, _)) = ring.first() {
            region[i] = mesh.cells[e as usize].region;
            material[i] = mesh.cells[e as usize].material;
        }
    }
    let pos = separated_positions(mesh, &offsets, &cells, &spacing);
    let (lo, hi) = bounding_box(&mesh.nodes);
    let cloud = Cloud {
        dim: d,
        tau: mesh.tau,
        pos,
        volume: sys.measure.clone(),
        spacing,
        horizon: vec![0.0; nn],
        material,
        region,
        n_body: nn,
        min: lo,
        max: hi,
        symmetry: mesh.symmetry,
        ..Default::default()
    };
    (
        cloud,
        Recovery {
            grads,
            offsets,
            around,
        },
    )
}

/// k ∂N_a/∂x at the centre of every cell of `mesh`, W/(m·K) per m.
fn centre_gradients(mesh: &FemMesh, materials: &[Material]) -> Vec<[[f64; 3]; MAX_NODES]> {
    mesh.cells
        .iter()
        .map(|c| {
            let s = shape(c.kind, centre(c.kind));
            let (mut g, _) = physical(c.kind, &s, &mesh.corners(c), mesh.dim);
            let k = materials[c.material as usize].conductivity;
            for row in g.iter_mut() {
                for v in row.iter_mut() {
                    *v *= k;
                }
            }
            g
        })
        .collect()
}

/// The output positions of the mesh nodes: the copies of a node split along a crack moved
/// 1e-9 × their spacing towards the centre of their cells (`offsets`/`cells` from
/// [`FemMesh::node_cells`]), the other nodes where they are, m.
fn separated_positions(
    mesh: &FemMesh,
    offsets: &[usize],
    cells: &[(u32, u8)],
    spacing: &[f64],
) -> Vec<Point> {
    let mut pos = mesh.nodes.clone();
    let mut at: std::collections::HashMap<[u64; 3], Vec<usize>> = Default::default();
    for (i, p) in mesh.nodes.iter().enumerate() {
        at.entry([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .or_default()
            .push(i);
    }
    for group in at.values().filter(|g| g.len() > 1) {
        for &i in group {
            let ring = &cells[offsets[i]..offsets[i + 1]];
            let mut c = Vector::zeros();
            for &(e, _) in ring {
                let cell = &mesh.cells[e as usize];
                let corners = mesh.corners(cell);
                c += corners[..cell.kind.n_nodes()]
                    .iter()
                    .map(|q| q.coords)
                    .sum::<Vector>()
                    / cell.kind.n_nodes() as f64;
            }
            let towards = c / ring.len().max(1) as f64 - mesh.nodes[i].coords;
            if towards.norm() > 0.0 {
                pos[i] += towards.normalize() * (1e-9 * spacing[i]);
            }
        }
    }
    pos
}

/// The lower and upper corners of the box around `nodes`, m.
fn bounding_box(nodes: &[Point]) -> (Point, Point) {
    let mut lo = Point::new(f64::MAX, f64::MAX, f64::MAX);
    let mut hi = Point::new(f64::MIN, f64::MIN, f64::MIN);
    for p in nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

impl Recovery {
    /// q = −k∇θ at every node into `q`, W/m² (gather over the cells around each node).
    pub fn flux(&self, mesh: &FemMesh, theta: &[f64], q: &mut [Vector]) {
        for (i, qi) in q.iter_mut().enumerate() {
            let mut s = Vector::zeros();
            for &(e, w) in &self.around[self.offsets[i]..self.offsets[i + 1]] {
                let c = &mesh.cells[e as usize];
                let g = &self.grads[e as usize];
                for (a, &n) in c.nodes().iter().enumerate() {
                    let t = theta[n as usize] * w;
                    s.x -= g[a][0] * t;
                    s.y -= g[a][1] * t;
                    s.z -= g[a][2] * t;
                }
            }
            *qi = s;
        }
    }
}
