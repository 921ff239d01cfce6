//! A ready-to-integrate model: cloud, bonds, conductance, capacities and boundary.

use crate::bc::{Boundary, BoundaryInput, FaceBc};
use crate::cloud::mesh::MeshGeometry;
use crate::cloud::{BoxGeometry, Cloud, Sides};
use crate::crack::{
    bond_factors, facet_cutters, growing_path, segments, Cuts, Cutter, DamageBonds, Growth,
};
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::gather::StepStorage;
use crate::horizons::Horizons;
use crate::kernel::{Kernel, PartialVolume};
use crate::material::{any_phase_change, BondRule, Enthalpy, Material};
use crate::math::Point;
use crate::operator::{Conductance, HalfConductance};
use crate::partition::Partition;
use crate::symmetry::Symmetry;
use crate::weights::store::Store;
use crate::weights::{correct_reusing, correct_stored, Consistency, Order};
use std::ops::Range;

/// Initial temperature field.
#[derive(Debug, Clone)]
pub enum Initial {
    /// θ0(x, y, z), °C.
    Field(Expr),
    /// One value per region, °C.
    PerRegion(Vec<f64>),
}

impl Initial {
    /// The initial temperature at points `pos` of regions `region`, °C; `what` names the
    /// points in the error for a non-finite value ("node", "FEM node").
    pub fn at(&self, pos: &[Point], region: &[u16], what: &str) -> Result<Vec<f64>> {
        let theta0: Vec<f64> = match self {
            Initial::Field(e) => pos.iter().map(|p| e.eval(p.x, p.y, p.z, 0.0)).collect(),
            Initial::PerRegion(v) => region.iter().map(|&r| v[r as usize]).collect(),
        };
        match theta0.iter().position(|v| !v.is_finite()) {
            Some(i) => {
                let p = pos[i];
                let key = match self {
                    Initial::Field(_) => "initial.value",
                    Initial::PerRegion(_) => "initial",
                };
                Err(Error::model(
                    key,
                    format!(
                        "not finite ({}) at {what} {i}, ({}, {}, {}) m, t = 0 s",
                        theta0[i], p.x, p.y, p.z
                    ),
                ))
            }
            None => Ok(theta0),
        }
    }
}

/// Where the nodes come from.
#[derive(Debug, Clone)]
pub enum Geometry {
    /// A box tiled by lattice regions.
    Box(BoxGeometry),
    /// A mesh: one node per element.
    Mesh(MeshGeometry),
}

impl Geometry {
    /// The body nodes and boundary sets alone (no fictitious layer), for post-processing.
    pub fn bare_cloud(&self) -> Result<Cloud> {
        match self {
            Geometry::Box(g) => g.generate(0, 0.0),
            Geometry::Mesh(g) => g.generate(&[], 0.0),
        }
    }
}

/// Where a pre-crack lies.
#[derive(Debug, Clone)]
pub enum CrackShape {
    /// The facets of a mesh boundary set (a physical group embedded in the body).
    Set(usize),
    /// A polyline through these points (2D), m.
    Polyline(Vec<Point>),
    /// A planar polygon with these corners (3D), m; split into a fan of triangles.
    Polygon(Vec<Point>),
}

/// A pre-crack (theory §5).
#[derive(Debug, Clone)]
pub struct Crack {
    /// Its shape.
    pub shape: CrackShape,
    /// Conductance fraction μ kept by the bonds it cuts (0 = insulated).
    pub mu: f64,
    /// How a polyline crack grows from its first point; None for a standing crack.
    pub growth: Option<Growth>,
}

