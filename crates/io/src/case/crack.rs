//! `[[crack]]`: pre-cracks along a mesh group or a polyline (2D) or planar polygon (3D),
//! optionally growing along the polyline.

use super::Ctx;
use crate::error::Result;
use peritherm_core::bc::FaceBc;
use peritherm_core::crack::Growth;
use peritherm_core::math::Point;
use peritherm_core::model::{Crack, CrackShape, Geometry};
use serde::Deserialize;

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

/// What a validator of one `[[crack]]` needs: the case, the crack's index, the body.
#[derive(Clone, Copy)]
struct At<'a> {
    cx: Ctx<'a>,
    c: usize,
    dim: usize,
    geometry: &'a Geometry,
}

impl At<'_> {
    /// The dotted key `crack[c].k`.
    fn key(&self, k: &str) -> String {
        format!("crack[{}].{k}", self.c)
    }
}

/// Validates the `[[crack]]` entries of a body with boundary sets `set_names` and their
/// conditions `faces`.
pub(super) fn cracks(
    cx: Ctx,
    specs: &[CrackSpec],
    dim: usize,
    set_names: &[String],
    geometry: &Geometry,
    faces: &[FaceBc],
) -> Result<Vec<Crack>> {
    let mut out = Vec::new();
    for (c, spec) in specs.iter().enumerate() {
        let at = At {
            cx,
            c,
            dim,
            geometry,
        };
        let mu = spec.conductance.unwrap_or(0.0);
        if !(0.0..1.0).contains(&mu) {
            return Err(cx.err(
                at.key("conductance"),
                format!("must be in [0, 1), got {mu}"),
            ));
        }
        let key = format!("crack[{c}]");
        let either = (key.as_str(), "give either group or points");
        let along = [
            spec.group.as_deref().map(Along::Group),
            spec.points.as_deref().map(Along::Points),
        ];
        let shape = match cx.exactly_one(along, either, either)? {
            Along::Group(g) => CrackShape::Set(group(at, g, set_names, faces)?),
            Along::Points(pts) => shape(at, pts)?,
        };
        let growth = growth(at, spec, &shape)?;
        out.push(Crack { shape, mu, growth });
    }
    Ok(out)
}

/// What a crack follows: `group` or `points`, the one given.
enum Along<'a> {
    /// A mesh physical group.
    Group(&'a str),
    /// A polyline (2D) or planar polygon (3D), m.
    Points(&'a [Vec<f64>]),
}

/// The boundary set of a crack along the mesh group `g`: a non-empty group with no condition.
fn group(at: At, g: &str, set_names: &[String], faces: &[FaceBc]) -> Result<usize> {
    let (cx, key) = (at.cx, at.key("group"));
    let Geometry::Mesh(m) = at.geometry else {
        return Err(cx.err(key, "needs a [mesh]; a box case gives points"));
    };
    let s = set_names.iter().position(|n| n == g).ok_or_else(|| {
        cx.err(
            &key,
            format!(
                "`{g}` is not a physical group of dimension {}; the mesh has {set_names:?}",
                at.dim - 1
            ),
        )
    })?;
    if faces[s] != FaceBc::Free {
        return Err(cx.err(key, format!("`{g}` also has a [boundary.{g}] condition")));
    }
    if m.set_is_empty(s) {
        return Err(cx.err(key, format!("the mesh's group `{g}` has no elements")));
    }
    Ok(s)
}

/// The shape of a crack along `pts`: a 2D polyline or a 3D planar polygon.
fn shape(at: At, pts: &[Vec<f64>]) -> Result<CrackShape> {
    let (cx, dim, key) = (at.cx, at.dim, at.key("points"));
    if dim == 1 {
        return Err(cx.err(key, "a 1D crack is a mesh point group"));
    }
    let need = if dim == 2 { 2 } else { 3 };
    if pts.len() < need {
        return Err(cx.err(key, format!("needs at least {need} points")));
    }
    let list = points(at, pts)?;
    if dim == 2 {
        return Ok(CrackShape::Polyline(list));
    }
    let n = (list[1] - list[0]).cross(&(list[2] - list[0]));
    let size = (list[1] - list[0]).norm().max((list[2] - list[0]).norm());
    let planar = list
        .iter()
        .all(|p| (p - list[0]).dot(&n).abs() <= 1e-9 * n.norm() * size);
    if n.norm() <= 1e-12 * size * size || !planar {
        return Err(cx.err(
            key,
            "a 3D crack is a planar polygon: its points must span one plane",
        ));
    }
    Ok(CrackShape::Polygon(list))
}

/// The growth of a crack with a `speed`: along a polyline, from `start` (s) with
/// `initial_length` (m) already cracked; without it, neither of those keys.
fn growth(at: At, spec: &CrackSpec, shape: &CrackShape) -> Result<Option<Growth>> {
    let cx = at.cx;
    let Some(v) = spec.speed else {
        for (k, present) in [
            ("start", spec.start.is_some()),
            ("initial_length", spec.initial_length.is_some()),
        ] {
            if present {
                return Err(cx.err(at.key(k), "applies to a growing crack: give speed too"));
            }
        }
        return Ok(None);
    };
    if spec.points.is_none() {
        return Err(cx.err(
            at.key("speed"),
            "a growing crack follows a polyline: give points",
        ));
    }
    let start = spec.start.unwrap_or(0.0);
    if !(start.is_finite() && start >= 0.0) {
        return Err(cx.err(at.key("start"), format!("must be a time >= 0, got {start}")));
    }
    let initial = spec.initial_length.unwrap_or(0.0);
    if !(initial.is_finite() && initial >= 0.0) {
        return Err(cx.err(
            at.key("initial_length"),
            format!("must be a length >= 0, got {initial}"),
        ));
    }
    let total = match shape {
        CrackShape::Polyline(p) => p.windows(2).map(|w| (w[1] - w[0]).norm()).sum(),
        _ => f64::INFINITY,
    };
    if initial > total {
        return Err(cx.err(
            at.key("initial_length"),
            format!("{initial} m exceeds the length of the path, {total} m"),
        ));
    }
    Ok(Some(Growth {
        start,
        speed: cx.positive(&at.key("speed"), v)?,
        initial,
        arc: 0.0,
    }))
}

/// The points of a crack: coordinates of the dimension, no segment of zero length, and a
/// path that enters the body's interior.
fn points(at: At, pts: &[Vec<f64>]) -> Result<Vec<Point>> {
    let (cx, dim) = (at.cx, at.dim);
    let mut list: Vec<Point> = Vec::new();
    for (k, p) in pts.iter().enumerate() {
        let key = at.key(&format!("points[{k}]"));
        let q = cx.point(dim, p, &key)?;
        if list
            .last()
            .is_some_and(|l| (q - l).norm() <= 1e-12 * q.coords.amax())
        {
            return Err(cx.err(
                key,
                "repeats the previous point: a crack segment of zero length",
            ));
        }
        list.push(q);
    }
    let (lo, hi) = geometry_bounds(at.geometry, dim);
    if !crosses_interior(&list, dim, lo, hi) {
        return Err(cx.err(
            at.key("points"),
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
