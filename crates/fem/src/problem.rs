//! Running a case with the FEM solver: the same outputs as `peritherm run` (`field_<k>.csv`,
//! `field_<k>.vtu`, run.json with the reference comparison), written atomically.

use super::assemble::{assemble, System};
use super::boundary::Conditions;
use super::field::{output_cloud, Recovery};
use super::grid::box_mesh;
use super::mesh::FemMesh;
use super::solve::{Scheme, Stepper};
use super::split::{check_cracks, crack_facets, split};
use crate::bc::FaceBc;
use crate::case::Case;
use crate::case::ReferenceSource;
use crate::cloud::mesh::{MeshGeometry, MeshRegion};
use crate::cloud::Cloud;
use crate::error::{Error, Result};
use crate::math::Vector;
use crate::model::{crack_cutters, CrackShape, Geometry};
use crate::output::{field_csv, field_path, field_vtu, vtu_path, write_atomic, Fields, RunSummary};
use crate::report::{classical_at, compare};
use std::path::{Path, PathBuf};
use std::time::Instant;

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

/// Default step: min(end/1000, first output/100), s. The case's `time.dt` is the explicit PD
/// step (tiny, stability-bound) and is not used.
pub fn default_dt(case: &Case) -> f64 {
    let first = case.outputs.first().copied().unwrap_or(case.end);
    (case.end / 1000.0).min(first / 100.0)
}

