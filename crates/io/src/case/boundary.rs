//! `[boundary.<name>]`: a condition per face or mesh group, chosen by its `type`. Each type
//! is a struct of exactly its own keys, so a key of another type is an unknown field and a
//! missing required one a missing field, both reported by serde; `method` is an enum per type.

use super::{named, Ctx, ValueSpec};
use crate::error::Result;
use peritherm_core::bc::{FaceBc, Layer};
use peritherm_core::cloud::mesh::{MeshGeometry, UNNAMED};
use peritherm_core::cloud::FACE_NAMES;
use peritherm_core::model::{Crack, CrackShape, Geometry};
use serde::Deserialize;
use std::collections::BTreeMap;

/// `[boundary.<face>]`: one condition, chosen by `type`; each type takes only its own keys.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum BoundarySpec {
    /// `type = "free"`: no bonds leave the body.
    Free(FreeBc),
    /// `type = "temperature"`: a prescribed temperature.
    Temperature(TemperatureBc),
    /// `type = "insulated"`: zero flux.
    Insulated(InsulatedBc),
    /// `type = "flux"`: a prescribed flux into the body.
    Flux(FluxBc),
    /// `type = "convection"`: a film coefficient and an ambient temperature.
    Convection(ConvectionBc),
}

/// `type = "free"`: no keys besides `type`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FreeBc {}

/// `type = "temperature"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureBc {
    /// Temperature, °C: number or expression of x, y, z, t.
    #[serde(deserialize_with = "named::value")]
    pub value: ValueSpec,
    /// `nodal` (default on boxes), `mirror` (default on meshes) or `naive`.
    #[serde(default, deserialize_with = "named::method")]
    pub method: Option<TemperatureMethod>,
    /// Node layers held by a nodal condition (default 1).
    #[serde(default, deserialize_with = "named::layers")]
    pub layers: Option<f64>,
}

/// How a temperature condition is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TemperatureMethod {
    /// The first `layers` node layers are held at the value (Bobaru & Duangpanya 2010, 2012).
    Nodal,
    /// A fictitious layer reflecting the body field across the face about the value.
    Mirror,
    /// A fictitious layer held at the value, θ_f = θ_b(t).
    Naive,
}

/// `type = "insulated"`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InsulatedBc {
    /// `mirror` (default) or `free`.
    #[serde(default, deserialize_with = "named::method")]
    pub method: InsulatedMethod,
}

/// How an insulated face is modelled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InsulatedMethod {
    /// Zero flux through a mirrored fictitious layer (corrects the surface skin effect).
    #[default]
    Mirror,
    /// No bonds leave the body: the uncorrected surface, with its skin effect.
    Free,
}

/// `type = "flux"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluxBc {
    /// Flux into the body, W/m²: number or expression of x, y, z, t.
    #[serde(deserialize_with = "named::value")]
    pub value: ValueSpec,
    /// `mirror` (default) or `relation`.
    #[serde(default, deserialize_with = "named::method")]
    pub method: FluxMethod,
}

/// How a flux condition is imposed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FluxMethod {
    /// A mirrored fictitious layer, θ_f = θ_m + (q/k) d.
    #[default]
    Mirror,
    /// A nodal relation: Bobaru & Duangpanya 2010 eq. 22 in 1D, 2012 §3.2 in 2D/3D.
    Relation,
}

/// `type = "convection"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConvectionBc {
    /// Film coefficient, W/(m²·K).
    #[serde(deserialize_with = "named::h")]
    pub h: f64,
    /// Ambient temperature, °C: number or expression of x, y, z, t.
    #[serde(deserialize_with = "named::ambient")]
    pub ambient: ValueSpec,
    /// `surface` (default) or `mirror`.
    #[serde(default, deserialize_with = "named::method")]
    pub method: ConvectionMethod,
}

/// How a convection condition is imposed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConvectionMethod {
    /// A source s = h A (T∞ − θ)/V on the face's first node layer.
    #[default]
    Surface,
    /// A mirrored fictitious layer, θ_f = ((1 − β/2) θ_m + β T∞)/(1 + β/2), β = h d/k.
    Mirror,
}

impl BoundarySpec {
    /// The `type` as written in the case file.
    pub fn name(&self) -> &'static str {
        match self {
            BoundarySpec::Free(_) => "free",
            BoundarySpec::Temperature(_) => "temperature",
            BoundarySpec::Insulated(_) => "insulated",
            BoundarySpec::Flux(_) => "flux",
            BoundarySpec::Convection(_) => "convection",
        }
    }

    /// The model's condition; `key` is the table's dotted key, `mesh` whether the body is a mesh.
    fn face(&self, cx: Ctx, key: &str, mesh: bool) -> Result<FaceBc> {
        let key = |k: &str| format!("{key}.{k}");
        Ok(match self {
            BoundarySpec::Free(FreeBc {}) => FaceBc::Free,
            BoundarySpec::Temperature(t) => t.face(cx, &key, mesh)?,
            BoundarySpec::Insulated(i) => match i.method {
                InsulatedMethod::Mirror => FaceBc::LayerInsulated,
                InsulatedMethod::Free => FaceBc::Free,
            },
            BoundarySpec::Flux(f) => {
                let value = cx.expr(&f.value, &key("value"))?;
                match f.method {
                    FluxMethod::Mirror => FaceBc::LayerFlux { value },
                    FluxMethod::Relation => FaceBc::RelationFlux { value },
                }
            }
            BoundarySpec::Convection(c) => {
                let h = cx.positive(&key("h"), c.h)?;
                let ambient = cx.expr(&c.ambient, &key("ambient"))?;
                match c.method {
                    ConvectionMethod::Surface => FaceBc::Convection { h, ambient },
                    ConvectionMethod::Mirror => FaceBc::LayerConvection { h, ambient },
                }
            }
        })
    }
}

