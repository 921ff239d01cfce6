//! Case files: the TOML schema, its validation, and the conversion to a [`ModelSpec`].
//!
//! Every key is documented in docs/case-reference.md. Unknown keys, missing
//! fields and out-of-range values are errors that name the file and the key.

use crate::history::{HistoryPlot, HistorySpec};
use crate::reference::ReferenceTable;
use crate::series::SeriesCheck;
use peritherm_core::analytic::Reference;
use peritherm_core::bc::{FaceBc, Layer};
use peritherm_core::cloud::mesh::{MeshGeometry, MeshRegion};
use peritherm_core::cloud::{BoxGeometry, BoxRegion, HorizonRule, FACE_NAMES};
use peritherm_core::crack::Growth;
use peritherm_core::error::{Error, Result};
use peritherm_core::expr::Expr;
use peritherm_core::kernel::{Calibration, Kernel, PartialVolume, Profile};
use peritherm_core::material::{BondRule, Material};
use peritherm_core::math::Point;
use peritherm_core::model::{Crack, CrackShape, Geometry, Initial, ModelSpec};
use peritherm_core::solve::explicit::Integrator;
use peritherm_core::symmetry::Symmetry;
use peritherm_core::weights::Order;
use peritherm_fem::{FemOptions, Scheme};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A number or an expression string.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum ValueSpec {
    /// A constant.
    Number(f64),
    /// An expression of x, y, z, t.
    Expr(String),
}

/// The whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Free text shown in run.json.
    #[serde(default)]
    pub title: String,
    /// Spatial dimension, 1..=3.
    pub dimension: usize,
    /// `planar` (default), `axisymmetric` (x = r, y = z) or `spherical` (x = r); the axisymmetric
    /// phase-change paper (doi:10.1007/s42102-022-00092-3).
    #[serde(default)]
    pub symmetry: Symmetry,
    /// The built-in box domain (or give `mesh`).
    #[serde(default)]
    pub domain: Option<DomainSpec>,
    /// A gmsh mesh (or give `domain`).
    #[serde(default)]
    pub mesh: Option<MeshSpec>,
    /// Regions: boxes tiling the domain, or the mesh's physical groups (at least one).
    pub region: Vec<RegionSpec>,
    /// Pre-cracks.
    #[serde(default)]
    pub crack: Vec<CrackSpec>,
    /// Materials by name.
    pub material: BTreeMap<String, Material>,
    /// Kernel settings.
    #[serde(default)]
    pub kernel: KernelSpec,
    /// Boundary conditions by face name (x_min … z_max); missing faces are free.
    #[serde(default)]
    pub boundary: BTreeMap<String, BoundarySpec>,
    /// Initial temperature.
    #[serde(default)]
    pub initial: InitialSpec,
    /// Volumetric source.
    #[serde(default)]
    pub source: Option<SourceSpec>,
    /// Time integration.
    pub time: TimeSpec,
    /// Classical reference to compare with.
    #[serde(default)]
    pub reference: Option<ReferenceSection>,
    /// Temperature histories at points.
    #[serde(default)]
    pub history: Option<HistorySection>,
}

/// `[history]` as written: points sampled at a regular interval up to the last output.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HistorySection {
    /// Points whose nearest body node is recorded, m (one coordinate per dimension each).
    pub points: Vec<Vec<f64>>,
    /// Sampling interval, s.
    pub interval: f64,
    /// The report's plot: `temperature` (default) or `normalised` (also T / T_max).
    #[serde(default)]
    pub plot: Option<String>,
}

/// `[domain]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    /// Min corner, one coordinate per dimension, m.
    pub min: Vec<f64>,
    /// Max corner, m.
    pub max: Vec<f64>,
    /// Thickness h of a 2D body, m.
    #[serde(default)]
    pub thickness: Option<f64>,
    /// Cross-section A of a 1D bar, m².
    #[serde(default)]
    pub area: Option<f64>,
    /// `cell` (cell-centred nodes of equal volume) or `boundary` (nodes on the boundary).
    #[serde(default)]
    pub placement: Placement,
}

/// `[mesh]`: a gmsh MSH 4.1 file whose elements become nodes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Path of the .msh file, relative to the case file.
    pub file: PathBuf,
    /// Metres per mesh unit (default 1).
    #[serde(default)]
    pub scale: Option<f64>,
    /// Thickness h of a 2D body, m.
    #[serde(default)]
    pub thickness: Option<f64>,
    /// Cross-section A of a 1D bar, m².
    #[serde(default)]
    pub area: Option<f64>,
    /// Largest ratio of horizons between neighbouring nodes (> 1); larger ones are reduced.
    #[serde(default)]
    pub horizon_ratio: Option<f64>,
}

/// `[[crack]]`: a pre-crack along a mesh group or a polyline.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrackSpec {
    /// A mesh physical group (curves in 2D, surfaces in 3D) embedded in the body.
    #[serde(default)]
    pub group: Option<String>,
    /// A 2D polyline, m.
    #[serde(default)]
    pub points: Option<Vec<Vec<f64>>>,
    /// Conductance fraction μ kept across the crack (default 0: insulated).
    #[serde(default)]
    pub conductance: Option<f64>,
    /// Tip speed of a crack growing along `points` from the first one, m/s.
    #[serde(default)]
    pub speed: Option<f64>,
    /// Time the tip starts moving, s (default 0).
    #[serde(default)]
    pub start: Option<f64>,
    /// Length already cracked from the first point, m (default 0).
    #[serde(default)]
    pub initial_length: Option<f64>,
}

/// Node placement.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// Cell-centred nodes of equal volume (Bobaru & Duangpanya 2010 §3; Wang, Oterkus & Oterkus).
    #[default]
    Cell,
    /// Nodes on the boundary with partial volumes (Bobaru & Duangpanya 2012 §3).
    Boundary,
}

/// Horizon rule of a region.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum HorizonSpec {
    /// δ = factor · Δ.
    Factor(f64),
    /// δ given, m.
    Radius(f64),
}

/// `[[region]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// Name.
    pub name: String,
    /// Min corner (default: the domain's), m.
    #[serde(default)]
    pub min: Option<Vec<f64>>,
    /// Max corner (default: the domain's), m.
    #[serde(default)]
    pub max: Option<Vec<f64>>,
    /// Node spacing Δ, m (or give `cells`).
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Cells per axis (or give `spacing`).
    #[serde(default)]
    pub cells: Option<Vec<usize>>,
    /// Horizon rule.
    pub horizon: HorizonSpec,
    /// Material name (default: the only material).
    #[serde(default)]
    pub material: Option<String>,
    /// Initial temperature of this region, °C (overrides `[initial]`).
    #[serde(default)]
    pub initial: Option<f64>,
}