/// Everything that defines a model, independent of any file format.
#[derive(Debug, Clone)]
pub struct ModelSpec {
    /// The geometry.
    pub geometry: Geometry,
    /// Materials, indexed by the regions' material index.
    pub materials: Vec<Material>,
    /// Kernel.
    pub kernel: Kernel,
    /// Interface rule for bonds between materials.
    pub bond_rule: BondRule,
    /// Conditions by boundary set: the six faces x_min … z_max of a box, or a mesh's groups.
    pub faces: Vec<FaceBc>,
    /// Pre-cracks.
    pub cracks: Vec<Crack>,
    /// Volumetric heat source s(x, y, z, t), W/m³.
    pub source: Option<Expr>,
    /// Initial temperature.
    pub initial: Initial,
    /// Which polynomial fields the corrected weights integrate exactly at nodes with a complete
    /// horizon ([`crate::weights`]).
    pub consistency: Order,
    /// Restore, at nodes whose bonds a pre-crack cuts, the second moment of their horizon
    /// ([`crate::crack::restore_moment`]).
    pub crack_correction: bool,
    /// Planar, axisymmetric or spherical body (PCS2022; theory §7).
    pub symmetry: Symmetry,
    /// How the explicit step stores K's columns and values ([`crate::gather`]).
    pub step: StepStorage,
}

/// Cutting facets of the cracks (theory §5).
pub fn crack_cutters(cloud: &Cloud, cracks: &[Crack]) -> Vec<Cutter> {
    let mut out = Vec::new();
    for c in cracks {
        match &c.shape {
            CrackShape::Polyline(pts) => match c.growth {
                Some(g) => out.extend(growing_path(pts, c.mu, g)),
                None => {
                    let pairs: Vec<[Point; 2]> = pts.windows(2).map(|w| [w[0], w[1]]).collect();
                    out.extend(segments(&pairs, c.mu));
                }
            },
            CrackShape::Polygon(pts) => {
                for w in pts[1..].windows(2) {
                    out.extend(facet_cutters(&[pts[0], w[0], w[1]], c.mu, None));
                }
            }
            CrackShape::Set(s) => {
                let Sides::Mesh(m) = &cloud.sides else {
                    continue;
                };
                let facets = &m.sets[*s].facets;
                if cloud.dim == 2 {
                    let pairs: Vec<[Point; 2]> = facets
                        .iter()
                        .map(|f| [f.corners[0], f.corners[1]])
                        .collect();
                    out.extend(segments(&pairs, c.mu));
                } else {
                    for f in facets {
                        out.extend(facet_cutters(&f.corners, c.mu, None));
                    }
                }
            }
        }
    }
    out
}

/// Cutting facets of the cracks and, for a mesh, of the body's boundary.
fn cutters(cloud: &Cloud, cracks: &[Crack]) -> Vec<Cutter> {
    let mut out = crack_cutters(cloud, cracks);
    if let Sides::Mesh(m) = &cloud.sides {
        for f in &m.boundary.facets {
            out.extend(facet_cutters(&f.corners, 0.0, Some(f.set)));
        }
    }
    out
}

/// Body nodes whose horizon is complete: no boundary without a fictitious layer within reach,
/// no bond cut (by a crack or the boundary) and one material throughout (material interfaces
/// keep the bond rule of theory §2.4, cracks their own correction).
fn complete_horizons(
    cloud: &Cloud,
    horizons: &Horizons,
    layered: &[bool],
    mu: &[f64],
) -> Vec<bool> {
    let free = cloud.distances_to_free(layered);
    (0..cloud.n_body)
        .map(|i| {
            free[i] > cloud.horizon[i] + cloud.spacing[i]
                && horizons.row(i).all(|b| {
                    mu.get(b).is_none_or(|&m| m == 1.0)
                        && cloud.material[horizons.targets[b] as usize] == cloud.material[i]
                })
        })
        .collect()
}

/// Directed bonds of the body rows `rows` of `horizons`, plus the bonds from fictitious nodes
/// into them: summed over the ranges of a partition, the bonds of the whole model.
fn bonds_into(cloud: &Cloud, h: &Horizons, rows: Range<usize>) -> usize {
    let rows = &rows;
    let body = h.offsets[rows.end] - h.offsets[rows.start];
    let fictitious: usize = (cloud.n_body..h.len())
        .map(|f| {
            let t = &h.targets[h.row(f)];
            t.iter().filter(|&&i| rows.contains(&(i as usize))).count()
        })
        .sum();
    body + fictitious
}

