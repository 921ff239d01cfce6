//! Boundary conditions and loads of theory §3, applied to a state vector.
//!
//! Constraints overwrite node temperatures at each stage (nodal Dirichlet, the 1D flux
//! relation of Bobaru & Duangpanya 2010, eq. 22, the nodal flux relation of Bobaru & Duangpanya
//! 2012 §3.2, and the fictitious layers of Wang, Oterkus & Oterkus and PCS2022);
//! loads add to the rates (convection of PCS2022, doi:10.1007/s42102-022-00092-3, volumetric
//! sources).

// the layer kind, now in cloud::fictitious, under its old path
pub use crate::cloud::fictitious::Layer;

use crate::cloud::fictitious::{Fictitious, Reflection};
use crate::cloud::Cloud;
use crate::expr::Expr;
use crate::math::{NodeId, Point};
use crate::spatial::PointIndex;

/// The condition on one boundary set (a box face or a mesh's physical group).
#[derive(Debug, Clone, PartialEq)]
pub enum FaceBc {
    /// No bonds leave the body: insulated with the surface skin effect (Bobaru & Duangpanya 2012
    /// §3.5).
    Free,
    /// Nodal Dirichlet on the first `layers` node layers (Bobaru & Duangpanya 2010, 2012).
    NodalTemperature {
        /// θ_b(x, y, z, t), °C.
        value: Expr,
        /// Number of node layers held.
        layers: f64,
    },
    /// Dirichlet through a fictitious layer.
    LayerTemperature {
        /// θ_b(x, y, z, t), °C.
        value: Expr,
        /// Naive or mirror.
        layer: Layer,
    },
    /// Zero flux through a mirrored fictitious layer.
    LayerInsulated,
    /// Heat flux into the body through a mirrored fictitious layer, θ_f = θ_m + (q/k) d.
    LayerFlux {
        /// q(x, y, z, t) into the body, W/m².
        value: Expr,
    },
    /// Heat flux into the body by a nodal relation: Bobaru & Duangpanya 2010, eq. 22 in 1D, Bobaru
    /// & Duangpanya 2012 §3.2 in 2D/3D.
    RelationFlux {
        /// q(x, y, z, t) into the body, W/m².
        value: Expr,
    },
    /// Convection through a mirrored fictitious layer (PCS2022 §3.1c):
    /// the ghost at distance d from its mirror node satisfies k(θ_f − θ_m)/d = h(T∞ − (θ_f +
    /// θ_m)/2), i.e. θ_f = ((1 − β/2) θ_m + β T∞)/(1 + β/2) with β = h d/k.
    LayerConvection {
        /// Film coefficient h, W/(m²·K).
        h: f64,
        /// T∞(t), °C.
        ambient: Expr,
    },
    /// Convection to an ambient temperature (PCS2022): s = h A (T∞ −
    /// θ)/V on surface nodes.
    Convection {
        /// Film coefficient h, W/(m²·K).
        h: f64,
        /// T∞(t), °C.
        ambient: Expr,
    },
}

impl FaceBc {
    /// True when the condition needs a fictitious layer.
    pub fn needs_layer(&self) -> bool {
        matches!(
            self,
            FaceBc::LayerTemperature { .. }
                | FaceBc::LayerInsulated
                | FaceBc::LayerFlux { .. }
                | FaceBc::LayerConvection { .. }
        )
    }
}

/// Nodes held at θ_b(x, t).
#[derive(Debug, Clone)]
struct Nodal {
    face: usize,
    nodes: Vec<usize>,
    value: Expr,
}

/// Bobaru & Duangpanya 2010, eq. 22: θ_s = θ_anchor + (q/k)(d_anchor − d_s) for the nodes within δ
/// of the end.
#[derive(Debug, Clone)]
struct Relation1d {
    face: usize,
    slaved: Vec<(usize, f64)>,
    anchor: usize,
    value: Expr,
    conductivity: f64,
    at: Point,
}

/// Bobaru & Duangpanya 2012 §3.2: θ_i = (Σ_p w_p θ_p + q) / Σ_p w_p over the inward half of H_i.
#[derive(Debug, Clone)]
struct RelationNodal {
    face: usize,
    node: usize,
    stencil: Vec<(NodeId, f64)>,
    wsum: f64,
    value: Expr,
}

/// One fictitious node's rule: θ_f = σ θ(mirror) + Σ coef · g_set(t, d) at a foot point.
#[derive(Debug, Clone)]
struct Ghost {
    node: usize,
    /// Conductivity the flux terms' 1/k was taken with, W/(m·K).
    k: f64,
    sigma: f64,
    stencil: Vec<(NodeId, f64)>,
    terms: Vec<(usize, f64, f64, Point)>,
}