/// `[kernel]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelSpec {
    /// Exponent p: 1 or 2.
    #[serde(default = "default_p")]
    pub p: u8,
    /// Profile: constant, conical (alias triangular).
    #[serde(default = "default_profile")]
    pub profile: Profile,
    /// Partial volumes: algorithm1 or all_or_nothing.
    #[serde(default = "default_pv")]
    pub partial_volume: PartialVolume,
    /// Bond conductivity between materials: harmonic, lower, arithmetic.
    #[serde(default)]
    pub bond_rule: BondRule,
    /// Normalisation: continuum (exact integral, default) or lattice (midpoint sum).
    #[serde(default)]
    pub calibration: Calibration,
    /// Consistent weights: quadratic (default on meshes), linear, or none (default on boxes).
    #[serde(default)]
    pub consistency: Option<Order>,
    /// Older spelling of `consistency = "linear"`.
    #[serde(default)]
    pub linear_consistency: bool,
    /// Restore the horizon's second moment at nodes whose bonds a pre-crack cuts.
    #[serde(default)]
    pub crack_correction: bool,
}

/// On a mesh, every boundary set that no `[boundary]` names (and the facets in no group,
/// unless `[boundary."(no group)"]` names them) is insulated through a mirrored layer: the
/// surface correction of the free-surface skin effect (theory §3). `type = "free"` keeps
/// the uncorrected surface; crack groups stay as they are.
fn unnamed_insulated(
    faces: &mut [FaceBc],
    geometry: &MeshGeometry,
    named: &BTreeMap<String, BoundarySpec>,
    cracks: &[Crack],
) {
    let names = geometry.set_names();
    let cracked: Vec<usize> = cracks
        .iter()
        .filter_map(|c| match c.shape {
            CrackShape::Set(s) => Some(s),
            _ => None,
        })
        .collect();
    for (s, face) in faces.iter_mut().enumerate() {
        let name = names
            .get(s)
            .map_or(peritherm_core::cloud::mesh::UNNAMED, String::as_str);
        let given = named.contains_key(name);
        if !given && !cracked.contains(&s) {
            *face = FaceBc::LayerInsulated;
        }
    }
}

impl KernelSpec {
    /// The consistency order asked for, or the default: quadratic on meshes, none on boxes.
    fn order(&self, mesh: bool) -> Order {
        match (self.consistency, self.linear_consistency) {
            (Some(o), _) => o,
            (None, true) => Order::Linear,
            (None, false) if mesh => Order::Quadratic,
            (None, false) => Order::None,
        }
    }
}

fn default_p() -> u8 {
    2
}
fn default_profile() -> Profile {
    Profile::Constant
}
fn default_pv() -> PartialVolume {
    PartialVolume::Algorithm1
}

impl Default for KernelSpec {
    fn default() -> Self {
        KernelSpec {
            p: default_p(),
            profile: default_profile(),
            partial_volume: default_pv(),
            bond_rule: BondRule::default(),
            calibration: Calibration::default(),
            consistency: None,
            linear_consistency: false,
            crack_correction: false,
        }
    }
}

/// `[boundary.<face>]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// free, temperature, insulated, flux or convection.
    #[serde(rename = "type")]
    pub kind: BoundaryKind,
    /// temperature: nodal (default), mirror, naive; insulated: mirror (default) or free;
    /// flux: mirror (default) or relation; convection: surface (default) or mirror.
    #[serde(default)]
    pub method: Option<String>,
    /// Temperature (°C) or flux into the body (W/m²): number or expression.
    #[serde(default)]
    pub value: Option<ValueSpec>,
    /// Node layers held by a nodal temperature condition (default 1).
    #[serde(default)]
    pub layers: Option<f64>,
    /// Film coefficient of a convection condition, W/(m²·K).
    #[serde(default)]
    pub h: Option<f64>,
    /// Ambient temperature of a convection condition, °C.
    #[serde(default)]
    pub ambient: Option<ValueSpec>,
}

/// Kind of a boundary condition.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryKind {
    /// No bonds leave the body.
    Free,
    /// Prescribed temperature.
    Temperature,
    /// Zero flux.
    Insulated,
    /// Prescribed flux into the body.
    Flux,
    /// Convection.
    Convection,
}

/// `[initial]`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// θ0: number or expression of x, y, z (default 0).
    #[serde(default)]
    pub value: Option<ValueSpec>,
}

/// `[source]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSpec {
    /// s(x, y, z, t), W/m³.
    pub value: ValueSpec,
}

/// `[time]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time, s.
    pub end: f64,
    /// Time step, s (default: 0.95 of the stable bound).
    #[serde(default)]
    pub dt: Option<f64>,
    /// euler, rk4 or an implicit scheme (default rk4; euler with phase change, the axisymmetric
    /// phase-change paper).
    #[serde(default)]
    pub integrator: Option<Integrator>,
    /// Output times, s (default: the end time).
    #[serde(default)]
    pub outputs: Vec<f64>,
    /// Adaptive Δt of the implicit schemes: local error allowed per step, max over the
    /// unknowns, K (default: none, fixed Δt).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Largest adaptive step, s (default: a tenth of the last output time).
    #[serde(default)]
    pub dt_max: Option<f64>,
}

/// `[reference]` as written: one classical solution and where to compare.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSection {
    /// An analytical solution and its parameters.
    #[serde(default)]
    pub solution: Option<Reference>,
    /// A CSV table exported by another code (path relative to the case file).
    #[serde(default)]
    pub file: Option<PathBuf>,
    /// The built-in classical FEM solve of the same case.
    #[serde(default)]
    pub fem: Option<FemReferenceSpec>,
    /// Probe line for Bobaru & Duangpanya 2012, eq. 13: nodes within half a spacing of `y =
    /// line_y`, m.
    #[serde(default)]
    pub line_y: Option<f64>,
    /// A vertical probe line x = `line_x` for the report's plots (Wang, Oterkus & Oterkus §4.3), m.
    #[serde(default)]
    pub line_x: Option<f64>,
    /// More vertical probe lines x = each value for the report's plots, m.
    #[serde(default)]
    pub lines_x: Vec<f64>,
    /// More horizontal probe lines y = each value for the report's plots, m.
    #[serde(default)]
    pub lines_y: Vec<f64>,
    /// Leave the nodes within this distance of a crack tip out of the measures, m.
    #[serde(default)]
    pub exclude_tips: Option<f64>,
    /// A point whose nearest body node is reported at every output (e.g. the midpoint of Bobaru &
    /// Duangpanya 2010), m.
    #[serde(default)]
    pub probe: Option<Vec<f64>>,
}

/// `[reference.fem]`: settings of the built-in FEM reference (see `peritherm fem`).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FemReferenceSpec {
    /// Element size of a box case's structured mesh, m (default: the finest region spacing).
    #[serde(default)]
    pub h: Option<f64>,
    /// `crank_nicolson` (default), `backward_euler` or `steady`.
    #[serde(default)]
    pub scheme: Option<Scheme>,
    /// Time step, s (default: min(end/1000, first output/100)).
    #[serde(default)]
    pub dt: Option<f64>,
    /// Another gmsh file (same group names) to solve a gmsh case on, relative to the case file.
    #[serde(default)]
    pub mesh: Option<PathBuf>,
}