/// An assembled model.
#[derive(Debug, Clone)]
pub struct Model {
    /// Nodes (body first, then fictitious).
    pub cloud: Cloud,
    /// Directed bonds of the body rows it holds and from fictitious nodes into them (the
    /// neighbour lists themselves are dropped once K is assembled: K holds every pair).
    pub bonds: usize,
    /// The body nodes of its rows without a directed bond of their own (a horizon that
    /// reaches no node; empty in a model a run accepts).
    pub bondless: Vec<usize>,
    /// Symmetric pair conductance, W/K.
    pub conductance: Conductance,
    /// Conductivity per node (with phase change: the largest of its phases), W/(m·K).
    pub conductivity: Vec<f64>,
    /// Volumetric heat capacity ρc per node (with phase change: the smallest), J/(m³·K).
    pub capacity: Vec<f64>,
    /// 1 / (V_i ρc_i) per body node, K/J.
    pub inv_heat_capacity: Vec<f64>,
    /// With phase change (theory §6): each material's enthalpy relation, and then
    /// `conductance` holds K for unit conductivity, K_ij(t) = λ̄_ij(t)·K_ij with λ̄ from
    /// `bond_rule`; the boundary's loads are then in W/m³. None for a linear model.
    pub enthalpy: Option<Vec<Enthalpy>>,
    /// Interface rule for the bond conductivity λ̄_ij (theory §2.4).
    pub bond_rule: BondRule,
    /// Boundary conditions and loads.
    pub boundary: Boundary,
    /// Initial temperature of every node, °C.
    pub theta0: Vec<f64>,
    /// Result of the consistent-weights correction, when it was asked for.
    pub correction: Option<Consistency>,
    /// Body nodes whose moments the correction met (all false without it).
    pub consistent: Vec<bool>,
    /// Later cuts of pairs by growing cracks, in time order.
    pub growth: Vec<PairCut>,
    /// What the damage of cracks needs of the directed bonds (None without cracks).
    pub damage: Option<DamageBonds>,
    /// The body rows whose bonds and K this model holds: all of them, or one rank's share
    /// ([`Model::build_share`]).
    pub rows: Range<usize>,
    /// The bound of [`Model::lambda_max`] over every rank's rows, once a share has been told
    /// it ([`Model::set_lambda_max`]), 1/s.
    pub shared_lambda: Option<f64>,
    /// How the explicit step stores K's columns and values (the spec's).
    pub step: StepStorage,
}

/// A pair that a growing crack cuts at `time`: its K entries keep the fraction `mu`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairCut {
    /// When the tip passes the pair, s.
    pub time: f64,
    /// Fraction kept.
    pub mu: f64,
    /// (row, index into the CSR arrays) of K_ij and K_ji; rows of fictitious nodes are absent.
    pub entries: [Option<(usize, usize)>; 2],
}

/// The K entries of the pairs in `later` (directed bonds cut later), earliest cut per pair.
fn pair_cuts(
    cloud: &Cloud,
    horizons: &Horizons,
    k: &Conductance,
    later: &[(usize, f64, f64)],
) -> Vec<PairCut> {
    if later.is_empty() {
        return Vec::new();
    }
    let mut rows = vec![0usize; horizons.n_bonds()];
    for i in 0..horizons.len() {
        for b in horizons.row(i) {
            rows[b] = i;
        }
    }
    let mut pairs: std::collections::BTreeMap<(usize, usize), (f64, f64)> = Default::default();
    for &(b, t, mu) in later {
        let (i, j) = (rows[b], horizons.targets[b] as usize);
        let e = pairs.entry((i.min(j), i.max(j))).or_insert((t, mu));
        if t < e.0 {
            *e = (t, mu);
        }
    }
    let entry = |r: usize, c: usize| -> Option<(usize, usize)> {
        if r >= cloud.n_body {
            return None;
        }
        let range = k.offsets[r]..k.offsets[r + 1];
        let p = k.cols[range.clone()].binary_search(&(c as u32)).ok()?;
        Some((r, range.start + p))
    };
    let mut out: Vec<PairCut> = pairs
        .into_iter()
        .map(|((i, j), (time, mu))| PairCut {
            time,
            mu,
            entries: [entry(i, j), entry(j, i)],
        })
        .collect();
    out.sort_by(|a, b| a.time.total_cmp(&b.time));
    out
}

