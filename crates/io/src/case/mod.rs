//! Case files: the TOML schema, its validation, and the conversion to a [`ModelSpec`].
//!
//! Every key is documented in docs/case-reference.md. Unknown keys, missing
//! fields and out-of-range values are errors that name the file and the key. Each section
//! has its module: its schema types (read by serde) and a small validator that turns them
//! into the model's types.

mod body;
mod boundary;
mod crack;
mod history;
mod kernel;
mod reference;
mod time;

pub use body::{DomainSpec, HorizonSpec, MeshSpec, Placement, RegionSpec};
pub use boundary::{
    BoundarySpec, ConvectionBc, ConvectionMethod, FluxBc, FluxMethod, FreeBc, InsulatedBc,
    InsulatedMethod, TemperatureBc, TemperatureMethod,
};
pub use crack::CrackSpec;
pub use history::HistorySection;
pub use kernel::KernelSpec;
pub use reference::{FemReferenceSpec, ReferenceSection, ReferenceSource, ReferenceSpec};
pub use time::{InitialSpec, SourceSpec, TimeSpec};

use crate::error::{CoreError, Error, Result};
use crate::history::HistorySpec;
use peritherm_core::expr::Expr;
use peritherm_core::material::Material;
use peritherm_core::math::Point;
use peritherm_core::model::{Geometry, ModelSpec};
use peritherm_core::solve::Integrator;
use peritherm_core::symmetry::Symmetry;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A number or an expression string.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged, expecting = "expected a number or an expression string")]
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
    /// `planar` (default), `axisymmetric` (x = r, y = z) or `spherical` (x = r); PCS2022
    /// (doi:10.1007/s42102-022-00092-3).
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
        Ctx::new(&self.path).err(key, message)
    }

    /// A library error keyed to this case file: a model error's key becomes a key of the
    /// file; every other error is returned as it is.
    pub fn keyed(&self, e: impl Into<Error>) -> Error {
        Ctx::new(&self.path).keyed(e)
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
        let text = std::fs::read_to_string(path)
            .map_err(|e| Ctx::new(path).err("-", format!("cannot read: {e}")))?;
        Case::parse(&text, path)
    }

    /// Parses and validates case text; `path` is used in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Case> {
        let file: CaseFile = toml::from_str(text).map_err(|e| parse_error(text, path, &e))?;
        let inputs = file.inputs(path);
        let mut case = file.validate(path)?;
        case.source = text.to_string();
        case.inputs = inputs;
        Ok(case)
    }
}

/// A TOML syntax or schema error as one line keyed by its line in `text`; a schema error
/// also names the dotted key it is about (`unknown field `h`, expected … (in boundary.left)`).
fn parse_error(text: &str, path: &Path, e: &toml::de::Error) -> Error {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
        .unwrap_or(0);
    // a field of a `type`-tagged table names itself (see `named`)
    let (field, msg) = match e.message().split_once(named::MARK) {
        Some((field, msg)) => (Some(field), msg),
        None => (None, e.message()),
    };
    let msg = msg.replace('\n', " ");
    // without its input, the error's text ends with the dotted keys it was found under
    let mut bare = e.clone();
    bare.set_input(None);
    let shown = bare.to_string();
    let table = shown
        .trim_end()
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("in `")?.strip_suffix('`'))
        .filter(|k| !k.is_empty());
    let keys: Vec<&str> = table.into_iter().chain(field).collect();
    let message = match keys.is_empty() {
        true => msg.trim().to_string(),
        false => format!("{} (in {})", msg.trim(), keys.join(".")),
    };
    Ctx::new(path).err(format!("line {line}"), message)
}

/// Field deserializers that name their key in the error: serde's errors inside a `type`-tagged
/// table (buffered before its variant is known) say neither key nor line; [`parse_error`] reads
/// the name back.
mod named {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer};

    /// Separates the key from serde's message.
    pub(super) const MARK: char = '\u{1f}';

    /// `T`, or serde's error prefixed with `key` and [`MARK`].
    fn field<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
        key: &str,
    ) -> Result<T, D::Error> {
        T::deserialize(d).map_err(|e| D::Error::custom(format!("{key}{MARK}{e}")))
    }

    /// The key `method`.
    pub(super) fn method<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        field(d, "method")
    }

    /// The key `value`.
    pub(super) fn value<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        field(d, "value")
    }

    /// The key `layers`.
    pub(super) fn layers<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        field(d, "layers")
    }

    /// The key `h`.
    pub(super) fn h<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
        field(d, "h")
    }

    /// The key `ambient`.
    pub(super) fn ambient<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        field(d, "ambient")
    }
}

/// The case file under validation: every error names it and a dotted key.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    /// The case file.
    path: &'a Path,
}

impl<'a> Ctx<'a> {
    fn new(path: &'a Path) -> Self {
        Ctx { path }
    }