/// Where the classical temperatures of a reference come from.
#[derive(Debug, Clone)]
pub enum ReferenceSource {
    /// An analytical series of [`peritherm_core::analytic`].
    Analytic(Reference),
    /// A table exported by another code, interpolated at the nodes.
    Table(Arc<ReferenceTable>),
    /// The built-in FEM solve of the same case (run first, then used as a table).
    Fem(FemOptions),
}

/// A validated reference: its source and where to compare.
#[derive(Debug, Clone)]
pub struct ReferenceSpec {
    /// The classical solution.
    pub source: ReferenceSource,
    /// Probe line for Bobaru & Duangpanya 2012, eq. 13 (y = line_y), m.
    pub line_y: Option<f64>,
    /// Vertical probe line x = line_x of the report, m.
    pub line_x: Option<f64>,
    /// More vertical probe lines of the report, m.
    pub lines_x: Vec<f64>,
    /// More horizontal probe lines of the report, m.
    pub lines_y: Vec<f64>,
    /// Nodes within this distance of a crack tip are left out of the measures, m (0: none).
    pub exclude_tips: f64,
    /// The point whose nearest body node is reported, m.
    pub probe: Option<Point>,
}

/// A validated case: the model spec plus run settings.
#[derive(Debug, Clone)]
pub struct Case {
    /// Where it came from.
    pub path: PathBuf,
    /// Title.
    pub title: String,
    /// The model.
    pub spec: ModelSpec,
    /// Integrator.
    pub integrator: Integrator,
    /// User Δt, s (with `tolerance`: the first step).
    pub dt: Option<f64>,
    /// Local error allowed per adaptive step, K (None: fixed Δt).
    pub tolerance: Option<f64>,
    /// Largest adaptive step, s (None: a tenth of the last output time).
    pub dt_max: Option<f64>,
    /// End time, s.
    pub end: f64,
    /// Output times, s, increasing.
    pub outputs: Vec<f64>,
    /// Reference, if any.
    pub reference: Option<ReferenceSpec>,
    /// Temperature histories, if any.
    pub history: Option<HistorySpec>,
    /// The model's estimated size, checked against the memory before it is built.
    pub budget: peritherm_core::budget::Estimate,
    /// The case file's text as read (a run writes it into its directory as `case.toml`).
    pub source: String,
    /// The other files the case reads (mesh, reference table, FEM mesh), resolved.
    pub inputs: Vec<PathBuf>,
    /// Keys set on the command line over the file's (`run --set`, a sweep's variant), as
    /// `KEY=VALUE`.
    pub settings: Vec<String>,
}

impl Case {
    /// An error about `key` (dotted, e.g. `time.dt`) of this case file.
    pub fn error(&self, key: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Case {
            file: self.path.clone(),
            key: key.into(),
            message: message.into(),
        }
    }

    /// A library error keyed to this case file: a model error's key becomes a key of the
    /// file; every other error is returned as it is.
    pub fn keyed(&self, e: Error) -> Error {
        match e {
            Error::Model { key, message } => self.error(key, message),
            other => other,
        }
    }

    /// The times the run stops at, s: the outputs and the history's samples up to the last
    /// output, increasing.
    pub fn times(&self) -> Vec<f64> {
        let last = self.outputs.last().copied().unwrap_or(self.end);
        match &self.history {
            Some(h) => {
                let samples: Vec<f64> = h
                    .times
                    .iter()
                    .copied()
                    .filter(|&t| t <= last * (1.0 + 1e-9))
                    .collect();
                crate::history::merge(&self.outputs, &samples)
            }
            None => self.outputs.clone(),
        }
    }

    /// Reads, parses and validates a case file.
    pub fn load(path: &Path) -> Result<Case> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Case {
            file: path.to_path_buf(),
            key: "-".into(),
            message: format!("cannot read: {e}"),
        })?;
        Case::parse(&text, path)
    }

    /// Parses and validates case text; `path` is used in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Case> {
        let file: CaseFile = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].lines().count().max(1))
                .unwrap_or(0);
            let msg = e.message().replace('\n', " ");
            Error::Case {
                file: path.to_path_buf(),
                key: format!("line {line}"),
                message: msg.trim().to_string(),
            }
        })?;
        let inputs = file.inputs(path);
        let mut case = file.validate(path)?;
        case.source = text.to_string();
        case.inputs = inputs;
        Ok(case)
    }
}

/// `file` (as a case file writes it) resolved against the folder of the case file `path`.
fn beside(path: &Path, file: &Path) -> PathBuf {
    path.parent().unwrap_or(Path::new(".")).join(file)
}

fn expr(v: &ValueSpec, path: &Path, key: &str) -> Result<Expr> {
    match v {
        ValueSpec::Number(x) if x.is_finite() => Ok(Expr::constant(*x)),
        ValueSpec::Number(x) => Err(case_err(path, key, format!("must be finite, got {x}"))),
        ValueSpec::Expr(s) => Expr::parse(s).map_err(|e| case_err(path, key, e.to_string())),
    }
}

/// Validates `[reference]`: exactly one source, a table that has every output time.
fn reference(
    r: ReferenceSection,
    path: &Path,
    dim: usize,
    outputs: &[f64],
) -> Result<ReferenceSpec> {
    let probe = match &r.probe {
        Some(p) => {
            let c = coords(path, dim, p, "reference.probe")?;
            Some(Point::new(c[0], c[1], c[2]))
        }
        None => None,
    };
    for (key, v) in [
        ("reference.line_y", r.line_y),
        ("reference.line_x", r.line_x),
    ] {
        if v.is_some_and(|v| !v.is_finite() || dim < 2) {
            return Err(case_err(
                path,
                key,
                "must be a finite coordinate of a 2D or 3D case",
            ));
        }
    }
    for (key, v) in [
        ("reference.lines_x", &r.lines_x),
        ("reference.lines_y", &r.lines_y),
    ] {
        if !v.is_empty() && (dim < 2 || v.iter().any(|x| !x.is_finite())) {
            return Err(case_err(
                path,
                key,
                "must be finite coordinates of a 2D or 3D case",
            ));
        }
        if v.len() > peritherm_core::limits::MAX_HISTORY_POINTS {
            return Err(case_err(
                path,
                key,
                format!(
                    "at most {} lines, got {}",
                    peritherm_core::limits::MAX_HISTORY_POINTS,
                    v.len()
                ),
            ));
        }
    }
    let source = match (r.solution, r.file, r.fem) {
        (Some(s), None, None) => {
            if let Some(m) = s.check() {
                return Err(case_err(path, "reference.solution", m));
            }
            ReferenceSource::Analytic(s)
        }
        (None, None, Some(f)) => {
            for (key, v) in [("reference.fem.h", f.h), ("reference.fem.dt", f.dt)] {
                if let Some(v) = v {
                    positive(path, key, v)?;
                }
            }
            ReferenceSource::Fem(FemOptions {
                h: f.h,
                scheme: f.scheme.unwrap_or(Scheme::CrankNicolson),
                dt: f.dt,
                mesh: f
                    .mesh
                    .map(|m| beside(path, &m)),
            })
        }
        (None, Some(file), None) => {
            let file = beside(path, &file);
            let table = ReferenceTable::read(&file, dim)?;
            table
                .check_times(outputs)
                .map_err(|m| case_err(path, "reference.file", m))?;
            ReferenceSource::Table(Arc::new(table))
        }
        _ => {
            return Err(case_err(
                path,
                "reference",
                "give exactly one of `solution` (analytical), `file` (a CSV table) or `fem` (the built-in FEM solve)",
            ))
        }
    };
    Ok(ReferenceSpec {
        source,
        line_y: r.line_y,
        line_x: r.line_x,
        lines_x: r.lines_x,
        lines_y: r.lines_y,
        exclude_tips: match r.exclude_tips {
            Some(v) => positive(path, "reference.exclude_tips", v)?,
            None => 0.0,
        },
        probe,
    })
}