/// The bonds of a model after the cracks and the consistency correction: the stage of
/// [`Model::build`] between the neighbour search and the boundary.
struct Bonds {
    /// Directed bond weights ([`directed_weights`]) with the cut factors applied, held only
    /// where a later stage reads them (nodal flux relations: [`Bonds::micro`]).
    weights: Option<Vec<f64>>,
    /// The assembled (and possibly corrected) conductance.
    conductance: Conductance,
    /// The consistency correction, when one was asked for and applies.
    correction: Option<Consistency>,
    /// Which body nodes met the consistency conditions.
    consistent: Vec<bool>,
    /// Conductance entries of the bonds cut later by growing cracks.
    growth: Vec<PairCut>,
    /// What the damage needs (a model with cracks; None without).
    damage: Option<DamageBonds>,
}

/// Checks the materials of a spec and the conditions that do not combine with phase change;
/// true when some material changes phase.
fn check_spec(spec: &ModelSpec) -> Result<bool> {
    for (m, mat) in spec.materials.iter().enumerate() {
        mat.check()
            .map_err(|(key, message)| Error::model(format!("material[{m}].{key}"), message))?;
    }
    let phase = any_phase_change(&spec.materials);
    if phase
        && spec
            .faces
            .iter()
            .any(|f| matches!(f, FaceBc::RelationFlux { .. }))
    {
        return Err(Error::model(
            "boundary",
            "a flux condition with method = \"relation\" does not apply with phase change; use method = \"mirror\"",
        ));
    }
    Ok(phase)
}

/// The node cloud of a spec with its fictitious layers on the `layered` faces and its
/// symmetry applied.
fn build_cloud(spec: &ModelSpec, layered: &[bool]) -> Result<Cloud> {
    let band = match spec.kernel.partial_volume {
        PartialVolume::AllOrNothing => 0.0,
        PartialVolume::Algorithm1 => 0.5,
    };
    let mut cloud = match &spec.geometry {
        Geometry::Box(g) => {
            let mask = (0..6).filter(|&f| layered[f]).fold(0u8, |m, f| m | 1 << f);
            // one horizon plus the partial-volume band of the coarsest spacing
            let max_spacing = g.regions.iter().map(|r| r.spacing()).fold(0.0, f64::max);
            let max_horizon = g
                .regions
                .iter()
                .map(|r| r.horizon.horizon(r.spacing()))
                .fold(0.0, f64::max);
            g.generate(mask, max_horizon + band * max_spacing)?
        }
        Geometry::Mesh(g) => g.generate(layered, band)?,
    };
    cloud.apply_symmetry(spec.symmetry)?;
    Ok(cloud)
}

impl Bonds {
    /// Weights, crack and boundary cuts, the conductance and its consistency correction;
    /// `bond_conductivity` per node, W/(m·K).
    fn build(
        spec: &ModelSpec,
        cloud: &Cloud,
        horizons: &Horizons,
        layered: &[bool],
        bond_conductivity: &[f64],
        rows: Range<usize>,
        store: Option<&dyn Store>,
    ) -> Bonds {
        let half = HalfConductance::new(
            cloud,
            horizons,
            &spec.kernel,
            bond_conductivity,
            spec.bond_rule,
        );
        let cuts = bond_factors(cloud, horizons, &cutters(cloud, &spec.cracks));
        let mu = &cuts.mu;
        // damage counts cracks only: bonds the boundary cuts (holes, notches) never existed
        let crack_cuts = if spec.cracks.is_empty() {
            Cuts::default()
        } else {
            bond_factors(cloud, horizons, &crack_cutters(cloud, &spec.cracks))
        };
        let restores = spec.crack_correction && !crack_cuts.mu.is_empty();
        // the directed weights are stored only where they change or are read again
        let weights = (restores || needs_micro(spec, cloud)).then(|| {
            let mut weights = half.all();
            if restores {
                crate::crack::restore_moment(cloud, horizons, &crack_cuts.mu, &mut weights);
            }
            for (w, m) in weights.iter_mut().zip(mu) {
                *w *= m;
            }
            weights
        });
        let mut conductance = match &weights {
            Some(w) => Conductance::assemble_rows(cloud, horizons, w, rows),
            None => {
                let at = |i: usize, b: usize| {
                    let w = half.at(i, b);
                    mu.get(b).map_or(w, |m| w * m)
                };
                Conductance::assemble_rows_with(cloud, horizons, &at, rows)
            }
        };
        let (correction, consistent) = correction_of(
            spec,
            (cloud, horizons, layered, mu),
            bond_conductivity,
            &mut conductance,
            (store, Weights::Solve),
        );
        let growth = pair_cuts(cloud, horizons, &conductance, &cuts.later);
        let damage = (!spec.cracks.is_empty())
            .then(|| DamageBonds::new(cloud, horizons, &spec.kernel, crack_cuts));
        Bonds {
            weights,
            conductance,
            correction,
            consistent,
            growth,
            damage,
        }
    }

