//! The body: `dimension`, `symmetry`, `[domain]` or `[mesh]`, and the `[[region]]` entries.

use super::{CaseFile, Ctx};
use crate::error::Result;
use peritherm_core::cloud::mesh::{MeshGeometry, MeshRegion};
use peritherm_core::cloud::{BoxGeometry, BoxRegion, HorizonRule, FACE_NAMES};
use peritherm_core::material::Material;
use peritherm_core::model::Geometry;
use peritherm_core::symmetry::Symmetry;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

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

/// The validated dimension and measure of the body.
pub(super) struct Body {
    /// Spatial dimension, 1..=3.
    pub dim: usize,
    /// Measure per planar cell: a 1D bar's area, a 2D body's thickness, 1 in 3D.
    pub tau: f64,
}

/// The validated `[[region]]` entries: horizon rule and material of each, and their initial
/// temperatures.
pub(super) struct Regions {
    /// Horizon rule and material index of each region.
    pub rules: Vec<(HorizonRule, u16)>,
    /// Each region's initial temperature, °C, if given.
    pub initial: Vec<Option<f64>>,
}

/// The dotted key of region `r`'s horizon rule, `region[r].horizon.factor` or `.radius`.
fn horizon_key(r: usize, reg: &RegionSpec) -> String {
    match reg.horizon {
        HorizonSpec::Factor(_) => format!("region[{r}].horizon.factor"),
        HorizonSpec::Radius(_) => format!("region[{r}].horizon.radius"),
    }
}

/// The boundary sets' names: a box's faces, a mesh's lower-dimensional groups.
pub(super) fn set_names(geometry: &Geometry, dim: usize) -> Vec<String> {
    match geometry {
        Geometry::Box(_) => FACE_NAMES[..2 * dim]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        Geometry::Mesh(g) => g.set_names(),
    }
}

/// Validates the `[[region]]` entries: unique names, positive horizons, known materials.
pub(super) fn regions(
    cx: Ctx,
    regions: &[RegionSpec],
    materials: &BTreeMap<String, Material>,
) -> Result<Regions> {
    if regions.is_empty() {
        return Err(cx.err("region", "define at least one [[region]]"));
    }
    let names: Vec<&String> = materials.keys().collect();
    let mut out = Regions {
        rules: Vec::new(),
        initial: Vec::new(),
    };
    for (r, reg) in regions.iter().enumerate() {
        let key = |k: &str| format!("region[{r}].{k}");
        if let Some(first) = regions[..r].iter().position(|o| o.name == reg.name) {
            return Err(cx.err(
                key("name"),
                format!("`{}` is also the name of region[{first}]", reg.name),
            ));
        }
        let horizon = match reg.horizon {
            HorizonSpec::Factor(n) => HorizonRule::Factor(cx.positive(&key("horizon.factor"), n)?),
            HorizonSpec::Radius(d) => HorizonRule::Radius(cx.positive(&key("horizon.radius"), d)?),
        };
        let material = match &reg.material {
            Some(m) => names.iter().position(|n| *n == m).ok_or_else(|| {
                cx.err(
                    key("material"),
                    format!("unknown material `{m}`; defined: {names:?}"),
                )
            })?,
            None if names.len() == 1 => 0,
            None => return Err(cx.err(key("material"), "several materials are defined: name one")),
        };
        out.initial.push(reg.initial);
        out.rules.push((horizon, material as u16));
    }
    Ok(out)
}