/// Convection on surface nodes.
#[derive(Debug, Clone)]
struct Convective {
    face: usize,
    nodes: Vec<(usize, f64)>,
    ambient: Expr,
}

/// A condition's expression, or the source, that is not finite at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonFinite {
    /// The boundary set of the condition (None: the volumetric source).
    pub face: Option<usize>,
    /// Where it was evaluated, m.
    pub at: Point,
    /// The value there (NaN or ±inf), the condition's unit.
    pub value: f64,
}

/// All boundary conditions and loads of a model, ready to apply.
#[derive(Debug, Clone, Default)]
pub struct Boundary {
    faces: Vec<FaceBc>,
    nodal: Vec<Nodal>,
    relation1d: Vec<Relation1d>,
    relation_nodal: Vec<RelationNodal>,
    ghosts: Vec<Ghost>,
    convective: Vec<Convective>,
    /// Volumetric source s(x, t), W/m³, divided by ρc at each node when loaded.
    source: Option<Expr>,
    /// Precomputed s/ρc per body node when the source does not depend on t, K/s.
    source_fixed: Vec<f64>,
    /// True for body nodes whose temperature is set by a constraint.
    pub driven: Vec<bool>,
}

/// Everything needed to build the boundary from a cloud.
pub struct BoundaryInput<'a> {
    /// The cloud, with fictitious nodes already generated.
    pub cloud: &'a Cloud,
    /// Conditions by boundary set (box: the 6 faces, unused axes Free).
    pub faces: Vec<FaceBc>,
    /// Conductivity per node, W/(m·K).
    pub conductivity: &'a [f64],
    /// Volumetric heat capacity per node, J/(m³·K).
    pub capacity: &'a [f64],
    /// Directed bonds and their micro-conductance per unit volume pair (for Bobaru & Duangpanya
    /// 2012 §3.2).
    pub micro: Option<(&'a crate::horizons::Horizons, &'a [f64])>,
    /// Volumetric source, W/m³.
    pub source: Option<Expr>,
}

impl Relation1d {
    /// The flux relation of `face` of a 1D cloud: the nodes within a horizon of the face are
    /// slaved to the nearest node beyond (the anchor); `None` without an anchor.
    fn build(input: &BoundaryInput, face: usize, value: &Expr) -> Option<Relation1d> {
        let cloud = input.cloud;
        let mut slaved = Vec::new();
        let mut anchor = None;
        let mut best = f64::INFINITY;
        for i in 0..cloud.n_body {
            let d = cloud.set_distance(&cloud.pos[i], face);
            if d < cloud.horizon[i] * (1.0 - 1e-9) {
                slaved.push((i, d));
            } else if d < best {
                best = d;
                anchor = Some(i);
            }
        }
        let a = anchor?;
        Some(Relation1d {
            face,
            slaved: slaved.into_iter().map(|(i, d)| (i, best - d)).collect(),
            anchor: a,
            value: value.clone(),
            conductivity: input.conductivity[a],
            at: cloud.set_foot(&cloud.pos[a], face).0,
        })
    }
}

impl RelationNodal {
    /// The flux relations of the first node layer of `face` (2D, 3D; Bobaru & Duangpanya
    /// 2012 §3.2): each node's stencil of inward body neighbours weighted by micro-conductance
    /// times the normal offset; nodes without one are left out.
    fn build_face(input: &BoundaryInput, face: usize, value: &Expr) -> Vec<RelationNodal> {
        let cloud = input.cloud;
        let nb = cloud.n_body;
        let (h, micro) = input
            .micro
            .expect("micro-conductances are given for nodal flux relations");
        let mut out = Vec::new();
        for i in cloud.set_layer(face, 1.0) {
            let normal = cloud.set_foot(&cloud.pos[i], face).1;
            let mut stencil = Vec::new();
            let mut wsum = 0.0;
            for bnd in h.row(i) {
                let j = h.targets[bnd] as usize;
                let l = (cloud.pos[j] - cloud.pos[i]).dot(&normal);
                if l > 0.0 && j < nb {
                    let w = micro[bnd] * l;
                    stencil.push((j as NodeId, w));
                    wsum += w;
                }
            }
            if wsum > 0.0 {
                out.push(RelationNodal {
                    face,
                    node: i,
                    stencil,
                    wsum,
                    value: value.clone(),
                });
            }
        }
        out
    }
}

