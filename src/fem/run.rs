//! Running a case with the FEM solver: the case mapped to a [`FemProblem`] (the numerics
//! of `peritherm-fem`), its errors keyed to the case's keys, and the same outputs as
//! `peritherm run` (`field_<k>.csv`, `field_<k>.vtu`, run.json with the reference
//! comparison), written atomically.

use super::problem::{budget, default_dt, steps_for, FemModel, FemOptions, FemProblem};
use super::solve::{Scheme, Stepper};
use crate::atomic::write_atomic_with;
use crate::case::{Case, ReferenceSource, ReferenceSpec};
use crate::cloud::Cloud;
use crate::crack::Cutter;
use crate::error::{CoreError, Error, Result};
use crate::math::Vector;
use crate::model::crack_cutters;
use crate::output::{field_csv, field_path, field_vtu, vtu_path, Comparison, Fields, RunSummary};
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
        read_mesh: &|path| crate::gmsh::read(path).map_err(|e| e.to_string()),
    }
}

/// Builds mesh, matrices and conditions of `case` on elements of size `h` (box cases) or
/// on its own mesh (errors keyed as [`CoreError::Model`]).
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
    Ok(FemModel::build(&problem(case, opts))?)
}

/// A numerics error keyed to the case file (a non-finite state to the key `state`).
fn keyed(case: &Case, e: CoreError) -> Error {
    match e {
        CoreError::NonFinite { time, .. } => case.error(
            "state",
            format!("fem: temperature became non-finite by t = {time:e} s; check source and boundary values"),
        ),
        other => case.keyed(other),
    }
    .into()
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
            CoreError::model("--dt", format!("fem: must be a positive step, got {dt}")),
        ));
    }
    budget(&problem, dt).map_err(|e| keyed(case, e))?;
    let model = FemModel::build(&problem).map_err(|e| keyed(case, e))?;
    let name = case.path.display().to_string();
    crate::staging::write_into(out, &name, |dir| {
        solve(case, &model, dir, opts, dt, t_setup, progress)
    })
}

/// The FEM solve of the built `model` with its set-up timed from `t_setup`: the time loop
/// ([`run_outputs`]) and run.json, written into the staged directory `out`.
fn solve(
    case: &Case,
    model: &FemModel,
    out: &Path,
    opts: &FemOptions,
    dt: f64,
    t_setup: Instant,
    progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let mut clock = Clock {
        case,
        stepper: Stepper::new(&model.mesh, &model.system, &model.conditions, opts.scheme),
        scheme: opts.scheme,
        dt,
        steps: 0,
        total: total_steps(case, opts.scheme, dt),
        progress,
    };
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let origin = crate::provenance::write_copy(out, case)?;
    let reference = ReferenceCheck::of(case)?;
    let t_run = Instant::now();
    let initial_energy = model.energy(&model.theta0);
    let Record {
        energy,
        fields,
        comparisons,
        reference_seconds,
    } = run_outputs(&mut clock, model, out, reference)?;
    let summary = RunSummary {
        status: "complete".into(),
        title: case.title.clone(),
        case: case.path.display().to_string(),
        solver: "fem".into(),
        nodes: model.cloud.n_body,
        fictitious_nodes: 0,
        bonds: 0,
        pairs: model.system.cols.len(),
        steps: clock.steps,
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
        ranks: None,
        step_storage: None,
    };
    summary.write(out)?;
    Ok(summary)
}

/// What the output times of a FEM run recorded.
struct Record {
    /// Energy of the body at each output time, J.
    energy: Vec<f64>,
    /// The CSV field file of each output time.
    fields: Vec<String>,
    /// The comparisons with the reference at each output time (none without one).
    comparisons: Vec<Comparison>,
    /// Time spent evaluating and comparing the reference, s.
    reference_seconds: f64,
}

/// Steps from the model's initial field at t = 0 through every output time of the case,
/// writing each output's fields into `out` and comparing them with the `reference`, if any.
fn run_outputs<P: FnMut(u64, u64)>(
    clock: &mut Clock<'_, P>,
    model: &FemModel,
    out: &Path,
    mut reference: Option<ReferenceCheck>,
) -> Result<Record> {
    let mut theta = model.theta0.clone();
    let mut flux = vec![Vector::zeros(); theta.len()];
    let damage = vec![0.0; theta.len()];
    let (mut energy, mut fields, mut t) = (Vec::new(), Vec::new(), 0.0);
    for (k, &to) in clock.case.outputs.iter().enumerate() {
        clock.advance(&mut theta, t, to)?;
        t = to;
        energy.push(model.energy(&theta));
        model.recovery.flux(&model.mesh, &theta, &mut flux);
        let classical = reference
            .as_mut()
            .map(|r| r.compare(model, &theta, to))
            .transpose()?;
        let f = Fields {
            theta: &theta,
            damage: &damage,
            flux: &flux,
            reference: classical.as_deref(),
        };
        fields.push(write_field(out, k + 1, &model.cloud, &f)?);
    }
    let (comparisons, reference_seconds) =
        reference.map_or((Vec::new(), 0.0), |r| (r.comparisons, r.seconds));
    Ok(Record {
        energy,
        fields,
        comparisons,
        reference_seconds,
    })
}