impl TemperatureMethod {
    /// The name as written in the case file.
    pub fn name(self) -> &'static str {
        match self {
            TemperatureMethod::Nodal => "nodal",
            TemperatureMethod::Mirror => "mirror",
            TemperatureMethod::Naive => "naive",
        }
    }
}

impl TemperatureBc {
    /// The method given, or the default: `nodal` on boxes, `mirror` on meshes (element
    /// centroids never lie on a mesh's boundary).
    pub fn method(&self, mesh: bool) -> TemperatureMethod {
        match self.method {
            Some(m) => m,
            None if mesh => TemperatureMethod::Mirror,
            None => TemperatureMethod::Nodal,
        }
    }

    /// The model's condition: `layers` (a whole number >= 1) only with the nodal method.
    fn face(&self, cx: Ctx, key: &dyn Fn(&str) -> String, mesh: bool) -> Result<FaceBc> {
        let method = self.method(mesh);
        if self.layers.is_some() && method != TemperatureMethod::Nodal {
            return Err(cx.err(
                key("layers"),
                format!(
                    "does not apply to method = \"{}\": only a nodal temperature holds node layers",
                    method.name()
                ),
            ));
        }
        let value = cx.expr(&self.value, &key("value"))?;
        Ok(match method {
            TemperatureMethod::Nodal => {
                let layers = self.layers.unwrap_or(1.0);
                if !(layers >= 1.0 && layers.fract() == 0.0) {
                    return Err(cx.err(
                        key("layers"),
                        format!("must be a whole number >= 1, got {layers}"),
                    ));
                }
                FaceBc::NodalTemperature { value, layers }
            }
            TemperatureMethod::Mirror => FaceBc::LayerTemperature {
                value,
                layer: Layer::Mirror,
            },
            TemperatureMethod::Naive => FaceBc::LayerTemperature {
                value,
                layer: Layer::Naive,
            },
        })
    }
}

/// The conditions of every boundary set (a box's six faces, or a mesh's groups and then the
/// facets in no group), free where no `[boundary]` names it.
pub(super) fn faces(
    cx: Ctx,
    given: &BTreeMap<String, BoundarySpec>,
    geometry: &Geometry,
    set_names: &[String],
    dim: usize,
) -> Result<Vec<FaceBc>> {
    let mesh = matches!(geometry, Geometry::Mesh(_));
    let mut faces = match geometry {
        Geometry::Box(_) => vec![FaceBc::Free; 6],
        Geometry::Mesh(_) => vec![FaceBc::Free; set_names.len() + 1],
    };
    for (name, b) in given {
        let f = face_index(cx, name, geometry, set_names, dim)?;
        faces[f] = b.face(cx, &format!("boundary.{name}"), mesh)?;
    }
    Ok(faces)
}

/// The boundary set `[boundary.<name>]` names: a face of the box, a non-empty group of the
/// mesh, or (on a mesh) `"(no group)"`, the facets in no group.
fn face_index(
    cx: Ctx,
    name: &str,
    geometry: &Geometry,
    set_names: &[String],
    dim: usize,
) -> Result<usize> {
    let unnamed = match geometry {
        Geometry::Mesh(_) if name == UNNAMED => Some(set_names.len()),
        _ => None,
    };
    let f = set_names.iter().position(|n| n == name).or(unnamed);
    let Some(f) = f else {
        let what = match geometry {
            Geometry::Box(_) if FACE_NAMES.contains(&name) => {
                format!("a {dim}D case has faces {set_names:?}")
            }
            Geometry::Box(_) => format!("unknown face; use one of {set_names:?}"),
            Geometry::Mesh(_) => format!(
                "no physical group of dimension {} has this name; the mesh has {set_names:?}",
                dim - 1
            ),
        };
        return Err(cx.err(format!("boundary.{name}"), what));
    };
    if let Geometry::Mesh(g) = geometry {
        if unnamed.is_none() && g.set_is_empty(f) {
            return Err(cx.err(
                format!("boundary.{name}"),
                "the mesh's physical group of this name has no elements",
            ));
        }
    }
    Ok(f)
}

/// On a mesh, every boundary set that no `[boundary]` names (and the facets in no group,
/// unless `[boundary."(no group)"]` names them) is insulated through a mirrored layer: the
/// surface correction of the free-surface skin effect (theory §3). `type = "free"` keeps
/// the uncorrected surface; crack groups stay as they are.
pub(super) fn unnamed_insulated(
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
        let name = names.get(s).map_or(UNNAMED, String::as_str);
        let given = named.contains_key(name);
        if !given && !cracked.contains(&s) {
            *face = FaceBc::LayerInsulated;
        }
    }
}
