//! Boundary conditions and loads of the FEM solver, from the case's conditions by boundary set.
//!
//! Every temperature condition (`nodal`, `mirror` or `naive` on the PD side) is a Dirichlet
//! condition on the nodes of the set's facets, imposed strongly by elimination; `insulated`
//! and `free` are the natural condition (nothing to add); `flux` (either method) is the load
//! ∫ q N_i dS; `convection` adds ∫ h N_i N_j dS to K and ∫ h T∞ N_i dS to the load; a
//! volumetric source is the load ∫ s N_i dV. Out-of-plane measures τ multiply every integral,
//! and on axisymmetric or spherical meshes so does the ring or shell measure 2πr or 4πr² at
//! each quadrature point (a flux q on the face r = a loads 2πa q per unit length of axis).

use crate::assemble::System;
use crate::mesh::{FacetRef, FemMesh};
use crate::shape::{facet_density, physical, quadrature, quadrature_for, shape, MAX_NODES};
use peritherm_core::bc::FaceBc;
use peritherm_core::expr::Expr;
use peritherm_core::math::Point;

/// One quadrature point of a load integral: where, its weight (m², m³ with τ) and the shape
/// functions of the nodes it feeds.
#[derive(Debug, Clone, Copy)]
struct QPoint {
    pos: Point,
    weight: f64,
    nodes: [u32; MAX_NODES],
    n: [f64; MAX_NODES],
    len: u8,
}

/// A load ∫ scale · value(x, t) N_i over a set of quadrature points.
#[derive(Debug, Clone)]
struct Load {
    value: Expr,
    scale: f64,
    points: Vec<QPoint>,
}

impl Load {
    fn add(&self, t: f64, f: &mut [f64]) {
        for q in &self.points {
            let v = self.scale * self.value.eval(q.pos.x, q.pos.y, q.pos.z, t) * q.weight;
            for a in 0..q.len as usize {
                f[q.nodes[a] as usize] += v * q.n[a];
            }
        }
    }
}

/// Dirichlet nodes and the loads of a model, ready to evaluate at any time.
#[derive(Debug, Clone)]
pub struct Conditions {
    /// For each node, the index of its Dirichlet value in `values`, or `u32::MAX` when free.
    pub held: Vec<u32>,
    values: Vec<Expr>,
    /// Loads that depend on t.
    varying: Vec<Load>,
    /// Sum of the loads that do not depend on t, W.
    fixed: Vec<f64>,
    /// True when some set has a convection condition.
    convective: bool,
}

fn facet_points(mesh: &FemMesh, f: FacetRef) -> Vec<QPoint> {
    let kind = mesh.facet_kind(f);
    let mut nodes = [0u32; MAX_NODES];
    let mut x = [Point::origin(); MAX_NODES];
    for (a, n) in mesh.facet_nodes(f).enumerate() {
        nodes[a] = n;
        x[a] = mesh.nodes[n as usize];
    }
    let tau = mesh.tau;
    quadrature(kind)
        .iter()
        .map(|&(xi, w)| {
            let s = shape(kind, xi);
            let len = kind.n_nodes();
            let pos = Point::from(
                (0..len)
                    .map(|a| x[a].coords * s.n[a])
                    .sum::<peritherm_core::math::Vector>(),
            );
            QPoint {
                pos,
                weight: w * facet_density(kind, &s, &x[..len]) * tau * mesh.symmetry_weight(&pos),
                nodes,
                n: s.n,
                len: len as u8,
            }
        })
        .collect()
}

fn cell_points(mesh: &FemMesh) -> Vec<QPoint> {
    let mut out = Vec::new();
    for c in &mesh.cells {
        let x = mesh.corners(c);
        let len = c.kind.n_nodes();
        for &(xi, w) in quadrature_for(c.kind, mesh.symmetry) {
            let s = shape(c.kind, xi);
            let (_, det) = physical(c.kind, &s, &x, mesh.dim);
            let pos = Point::from(
                (0..len)
                    .map(|a| x[a].coords * s.n[a])
                    .sum::<peritherm_core::math::Vector>(),
            );
            out.push(QPoint {
                pos,
                weight: w * det * mesh.tau * mesh.symmetry_weight(&pos),
                nodes: c.nodes,
                n: s.n,
                len: len as u8,
            });
        }
    }
    out
}

