//! Running a case with the FEM solver: the case mapped to a [`FemProblem`] (the numerics
//! of `peritherm-fem`), its errors keyed to the case's keys, and the same outputs as
//! `peritherm run` (`field_<k>.csv`, `field_<k>.vtu`, run.json with the reference
//! comparison), written atomically.

use super::problem::{budget, default_dt, steps_for, FemModel, FemOptions, FemProblem};
use super::solve::{Scheme, Stepper};
use crate::atomic::write_atomic;
use crate::case::Case;
use crate::case::ReferenceSource;
use crate::error::{Error, Result};
use crate::math::Vector;
use crate::model::crack_cutters;
use crate::output::{field_csv, field_path, field_vtu, vtu_path, Fields, RunSummary};
use crate::report::{classical_at, compare};
use std::path::Path;
use std::time::Instant;

/// The FEM problem of `case` with the settings `opts` (a mesh file named by `opts` is read
/// with the gmsh reader).
pub fn problem<'a>(case: &'a Case, opts: &'a FemOptions) -> FemProblem<'a> {
    FemProblem {
        spec: &case.spec,
        outputs: &case.outputs,
        end: case.end,
        options: opts,
        read_mesh: &crate::gmsh::read,
    }
}

/// Builds mesh, matrices and conditions of `case` on elements of size `h` (box cases) or
/// on its own mesh (errors keyed as [`Error::Model`]).
pub fn model(case: &Case, h: Option<f64>) -> Result<FemModel> {
    model_with(
        case,
        &FemOptions {
            h,
            ..Default::default()
        },
    )
}

/// Builds mesh, matrices and conditions of `case` with the mesh settings of `opts`.
pub fn model_with(case: &Case, opts: &FemOptions) -> Result<FemModel> {
    FemModel::build(&problem(case, opts))
}

/// A library error keyed to the case file (a non-finite state to the key `state`).
fn keyed(case: &Case, e: Error) -> Error {
    match e {
        Error::NonFinite { time, .. } => case.error(
            "state",
            format!("fem: temperature became non-finite by t = {time:e} s; check source and boundary values"),
        ),
        other => case.keyed(other),
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
    let problem = problem(case, opts);
    let dt = opts.dt.unwrap_or_else(|| default_dt(&problem));
    if !(dt.is_finite() && dt > 0.0) {
        return Err(keyed(
            case,
            Error::model("--dt", format!("fem: must be a positive step, got {dt}")),
        ));
    }
    budget(&problem, dt).map_err(|e| keyed(case, e))?;
    let model = FemModel::build(&problem).map_err(|e| keyed(case, e))?;
    let name = case.path.display().to_string();
    crate::staging::write_into(out, &name, |dir| {
        solve(case, &model, dir, opts, dt, t_setup, progress)
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
        settings: case.settings.clone(),
        origin: Some(origin),
    };
    summary.write(out)?;
    Ok(summary)
}