/// Validates `[history]`: at least one point inside the case's dimension, a positive
/// interval giving at most [`peritherm_core::limits::MAX_HISTORY_ROWS`] rows, a known plot.
fn history(
    h: HistorySection,
    path: &Path,
    dim: usize,
    outputs: &[f64],
    integrator: Integrator,
) -> Result<HistorySpec> {
    if integrator == Integrator::Steady {
        return Err(case_err(
            path,
            "history",
            "a steady solve has no history; use a transient integrator",
        ));
    }
    if h.points.is_empty() || h.points.len() > peritherm_core::limits::MAX_HISTORY_POINTS {
        return Err(case_err(
            path,
            "history.points",
            format!(
                "give 1 to {} points, got {}",
                peritherm_core::limits::MAX_HISTORY_POINTS,
                h.points.len()
            ),
        ));
    }
    let mut points = Vec::new();
    for (k, p) in h.points.iter().enumerate() {
        let c = coords(path, dim, p, &format!("history.points[{k}]"))?;
        points.push(Point::new(c[0], c[1], c[2]));
    }
    let interval = positive(path, "history.interval", h.interval)?;
    let last = outputs.last().copied().unwrap_or(interval);
    let max = peritherm_core::limits::MAX_HISTORY_ROWS / points.len() as f64;
    let times = crate::history::sample_times(interval, last, max)
        .map_err(|m| case_err(path, "history.interval", m))?;
    let plot = match h.plot.as_deref() {
        None | Some("temperature") => HistoryPlot::Temperature,
        Some("normalised") => HistoryPlot::Normalised,
        Some(other) => {
            return Err(case_err(
                path,
                "history.plot",
                format!("`{other}` is not one of temperature, normalised"),
            ))
        }
    };
    Ok(HistorySpec {
        points,
        times,
        plot,
    })
}

fn case_err(path: &Path, key: &str, message: impl Into<String>) -> Error {
    Error::Case {
        file: path.to_path_buf(),
        key: key.to_string(),
        message: message.into(),
    }
}

fn positive(path: &Path, key: &str, v: f64) -> Result<f64> {
    // subnormal values (below 2.2e-308) underflow in any product: refused as well
    if v.is_normal() && v > 0.0 {
        Ok(v)
    } else {
        Err(case_err(
            path,
            key,
            if v != 0.0 && !(1e-6..1e9).contains(&v.abs()) {
                format!("must be a positive number, got {v:e}")
            } else {
                format!("must be a positive number, got {v}")
            },
        ))
    }
}

fn coords(path: &Path, dim: usize, v: &[f64], key: &str) -> Result<[f64; 3]> {
    if v.len() != dim {
        return Err(case_err(
            path,
            key,
            format!("needs {dim} coordinates, got {}", v.len()),
        ));
    }
    let mut p = [0.0; 3];
    for (a, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(case_err(path, key, "coordinates must be finite"));
        }
        p[a] = *x;
    }
    Ok(p)
}

/// The dotted key of region `r`'s horizon rule, `region[r].horizon.factor` or `.radius`.
pub(crate) fn horizon_key(r: usize, reg: &RegionSpec) -> String {
    match reg.horizon {
        HorizonSpec::Factor(_) => format!("region[{r}].horizon.factor"),
        HorizonSpec::Radius(_) => format!("region[{r}].horizon.radius"),
    }
}

/// The points of `crack[c]`: coordinates of the dimension, no segment of zero length, and a
/// path that enters the body's interior.
fn crack_points(
    path: &Path,
    c: usize,
    dim: usize,
    pts: &[Vec<f64>],
    geometry: &Geometry,
) -> Result<Vec<Point>> {
    let key = |k: &str| format!("crack[{c}].{k}");
    let mut list: Vec<Point> = Vec::new();
    for (k, p) in pts.iter().enumerate() {
        let q = coords(path, dim, p, &key(&format!("points[{k}]")))?;
        let q = Point::new(q[0], q[1], q[2]);
        if list
            .last()
            .is_some_and(|l| (q - l).norm() <= 1e-12 * q.coords.amax())
        {
            return Err(case_err(
                path,
                &key(&format!("points[{k}]")),
                "repeats the previous point: a crack segment of zero length",
            ));
        }
        list.push(q);
    }
    let (lo, hi) = geometry_bounds(geometry, dim);
    if !crosses_interior(&list, dim, lo, hi) {
        return Err(case_err(
            path,
            &key("points"),
            format!(
                "the crack does not pass through the body's interior ({:?} to {:?} m): it lies outside it or along its boundary",
                &lo[..dim],
                &hi[..dim]
            ),
        ));
    }
    Ok(list)
}

/// The body's bounding box, m: a box's domain, a mesh's nodes (scaled).
fn geometry_bounds(geometry: &Geometry, dim: usize) -> ([f64; 3], [f64; 3]) {
    match geometry {
        Geometry::Box(g) => (g.min, g.max),
        Geometry::Mesh(g) => {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for p in &g.mesh.nodes {
                for a in 0..dim {
                    lo[a] = lo[a].min(p[a] * g.scale);
                    hi[a] = hi[a].max(p[a] * g.scale);
                }
            }
            (lo, hi)
        }
    }
}