    /// The micro-conductances 2w/V_i of every directed bond (w its weight, V_i the volume
    /// of its node), when a nodal flux relation needs them (2D and 3D); `None` otherwise.
    fn micro(&self, spec: &ModelSpec, cloud: &Cloud, horizons: &Horizons) -> Option<Vec<f64>> {
        let weights = self.weights.as_ref().filter(|_| needs_micro(spec, cloud))?;
        let micro = (0..horizons.len())
            .flat_map(|i| horizons.row(i).map(move |b| (i, b)))
            .map(|(i, b)| 2.0 * weights[b] / cloud.volume[i])
            .collect();
        Some(micro)
    }
}

/// Whether a nodal flux relation of `spec` needs the bonds' micro-conductances (2D and 3D).
fn needs_micro(spec: &ModelSpec, cloud: &Cloud) -> bool {
    cloud.dim > 1
        && spec
            .faces
            .iter()
            .any(|f| matches!(f, FaceBc::RelationFlux { .. }))
}

/// Whether `spec` asks for consistent weights where they apply (not on a symmetric cloud).
pub fn corrects(spec: &ModelSpec, cloud: &Cloud) -> bool {
    spec.consistency != Order::None && !cloud.symmetry.is_symmetric()
}

/// The consistency correction of `conductance` when `spec` asks for one ([`corrects`]), on
/// the nodes whose horizon is complete (`layered`: the sets with a fictitious layer; `mu`:
/// the bonds' cut factors), and which body nodes meet it.
fn correction_of(
    spec: &ModelSpec,
    (cloud, horizons, layered, mu): (&Cloud, &Horizons, &[bool], &[f64]),
    bond_conductivity: &[f64],
    conductance: &mut Conductance,
    (store, weights): (Option<&dyn Store>, Weights),
) -> (Option<Consistency>, Vec<bool>) {
    if !corrects(spec, cloud) {
        return (None, vec![false; cloud.n_body]);
    }
    let sel = complete_horizons(cloud, horizons, layered, mu);
    let order = spec.consistency;
    if weights == Weights::StoredOnly {
        let stored = store
            .and_then(|s| correct_stored(conductance, cloud, &sel, bond_conductivity, order, s));
        return match stored {
            Some((c, met)) => (Some(c), met),
            None => (None, vec![false; cloud.n_body]),
        };
    }
    let (c, met) = correct_reusing(conductance, cloud, &sel, bond_conductivity, order, store);
    (Some(c), met)
}

/// Whether a build solves the consistent weights it asks for, or only loads stored ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weights {
    /// Load them from the store if it holds them, else solve them (and keep them there).
    Solve,
    /// Load them from the store if it holds them, else leave K as it is (`peritherm check`,
    /// which estimates the set-up instead: [`crate::weights::estimate`]).
    StoredOnly,
}

