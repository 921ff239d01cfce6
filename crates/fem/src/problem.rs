//! The problem the FEM reference solves, as a model description rather than a case file:
//! [`FemProblem`] (the model, its output times and the FEM's settings [`FemOptions`]) and
//! everything assembled from it ([`FemModel`]); the mesh budget and the step counts of a
//! run. Reading a case, keying errors to its keys and writing the output files is the
//! driver's part (`peritherm::fem::run`).

use crate::assemble::{assemble, System};
use crate::boundary::Conditions;
use crate::field::{output_cloud, Recovery};
use crate::grid::box_mesh;
use crate::mesh::FemMesh;
use crate::solve::Scheme;
use crate::split::{check_cracks, crack_facets, split};
use peritherm_core::bc::FaceBc;
use peritherm_core::cloud::mesh::{MeshGeometry, MeshRegion};
use peritherm_core::cloud::Cloud;
use peritherm_core::error::{Error, Result};
use peritherm_core::material::any_phase_change;
use peritherm_core::mesh::Mesh;
use peritherm_core::model::{CrackShape, Geometry, ModelSpec};
use std::path::{Path, PathBuf};

/// Settings of a FEM run that the case file does not hold.
#[derive(Debug, Clone, PartialEq)]
pub struct FemOptions {
    /// Element size of the structured mesh of a box case, m (default: the finest region spacing).
    pub h: Option<f64>,
    /// Time scheme (default Crank–Nicolson).
    pub scheme: Scheme,
    /// Time step, s (default [`default_dt`]); steps shrink to land on every output time.
    pub dt: Option<f64>,
    /// Another gmsh file to solve a gmsh case on (e.g. finer, or graded towards a singular
    /// point), with the same physical group names; default the case's own mesh.
    pub mesh: Option<PathBuf>,
}

impl Default for FemOptions {
    fn default() -> Self {
        FemOptions {
            h: None,
            scheme: Scheme::CrankNicolson,
            dt: None,
            mesh: None,
        }
    }
}

/// What the FEM reference solves: a model, the times to solve it at and the FEM's settings.
#[derive(Clone, Copy)]
pub struct FemProblem<'a> {
    /// The model: geometry, materials, boundary conditions, source, initial temperature,
    /// cracks and symmetry (the peridynamic kernel, bond rule and weights are not used).
    pub spec: &'a ModelSpec,
    /// Output times, s, increasing.
    pub outputs: &'a [f64],
    /// End time, s.
    pub end: f64,
    /// Mesh and time settings.
    pub options: &'a FemOptions,
    /// Reads the element mesh file of [`FemOptions::mesh`] (the IO layer's gmsh reader; its
    /// error as the reader's one-line message): the FEM reads no file itself.
    pub read_mesh: &'a dyn Fn(&Path) -> std::result::Result<Mesh, String>,
}

/// Default step: min(end/1000, first output/100), s. The case's `time.dt` is the explicit PD
/// step (tiny, stability-bound) and is not used.
pub fn default_dt(problem: &FemProblem) -> f64 {
    let first = problem.outputs.first().copied().unwrap_or(problem.end);
    (problem.end / 1000.0).min(first / 100.0)
}

/// The FEM mesh of a gmsh case read from another file `file`: the case's regions and
/// boundary sets found by name in it (the sets in the case's order; a set the file lacks is
/// empty, which is an error unless the case leaves it free and no crack uses it).
fn other_mesh(problem: &FemProblem, g: &MeshGeometry, file: &Path) -> Result<FemMesh> {
    let key = "reference.fem.mesh";
    let other = (problem.read_mesh)(file).map_err(|e| Error::model(key, e))?;
    let name_of = |m: &Mesh, gr: usize| m.groups[gr].name.clone();
    let mut regions = Vec::with_capacity(g.regions.len());
    for r in &g.regions {
        let group = other.group(g.dim(), &r.name).ok_or_else(|| {
            Error::model(
                key,
                format!(
                    "{}: has no {}D physical group `{}` (a region of the case)",
                    file.display(),
                    g.dim(),
                    r.name
                ),
            )
        })?;
        regions.push(MeshRegion { group, ..r.clone() });
    }
    let geometry = MeshGeometry {
        mesh: std::sync::Arc::new(other),
        regions,
        ..g.clone()
    };
    let mut m = FemMesh::from_gmsh(&geometry)?;
    m.check_conforming()?;
    let have = geometry.set_names();
    let mut sets = Vec::new();
    for (s, name) in g.set_names().iter().enumerate() {
        match have.iter().position(|n| n == name) {
            Some(k) => sets.push(std::mem::take(&mut m.sets[k])),
            None if matches!(problem.spec.faces.get(s), None | Some(FaceBc::Free))
                && !problem
                    .spec
                    .cracks
                    .iter()
                    .any(|c| matches!(c.shape, CrackShape::Set(k) if k == s)) =>
            {
                sets.push(Vec::new())
            }
            None => {
                return Err(Error::model(
                    key,
                    format!(
                        "{}: has no physical group `{name}` (a boundary of the case); it has {:?}",
                        file.display(),
                        geometry
                            .set_groups()
                            .iter()
                            .map(|&gr| name_of(&geometry.mesh, gr))
                            .collect::<Vec<_>>()
                    ),
                ))
            }
        }
    }
    m.sets = sets;
    Ok(m)
}