impl Boundary {
    /// Builds the constraint and load structures.
    pub fn build(input: BoundaryInput) -> Self {
        let cloud = input.cloud;
        let nb = cloud.n_body;
        let mut b = Boundary {
            faces: input.faces.clone(),
            driven: vec![false; nb],
            source: input.source.clone(),
            ..Default::default()
        };
        for (face, bc) in input.faces.iter().enumerate() {
            match bc {
                FaceBc::NodalTemperature { value, layers } => {
                    let nodes = cloud.set_layer(face, *layers);
                    b.nodal.push(Nodal {
                        face,
                        nodes,
                        value: value.clone(),
                    });
                }
                FaceBc::RelationFlux { value } if cloud.dim == 1 => {
                    if let Some(r) = Relation1d::build(&input, face, value) {
                        b.relation1d.push(r);
                    }
                }
                FaceBc::RelationFlux { value } => {
                    b.relation_nodal
                        .extend(RelationNodal::build_face(&input, face, value));
                }
                FaceBc::Convection { h, ambient } => {
                    let nodes = cloud
                        .exposed(face)
                        .into_iter()
                        .map(|(i, area)| (i, *h * area / (cloud.volume[i] * input.capacity[i])))
                        .collect();
                    b.convective.push(Convective {
                        face,
                        nodes,
                        ambient: ambient.clone(),
                    });
                }
                _ => {}
            }
        }
        b.mark_driven();
        b.build_ghosts(cloud, input.conductivity);
        if let Some(s) = &b.source {
            if s.is_time_independent() {
                b.source_fixed = (0..nb)
                    .map(|i| {
                        let p = cloud.pos[i];
                        s.eval(p.x, p.y, p.z, 0.0) / input.capacity[i]
                    })
                    .collect();
            }
        }
        b
    }

    /// Marks the body nodes that a nodal condition or a flux relation sets.
    fn mark_driven(&mut self) {
        for n in &self.nodal {
            for &i in &n.nodes {
                self.driven[i] = true;
            }
        }
        for r in &self.relation1d {
            for &(i, _) in &r.slaved {
                self.driven[i] = true;
            }
        }
        for r in &self.relation_nodal {
            self.driven[r.node] = true;
        }
    }

    /// θ_f = σ θ(image) + Σ coef·g along a chain of reflections (outermost first).
    fn compose(&self, chain: &[Reflection], k: f64) -> (f64, Vec<(usize, f64, f64, Point)>) {
        let mut s = 1.0;
        let mut terms = Vec::new();
        for r in chain {
            let (sigma, coef) = match &self.faces[r.set] {
                FaceBc::LayerTemperature {
                    layer: Layer::Naive,
                    ..
                } => (0.0, 1.0),
                FaceBc::LayerTemperature {
                    layer: Layer::Mirror,
                    ..
                } => (-1.0, 2.0),
                FaceBc::LayerFlux { .. } => (1.0, 1.0 / k),
                FaceBc::LayerConvection { h, .. } => {
                    let beta = h * r.distance / k;
                    (
                        (1.0 - 0.5 * beta) / (1.0 + 0.5 * beta),
                        beta / (1.0 + 0.5 * beta),
                    )
                }
                _ => (1.0, 0.0),
            };
            if coef != 0.0 && s != 0.0 {
                terms.push((r.set, s * coef, r.distance, r.foot));
            }
            s *= sigma;
        }
        (s, terms)
    }

    /// Lattice ghosts of a box: reflections across the faces the node lies outside of
    /// (naive faces first: they fix the value whatever follows), ending at a point in the body.
    fn lattice_chain(&self, cloud: &Cloud, node: usize, outside: u8) -> (Vec<Reflection>, Point) {
        let mut faces: Vec<usize> = (0..6).filter(|&fc| outside & (1 << fc) != 0).collect();
        faces.sort_by_key(|&fc| {
            !matches!(
                self.faces[fc],
                FaceBc::LayerTemperature {
                    layer: Layer::Naive,
                    ..
                }
            )
        });
        let mut p = cloud.pos[node];
        let mut chain = Vec::new();
        for set in faces {
            let (foot, _) = cloud.set_foot(&p, set);
            let q = p + (foot - p) * 2.0;
            chain.push(Reflection {
                set,
                foot,
                distance: (q - p).norm(),
            });
            p = q;
        }
        (chain, p)
    }