/// True when a crack (2D polyline or 3D polygon) enters the open box (lo, hi) shrunk by a
/// relative 1e-9: a 2D segment clipped to it keeps a positive length, a 3D polygon's bounding
/// box overlaps it on every axis.
fn crosses_interior(pts: &[Point], dim: usize, lo: [f64; 3], hi: [f64; 3]) -> bool {
    let eps: Vec<f64> = (0..dim).map(|a| 1e-9 * (hi[a] - lo[a]).abs()).collect();
    if dim == 3 {
        return (0..3).all(|a| {
            let (pmin, pmax) = pts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(p[a]), h.max(p[a]))
                });
            pmin < hi[a] - eps[a] && pmax > lo[a] + eps[a]
        });
    }
    // Liang–Barsky clipping of each segment
    pts.windows(2).any(|w| {
        let (p, d) = (w[0], w[1] - w[0]);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for a in 0..dim {
            let (l, h) = (lo[a] + eps[a], hi[a] - eps[a]);
            if d[a] == 0.0 {
                if p[a] <= l || p[a] >= h {
                    return false;
                }
                continue;
            }
            let (ta, tb) = ((l - p[a]) / d[a], (h - p[a]) / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        t1 > t0
    })
}

/// Keys a [`Error::Model`] from geometry validation to the case file.
fn in_case(path: &Path, e: Error) -> Error {
    match e {
        Error::Model { key, message } => case_err(path, &key, message),
        other => other,
    }
}

impl CaseFile {
    /// The key that sets each region's node count, for the budget's message.
    fn size_keys(&self) -> Vec<String> {
        self.region
            .iter()
            .enumerate()
            .map(|(r, reg)| match (&self.mesh, &reg.cells) {
                (Some(_), _) => "mesh.file".to_string(),
                (None, Some(_)) => format!("region[{r}].cells"),
                (None, None) => format!("region[{r}].spacing"),
            })
            .collect()
    }

    /// The built-in box geometry of `[domain]` and the `[[region]]` boxes.
    fn box_geometry(
        &self,
        path: &Path,
        d: &DomainSpec,
        tau: f64,
        rules: &[(HorizonRule, u16)],
    ) -> Result<BoxGeometry> {
        let dim = self.dimension;
        let err = |key: &str, m: String| case_err(path, key, m);
        let dmin = coords(path, dim, &d.min, "domain.min")?;
        let dmax = coords(path, dim, &d.max, "domain.max")?;
        for a in 0..dim {
            if dmax[a] <= dmin[a] {
                return Err(err(
                    "domain.max",
                    "must exceed domain.min on every axis".into(),
                ));
            }
        }
        let mut regions = Vec::new();
        for (r, reg) in self.region.iter().enumerate() {
            let key = |k: &str| format!("region[{r}].{k}");
            let rmin = match &reg.min {
                Some(v) => coords(path, dim, v, &key("min"))?,
                None => dmin,
            };
            let rmax = match &reg.max {
                Some(v) => coords(path, dim, v, &key("max"))?,
                None => dmax,
            };
            for a in 0..dim {
                if rmax[a] <= rmin[a] {
                    return Err(err(&key("max"), "must exceed min on every axis".into()));
                }
            }
            let mut cells = [1usize; 3];
            match (&reg.spacing, &reg.cells) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        &key("spacing"),
                        "give spacing or cells, not both".into(),
                    ))
                }
                (None, None) => {
                    return Err(err(
                        &key("spacing"),
                        "missing: give spacing or cells".into(),
                    ))
                }
                (Some(h), None) => {
                    let h = positive(path, &key("spacing"), *h)?;
                    for a in 0..dim {
                        let n = (rmax[a] - rmin[a]) / h;
                        let nr = n.round();
                        if nr < 1.0 || (n - nr).abs() > 1e-6 * n {
                            return Err(err(
                                &key("spacing"),
                                format!(
                                    "{h} does not divide the region's side {} into whole cells",
                                    rmax[a] - rmin[a]
                                ),
                            ));
                        }
                        cells[a] = nr as usize;
                    }
                }
                (None, Some(c)) => {
                    if c.len() != dim || c.contains(&0) {
                        return Err(err(&key("cells"), format!("needs {dim} positive counts")));
                    }
                    cells[..dim].copy_from_slice(c);
                }
            }
            let region = BoxRegion {
                name: reg.name.clone(),
                min: rmin,
                max: rmax,
                cells,
                horizon: rules[r].0,
                material: rules[r].1,
            };
            peritherm_core::budget::check_horizon(dim, region.spacing(), &region.horizon)
                .map_err(|m| err(&horizon_key(r, reg), m))?;
            regions.push(region);
        }
        let g = BoxGeometry {
            dim,
            tau,
            min: dmin,
            max: dmax,
            boundary_placement: d.placement == Placement::Boundary,
            regions,
        };
        g.validate().map_err(|e| in_case(path, e))?;
        Ok(g)
    }

    /// The geometry of `[mesh]`: reads the gmsh file and maps `[[region]]` names to groups.
    fn mesh_geometry(
        &self,
        path: &Path,
        m: &MeshSpec,
        tau: f64,
        rules: &[(HorizonRule, u16)],
    ) -> Result<MeshGeometry> {
        let dim = self.dimension;
        let file = beside(path, &m.file);
        let mesh =
            crate::gmsh::read(&file).map_err(|e| case_err(path, "mesh.file", e.to_string()))?;
        if mesh.dim() != dim {
            return Err(case_err(
                path,
                "dimension",
                format!(
                    "is {dim} but the mesh {} has {}D elements",
                    file.display(),
                    mesh.dim()
                ),
            ));
        }
        let scale = positive(path, "mesh.scale", m.scale.unwrap_or(1.0))?;
        if let Some(r) = m.horizon_ratio {
            if !(r.is_finite() && r > 1.0) {
                return Err(case_err(
                    path,
                    "mesh.horizon_ratio",
                    format!("must be a number > 1, got {r}"),
                ));
            }
        }
        let mut regions = Vec::new();
        for (r, reg) in self.region.iter().enumerate() {
            let key = |k: &str| format!("region[{r}].{k}");
            for (k, present) in [
                ("min", reg.min.is_some()),
                ("max", reg.max.is_some()),
                ("spacing", reg.spacing.is_some()),
                ("cells", reg.cells.is_some()),
            ] {
                if present {
                    return Err(case_err(
                        path,
                        &key(k),
                        "does not apply to a mesh: the elements give positions and spacings",
                    ));
                }
            }
            let group = mesh.group(dim, &reg.name).ok_or_else(|| {
                let have: Vec<&str> = mesh
                    .groups
                    .iter()
                    .filter(|g| g.dim == dim)
                    .map(|g| g.name.as_str())
                    .collect();
                case_err(
                    path,
                    &key("name"),
                    format!(
                        "`{}` is not a {dim}D physical group of the mesh; it has {have:?}",
                        reg.name
                    ),
                )
            })?;
            regions.push(MeshRegion {
                name: reg.name.clone(),
                group,
                horizon: rules[r].0,
                material: rules[r].1,
            });
        }
        Ok(MeshGeometry {
            mesh: std::sync::Arc::new(mesh),
            scale,
            tau,
            regions,
            horizon_ratio: m.horizon_ratio,
        })
    }

    /// The `[[crack]]` entries.
    fn cracks(
        &self,
        path: &Path,
        dim: usize,
        set_names: &[String],
        geometry: &Geometry,
        faces: &[FaceBc],
    ) -> Result<Vec<Crack>> {
        let mut out = Vec::new();
        for (c, spec) in self.crack.iter().enumerate() {
            let key = |k: &str| format!("crack[{c}].{k}");
            let mu = spec.conductance.unwrap_or(0.0);
            if !(0.0..1.0).contains(&mu) {
                return Err(case_err(
                    path,
                    &key("conductance"),
                    format!("must be in [0, 1), got {mu}"),
                ));
            }
            let shape = match (&spec.group, &spec.points) {
                (Some(g), None) => {
                    if !matches!(geometry, Geometry::Mesh(_)) {
                        return Err(case_err(
                            path,
                            &key("group"),
                            "needs a [mesh]; a box case gives points",
                        ));
                    }
                    let s = set_names.iter().position(|n| n == g).ok_or_else(|| {
                        case_err(path, &key("group"), format!("`{g}` is not a physical group of dimension {}; the mesh has {set_names:?}", dim - 1))
                    })?;
                    if faces[s] != FaceBc::Free {
                        return Err(case_err(
                            path,
                            &key("group"),
                            format!("`{g}` also has a [boundary.{g}] condition"),
                        ));
                    }
                    if let Geometry::Mesh(m) = geometry {
                        if m.set_is_empty(s) {
                            return Err(case_err(
                                path,
                                &key("group"),
                                format!("the mesh's group `{g}` has no elements"),
                            ));
                        }
                    }
                    CrackShape::Set(s)
                }
                (None, Some(pts)) => {
                    if dim == 1 {
                        return Err(case_err(
                            path,
                            &key("points"),
                            "a 1D crack is a mesh point group",
                        ));
                    }
                    let need = if dim == 2 { 2 } else { 3 };
                    if pts.len() < need {
                        return Err(case_err(
                            path,
                            &key("points"),
                            format!("needs at least {need} points"),
                        ));
                    }
                    let list = crack_points(path, c, dim, pts, geometry)?;
                    if dim == 2 {
                        CrackShape::Polyline(list)
                    } else {
                        let n = (list[1] - list[0]).cross(&(list[2] - list[0]));
                        let size = (list[1] - list[0]).norm().max((list[2] - list[0]).norm());
                        let planar = list
                            .iter()
                            .all(|p| (p - list[0]).dot(&n).abs() <= 1e-9 * n.norm() * size);
                        if n.norm() <= 1e-12 * size * size || !planar {
                            return Err(case_err(
                                path,
                                &key("points"),
                                "a 3D crack is a planar polygon: its points must span one plane",
                            ));
                        }
                        CrackShape::Polygon(list)
                    }
                }
                _ => {
                    return Err(case_err(
                        path,
                        &format!("crack[{c}]"),
                        "give either group or points",
                    ))
                }
            };
            let growth = match spec.speed {
                None => {
                    for (k, present) in [
                        ("start", spec.start.is_some()),
                        ("initial_length", spec.initial_length.is_some()),
                    ] {
                        if present {
                            return Err(case_err(
                                path,
                                &key(k),
                                "applies to a growing crack: give speed too",
                            ));
                        }
                    }
                    None
                }
                Some(v) => {
                    if spec.points.is_none() {
                        return Err(case_err(
                            path,
                            &key("speed"),
                            "a growing crack follows a polyline: give points",
                        ));
                    }
                    let start = spec.start.unwrap_or(0.0);
                    if !(start.is_finite() && start >= 0.0) {
                        return Err(case_err(
                            path,
                            &key("start"),
                            format!("must be a time >= 0, got {start}"),
                        ));
                    }
                    let initial = spec.initial_length.unwrap_or(0.0);
                    if !(initial.is_finite() && initial >= 0.0) {
                        return Err(case_err(
                            path,
                            &key("initial_length"),
                            format!("must be a length >= 0, got {initial}"),
                        ));
                    }
                    let total = match &shape {
                        CrackShape::Polyline(p) => p.windows(2).map(|w| (w[1] - w[0]).norm()).sum(),
                        _ => f64::INFINITY,
                    };
                    if initial > total {
                        return Err(case_err(
                            path,
                            &key("initial_length"),
                            format!("{initial} m exceeds the length of the path, {total} m"),
                        ));
                    }
                    Some(Growth {
                        start,
                        speed: positive(path, &key("speed"), v)?,
                        initial,
                        arc: 0.0,
                    })
                }
            };
            out.push(Crack { shape, mu, growth });
        }
        Ok(out)
    }

    fn validate(self, path: &Path) -> Result<Case> {
        let err = |key: &str, m: String| case_err(path, key, m);
        let dim = self.dimension;
        let size_keys = self.size_keys();
        if !(1..=3).contains(&dim) {
            return Err(err("dimension", format!("must be 1, 2 or 3, got {dim}")));
        }
        let (section, thickness, area) = match (&self.domain, &self.mesh) {
            (Some(d), None) => ("domain", d.thickness, d.area),
            (None, Some(m)) => ("mesh", m.thickness, m.area),
            (Some(_), Some(_)) => {
                return Err(err(
                    "mesh",
                    "give [domain] (a built-in box) or [mesh] (a gmsh file), not both".into(),
                ))
            }
            (None, None) => {
                return Err(err(
                    "domain",
                    "missing: give [domain] with box regions, or [mesh] with a gmsh file".into(),
                ))
            }
        };
        if !self.symmetry.allows_dimension(dim) {
            return Err(err(
                "symmetry",
                format!(
                    "{} symmetry needs dimension {}, got {dim}",
                    self.symmetry.name(),
                    if self.symmetry == Symmetry::Spherical {
                        "1"
                    } else {
                        "1 or 2"
                    }
                ),
            ));
        }
        let asked = self.kernel.linear_consistency
            || self.kernel.consistency.is_some_and(|o| o != Order::None);
        if self.symmetry.is_symmetric() && asked {
            return Err(err(
                if self.kernel.linear_consistency {
                    "kernel.linear_consistency"
                } else {
                    "kernel.consistency"
                },
                format!(
                    "does not apply with symmetry = \"{}\": the correction zeroes every node's first moment Σ K_ij ξ_ij, which the ring/shell pair factors must keep (it carries the (1/r)∂θ/∂r term, Bobaru & Duangpanya's axisymmetric form, doi:10.1007/s42102-022-00092-3 eqs 10, 21)",
                    self.symmetry.name()
                ),
            ));
        }
        if self.kernel.linear_consistency && self.kernel.consistency.is_some() {
            return Err(err(
                "kernel.linear_consistency",
                "give either linear_consistency or consistency, not both".to_string(),
            ));
        }
        if self.symmetry.is_symmetric() && (thickness.is_some() || area.is_some()) {
            return Err(err(
                &format!("{section}.{}", if dim == 1 { "area" } else { "thickness" }),
                format!(
                    "does not apply to a {} body: its nodes are rings or shells of measure 2πr or 4πr² per planar cell",
                    self.symmetry.name()
                ),
            ));
        }
        let tau = match dim {
            1 => {
                if thickness.is_some() {
                    return Err(err(
                        &format!("{section}.thickness"),
                        "is for 2D; a 1D bar takes area".into(),
                    ));
                }
                positive(path, &format!("{section}.area"), area.unwrap_or(1.0))?
            }
            2 => {
                if area.is_some() {
                    return Err(err(
                        &format!("{section}.area"),
                        "is for 1D; a 2D body takes thickness".into(),
                    ));
                }
                positive(
                    path,
                    &format!("{section}.thickness"),
                    thickness.unwrap_or(1.0),
                )?
            }
            _ => {
                if area.is_some() || thickness.is_some() {
                    return Err(err(
                        section,
                        "a 3D body takes neither area nor thickness".into(),
                    ));
                }
                1.0
            }
        };
        if self.material.is_empty() {
            return Err(err(
                "material",
                "define at least one [material.<name>]".into(),
            ));
        }
        let names: Vec<&String> = self.material.keys().collect();
        let mut materials = Vec::new();
        for (name, m) in &self.material {
            m.check()
                .map_err(|(key, message)| err(&format!("material.{name}.{key}"), message))?;
            materials.push(*m);
        }
        if self.region.is_empty() {
            return Err(err("region", "define at least one [[region]]".into()));
        }
        let mut per_region_initial = Vec::new();
        let mut rules = Vec::new();
        for (r, reg) in self.region.iter().enumerate() {
            let key = |k: &str| format!("region[{r}].{k}");
            if let Some(first) = self.region[..r].iter().position(|o| o.name == reg.name) {
                return Err(err(
                    &key("name"),
                    format!("`{}` is also the name of region[{first}]", reg.name),
                ));
            }
            let horizon = match reg.horizon {
                HorizonSpec::Factor(n) => {
                    HorizonRule::Factor(positive(path, &key("horizon.factor"), n)?)
                }
                HorizonSpec::Radius(d) => {
                    HorizonRule::Radius(positive(path, &key("horizon.radius"), d)?)
                }
            };
            let material = match &reg.material {
                Some(m) => names.iter().position(|n| *n == m).ok_or_else(|| {
                    err(
                        &key("material"),
                        format!("unknown material `{m}`; defined: {names:?}"),
                    )
                })?,
                None if names.len() == 1 => 0,
                None => {
                    return Err(err(
                        &key("material"),
                        "several materials are defined: name one".into(),
                    ))
                }
            };
            per_region_initial.push(reg.initial);
            rules.push((horizon, material as u16));
        }
        let geometry = match (&self.domain, &self.mesh) {
            (Some(d), _) => Geometry::Box(self.box_geometry(path, d, tau, &rules)?),
            (_, Some(m)) => Geometry::Mesh(self.mesh_geometry(path, m, tau, &rules)?),
            (None, None) => unreachable!("checked above"),
        };
        let set_names: Vec<String> = match &geometry {
            Geometry::Box(_) => FACE_NAMES[..2 * dim]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            Geometry::Mesh(g) => g.set_names(),
        };
        if self.kernel.p != 1 && self.kernel.p != 2 {
            return Err(err(
                "kernel.p",
                format!("must be 1 or 2, got {}", self.kernel.p),
            ));
        }
        let kernel = Kernel {
            p: self.kernel.p,
            profile: self.kernel.profile,
            partial_volume: self.kernel.partial_volume,
            calibration: self.kernel.calibration,
        };
        let mesh = matches!(geometry, Geometry::Mesh(_));
        let mut faces = match &geometry {
            Geometry::Box(_) => vec![FaceBc::Free; 6],
            // the groups' sets, then the facets that no group names
            Geometry::Mesh(_) => vec![FaceBc::Free; set_names.len() + 1],
        };
        for (name, b) in &self.boundary {
            let key = |k: &str| format!("boundary.{name}.{k}");
            // on a mesh, `[boundary."(no group)"]` names the facets in no group
            let unnamed =
                (mesh && name == peritherm_core::cloud::mesh::UNNAMED).then_some(set_names.len());
            let f = set_names.iter().position(|n| n == name).or(unnamed).ok_or_else(|| {
                let what = match &geometry {
                    Geometry::Box(_) if FACE_NAMES.contains(&name.as_str()) => {
                        format!("a {dim}D case has faces {set_names:?}")
                    }
                    Geometry::Box(_) => format!("unknown face; use one of {set_names:?}"),
                    Geometry::Mesh(_) => format!(
                        "no physical group of dimension {} has this name; the mesh has {set_names:?}",
                        dim - 1
                    ),
                };
                err(&format!("boundary.{name}"), what)
            })?;
            if let Geometry::Mesh(g) = &geometry {
                if unnamed.is_none() && g.set_is_empty(f) {
                    return Err(err(
                        &format!("boundary.{name}"),
                        "the mesh's physical group of this name has no elements".into(),
                    ));
                }
            }
            let value = |required: bool| -> Result<Option<Expr>> {
                match &b.value {
                    Some(v) => Ok(Some(expr(v, path, &key("value"))?)),
                    None if required => Err(err(&key("value"), "missing".into())),
                    None => Ok(None),
                }
            };
            let method = b.method.as_deref();
            let bad_method = |allowed: &str| {
                err(
                    &key("method"),
                    format!("`{}` is not one of {allowed}", method.unwrap_or("")),
                )
            };
            let unused = |k: &str, present: bool| -> Result<()> {
                if present {
                    Err(err(
                        &key(k),
                        format!("does not apply to type = \"{:?}\"", b.kind).to_lowercase(),
                    ))
                } else {
                    Ok(())
                }
            };
            let nodal = match method {
                Some(m) => m == "nodal",
                None => !mesh,
            };
            unused(
                "layers",
                b.layers.is_some() && !(b.kind == BoundaryKind::Temperature && nodal),
            )?;
            unused("h", b.h.is_some() && b.kind != BoundaryKind::Convection)?;
            unused(
                "ambient",
                b.ambient.is_some() && b.kind != BoundaryKind::Convection,
            )?;
            faces[f] = match b.kind {
                BoundaryKind::Free => {
                    unused("value", b.value.is_some())?;
                    FaceBc::Free
                }
                BoundaryKind::Temperature => {
                    let v = value(true)?.expect("required");
                    match method {
                        // element centroids never lie on a mesh's boundary: hold a mirror
                        None if mesh => FaceBc::LayerTemperature {
                            value: v,
                            layer: Layer::Mirror,
                        },
                        None | Some("nodal") => {
                            let layers = b.layers.unwrap_or(1.0);
                            if !(layers >= 1.0 && layers.fract() == 0.0) {
                                return Err(err(
                                    &key("layers"),
                                    format!("must be a whole number >= 1, got {layers}"),
                                ));
                            }
                            FaceBc::NodalTemperature { value: v, layers }
                        }
                        Some("mirror") => FaceBc::LayerTemperature {
                            value: v,
                            layer: Layer::Mirror,
                        },
                        Some("naive") => FaceBc::LayerTemperature {
                            value: v,
                            layer: Layer::Naive,
                        },
                        _ => return Err(bad_method("nodal, mirror, naive")),
                    }
                }
                BoundaryKind::Insulated => {
                    unused("value", b.value.is_some())?;
                    match method {
                        None | Some("mirror") => FaceBc::LayerInsulated,
                        Some("free") => FaceBc::Free,
                        _ => return Err(bad_method("mirror, free")),
                    }
                }
                BoundaryKind::Flux => {
                    let v = value(true)?.expect("required");
                    match method {
                        None | Some("mirror") => FaceBc::LayerFlux { value: v },
                        Some("relation") => FaceBc::RelationFlux { value: v },
                        _ => return Err(bad_method("mirror, relation")),
                    }
                }
                BoundaryKind::Convection => {
                    unused("value", b.value.is_some())?;
                    let h = positive(
                        path,
                        &key("h"),
                        b.h.ok_or_else(|| err(&key("h"), "missing".into()))?,
                    )?;
                    let amb = b
                        .ambient
                        .as_ref()
                        .ok_or_else(|| err(&key("ambient"), "missing".into()))?;
                    let ambient = expr(amb, path, &key("ambient"))?;
                    match method {
                        None | Some("surface") => FaceBc::Convection { h, ambient },
                        Some("mirror") => FaceBc::LayerConvection { h, ambient },
                        _ => return Err(bad_method("surface, mirror")),
                    }
                }
            };
        }
        let base = match &self.initial.value {
            Some(v) => expr(v, path, "initial.value")?,
            None => Expr::constant(0.0),
        };
        if !base.is_time_independent() {
            return Err(err("initial.value", "must not depend on t".into()));
        }
        let initial = if per_region_initial.iter().any(Option::is_some) {
            if !base.is_uniform() {
                return Err(err(
                    "region.initial",
                    "cannot be combined with an [initial] expression of x, y, z".into(),
                ));
            }
            let b0 = base.eval(0.0, 0.0, 0.0, 0.0);
            Initial::PerRegion(per_region_initial.iter().map(|v| v.unwrap_or(b0)).collect())
        } else {
            Initial::Field(base)
        };
        let source = match &self.source {
            Some(s) => Some(expr(&s.value, path, "source.value")?),
            None => None,
        };
        let end = positive(path, "time.end", self.time.end)?;
        if let Some(dt) = self.time.dt {
            positive(path, "time.dt", dt)?;
        }
        let mut outputs = self.time.outputs.clone();
        if outputs.is_empty() {
            outputs.push(end);
        }
        for (k, &t) in outputs.iter().enumerate() {
            if !(t > 0.0 && t <= end * (1.0 + 1e-12)) {
                return Err(err(
                    &format!("time.outputs[{k}]"),
                    format!("{t} is not in (0, time.end = {end}]"),
                ));
            }
            if k > 0 && t <= outputs[k - 1] {
                return Err(err(
                    &format!("time.outputs[{k}]"),
                    "output times must increase".into(),
                ));
            }
        }
        let cracks = self.cracks(path, dim, &set_names, &geometry, &faces)?;
        if let Geometry::Mesh(g) = &geometry {
            unnamed_insulated(&mut faces, g, &self.boundary, &cracks);
        }
        let reference = match self.reference {
            Some(r) => Some(reference(r, path, dim, &outputs)?),
            None => None,
        };
        let integrator =
            self.time
                .integrator
                .unwrap_or(if materials.iter().any(|m| m.phase_change.is_some()) {
                    Integrator::Euler
                } else {
                    Integrator::Rk4
                });
        if let Some(tol) = self.time.tolerance {
            positive(path, "time.tolerance", tol)?;
            if !matches!(
                integrator,
                Integrator::BackwardEuler | Integrator::CrankNicolson | Integrator::Bdf2
            ) {
                return Err(err(
                    "time.tolerance",
                    format!(
                        "adaptive steps are an option of backward_euler, crank_nicolson and bdf2, not of {}",
                        integrator.name()
                    ),
                ));
            }
            if materials.iter().any(|m| m.phase_change.is_some()) {
                return Err(err(
                    "time.tolerance",
                    "adaptive steps need a linear material; phase change is integrated by euler"
                        .into(),
                ));
            }
        }
        if let Some(h) = self.time.dt_max {
            positive(path, "time.dt_max", h)?;
            if self.time.tolerance.is_none() {
                return Err(err(
                    "time.dt_max",
                    "bounds adaptive steps only: give time.tolerance too".into(),
                ));
            }
            if let Some(dt) = self.time.dt.filter(|&dt| dt > h) {
                return Err(err(
                    "time.dt",
                    format!("the first adaptive step {dt} exceeds time.dt_max = {h}"),
                ));
            }
        }
        let spec = ModelSpec {
            geometry,
            materials,
            kernel,
            bond_rule: self.kernel.bond_rule,
            faces,
            cracks,
            source,
            initial,
            consistency: self
                .kernel
                .order(self.mesh.is_some() && !self.symmetry.is_symmetric()),
            crack_correction: self.kernel.crack_correction,
            symmetry: self.symmetry,
        };
        let history = match self.history {
            Some(h) => Some(history(h, path, dim, &outputs, integrator)?),
            None => None,
        };
        let budget = peritherm_core::budget::estimate(&spec, &size_keys, integrator.is_implicit())
            .map_err(|e| in_case(path, e))?;
        Ok(Case {
            path: path.to_path_buf(),
            title: self.title,
            spec,
            budget,
            integrator,
            dt: self.time.dt,
            tolerance: self.time.tolerance,
            dt_max: self.time.dt_max,
            end,
            outputs,
            reference,
            history,
            source: String::new(),
            inputs: Vec::new(),
            settings: Vec::new(),
        })
    }

    /// The files besides itself that the case at `path` reads, resolved against its folder.
    fn inputs(&self, path: &Path) -> Vec<PathBuf> {
        let reference = self.reference.as_ref();
        let table = reference.and_then(|r| r.file.as_ref());
        let fem_mesh = reference
            .and_then(|r| r.fem.as_ref())
            .and_then(|f| f.mesh.as_ref());
        let mesh = self.mesh.as_ref().map(|m| &m.file);
        [mesh, table, fem_mesh]
            .into_iter()
            .flatten()
            .map(|f| beside(path, f))
            .collect()
    }
}