/// The FEM mesh of a problem (split along its cracks) and the number of nodes the split added.
pub fn build_mesh(problem: &FemProblem) -> Result<(FemMesh, usize)> {
    let (spec, opts) = (problem.spec, problem.options);
    let h = opts.h;
    check_cracks(&spec.cracks)?;
    if any_phase_change(&spec.materials) {
        return Err(Error::model(
            "material",
            "the FEM reference is linear: phase change (material.<name>.phase_change) is not supported",
        ));
    }
    let mut mesh = match &spec.geometry {
        Geometry::Box(_) if opts.mesh.is_some() => {
            return Err(Error::model(
                "reference.fem.mesh",
                "applies to a gmsh case (its physical groups name the regions and boundaries); a box case takes `h`",
            ))
        }
        Geometry::Mesh(_) if h.is_some() && opts.mesh.is_some() => {
            return Err(Error::model(
                "reference.fem.h",
                "give either `h` (box cases) or `mesh` (gmsh cases), not both",
            ))
        }
        Geometry::Mesh(g) if opts.mesh.is_some() => {
            other_mesh(problem, g, opts.mesh.as_deref().expect("checked"))?
        }
        Geometry::Box(g) => {
            let finest = g
                .regions
                .iter()
                .map(|r| r.spacing())
                .fold(f64::INFINITY, f64::min);
            box_mesh(g, h.unwrap_or(finest), &spec.cracks)?
        }
        Geometry::Mesh(g) => {
            if h.is_some() {
                return Err(Error::model(
                    "--h",
                    "fem: applies to the built-in box geometry; a gmsh case is solved on its own mesh",
                ));
            }
            let m = FemMesh::from_gmsh(g)?;
            m.check_conforming()?;
            m
        }
    };
    mesh.symmetry = spec.symmetry;
    if spec.symmetry.is_symmetric() {
        if let Some(p) = mesh.nodes.iter().find(|p| p.x < 0.0) {
            return Err(Error::model(
                "symmetry",
                format!(
                    "fem: {} model: a mesh node lies at r = x = {:e} < 0; the body must lie at x ≥ 0 (x is the radius)",
                    spec.symmetry.name(),
                    p.x
                ),
            ));
        }
    }
    let keys = crack_facets(&mesh, &spec.cracks)?;
    let added = split(&mut mesh, &keys);
    Ok((mesh, added))
}

/// Everything assembled for a FEM solve.
pub struct FemModel {
    /// The mesh, split along the cracks.
    pub mesh: FemMesh,
    /// Nodes added by the split.
    pub split_nodes: usize,
    /// K (with convection) and M.
    pub system: System,
    /// Held nodes and loads.
    pub conditions: Conditions,
    /// The nodes as an output cloud.
    pub cloud: Cloud,
    /// Flux recovery.
    pub recovery: Recovery,
    /// Initial temperature of every node (held values at t = 0 imposed), °C.
    pub theta0: Vec<f64>,
}

impl FemModel {
    /// Builds mesh, matrices and conditions of `problem` with its mesh settings (errors
    /// keyed as [`Error::Model`]).
    pub fn build(problem: &FemProblem) -> Result<FemModel> {
        let spec = problem.spec;
        let (mesh, split_nodes) = build_mesh(problem)?;
        let mut system = assemble(&mesh, &spec.materials);
        let conditions = Conditions::build(&mesh, &spec.faces, spec.source.as_ref(), &mut system);
        let (cloud, recovery) = output_cloud(&mesh, &system, &spec.materials);
        let mut theta0 = spec.initial.at(&mesh.nodes, &cloud.region, "FEM node")?;
        conditions.impose(&mesh, 0.0, &mut theta0);
        Ok(FemModel {
            mesh,
            split_nodes,
            system,
            conditions,
            cloud,
            recovery,
            theta0,
        })
    }

    /// Thermal energy Σ_i (Σ_j M_ij) θ_i = ∫ρcθ dV, J (relative to 0 °C).
    pub fn energy(&self, theta: &[f64]) -> f64 {
        self.system
            .capacity
            .iter()
            .zip(theta)
            .map(|(c, t)| c * t)
            .sum()
    }
}

/// Number of equal steps no longer than `dt` that cover `span`, s.
pub fn steps_for(span: f64, dt: f64) -> u64 {
    peritherm_core::solve::steps_between(0.0, span, dt).max(1)
}

/// Refuses, before anything is allocated, a structured box mesh beyond the memory and a step
/// count beyond [`peritherm_core::limits::MAX_STEPS`].
pub fn budget(problem: &FemProblem, dt: f64) -> Result<()> {
    let opts = problem.options;
    let end = problem.outputs.last().copied().unwrap_or(problem.end);
    if opts.scheme != Scheme::Steady
        && !peritherm_core::limits::within(end / dt, peritherm_core::limits::MAX_STEPS)
    {
        return Err(Error::model(
            "--dt",
            format!(
                "fem: {:.3e} steps of {dt:e} s to reach {end} s; at most {:e} are allowed",
                end / dt,
                peritherm_core::limits::MAX_STEPS
            ),
        ));
    }
    let Geometry::Box(g) = &problem.spec.geometry else {
        return Ok(());
    };
    let finest = g
        .regions
        .iter()
        .map(|r| r.spacing())
        .fold(f64::INFINITY, f64::min);
    let h = opts.h.unwrap_or(finest);
    let size: Vec<f64> = (0..g.dim).map(|a| g.max[a] - g.min[a]).collect();
    let (nodes, bytes) = peritherm_core::budget::fem_box(&size, h);
    let estimate = peritherm_core::budget::Estimate {
        nodes,
        fictitious: 0.0,
        bonds: 0.0,
        bytes,
        key: "--h".into(),
    };
    estimate.enforce(None).map_err(|m| {
        Error::model(
            if opts.h.is_some() {
                "--h"
            } else {
                "region.spacing"
            },
            format!("fem: h = {h:e} m {m}"),
        )
    })
}
