//! Running a case end to end: build, integrate, write fields and the summary.

use crate::case::{Case, ReferenceSource, ReferenceSpec};
use crate::crack::tips_at;
use crate::error::{Error, Result};
use crate::fem::run_fem;
use crate::model::crack_cutters;
use crate::model::Model;
use crate::output::read_field;
use crate::output::{field_csv, field_path, field_vtu, vtu_path, write_atomic, Fields, RunSummary};
use crate::reference::{ReferenceTable, Snapshot};
use crate::report::{classical_at, compare};
use crate::solve::enthalpy::Enthalpic;
use crate::solve::explicit::{choose_dt, count_steps, Explicit, Integrator};
use crate::solve::implicit::{Adaptive, Implicit, Options, Scheme, Solver};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Runs `case`, writing its outputs into `out`; `progress(done, total)` reports steps.
pub fn run_case(case: &Case, out: &Path, progress: impl FnMut(u64, u64)) -> Result<RunSummary> {
    let t_setup = Instant::now();
    let model = Model::build(&case.spec).map_err(|e| match e {
        Error::Model { key, message } => Error::Case {
            file: case.path.clone(),
            key,
            message,
        },
        other => other,
    })?;
    run_model(case, &model, out, t_setup, progress)
}

/// Runs `case` on its already built `model` (set-up timed from `t_setup`), writing into `out`.
pub fn run_model(
    case: &Case,
    model: &Model,
    out: &Path,
    t_setup: Instant,
    mut progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let in_case = |e: Error| match e {
        Error::UnstableDt { .. } => Error::Case {
            file: case.path.clone(),
            key: "time.dt".into(),
            message: e.to_string(),
        },
        Error::Model { key, message } => Error::Case {
            file: case.path.clone(),
            key,
            message,
        },
        other => other,
    };
    let adaptive = case.tolerance.map(|tolerance| Adaptive {
        tolerance,
        first: case.dt,
        max: case.dt_max,
    });
    // adaptive runs: dt is the first step (None: chosen from the tolerance)
    let dt = match adaptive {
        Some(_) => case.dt.unwrap_or(0.0),
        None => choose_dt(model, case.integrator, case.dt).map_err(in_case)?,
    };
    let scheme = match case.integrator {
        Integrator::BackwardEuler => Some(Scheme::BackwardEuler),
        Integrator::CrankNicolson => Some(Scheme::CrankNicolson),
        Integrator::Bdf2 | Integrator::Steady => Some(Scheme::Bdf2),
        Integrator::Euler | Integrator::Rk4 => None,
    };
    // phase change: the enthalpy form of forward Euler (seed 001), refusing other integrators
    let mut enthalpic = match model.enthalpy {
        Some(_) => Some(Enthalpic::new(model, case.integrator).map_err(in_case)?),
        None => None,
    };
    // the implicit system (elimination, symbolic factorisation) is part of the set-up
    let mut implicit = match scheme {
        Some(s) => {
            // adaptive steps visit several Δt: CG until a factorisation pays (Solver::Auto)
            let options = Options {
                solver: match adaptive {
                    Some(_) => Solver::Auto,
                    None => Solver::Direct,
                },
                ..Options::default()
            };
            Some(Implicit::new(model, s, options).map_err(in_case)?)
        }
        None => None,
    };
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    std::fs::create_dir_all(out).map_err(|error| Error::Io {
        path: out.to_path_buf(),
        error,
    })?;
    let total = if case.integrator == Integrator::Steady || adaptive.is_some() {
        0
    } else {
        count_steps(0.0, &case.outputs, dt)
    };
    let mut theta = model.theta0.clone();
    let initial_energy = model.energy(&theta);
    let mut energy = Vec::new();
    let mut fields = Vec::new();
    let mut comparisons = Vec::new();
    let mut reference_seconds = 0.0;
    let t_run = Instant::now();
    let cutters = crack_cutters(&model.cloud, &case.spec.cracks);
    let started = Instant::now();
    let reference = resolve_reference(case, out)?;
    let fem_seconds = started.elapsed().as_secs_f64();
    let mut on_output =
        |k: usize, t: f64, th: &[f64], conductance: &crate::operator::Conductance, e: f64| {
            energy.push(e);
            let path = field_path(out, k + 1);
            let flux = conductance.flux(&model.cloud, th);
            let damage = model.damage_at(t);
            let classical = match &reference {
                Some(r) => {
                    let started = Instant::now();
                    let classical = classical_at(&model.cloud, &r.source, t, &cutters)?;
                    let tips = tips_at(&cutters, t);
                    comparisons.push(compare(&model.cloud, th, &classical, r, t, &tips));
                    reference_seconds += started.elapsed().as_secs_f64();
                    Some(classical)
                }
                None => None,
            };
            let f = Fields {
                theta: th,
                damage: &damage,
                flux: &flux,
                reference: classical.as_deref(),
            };
            write_atomic(&path, field_csv(&model.cloud, &f).as_bytes())?;
            write_atomic(
                &vtu_path(out, k + 1),
                field_vtu(&model.cloud, &f).as_bytes(),
            )?;
            fields.push(
                path.file_name()
                    .expect("file")
                    .to_string_lossy()
                    .into_owned(),
            );
            Ok(())
        };
    let linear_output = |k: usize, t: f64, th: &[f64], c: &crate::operator::Conductance| {
        on_output(k, t, th, c, model.energy(th))
    };
    let result = match (enthalpic.as_mut(), implicit.as_mut()) {
        (Some(stepper), _) => {
            stepper.run(&mut theta, 0.0, dt, &case.outputs, &mut on_output, |s| {
                progress(s, total)
            })
        }
        (None, Some(stepper)) if case.integrator == Integrator::Steady => {
            stepper.steady(&mut theta, &case.outputs, linear_output)
        }
        (None, Some(stepper)) if adaptive.is_some() => {
            let adaptive = adaptive.as_ref().expect("adaptive");
            let t_last = case.outputs.last().copied().unwrap_or(case.end);
            stepper.run_adaptive(
                &mut theta,
                0.0,
                adaptive,
                &case.outputs,
                linear_output,
                // the number of steps is not known: extrapolate it from the time reached
                |s, t| progress(s, ((s as f64) * t_last / t.max(f64::MIN_POSITIVE)) as u64),
            )
        }
        (None, Some(stepper)) => {
            stepper.run(&mut theta, 0.0, dt, &case.outputs, linear_output, |s| {
                progress(s, total)
            })
        }
        (None, None) => Explicit::new(model, case.integrator).run(
            &mut theta,
            0.0,
            dt,
            &case.outputs,
            linear_output,
            |s| progress(s, total),
        ),
    };
    let stats = result.map_err(|e| match e {
        Error::NonFinite { node, time } => {
            let p = model.cloud.pos[node];
            Error::Case {
                file: case.path.clone(),
                key: "state".into(),
                message: format!(
                    "temperature became non-finite near ({}, {}, {}) by t = {time:e} s; check source, boundary values and dt",
                    p.x, p.y, p.z
                ),
            }
        }
        other => other,
    })?;
    let summary = RunSummary {
        title: case.title.clone(),
        case: case.path.display().to_string(),
        solver: "peridynamics".into(),
        nodes: model.cloud.n_body,
        fictitious_nodes: model.cloud.n_fictitious(),
        bonds: model.horizons.n_bonds(),
        pairs: model.conductance.nnz(),
        steps: stats.steps,
        // implicit runs: the step taken (adaptive: the first; 0 for steady) and, for
        // comparison, Euler's bound
        dt: match (&implicit, adaptive) {
            (Some(st), Some(_)) => st.stats.first_step,
            _ if dt.is_finite() => dt,
            _ => 0.0,
        },
        dt_stable: if case.integrator.is_implicit() {
            Integrator::Euler.stable_dt(model)
        } else {
            case.integrator.stable_dt(model)
        },
        integrator: case.integrator.name().into(),
        output_times: case.outputs.clone(),
        fields,
        initial_energy,
        energy,
        setup_seconds,
        wall_seconds: t_run.elapsed().as_secs_f64() - reference_seconds - fem_seconds,
        reference_seconds: reference_seconds + fem_seconds,
        threads: rayon::current_num_threads(),
        consistency: model.correction,
        reference: comparisons,
        implicit: implicit.as_ref().map(|st| st.stats),
    };
    summary.write(out)?;
    Ok(summary)
}

/// The case's reference ready for comparison: a `[reference.fem]` is solved first (by
/// `peritherm fem`'s solver, into `out/fem/`) and its fields become a reference table.
pub fn resolve_reference(case: &Case, out: &Path) -> Result<Option<ReferenceSpec>> {
    let Some(r) = &case.reference else {
        return Ok(None);
    };
    let ReferenceSource::Fem(opts) = &r.source else {
        return Ok(Some(r.clone()));
    };
    let dir = out.join("fem");
    let summary = run_fem(case, &dir, opts, |_, _| {})?;
    let mut snapshots = Vec::new();
    for (t, f) in summary.output_times.iter().zip(&summary.fields) {
        let rows = read_field(&dir.join(f))?;
        snapshots.push(Snapshot {
            time: *t,
            pos: rows.pos,
            theta: rows.theta,
        });
    }
    let table = ReferenceTable {
        path: dir,
        dim: case.spec.geometry.bare_cloud()?.dim,
        snapshots,
    };
    Ok(Some(ReferenceSpec {
        source: ReferenceSource::Table(Arc::new(table)),
        ..r.clone()
    }))
}