/// Writes `field_<k>.csv` and `field_<k>.vtu` of output `k` (from 1) into `out`; returns
/// the CSV's name.
fn write_field(out: &Path, k: usize, cloud: &Cloud, f: &Fields) -> Result<String> {
    write_atomic_with(&field_path(out, k), |w| field_csv(w, cloud, f))?;
    write_atomic_with(&vtu_path(out, k), |w| field_vtu(w, cloud, f))?;
    Ok(format!("field_{k}.csv"))
}

/// The number of steps of a FEM run: one steady solve per output, or the steps of about
/// `dt` (s) that end on every output time.
fn total_steps(case: &Case, scheme: Scheme, dt: f64) -> u64 {
    match scheme {
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
    }
}

/// The stepping of a FEM run, counting the steps for `progress(done, total)`.
struct Clock<'a, P> {
    case: &'a Case,
    stepper: Stepper<'a>,
    scheme: Scheme,
    /// The step asked for, s.
    dt: f64,
    /// Steps done.
    steps: u64,
    /// Steps of the whole run.
    total: u64,
    progress: P,
}

impl<P: FnMut(u64, u64)> Clock<'_, P> {
    /// Takes θ from time `t` to the output time `to` (s): the steady state at `to`, or equal
    /// steps of at most `dt` that end on `to`.
    fn advance(&mut self, theta: &mut [f64], t: f64, to: f64) -> Result<()> {
        let case = self.case;
        if self.scheme == Scheme::Steady {
            self.stepper.steady(theta, to).map_err(|e| keyed(case, e))?;
            self.steps += 1;
            (self.progress)(self.steps, self.total);
        } else {
            let n = steps_for(to - t, self.dt);
            let h = (to - t) / n as f64;
            for s in 0..n {
                let now = if s + 1 == n { to - h } else { t + s as f64 * h };
                self.stepper
                    .step(theta, now, h)
                    .map_err(|e| keyed(case, e))?;
                self.steps += 1;
                (self.progress)(self.steps, self.total);
            }
        }
        Ok(())
    }
}

/// The comparison of a FEM run with the case's reference at every output time.
struct ReferenceCheck<'a> {
    reference: &'a ReferenceSpec,
    /// Crack facets for interpolating a reference table without looking across a crack
    /// (the geometry's own boundary sets hold a mesh's crack groups).
    cutters: Vec<Cutter>,
    /// The comparisons so far, one per output time.
    comparisons: Vec<Comparison>,
    /// Time spent evaluating and comparing, s.
    seconds: f64,
}

impl<'a> ReferenceCheck<'a> {
    /// The check of `case`'s reference; `None` without one, or when the reference is this
    /// FEM solve (nothing to compare with here).
    fn of(case: &'a Case) -> Result<Option<ReferenceCheck<'a>>> {
        let reference = case
            .reference
            .as_ref()
            .filter(|r| !matches!(r.source, ReferenceSource::Fem(_)));
        let Some(reference) = reference else {
            return Ok(None);
        };
        let cutters = if case.spec.cracks.is_empty() {
            Vec::new()
        } else {
            crack_cutters(&case.spec.geometry.bare_cloud()?, &case.spec.cracks)
        };
        Ok(Some(ReferenceCheck {
            reference,
            cutters,
            comparisons: Vec::new(),
            seconds: 0.0,
        }))
    }

    /// Compares θ at time `to` (s) with the reference and returns the reference's
    /// temperatures at the nodes, °C.
    fn compare(&mut self, model: &FemModel, theta: &[f64], to: f64) -> Result<Vec<f64>> {
        let started = Instant::now();
        let r = self.reference;
        let classical = classical_at(&model.cloud, &r.source, to, &self.cutters)?;
        let tips = crate::crack::tips_at(&self.cutters, to);
        self.comparisons
            .push(compare(&model.cloud, theta, &classical, r, to, &tips));
        self.seconds += started.elapsed().as_secs_f64();
        Ok(classical)
    }
}
