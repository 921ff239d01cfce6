//! `[reference]`: the classical solution a run is compared with, and where.

use super::Ctx;
use crate::error::Result;
use crate::reference::ReferenceTable;
use crate::series::SeriesCheck;
use peritherm_analytic::Reference;
use peritherm_core::limits::MAX_HISTORY_POINTS;
use peritherm_core::math::Point;
use peritherm_fem::{FemOptions, Scheme};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// An analytical series of [`peritherm_analytic`].
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

impl ReferenceSection {
    /// Validates `[reference]`: the probe and lines, exactly one source, a table that has
    /// every output time.
    pub(super) fn validate(self, cx: Ctx, dim: usize, outputs: &[f64]) -> Result<ReferenceSpec> {
        let probe = match &self.probe {
            Some(p) => Some(cx.point(dim, p, "reference.probe")?),
            None => None,
        };
        self.check_lines(cx, dim)?;
        let source = self.source(cx, dim, outputs)?;
        let exclude_tips = match self.exclude_tips {
            Some(v) => cx.positive("reference.exclude_tips", v)?,
            None => 0.0,
        };
        Ok(ReferenceSpec {
            source,
            line_y: self.line_y,
            line_x: self.line_x,
            lines_x: self.lines_x,
            lines_y: self.lines_y,
            exclude_tips,
            probe,
        })
    }

    /// The probe lines: finite coordinates of a 2D or 3D case, at most
    /// [`MAX_HISTORY_POINTS`] per list.
    fn check_lines(&self, cx: Ctx, dim: usize) -> Result<()> {
        for (key, v) in [
            ("reference.line_y", self.line_y),
            ("reference.line_x", self.line_x),
        ] {
            if v.is_some_and(|v| !v.is_finite() || dim < 2) {
                return Err(cx.err(key, "must be a finite coordinate of a 2D or 3D case"));
            }
        }
        for (key, v) in [
            ("reference.lines_x", &self.lines_x),
            ("reference.lines_y", &self.lines_y),
        ] {
            if !v.is_empty() && (dim < 2 || v.iter().any(|x| !x.is_finite())) {
                return Err(cx.err(key, "must be finite coordinates of a 2D or 3D case"));
            }
            if v.len() > MAX_HISTORY_POINTS {
                return Err(cx.err(
                    key,
                    format!("at most {MAX_HISTORY_POINTS} lines, got {}", v.len()),
                ));
            }
        }
        Ok(())
    }

    /// The one source given: `solution`, `file` or `fem`.
    fn source(&self, cx: Ctx, dim: usize, outputs: &[f64]) -> Result<ReferenceSource> {
        let one = (
            "reference",
            "give exactly one of `solution` (analytical), `file` (a CSV table) or `fem` (the built-in FEM solve)",
        );
        let given = [
            self.solution.as_ref().map(Given::Solution),
            self.file.as_deref().map(Given::File),
            self.fem.as_ref().map(Given::Fem),
        ];
        match cx.exactly_one(given, one, one)? {
            Given::Solution(s) => match s.check() {
                Some(m) => Err(cx.err("reference.solution", m)),
                None => Ok(ReferenceSource::Analytic(s.clone())),
            },
            Given::Fem(f) => {
                for (key, v) in [("reference.fem.h", f.h), ("reference.fem.dt", f.dt)] {
                    if let Some(v) = v {
                        cx.positive(key, v)?;
                    }
                }
                Ok(ReferenceSource::Fem(FemOptions {
                    h: f.h,
                    scheme: f.scheme.unwrap_or(Scheme::CrankNicolson),
                    dt: f.dt,
                    mesh: f.mesh.as_ref().map(|m| cx.beside(m)),
                }))
            }
            Given::File(file) => {
                let table = ReferenceTable::read(&cx.beside(file), dim)?;
                table
                    .check_times(outputs)
                    .map_err(|m| cx.err("reference.file", m))?;
                Ok(ReferenceSource::Table(Arc::new(table)))
            }
        }
    }
}

/// The source `[reference]` gives: `solution`, `file` or `fem`, the one given.
enum Given<'a> {
    /// An analytical solution.
    Solution(&'a Reference),
    /// A CSV table, its path as the case file writes it.
    File(&'a Path),
    /// The built-in FEM solve.
    Fem(&'a FemReferenceSpec),
}