/// The enthalpy curves of a phase-change model with the conductivity and capacity bounds
/// that set its stable step (maximum conductivity, minimum capacity per node); without phase
/// change, `conductivity` and `capacity` unchanged.
fn heat_properties(
    spec: &ModelSpec,
    cloud: &Cloud,
    phase: bool,
    conductivity: Vec<f64>,
    capacity: Vec<f64>,
) -> (Option<Vec<Enthalpy>>, Vec<f64>, Vec<f64>) {
    let enthalpy: Option<Vec<Enthalpy>> =
        phase.then(|| spec.materials.iter().map(Material::enthalpy).collect());
    let (conductivity, capacity) = match &enthalpy {
        Some(e) => {
            let at = |i: usize| e[cloud.material[i] as usize];
            (
                (0..cloud.len()).map(|i| at(i).max_conductivity()).collect(),
                (0..cloud.len()).map(|i| at(i).min_capacity()).collect(),
            )
        }
        None => (conductivity, capacity),
    };
    (enthalpy, conductivity, capacity)
}

/// What every build of a spec starts with: the materials checked (true with phase change),
/// the faces that carry a fictitious layer, and the cloud.
fn prelude(spec: &ModelSpec) -> Result<(bool, Vec<bool>, Cloud)> {
    let phase = check_spec(spec)?;
    let layered: Vec<bool> = spec.faces.iter().map(FaceBc::needs_layer).collect();
    let cloud = build_cloud(spec, &layered)?;
    Ok((phase, layered, cloud))
}

/// The conductivity (W/(m·K)) and volumetric heat capacity (J/(m³·K)) of every node's
/// material.
fn heat_of(spec: &ModelSpec, cloud: &Cloud) -> (Vec<f64>, Vec<f64>) {
    let mat = |i: usize| spec.materials[cloud.material[i] as usize];
    let conductivity = (0..cloud.len()).map(|i| mat(i).conductivity).collect();
    let capacity = (0..cloud.len()).map(|i| mat(i).capacity()).collect();
    (conductivity, capacity)
}

/// The boundary of `cloud` (`heat`: conductivity and capacity per node; `micro`: the bonds'
/// micro-conductances, for nodal flux relations).
fn boundary_of(
    spec: &ModelSpec,
    cloud: &Cloud,
    phase: bool,
    heat: (&[f64], &[f64]),
    micro: Option<(&Horizons, &[f64])>,
) -> Boundary {
    // with phase change the loads are enthalpy rates (W/m³): unit capacity
    let unit = vec![1.0; if phase { cloud.len() } else { 0 }];
    Boundary::build(BoundaryInput {
        cloud,
        faces: spec.faces.clone(),
        conductivity: heat.0,
        capacity: if phase { &unit } else { heat.1 },
        micro,
        source: spec.source.clone(),
    })
}

impl Model {
    /// The cloud and boundary of a spec without any bond (for planning a distributed run:
    /// [`crate::partition::loads`]); nodal flux relations get no micro-conductances.
    pub fn outline(spec: &ModelSpec) -> Result<(Cloud, Boundary)> {
        let (phase, _, cloud) = prelude(spec)?;
        let (conductivity, capacity) = heat_of(spec, &cloud);
        let boundary = boundary_of(spec, &cloud, phase, (&conductivity, &capacity), None);
        Ok((cloud, boundary))
    }

    /// Builds cloud, bonds, conductance and boundary from a spec.
    pub fn build(spec: &ModelSpec) -> Result<Model> {
        Self::build_with(spec, None)
    }

    /// [`Model::build`], reusing consistent weights kept in `store` (and keeping new ones
    /// there): the model is the same bits with or without it.
    pub fn build_with(spec: &ModelSpec, store: Option<&dyn Store>) -> Result<Model> {
        let (phase, layered, cloud) = prelude(spec)?;
        let horizons = Horizons::build(&cloud, &spec.kernel);
        let rows = 0..cloud.n_body;
        Self::finish(spec, cloud, &horizons, phase, &layered, rows, store)
    }