impl CaseFile {
    /// The key that sets each region's node count, for the budget's message.
    pub(super) fn size_keys(&self) -> Vec<String> {
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

    /// Validates `dimension`, `symmetry` and the measure (`area`, `thickness`) of `[domain]`
    /// or `[mesh]`, exactly one of which is given.
    pub(super) fn body(&self, cx: Ctx) -> Result<Body> {
        let dim = self.dimension;
        if !(1..=3).contains(&dim) {
            return Err(cx.err("dimension", format!("must be 1, 2 or 3, got {dim}")));
        }
        let (section, thickness, area) = cx.exactly_one(
            [
                self.domain
                    .as_ref()
                    .map(|d| ("domain", d.thickness, d.area)),
                self.mesh.as_ref().map(|m| ("mesh", m.thickness, m.area)),
            ],
            (
                "mesh",
                "give [domain] (a built-in box) or [mesh] (a gmsh file), not both",
            ),
            (
                "domain",
                "missing: give [domain] with box regions, or [mesh] with a gmsh file",
            ),
        )?;
        self.check_symmetry(cx, section, thickness.is_some() || area.is_some())?;
        let tau = match dim {
            1 if thickness.is_some() => Err(cx.err(
                format!("{section}.thickness"),
                "is for 2D; a 1D bar takes area",
            )),
            1 => cx.positive(&format!("{section}.area"), area.unwrap_or(1.0)),
            2 if area.is_some() => Err(cx.err(
                format!("{section}.area"),
                "is for 1D; a 2D body takes thickness",
            )),
            2 => cx.positive(&format!("{section}.thickness"), thickness.unwrap_or(1.0)),
            _ if area.is_some() || thickness.is_some() => {
                Err(cx.err(section, "a 3D body takes neither area nor thickness"))
            }
            _ => Ok(1.0),
        }?;
        Ok(Body { dim, tau })
    }

    /// A symmetric body: its dimension, no consistent weights, no area or thickness
    /// (`measure`: one of them is given in `section`).
    fn check_symmetry(&self, cx: Ctx, section: &str, measure: bool) -> Result<()> {
        let (dim, symmetry) = (self.dimension, self.symmetry);
        if !symmetry.allows_dimension(dim) {
            let need = if symmetry == Symmetry::Spherical {
                "1"
            } else {
                "1 or 2"
            };
            return Err(cx.err(
                "symmetry",
                format!(
                    "{} symmetry needs dimension {need}, got {dim}",
                    symmetry.name()
                ),
            ));
        }
        self.kernel.check_symmetry(cx, symmetry)?;
        if symmetry.is_symmetric() && measure {
            return Err(cx.err(
                format!("{section}.{}", if dim == 1 { "area" } else { "thickness" }),
                format!(
                    "does not apply to a {} body: its nodes are rings or shells of measure 2πr or 4πr² per planar cell",
                    symmetry.name()
                ),
            ));
        }
        Ok(())
    }

    /// The geometry of `[domain]` or `[mesh]` (`body` checked that exactly one is given).
    pub(super) fn geometry(
        &self,
        cx: Ctx,
        tau: f64,
        rules: &[(HorizonRule, u16)],
    ) -> Result<Geometry> {
        match (&self.domain, &self.mesh) {
            (Some(d), _) => Ok(Geometry::Box(self.box_geometry(cx, d, tau, rules)?)),
            (_, Some(m)) => Ok(Geometry::Mesh(self.mesh_geometry(cx, m, tau, rules)?)),
            (None, None) => unreachable!("checked by CaseFile::body"),
        }
    }

    /// The built-in box geometry of `[domain]` and the `[[region]]` boxes.
    fn box_geometry(
        &self,
        cx: Ctx,
        d: &DomainSpec,
        tau: f64,
        rules: &[(HorizonRule, u16)],
    ) -> Result<BoxGeometry> {
        let dim = self.dimension;
        let dmin = cx.coords(dim, &d.min, "domain.min")?;
        let dmax = cx.coords(dim, &d.max, "domain.max")?;
        if (0..dim).any(|a| dmax[a] <= dmin[a]) {
            return Err(cx.err("domain.max", "must exceed domain.min on every axis"));
        }
        let mut regions = Vec::new();
        for (r, reg) in self.region.iter().enumerate() {
            let region = box_region(cx, dim, r, reg, (dmin, dmax), rules[r])?;
            peritherm_core::budget::check_horizon(dim, region.spacing(), &region.horizon)
                .map_err(|m| cx.err(horizon_key(r, reg), m))?;
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
        g.validate().map_err(|e| cx.keyed(e))?;
        Ok(g)
    }

    /// The geometry of `[mesh]`: reads the gmsh file and maps `[[region]]` names to groups.
    fn mesh_geometry(
        &self,
        cx: Ctx,
        m: &MeshSpec,
        tau: f64,
        rules: &[(HorizonRule, u16)],
    ) -> Result<MeshGeometry> {
        let dim = self.dimension;
        let file = cx.beside(&m.file);
        let mesh = crate::gmsh::read(&file).map_err(|e| cx.err("mesh.file", e.to_string()))?;
        if mesh.dim() != dim {
            return Err(cx.err(
                "dimension",
                format!(
                    "is {dim} but the mesh {} has {}D elements",
                    file.display(),
                    mesh.dim()
                ),
            ));
        }
        let scale = cx.positive("mesh.scale", m.scale.unwrap_or(1.0))?;
        if let Some(r) = m.horizon_ratio.filter(|r| !(r.is_finite() && *r > 1.0)) {
            return Err(cx.err(
                "mesh.horizon_ratio",
                format!("must be a number > 1, got {r}"),
            ));
        }
        let mut regions = Vec::new();
        for (r, reg) in self.region.iter().enumerate() {
            regions.push(mesh_region(cx, &mesh, dim, r, reg, rules[r])?);
        }
        Ok(MeshGeometry {
            mesh: std::sync::Arc::new(mesh),
            scale,
            tau,
            regions,
            horizon_ratio: m.horizon_ratio,
        })
    }
}

/// How a box region is divided: `spacing` or `cells`, the one given.
enum Resolution<'a> {
    /// Node spacing Δ, m.
    Spacing(f64),
    /// Cells per axis.
    Cells(&'a [usize]),
}

/// `[[region]]` number `r` of a box case: its corners within the domain `(min, max)` and its
/// cells, from `spacing` or `cells`.
fn box_region(
    cx: Ctx,
    dim: usize,
    r: usize,
    reg: &RegionSpec,
    (dmin, dmax): ([f64; 3], [f64; 3]),
    (horizon, material): (HorizonRule, u16),
) -> Result<BoxRegion> {
    let key = |k: &str| format!("region[{r}].{k}");
    let rmin = match &reg.min {
        Some(v) => cx.coords(dim, v, &key("min"))?,
        None => dmin,
    };
    let rmax = match &reg.max {
        Some(v) => cx.coords(dim, v, &key("max"))?,
        None => dmax,
    };
    if (0..dim).any(|a| rmax[a] <= rmin[a]) {
        return Err(cx.err(key("max"), "must exceed min on every axis"));
    }
    let mut cells = [1usize; 3];
    let resolution = cx.exactly_one(
        [
            reg.spacing.map(Resolution::Spacing),
            reg.cells.as_deref().map(Resolution::Cells),
        ],
        (&key("spacing"), "give spacing or cells, not both"),
        (&key("spacing"), "missing: give spacing or cells"),
    )?;
    match resolution {
        Resolution::Spacing(h) => {
            let h = cx.positive(&key("spacing"), h)?;
            for a in 0..dim {
                let n = (rmax[a] - rmin[a]) / h;
                let nr = n.round();
                if nr < 1.0 || (n - nr).abs() > 1e-6 * n {
                    return Err(cx.err(
                        key("spacing"),
                        format!(
                            "{h} does not divide the region's side {} into whole cells",
                            rmax[a] - rmin[a]
                        ),
                    ));
                }
                cells[a] = nr as usize;
            }
        }
        Resolution::Cells(c) => {
            if c.len() != dim || c.contains(&0) {
                return Err(cx.err(key("cells"), format!("needs {dim} positive counts")));
            }
            cells[..dim].copy_from_slice(c);
        }
    }
    Ok(BoxRegion {
        name: reg.name.clone(),
        min: rmin,
        max: rmax,
        cells,
        horizon,
        material,
    })
}

/// `[[region]]` number `r` of a mesh case: a `dim`-dimensional physical group of `mesh`,
/// without the box keys.
fn mesh_region(
    cx: Ctx,
    mesh: &peritherm_core::mesh::Mesh,
    dim: usize,
    r: usize,
    reg: &RegionSpec,
    (horizon, material): (HorizonRule, u16),
) -> Result<MeshRegion> {
    let key = |k: &str| format!("region[{r}].{k}");
    for (k, present) in [
        ("min", reg.min.is_some()),
        ("max", reg.max.is_some()),
        ("spacing", reg.spacing.is_some()),
        ("cells", reg.cells.is_some()),
    ] {
        if present {
            return Err(cx.err(
                key(k),
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
        cx.err(
            key("name"),
            format!(
                "`{}` is not a {dim}D physical group of the mesh; it has {have:?}",
                reg.name
            ),
        )
    })?;
    Ok(MeshRegion {
        name: reg.name.clone(),
        group,
        horizon,
        material,
    })
}