    /// An error about `key` of the case file.
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Case {
            file: self.path.to_path_buf(),
            key: key.into(),
            message: message.into(),
        }
    }

    /// A model error's key becomes a key of the case file; other errors pass unchanged.
    fn keyed(&self, e: impl Into<Error>) -> Error {
        match e.into() {
            Error::Core(CoreError::Model { key, message }) => self.err(key, message),
            other => other,
        }
    }

    /// `file` (as a case file writes it) resolved against the case file's folder.
    fn beside(&self, file: &Path) -> PathBuf {
        beside(self.path, file)
    }

    /// `v` when it is a positive normal number (subnormals underflow in any product).
    fn positive(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_normal() && v > 0.0 {
            Ok(v)
        } else if v != 0.0 && !(1e-6..1e9).contains(&v.abs()) {
            Err(self.err(key, format!("must be a positive number, got {v:e}")))
        } else {
            Err(self.err(key, format!("must be a positive number, got {v}")))
        }
    }

    /// The value of the one key given among `options` (each key's value, None where it is
    /// absent), of keys of which at most one may be given: None when none is, and the error
    /// `several` (dotted key, message) when more than one is.
    fn at_most_one<T, const N: usize>(
        &self,
        options: [Option<T>; N],
        several: (&str, &str),
    ) -> Result<Option<T>> {
        let mut given = options.into_iter().flatten();
        let one = given.next();
        match given.next() {
            Some(_) => Err(self.err(several.0, several.1)),
            None => Ok(one),
        }
    }

    /// [`Ctx::at_most_one`] of keys one of which must be given: the error `missing` (dotted
    /// key, message) when none is.
    fn exactly_one<T, const N: usize>(
        &self,
        options: [Option<T>; N],
        several: (&str, &str),
        missing: (&str, &str),
    ) -> Result<T> {
        self.at_most_one(options, several)?
            .ok_or_else(|| self.err(missing.0, missing.1))
    }

    /// `v` as a point of `dim` finite coordinates (the others 0).
    fn coords(&self, dim: usize, v: &[f64], key: &str) -> Result<[f64; 3]> {
        if v.len() != dim {
            return Err(self.err(key, format!("needs {dim} coordinates, got {}", v.len())));
        }
        let mut p = [0.0; 3];
        for (a, x) in v.iter().enumerate() {
            if !x.is_finite() {
                return Err(self.err(key, "coordinates must be finite"));
            }
            p[a] = *x;
        }
        Ok(p)
    }

    /// [`Ctx::coords`] as a [`Point`].
    fn point(&self, dim: usize, v: &[f64], key: &str) -> Result<Point> {
        let c = self.coords(dim, v, key)?;
        Ok(Point::new(c[0], c[1], c[2]))
    }

    /// A finite constant or a parsed expression.
    fn expr(&self, v: &ValueSpec, key: &str) -> Result<Expr> {
        match v {
            ValueSpec::Number(x) if x.is_finite() => Ok(Expr::constant(*x)),
            ValueSpec::Number(x) => Err(self.err(key, format!("must be finite, got {x}"))),
            ValueSpec::Expr(s) => Expr::parse(s).map_err(|e| self.err(key, e.to_string())),
        }
    }
}

/// `file` (as a case file writes it) resolved against the folder of the case file `path`.
fn beside(path: &Path, file: &Path) -> PathBuf {
    path.parent().unwrap_or(Path::new(".")).join(file)
}

impl CaseFile {
    /// Validates every section in turn and assembles the [`Case`].
    fn validate(self, path: &Path) -> Result<Case> {
        let cx = Ctx::new(path);
        let size_keys = self.size_keys();
        let body = self.body(cx)?;
        let materials = kernel::materials(cx, &self.material)?;
        let regions = body::regions(cx, &self.region, &self.material)?;
        let geometry = self.geometry(cx, body.tau, &regions.rules)?;
        let set_names = body::set_names(&geometry, body.dim);
        let kernel = self.kernel.validate(cx)?;
        let mut faces = boundary::faces(cx, &self.boundary, &geometry, &set_names, body.dim)?;
        let initial = time::initial(cx, &self.initial, &regions.initial)?;
        let source = match &self.source {
            Some(s) => Some(cx.expr(&s.value, "source.value")?),
            None => None,
        };
        let (end, outputs) = self.time.outputs(cx)?;
        let cracks = crack::cracks(cx, &self.crack, body.dim, &set_names, &geometry, &faces)?;
        if let Geometry::Mesh(g) = &geometry {
            boundary::unnamed_insulated(&mut faces, g, &self.boundary, &cracks);
        }
        let reference = match self.reference {
            Some(r) => Some(r.validate(cx, body.dim, &outputs)?),
            None => None,
        };
        let integrator = self.time.integrator(cx, &materials)?;
        let step = self.kernel.step(cx, integrator, &materials)?;
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
            step,
        };
        let history = match self.history {
            Some(h) => Some(h.validate(cx, body.dim, &outputs, integrator)?),
            None => None,
        };
        let budget = peritherm_core::budget::estimate(&spec, &size_keys, integrator.is_implicit())
            .map_err(|e| cx.keyed(e))?;
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

#[cfg(test)]
mod tests;
