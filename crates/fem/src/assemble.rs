//! Global matrices: the conductance (stiffness) K and the consistent capacity (mass) M on one
//! symmetric sparsity pattern, assembled row by row from element matrices (gather form).
//!
//! The mass matrix is **consistent** (M_ab = ∫ ρc N_a N_b dV): it is the Galerkin choice, it
//! keeps the semi-discrete error O(h²) in the nodal values of 1D bars too (where a lumped mass
//! only matches it on uniform meshes), and it conserves ∫ρcθ dV = 1ᵀMθ exactly like a lumped
//! one, since K 1 = 0 for an insulated body. Its row sums (the lumped capacities) are kept
//! for the energy and the `volume` column.
//!
//! Axisymmetric and spherical meshes (x = r) weight every integrand by 2πr or 4πr² at the
//! quadrature point ([`FemMesh::symmetry_weight`]): K_ab = ∫ k ∇N_a·∇N_b 2πr dr dz is the
//! Galerkin form of ρc θ_t = (1/r)(r k θ_r)_r + (k θ_z)_z (and of (1/r²)(r² k θ_r)_r).

use crate::mesh::FemMesh;
use crate::shape::{physical, quadrature_for, shape, MAX_NODES};
use peritherm_core::material::Material;
use peritherm_core::math::{Point, Vector};
use rayon::prelude::*;

/// Entries per element matrix slot (8 × 8).
const BLOCK: usize = MAX_NODES * MAX_NODES;

/// The assembled system on a symmetric CSR pattern (rows = columns = mesh nodes).
#[derive(Debug, Clone)]
pub struct System {
    /// Row offsets into `cols`, `stiffness` and `mass`.
    pub offsets: Vec<usize>,
    /// Column of each entry, sorted within a row.
    pub cols: Vec<u32>,
    /// Conductance K_ij (plus convection ∫h N_i N_j dS once boundaries are added), W/K.
    pub stiffness: Vec<f64>,
    /// Consistent capacity M_ij = ∫ρc N_i N_j dV, J/K.
    pub mass: Vec<f64>,
    /// Lumped nodal measure ∫N_i dV (volume × τ), m³.
    pub measure: Vec<f64>,
    /// Lumped capacity Σ_j M_ij, J/K.
    pub capacity: Vec<f64>,
}

impl System {
    /// Number of rows (mesh nodes).
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when the system has no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Position of entry (i, j) in the value arrays, if it is in the pattern.
    pub fn position(&self, i: usize, j: u32) -> Option<usize> {
        let r = self.offsets[i]..self.offsets[i + 1];
        self.cols[r.clone()]
            .binary_search(&j)
            .ok()
            .map(|p| r.start + p)
    }
}

/// Element conductance and capacity matrices (row-major 8 × 8 blocks) and the element's
/// ∫N_a dV, W/K, J/K and m³, from quadrature.
fn element(
    mesh: &FemMesh,
    e: usize,
    mat: &Material,
) -> ([f64; BLOCK], [f64; BLOCK], [f64; MAX_NODES]) {
    let c = &mesh.cells[e];
    let n = c.kind.n_nodes();
    let x = mesh.corners(c);
    let (mut ke, mut me, mut ve) = ([0.0; BLOCK], [0.0; BLOCK], [0.0; MAX_NODES]);
    for &(xi, w) in quadrature_for(c.kind, mesh.symmetry) {
        let s = shape(c.kind, xi);
        let (g, det) = physical(c.kind, &s, &x, mesh.dim);
        // ring/shell measure at the quadrature point (PCS2022,
        // doi:10.1007/s42102-022-00092-3, §2.2–2.3): 2πr or 4πr² dr
        let at = Point::from((0..n).map(|a| x[a].coords * s.n[a]).sum::<Vector>());
        let dv = w * det * mesh.tau * mesh.symmetry_weight(&at);
        for a in 0..n {
            ve[a] += s.n[a] * dv;
            for b in 0..n {
                let dot = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
                ke[a * MAX_NODES + b] += mat.conductivity * dot * dv;
                me[a * MAX_NODES + b] += mat.capacity() * s.n[a] * s.n[b] * dv;
            }
        }
    }
    (ke, me, ve)
}

/// Assembles K, M and the lumped measures of `mesh` with the materials of its cells.
pub fn assemble(mesh: &FemMesh, materials: &[Material]) -> System {
    let (cell_offsets, around) = mesh.node_cells();
    let nn = mesh.nodes.len();
    let blocks: Vec<_> = (0..mesh.cells.len())
        .into_par_iter()
        .map(|e| element(mesh, e, &materials[mesh.cells[e].material as usize]))
        .collect();
    // pattern: each row's columns are the nodes of the cells around it
    let rows: Vec<Vec<u32>> = (0..nn)
        .into_par_iter()
        .map(|i| {
            let mut r: Vec<u32> = around[cell_offsets[i]..cell_offsets[i + 1]]
                .iter()
                .flat_map(|&(e, _)| mesh.cells[e as usize].nodes().iter().copied())
                .collect();
            r.sort_unstable();
            r.dedup();
            r
        })
        .collect();
    let mut offsets = vec![0usize; nn + 1];
    for (i, r) in rows.iter().enumerate() {
        offsets[i + 1] = offsets[i] + r.len();
    }
    let cols: Vec<u32> = rows.into_iter().flatten().collect();
    let nnz = cols.len();
    let mut sys = System {
        offsets,
        cols,
        stiffness: vec![0.0; nnz],
        mass: vec![0.0; nnz],
        measure: vec![0.0; nn],
        capacity: vec![0.0; nn],
    };
    // gather: row i sums the rows of the element matrices of the cells around node i
    let mut k_rows: Vec<&mut [f64]> = Vec::with_capacity(nn);
    let mut m_rows: Vec<&mut [f64]> = Vec::with_capacity(nn);
    {
        let (mut k, mut m) = (&mut sys.stiffness[..], &mut sys.mass[..]);
        for i in 0..nn {
            let len = sys.offsets[i + 1] - sys.offsets[i];
            let (a, rest) = std::mem::take(&mut k).split_at_mut(len);
            k_rows.push(a);
            k = rest;
            let (a, rest) = std::mem::take(&mut m).split_at_mut(len);
            m_rows.push(a);
            m = rest;
        }
    }
    let cols = &sys.cols;
    let offsets = &sys.offsets;
    k_rows
        .into_par_iter()
        .zip(m_rows)
        .zip(sys.measure.par_iter_mut().zip(sys.capacity.par_iter_mut()))
        .enumerate()
        .for_each(|(i, ((kr, mr), (vol, cap)))| {
            let row_cols = &cols[offsets[i]..offsets[i + 1]];
            for &(e, a) in &around[cell_offsets[i]..cell_offsets[i + 1]] {
                let (ke, me, ve) = &blocks[e as usize];
                let a = a as usize;
                *vol += ve[a];
                for (b, &j) in mesh.cells[e as usize].nodes().iter().enumerate() {
                    let p = row_cols
                        .binary_search(&j)
                        .expect("pattern holds the cell's nodes");
                    kr[p] += ke[a * MAX_NODES + b];
                    mr[p] += me[a * MAX_NODES + b];
                    *cap += me[a * MAX_NODES + b];
                }
            }
        });
    sys
}