impl Conditions {
    /// Builds the conditions of `faces` (by boundary set) and the `source`, and adds the
    /// convection matrices to `sys.stiffness`. A node on two held sets takes the first set's value.
    pub fn build(
        mesh: &FemMesh,
        faces: &[FaceBc],
        source: Option<&Expr>,
        sys: &mut System,
    ) -> Conditions {
        let nn = mesh.nodes.len();
        let mut c = Conditions {
            held: vec![u32::MAX; nn],
            values: Vec::new(),
            varying: Vec::new(),
            fixed: vec![0.0; nn],
            convective: false,
        };
        let mut loads = Vec::new();
        for (s, bc) in faces.iter().enumerate() {
            let set = mesh.sets.get(s).map_or(&[][..], |v| &v[..]);
            match bc {
                FaceBc::Free | FaceBc::LayerInsulated => {}
                FaceBc::NodalTemperature { value, .. } | FaceBc::LayerTemperature { value, .. } => {
                    let k = c.values.len() as u32;
                    c.values.push(value.clone());
                    for &f in set {
                        for n in mesh.facet_nodes(f) {
                            if c.held[n as usize] == u32::MAX {
                                c.held[n as usize] = k;
                            }
                        }
                    }
                }
                FaceBc::LayerFlux { value } | FaceBc::RelationFlux { value } => loads.push(Load {
                    value: value.clone(),
                    scale: 1.0,
                    points: set.iter().flat_map(|&f| facet_points(mesh, f)).collect(),
                }),
                FaceBc::Convection { h, ambient } | FaceBc::LayerConvection { h, ambient } => {
                    c.convective |= !set.is_empty();
                    let points: Vec<QPoint> =
                        set.iter().flat_map(|&f| facet_points(mesh, f)).collect();
                    for q in &points {
                        for a in 0..q.len as usize {
                            let i = q.nodes[a] as usize;
                            for b in 0..q.len as usize {
                                let p = sys
                                    .position(i, q.nodes[b])
                                    .expect("facet nodes share a cell");
                                sys.stiffness[p] += h * q.n[a] * q.n[b] * q.weight;
                            }
                        }
                    }
                    loads.push(Load {
                        value: ambient.clone(),
                        scale: *h,
                        points,
                    });
                }
            }
        }
        if let Some(s) = source {
            loads.push(Load {
                value: s.clone(),
                scale: 1.0,
                points: cell_points(mesh),
            });
        }
        for l in loads {
            if l.value.is_time_independent() {
                l.add(0.0, &mut c.fixed);
            } else {
                c.varying.push(l);
            }
        }
        c
    }

    /// The load vector at time `t` into `f` (overwritten), W.
    pub fn load(&self, t: f64, f: &mut [f64]) {
        f.copy_from_slice(&self.fixed);
        for l in &self.varying {
            l.add(t, f);
        }
    }

    /// True when node `i` is held.
    pub fn is_held(&self, i: usize) -> bool {
        self.held[i] != u32::MAX
    }

    /// Sets the held nodes of `theta` to their values at time `t`, °C.
    pub fn impose(&self, mesh: &FemMesh, t: f64, theta: &mut [f64]) {
        for (i, &k) in self.held.iter().enumerate() {
            if k != u32::MAX {
                let p = mesh.nodes[i];
                theta[i] = self.values[k as usize].eval(p.x, p.y, p.z, t);
            }
        }
    }

    /// True when the temperature is anchored (a held node or a convection boundary), i.e. the
    /// steady problem has a unique solution.
    pub fn anchored(&self) -> bool {
        self.convective || self.held.iter().any(|&k| k != u32::MAX)
    }

    /// True when some load or held value depends on t.
    pub fn depends_on_time(&self) -> bool {
        !self.varying.is_empty() || self.values.iter().any(|v| !v.is_time_independent())
    }
}