    fn build_ghosts(&mut self, cloud: &Cloud, conductivity: &[f64]) {
        if cloud.n_fictitious() == 0 || cloud.n_body == 0 {
            return;
        }
        let body = PointIndex::new(&cloud.pos[..cloud.n_body]);
        for (f, origin) in cloud.fictitious.iter().enumerate() {
            let node = cloud.n_body + f;
            let (sigma, terms, stencil) = match origin {
                Fictitious::Mirror { of, chain } => {
                    let (sigma, terms) = self.compose(chain, conductivity[node]);
                    (sigma, terms, vec![(*of, 1.0)])
                }
                Fictitious::Lattice { outside } => {
                    let (chain, image) = self.lattice_chain(cloud, node, *outside);
                    let (sigma, terms) = self.compose(&chain, conductivity[node]);
                    let mut stencil = Vec::new();
                    if sigma != 0.0 {
                        // the image's value: the node there, or inverse-distance weights
                        let near = body.nearest(&image, 1 << cloud.dim);
                        if near[0].1 <= 1e-6 * cloud.spacing[node] {
                            stencil.push((near[0].0 as NodeId, 1.0));
                        } else {
                            let tot: f64 = near.iter().map(|n| 1.0 / n.1).sum();
                            for (j, d) in near {
                                stencil.push((j as NodeId, 1.0 / d / tot));
                            }
                        }
                    }
                    (sigma, terms, stencil)
                }
            };
            self.ghosts.push(Ghost {
                node,
                k: conductivity[node],
                sigma,
                stencil,
                terms,
            });
        }
    }

    /// The first place where a condition's expression or the source is not finite at time
    /// `t` (s), each evaluated where [`Boundary::apply`] and [`Boundary::add_loads`] evaluate
    /// it; None when all are finite.
    pub fn non_finite(&self, cloud: &Cloud, t: f64) -> Option<NonFinite> {
        let bad = |face: Option<usize>, e: &Expr, at: Point| {
            let value = e.eval(at.x, at.y, at.z, t);
            (!value.is_finite()).then_some(NonFinite { face, at, value })
        };
        let origin = Point::origin();
        // a uniform value is the same at every node (apply takes it at the origin)
        let nodal = self.nodal.iter().flat_map(|n| {
            n.nodes
                .iter()
                .map(move |&i| (n.face, &n.value, cloud.pos[i]))
        });
        let relations = self.relation1d.iter().map(|r| (r.face, &r.value, r.at));
        let nodal_relations = self
            .relation_nodal
            .iter()
            .map(|r| (r.face, &r.value, cloud.pos[r.node]));
        let ghosts = self.ghosts.iter().flat_map(|g| {
            g.terms
                .iter()
                .filter_map(|&(fc, _, _, at)| match &self.faces[fc] {
                    FaceBc::LayerTemperature { value, .. } | FaceBc::LayerFlux { value } => {
                        Some((fc, value, at))
                    }
                    FaceBc::LayerConvection { ambient, .. } => Some((fc, ambient, at)),
                    _ => None,
                })
        });
        let convective = self.convective.iter().map(|c| (c.face, &c.ambient, origin));
        let found = nodal
            .chain(relations)
            .chain(nodal_relations)
            .chain(ghosts)
            .chain(convective)
            .find_map(|(face, e, at)| bad(Some(face), e, at));
        found.or_else(|| self.source_non_finite(cloud, t))
    }

    /// The body node of lowest index where the source is not finite at `t` (s), if any.
    fn source_non_finite(&self, cloud: &Cloud, t: f64) -> Option<NonFinite> {
        use rayon::prelude::*;
        let s = self.source.as_ref()?;
        let i = (0..cloud.n_body).into_par_iter().find_first(|&i| {
            let p = cloud.pos[i];
            !s.eval(p.x, p.y, p.z, t).is_finite()
        })?;
        let at = cloud.pos[i];
        Some(NonFinite {
            face: None,
            at,
            value: s.eval(at.x, at.y, at.z, t),
        })
    }

    /// Sets every constrained body node and every fictitious node at time `t`.
    pub fn apply(&self, cloud: &Cloud, theta: &mut [f64], t: f64) {
        self.apply_with(cloud, theta, t, None);
    }