    /// [`Model::build_with`], calling `check` on the model before its consistent weights are
    /// solved (they are the expensive part of a set-up and change nothing `check` should
    /// read but K): a case `check` refuses is refused in the time of a set-up without them.
    /// With [`Weights::Solve`] the model is the same bits as [`Model::build_with`]'s; with
    /// [`Weights::StoredOnly`] and nothing in `store`, K stays uncorrected and
    /// [`Model::correction`] is None. `check` may fail with the error of a layer above
    /// (`E`, which holds this crate's [`Error`]); so may the build then.
    pub fn build_checked<E: From<Error>>(
        spec: &ModelSpec,
        (store, weights): (Option<&dyn Store>, Weights),
        check: impl Fn(&Model) -> std::result::Result<(), E>,
    ) -> std::result::Result<Model, E> {
        let bare = ModelSpec {
            consistency: Order::None,
            ..spec.clone()
        };
        let (phase, layered, cloud) = prelude(&bare)?;
        let horizons = Horizons::build(&cloud, &bare.kernel);
        let rows = 0..cloud.n_body;
        let mut model = Self::finish(&bare, cloud, &horizons, phase, &layered, rows, None)?;
        check(&model)?;
        if corrects(spec, &model.cloud) {
            model.correct(spec, (phase, &horizons, &layered), (store, weights));
        }
        Ok(model)
    }

    /// Applies the consistency correction of `spec` to a model built without it (see
    /// [`Model::build_checked`]); `phase`: K holds unit conductivities.
    fn correct(
        &mut self,
        spec: &ModelSpec,
        (phase, horizons, layered): (bool, &Horizons, &[bool]),
        store: (Option<&dyn Store>, Weights),
    ) {
        let cloud = &self.cloud;
        let bond_conductivity = if phase {
            vec![1.0; cloud.len()]
        } else {
            heat_of(spec, cloud).0
        };
        let cuts = bond_factors(cloud, horizons, &cutters(cloud, &spec.cracks));
        let (correction, consistent) = correction_of(
            spec,
            (cloud, horizons, layered, &cuts.mu),
            &bond_conductivity,
            &mut self.conductance,
            store,
        );
        self.growth = pair_cuts(cloud, horizons, &self.conductance, &cuts.later);
        self.correction = correction;
        self.consistent = consistent;
    }

    /// Whether a spec can be built one rank's share at a time ([`Model::build_share`]): every
    /// row of K depends on its own neighbourhood only (cracks and phase change too: their
    /// cuts, restored moments, damage and unit conductances are per row). Not so for the
    /// consistent weights (one global solve) and nodal flux relations (their
    /// micro-conductances).
    pub fn shareable(spec: &ModelSpec) -> bool {
        let corrected = spec.consistency != Order::None && !spec.symmetry.is_symmetric();
        let relation = spec
            .faces
            .iter()
            .any(|f| matches!(f, FaceBc::RelationFlux { .. }));
        !(corrected || relation)
    }

    /// The share of rank `rank` of `ranks` of a [`Model::shareable`] spec, and the partition
    /// of the body rows ([`Partition::by_estimate`], the same on every rank): the whole cloud
    /// (positions, volumes, boundary: O(nodes)), but the bonds and K of the rank's rows
    /// alone, with the margin of rows their assembly reads ([`Horizons::build_rows`]). Its
    /// rows have the bits of [`Model::build`]'s; the others are empty.
    pub fn build_share(spec: &ModelSpec, ranks: usize, rank: usize) -> Result<(Model, Partition)> {
        let (phase, layered, cloud) = prelude(spec)?;
        let partition = Partition::by_estimate(&cloud, ranks);
        let rows = partition.range(rank.min(partition.ranks() - 1));
        let horizons = Horizons::build_rows(&cloud, &spec.kernel, rows.clone());
        let model = Self::finish(spec, cloud, &horizons, phase, &layered, rows, None)?;
        Ok((model, partition))
    }

    /// Tells a share the bound of [`Model::lambda_max`] over every rank (their largest), 1/s.
    pub fn set_lambda_max(&mut self, lambda: f64) {
        self.shared_lambda = Some(lambda);
    }