/// The FEM mesh of a gmsh case read from another file `file`: the case's regions and
/// boundary sets found by name in it (the sets in the case's order; a set the file lacks is
/// empty, which is an error unless the case leaves it free and no crack uses it).
fn other_mesh(case: &Case, g: &MeshGeometry, file: &Path) -> Result<FemMesh> {
    let key = "reference.fem.mesh";
    let other = crate::gmsh::read(file).map_err(|e| Error::model(key, e.to_string()))?;
    let name_of = |m: &crate::mesh::Mesh, gr: usize| m.groups[gr].name.clone();
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
            None if matches!(case.spec.faces.get(s), None | Some(FaceBc::Free))
                && !case
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

/// The FEM mesh of a case (split along its cracks) and the number of nodes the split added.
pub fn build_mesh(case: &Case, opts: &FemOptions) -> Result<(FemMesh, usize)> {
    let spec = &case.spec;
    let h = opts.h;
    check_cracks(&spec.cracks)?;
    if spec.materials.iter().any(|m| m.phase_change.is_some()) {
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
            other_mesh(case, g, opts.mesh.as_deref().expect("checked"))?
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
    /// Builds mesh, matrices and conditions of `case` on elements of size `h` (box cases) or
    /// on its own mesh (errors keyed as [`Error::Model`]).
    pub fn build(case: &Case, h: Option<f64>) -> Result<FemModel> {
        FemModel::build_with(
            case,
            &FemOptions {
                h,
                ..Default::default()
            },
        )
    }

    /// Builds mesh, matrices and conditions of `case` with the mesh settings of `opts`.
    pub fn build_with(case: &Case, opts: &FemOptions) -> Result<FemModel> {
        let spec = &case.spec;
        let (mesh, split_nodes) = build_mesh(case, opts)?;
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
    crate::solve::explicit::steps_between(0.0, span, dt).max(1)
}

fn keyed(case: &Case, e: Error) -> Error {
    match e {
        Error::Model { key, message } => Error::Case {
            file: case.path.clone(),
            key,
            message,
        },
        Error::NonFinite { time, .. } => Error::Case {
            file: case.path.clone(),
            key: "state".into(),
            message: format!("fem: temperature became non-finite by t = {time:e} s; check source and boundary values"),
        },
        other => other,
    }
}

/// Runs `case` with the FEM solver into `out`; `progress(done, total)` reports steps.
pub fn run_fem(
    case: &Case,
    out: &Path,
    opts: &FemOptions,
    progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let t_setup = Instant::now();
    let dt = opts.dt.unwrap_or_else(|| default_dt(case));
    if !(dt.is_finite() && dt > 0.0) {
        return Err(keyed(
            case,
            Error::model("--dt", format!("fem: must be a positive step, got {dt}")),
        ));
    }
    budget(case, opts, dt).map_err(|e| keyed(case, e))?;
    let model = FemModel::build_with(case, opts).map_err(|e| keyed(case, e))?;
    let name = case.path.display().to_string();
    crate::staging::write_into(out, &name, |dir| {
        solve(case, &model, dir, opts, dt, t_setup, progress)
    })
}

/// Refuses, before anything is allocated, a structured box mesh beyond the memory and a step
/// count beyond [`crate::limits::MAX_STEPS`].
fn budget(case: &Case, opts: &FemOptions, dt: f64) -> Result<()> {
    let end = case.outputs.last().copied().unwrap_or(case.end);
    if opts.scheme != Scheme::Steady && !crate::limits::within(end / dt, crate::limits::MAX_STEPS) {
        return Err(Error::model(
            "--dt",
            format!(
                "fem: {:.3e} steps of {dt:e} s to reach {end} s; at most {:e} are allowed",
                end / dt,
                crate::limits::MAX_STEPS
            ),
        ));
    }
    let Geometry::Box(g) = &case.spec.geometry else {
        return Ok(());
    };
    let finest = g
        .regions
        .iter()
        .map(|r| r.spacing())
        .fold(f64::INFINITY, f64::min);
    let h = opts.h.unwrap_or(finest);
    let size: Vec<f64> = (0..g.dim).map(|a| g.max[a] - g.min[a]).collect();
    let (nodes, bytes) = crate::budget::fem_box(&size, h);
    let estimate = crate::budget::Estimate {
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

/// The time loop of the FEM solve, writing into the staged directory `out`.
fn solve(
    case: &Case,
    model: &FemModel,
    out: &Path,
    opts: &FemOptions,
    dt: f64,
    t_setup: Instant,
    mut progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let mut stepper = Stepper::new(&model.mesh, &model.system, &model.conditions, opts.scheme);
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let origin = crate::provenance::write_copy(out, case)?;
    let total: u64 = match opts.scheme {
        Scheme::Steady => case.outputs.len() as u64,
        _ => {
            let mut t = 0.0;
            case.outputs
                .iter()
                .map(|&to| {
                    let n = steps_for(to - t, dt);
                    t = to;
                    n
                })
                .sum()
        }
    };
    // crack facets for interpolating a reference table without looking across a crack (the
    // geometry's own boundary sets hold a mesh's crack groups)
    // a case whose reference is this FEM solve has nothing to compare with here
    let reference = case
        .reference
        .as_ref()
        .filter(|r| !matches!(r.source, ReferenceSource::Fem(_)));
    let cutters = match reference {
        Some(_) if !case.spec.cracks.is_empty() => {
            crack_cutters(&case.spec.geometry.bare_cloud()?, &case.spec.cracks)
        }
        _ => Vec::new(),
    };
    let t_run = Instant::now();
    let mut theta = model.theta0.clone();
    let initial_energy = model.energy(&theta);
    let mut flux = vec![Vector::zeros(); theta.len()];
    let damage = vec![0.0; theta.len()];
    let (mut energy, mut fields, mut comparisons) = (Vec::new(), Vec::new(), Vec::new());
    let (mut reference_seconds, mut steps, mut t) = (0.0, 0u64, 0.0);
    for (k, &to) in case.outputs.iter().enumerate() {
        if opts.scheme == Scheme::Steady {
            stepper.steady(&mut theta, to).map_err(|e| keyed(case, e))?;
            steps += 1;
            progress(steps, total);
        } else {
            let n = steps_for(to - t, dt);
            let h = (to - t) / n as f64;
            for s in 0..n {
                let now = if s + 1 == n { to - h } else { t + s as f64 * h };
                stepper
                    .step(&mut theta, now, h)
                    .map_err(|e| keyed(case, e))?;
                steps += 1;
                progress(steps, total);
            }
        }
        t = to;
        energy.push(model.energy(&theta));
        model.recovery.flux(&model.mesh, &theta, &mut flux);
        let classical = match reference {
            Some(r) => {
                let started = Instant::now();
                let classical = classical_at(&model.cloud, &r.source, to, &cutters)?;
                let tips = crate::crack::tips_at(&cutters, to);
                comparisons.push(compare(&model.cloud, &theta, &classical, r, to, &tips));
                reference_seconds += started.elapsed().as_secs_f64();
                Some(classical)
            }
            None => None,
        };
        let f = Fields {
            theta: &theta,
            damage: &damage,
            flux: &flux,
            reference: classical.as_deref(),
        };
        let path = field_path(out, k + 1);
        write_atomic(&path, field_csv(&model.cloud, &f).as_bytes())?;
        write_atomic(
            &vtu_path(out, k + 1),
            field_vtu(&model.cloud, &f).as_bytes(),
        )?;
        fields.push(format!("field_{}.csv", k + 1));
    }
    let summary = RunSummary {
        status: "complete".into(),
        title: case.title.clone(),
        case: case.path.display().to_string(),
        solver: "fem".into(),
        nodes: model.cloud.n_body,
        fictitious_nodes: 0,
        bonds: 0,
        pairs: model.system.cols.len(),
        steps,
        dt: if opts.scheme == Scheme::Steady {
            0.0
        } else {
            dt
        },
        dt_stable: 0.0,
        integrator: opts.scheme.name().into(),
        output_times: case.outputs.clone(),
        fields,
        initial_energy,
        energy,
        setup_seconds,
        wall_seconds: t_run.elapsed().as_secs_f64() - reference_seconds,
        reference_seconds,
        threads: rayon::current_num_threads(),
        consistency: None,
        reference: comparisons,
        implicit: None,
        history: None,
        origin: Some(origin),
    };
    summary.write(out)?;
    Ok(summary)
}