    /// [`Boundary::apply`] with the body's conductivity as it is now (phase change,
    /// theory §6): a mirrored flux layer then takes q/k with k at its mirror point, W/(m·K).
    pub fn apply_with(
        &self,
        cloud: &Cloud,
        theta: &mut [f64],
        t: f64,
        conductivity: Option<&[f64]>,
    ) {
        for n in &self.nodal {
            if n.value.is_uniform() {
                let v = n.value.eval(0.0, 0.0, 0.0, t);
                for &i in &n.nodes {
                    theta[i] = v;
                }
            } else {
                for &i in &n.nodes {
                    let p = cloud.pos[i];
                    theta[i] = n.value.eval(p.x, p.y, p.z, t);
                }
            }
        }
        for r in &self.relation1d {
            let g = r.value.eval(r.at.x, r.at.y, r.at.z, t) / r.conductivity;
            let base = theta[r.anchor];
            for &(i, d) in &r.slaved {
                theta[i] = base + g * d;
            }
        }
        for r in &self.relation_nodal {
            let p = cloud.pos[r.node];
            let q = r.value.eval(p.x, p.y, p.z, t);
            let s: f64 = r.stencil.iter().map(|&(j, w)| w * theta[j as usize]).sum();
            theta[r.node] = (s + q) / r.wsum;
        }
        for g in &self.ghosts {
            let mut v = 0.0;
            if g.sigma != 0.0 {
                let m: f64 = g.stencil.iter().map(|&(j, w)| w * theta[j as usize]).sum();
                v = g.sigma * m;
            }
            for &(fc, coef, d, at) in &g.terms {
                let val = match &self.faces[fc] {
                    FaceBc::LayerTemperature { value, .. } => value.eval(at.x, at.y, at.z, t),
                    FaceBc::LayerFlux { value } => {
                        let scale = match conductivity {
                            Some(k) => {
                                let now: f64 =
                                    g.stencil.iter().map(|&(j, w)| w * k[j as usize]).sum();
                                if now > 0.0 {
                                    g.k / now
                                } else {
                                    1.0
                                }
                            }
                            None => 1.0,
                        };
                        value.eval(at.x, at.y, at.z, t) * d * scale
                    }
                    FaceBc::LayerConvection { ambient, .. } => ambient.eval(at.x, at.y, at.z, t),
                    _ => 0.0,
                };
                v += coef * val;
            }
            theta[g.node] = v;
        }
    }

    /// Adds the load rates (convection, volumetric source) of body nodes, K/s.
    pub fn add_loads(
        &self,
        cloud: &Cloud,
        capacity: &[f64],
        theta: &[f64],
        t: f64,
        rate: &mut [f64],
    ) {
        for c in &self.convective {
            let amb = c.ambient.eval(0.0, 0.0, 0.0, t);
            for &(i, coef) in &c.nodes {
                rate[i] += coef * (amb - theta[i]);
            }
        }
        if !self.source_fixed.is_empty() {
            for (r, s) in rate.iter_mut().zip(&self.source_fixed) {
                *r += s;
            }
        } else if let Some(s) = &self.source {
            use rayon::prelude::*;
            // a time-dependent source is evaluated at every node of every step: in parallel
            rate.par_iter_mut().enumerate().for_each(|(i, r)| {
                let p = cloud.pos[i];
                *r += s.eval(p.x, p.y, p.z, t) / capacity[i];
            });
        }
    }

    /// Largest load coefficient per body node that adds to the diagonal (for the Δt bound), 1/s.
    pub fn load_diagonal(&self, n_body: usize) -> Vec<f64> {
        let mut d = vec![0.0; n_body];
        for c in &self.convective {
            for &(i, coef) in &c.nodes {
                d[i] += coef;
            }
        }
        d
    }

    /// The linear part of every constraint, in the order [`Boundary::apply`] sets them:
    /// `(node, [(source, weight)])` with θ_node = Σ weight·θ_source + (a part that depends on t
    /// only: `apply` on a field whose free nodes are 0 gives it). Theory §3; the implicit
    /// solvers eliminate constrained and fictitious nodes with it.
    pub fn linear_rules(&self) -> Vec<(usize, Vec<(usize, f64)>)> {
        let mut out = Vec::new();
        for n in &self.nodal {
            out.extend(n.nodes.iter().map(|&i| (i, Vec::new())));
        }
        for r in &self.relation1d {
            out.extend(r.slaved.iter().map(|&(i, _)| (i, vec![(r.anchor, 1.0)])));
        }
        for r in &self.relation_nodal {
            let s = r
                .stencil
                .iter()
                .map(|&(j, w)| (j as usize, w / r.wsum))
                .collect();
            out.push((r.node, s));
        }
        for g in &self.ghosts {
            let s = if g.sigma != 0.0 {
                g.stencil
                    .iter()
                    .map(|&(j, w)| (j as usize, g.sigma * w))
                    .collect()
            } else {
                Vec::new()
            };
            out.push((g.node, s));
        }
        out
    }

    /// True when convection or a source adds to the rates.
    pub fn has_loads(&self) -> bool {
        !self.convective.is_empty() || self.source.is_some()
    }
}