    /// The model of `cloud` and `horizons`, its K assembled on `rows`.
    fn finish(
        spec: &ModelSpec,
        cloud: Cloud,
        horizons: &Horizons,
        phase: bool,
        layered: &[bool],
        rows: Range<usize>,
        store: Option<&dyn Store>,
    ) -> Result<Model> {
        let (conductivity, capacity) = heat_of(spec, &cloud);
        // with phase change, K for unit conductivity; λ̄_ij(t) scales it as the state evolves
        let bond_conductivity = if phase {
            vec![1.0; cloud.len()]
        } else {
            conductivity.clone()
        };
        let bonds = Bonds::build(
            spec,
            &cloud,
            horizons,
            layered,
            &bond_conductivity,
            rows.clone(),
            store,
        );
        let micro = bonds.micro(spec, &cloud, horizons);
        let micro = micro.as_deref().map(|m| (horizons, m));
        let boundary = boundary_of(spec, &cloud, phase, (&conductivity, &capacity), micro);
        let (enthalpy, conductivity, capacity) =
            heat_properties(spec, &cloud, phase, conductivity, capacity);
        let inv_heat_capacity = (0..cloud.n_body)
            .map(|i| 1.0 / (cloud.volume[i] * capacity[i]))
            .collect();
        let mut theta0 = spec.initial.at(&cloud.pos, &cloud.region, "node")?;
        boundary.apply(&cloud, &mut theta0, 0.0);
        let Bonds {
            conductance,
            correction,
            consistent,
            growth,
            damage,
            ..
        } = bonds;
        let bonds = bonds_into(&cloud, horizons, rows.clone());
        let bondless = rows
            .clone()
            .filter(|&i| horizons.row(i).is_empty())
            .collect();
        Ok(Model {
            cloud,
            bonds,
            bondless,
            conductance,
            conductivity,
            capacity,
            inv_heat_capacity,
            enthalpy,
            bond_rule: spec.bond_rule,
            boundary,
            theta0,
            correction,
            consistent,
            growth,
            damage,
            rows,
            shared_lambda: None,
            step: spec.step,
        })
    }

    /// Damage φ of every body node at time `t` (theory §5), growing cracks included.
    pub fn damage_at(&self, t: f64) -> Vec<f64> {
        match &self.damage {
            Some(d) => d.at(t),
            None => vec![0.0; self.cloud.n_body],
        }
    }

    /// Total thermal energy of the body, Σ V_i ρc_i θ_i, J (relative to 0 °C); with phase
    /// change Σ V_i H(θ_i), a node at T_f counted frozen (the stepper's own
    /// [`crate::solve::enthalpy::Enthalpic::energy`] knows where on the plateau it is).
    pub fn energy(&self, theta: &[f64]) -> f64 {
        if let Some(e) = &self.enthalpy {
            return (0..self.cloud.n_body)
                .map(|i| {
                    self.cloud.volume[i] * e[self.cloud.material[i] as usize].enthalpy(theta[i])
                })
                .sum();
        }
        (0..self.cloud.n_body)
            .map(|i| self.cloud.volume[i] * self.capacity[i] * theta[i])
            .sum()
    }

    /// Gershgorin bound on the largest eigenvalue of the free-node system, 1/s (theory §4).
    ///
    /// With phase change K holds unit conductivities and the loads are per unit capacity, so
    /// the bound takes the largest conductivity and the smallest capacity of any phase.
    pub fn lambda_max(&self) -> f64 {
        if let Some(l) = self.shared_lambda {
            return l;
        }
        let loads = self.boundary.load_diagonal(self.cloud.n_body);
        let (k_max, load_scale) = match self.enthalpy {
            Some(_) => (self.conductivity.iter().copied().fold(0.0, f64::max), true),
            None => (1.0, false),
        };
        (0..self.cloud.n_body)
            .filter(|&i| !self.boundary.driven[i])
            .map(|i| {
                let load = if load_scale {
                    loads[i] / self.capacity[i]
                } else {
                    loads[i]
                };
                2.0 * k_max * self.conductance.diag[i] * self.inv_heat_capacity[i] + load
            })
            .fold(0.0, f64::max)
    }
}
