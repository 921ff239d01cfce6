//! Running a case end to end: build, integrate, write fields and the summary.

use crate::atomic::{write_atomic, write_atomic_with};
use crate::case::{Case, ReferenceSource, ReferenceSpec};
use crate::crack::tips_at;
use crate::error::{CoreError, Error, IoError, Result};
use crate::fem::run_fem;
use crate::gather::StepStorage;
use crate::history::{output_index, Recorder};
use crate::model::crack_cutters;
use crate::model::Model;
use crate::operator::Conductance;
use crate::output::read_field;
use crate::output::{
    field_csv, field_path, field_pvtu, field_vtu, field_vtu_rows, piece_path, pvd_path, pvtu_path,
    series_pvd, vtu_path, Fields, Ranks, RunSummary,
};
use crate::prepare::{keyed, likely_cause, plan, Options, Plan};
use crate::reference::{ReferenceTable, Snapshot};
use crate::report::{classical_at, compare};
use crate::solve::exchange::{Exchange, Reduce};
use crate::solve::{integrate, Engine, Integrator, RunStats, Schedule};
use crate::staging::{reached, write_into};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Runs `case`, writing its outputs into `out`; `progress(done, total)` reports steps.
pub fn run_case(case: &Case, out: &Path, progress: impl FnMut(u64, u64)) -> Result<RunSummary> {
    run_case_with(case, out, &Options::default(), progress)
}

/// [`run_case`] with run options (the memory budget): the budget is checked before the model
/// is built ([`crate::prepare::build`]).
pub fn run_case_with(
    case: &Case,
    out: &Path,
    options: &Options,
    progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let t_setup = Instant::now();
    let model = crate::prepare::build(case, options)?;
    run_model(case, &model, out, t_setup, progress)
}

/// Runs `case` on its already built `model` (set-up timed from `t_setup`), writing into `out`
/// transactionally ([`crate::staging`]): nothing is written before the time loop is planned.
pub fn run_model(
    case: &Case,
    model: &Model,
    out: &Path,
    t_setup: Instant,
    progress: impl FnMut(u64, u64),
) -> Result<RunSummary> {
    let plan = plan(case, model)?;
    let name = case.path.display().to_string();
    write_into(out, &name, |dir| {
        execute(case, model, plan, dir, t_setup, progress, None)
    })
}

/// One rank's part in a distributed run.
pub struct Rank<'a> {
    /// The communication with the other ranks.
    pub exchange: &'a dyn Exchange,
    /// `rows` when the stepper is distributed, `replicated` when every rank steps it all.
    pub mode: &'static str,
}

/// Runs `case` on this rank's `model` (a share, or the whole model:
/// [`crate::prepare::build_rank`]) as one rank of a distributed run over `exchange`:
/// explicit runs, phase change included, step their rows only
/// ([`crate::solve::explicit::Explicit::distribute`],
/// [`crate::solve::enthalpy::Enthalpic::distribute`], and for fixed-step implicit and steady
/// runs with a symmetric system [`crate::solve::implicit::Implicit::distribute`]); adaptive
/// and asymmetric implicit runs step the whole model on every rank. Rank 0 writes `out` as a serial run
/// would, with the same bits, and returns the summary; the other ranks return None. A rank
/// that fails stops all of them.
pub fn run_ranked<'a>(
    case: &Case,
    model: &'a Model,
    out: &Path,
    t_setup: Instant,
    exchange: &'a dyn Exchange,
    progress: impl FnMut(u64, u64),
) -> Result<Option<RunSummary>> {
    let mut plan = plan(case, model)?;
    let adaptive = plan.adaptive.is_some();
    let mode = match &mut plan.engine {
        Engine::Explicit(e) => {
            e.distribute(exchange);
            "rows"
        }
        Engine::Enthalpic(e) => {
            e.distribute(exchange);
            "rows"
        }
        Engine::Implicit(e) if !adaptive => {
            if e.distribute(exchange).map_err(|e| keyed(case, e))? {
                "rows"
            } else if model.rows != (0..model.cloud.n_body) {
                return Err(case.error(
                    "time.integrator",
                    format!(
                        "a distributed implicit run needs a symmetric system, and this one is asymmetric to {:.1e} (interpolated mirror images or flux relations): run it on one rank, or with euler or rk4",
                        e.system().asymmetry
                    ),
                )
                .into());
            } else {
                "replicated"
            }
        }
        Engine::Implicit(_) => "replicated",
    };
    let rank = Rank { exchange, mode };
    if exchange.rank() != 0 {
        return follow(case, model, plan, &rank).map(|_| None);
    }
    let mut entered = false;
    let name = case.path.display().to_string();
    let done = write_into(out, &name, |dir| {
        entered = true;
        execute(case, model, plan, dir, t_setup, progress, Some(&rank))
    });
    if !entered {
        // the others wait for the start of the time loop: tell them it will not come
        agree(Some(exchange), false);
    }
    done.map(Some)
}

/// The heat flux (W/m²) and damage of every body node at output time `t` (s): a share
/// computes its own rows and the ranks gather them (a collective then); a whole model
/// computes them all.
fn output_fields(
    model: &Model,
    t: f64,
    theta: &[f64],
    conductance: &Conductance,
    exchange: Option<&dyn Exchange>,
) -> (Vec<crate::math::Vector>, Vec<f64>) {
    let mut flux = conductance.flux(&model.cloud, theta);
    let mut damage = model.damage_at(t);
    let Some(ex) = exchange.filter(|_| model.rows != (0..model.cloud.n_body)) else {
        return (flux, damage);
    };
    let mut part = vec![0.0; model.cloud.len()];
    for axis in 0..3 {
        for (p, q) in part.iter_mut().zip(&flux) {
            *p = q[axis];
        }
        ex.all_gather(&mut part);
        for (q, p) in flux.iter_mut().zip(&part) {
            q[axis] = *p;
        }
    }
    if model.damage.is_some() {
        // without cracks the damage is 0 everywhere, on every rank alike
        let n = damage.len();
        part[..n].copy_from_slice(&damage);
        ex.all_gather(&mut part);
        damage.copy_from_slice(&part[..n]);
    }
    (flux, damage)
}

/// True on every rank when `ok` on all ranks (a collective, [`Exchange::reduce`]); a
/// serial run (no exchange) agrees with itself.
fn agree(exchange: Option<&dyn Exchange>, ok: bool) -> bool {
    match exchange {
        Some(ex) => ex.reduce(if ok { 0.0 } else { 1.0 }, Reduce::Max) == 0.0,
        None => ok,
    }
}

/// The time loop of a rank other than 0: the same steps and collectives as rank 0's
/// ([`execute`]), no output.
fn follow(case: &Case, model: &Model, plan: Plan, rank: &Rank) -> Result<()> {
    let exchange = rank.exchange;
    let schedule = plan.schedule();
    let Plan { mut engine, .. } = plan;
    if !agree(Some(exchange), true) {
        return Err(CoreError::Peer.into());
    }
    let times = case.times();
    let mut theta = model.theta0.clone();
    let peer = |ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(Error::from(CoreError::Peer))
        }
    };
    integrate(
        &mut engine,
        &schedule,
        &mut theta,
        0.0,
        &times,
        |k, t, th, conductance, _| {
            if output_index(&case.outputs, times[k]).is_some() {
                output_fields(model, t, th, conductance, Some(exchange));
            }
            peer(agree(Some(exchange), true))
        },
        |_, _| {},
    )?;
    ranks(case, model, rank);
    Ok(())
}

/// Directed bonds of the body rows `rows` and from fictitious nodes into them: the model's own
/// count when it holds just those rows (a share), else counted by a search of those rows (a
/// whole model stepped in shares; the model keeps no neighbour lists).
fn bonds_of(case: &Case, model: &Model, rows: std::ops::Range<usize>) -> usize {
    if rows == model.rows {
        return model.bonds;
    }
    let census = crate::horizons::Horizons::census(&model.cloud, &case.spec.kernel, &[rows]);
    census[0].bonds
}

/// Per-rank sizes of a distributed run for run.json: the last collective of a run, which
/// rank 0 calls after its time loop and the others at the end of [`follow`].
fn ranks(case: &Case, model: &Model, rank: &Rank) -> Ranks {
    let ex = rank.exchange;
    let exchange_seconds = ex.reduce(ex.exchange_seconds(), Reduce::Max);
    let rows = ex.rows();
    let off = &model.conductance.offsets;
    let each = |x: usize| -> Vec<usize> {
        let all = ex.gather_counts(x as u64);
        all.into_iter().map(|v| v as usize).collect()
    };
    let ghosts = each(ex.plan().halo.ghosts());
    let bonds = each(bonds_of(case, model, rows.clone()));
    Ranks {
        size: ex.size(),
        mode: rank.mode.into(),
        nodes: each(rows.len()),
        pairs: each(off[rows.end] - off[rows.start]),
        halo_bytes: ghosts.iter().sum::<usize>() * 8,
        ghosts,
        bonds,
        setup: match model.rows == (0..model.cloud.n_body) {
            true => "whole".into(),
            false => "share".into(),
        },
        exchange_seconds,
    }
}

/// The time loop of a planned run, writing into the staged directory `out`; as rank 0 of a
/// distributed run when `rank` is given (the others [`follow`]).
fn execute(
    case: &Case,
    model: &Model,
    plan: Plan,
    out: &Path,
    t_setup: Instant,
    mut progress: impl FnMut(u64, u64),
    rank: Option<&Rank>,
) -> Result<RunSummary> {
    let ex = rank.map(|r| r.exchange);
    let schedule = plan.schedule();
    let Plan {
        total, mut engine, ..
    } = plan;
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    // first, so that a run that fails or is interrupted also says which case it was
    let origin = crate::provenance::write_copy(out, case).map_err(Error::from);
    let mut theta = model.theta0.clone();
    let initial_energy = model.energy(&theta);
    let t_run = Instant::now();
    let ready = origin.and_then(|origin| Ok((origin, OutputWriter::new(case, model, out)?)));
    if !agree(ex, ready.is_ok()) {
        return Err(ready.err().unwrap_or(CoreError::Peer.into()));
    }
    let (origin, mut writer) = ready?;
    writer.pieces = pieces(ex);
    let fem_seconds = t_run.elapsed().as_secs_f64();
    let reference = writer.reference.clone();
    // the steppers stop at the outputs and at the history's samples
    let times = case.times();
    let mut recorder = recorder(case, model, reference.as_ref(), &theta);
    let on_output = |k: usize, t: f64, th: &[f64], conductance: &Conductance, e: f64| {
        // an interrupted run reports at least the last output it wrote
        reached(t);
        if let Some(r) = recorder.as_mut() {
            r.record(t, th);
        }
        let written = match output_index(&case.outputs, times[k]) {
            Some(f) => {
                let (flux, damage) = output_fields(model, t, th, conductance, ex);
                writer.write_fields(f, t, th, (&flux, &damage), e)
            }
            None => Ok(()),
        };
        match (agree(ex, written.is_ok()), written) {
            (false, Ok(())) => Err(CoreError::Peer.into()),
            (_, w) => w,
        }
    };
    let mut on_step = step_progress(case, &schedule, total, &mut progress);
    // the stepping starts: a progress display's clock starts here (set-up and reference excluded)
    on_step(0, 0.0);
    let stats = integrate(
        &mut engine,
        &schedule,
        &mut theta,
        0.0,
        &times,
        on_output,
        on_step,
    )
    .map_err(|e| run_error(case, model, e))?;
    // the last collective: whatever fails below fails on rank 0 alone
    let ranks = rank.map(|r| ranks(case, model, r));
    let history = recorder.as_ref().map(|r| r.write(out)).transpose()?;
    let timing = Timing {
        setup_seconds,
        run_seconds: t_run.elapsed().as_secs_f64(),
        fem_seconds,
    };
    let mut summary = summary(case, model, &schedule, &engine, stats, writer, timing);
    summary.initial_energy = initial_energy;
    summary.history = history;
    summary.origin = Some(origin);
    with_ranks(&mut summary, model, ranks);
    summary.write(out)?;
    Ok(summary)
}

/// What a run reports after each step `s` reaching `t` (s): the time reached (for an
/// interrupted run) and `progress(done, total)` (adaptive: the number of steps is not known,
/// it is extrapolated from the time reached).
fn step_progress<'p>(
    case: &Case,
    schedule: &Schedule,
    total: u64,
    progress: &'p mut impl FnMut(u64, u64),
) -> impl FnMut(u64, f64) + 'p {
    let t_last = case.outputs.last().copied().unwrap_or(case.end);
    let adaptive = schedule.adaptive.is_some();
    move |s, t| {
        reached(t);
        match adaptive {
            true => progress(s, ((s as f64) * t_last / t.max(f64::MIN_POSITIVE)) as u64),
            false => progress(s, total),
        }
    }
}

/// The body rows of each rank of a distributed run, one VTK piece each; none for a serial
/// run or one rank.
fn pieces(exchange: Option<&dyn Exchange>) -> Vec<std::ops::Range<usize>> {
    match exchange.filter(|ex| ex.size() > 1) {
        Some(ex) => {
            let p = &ex.plan().partition;
            (0..p.ranks()).map(|r| p.range(r)).collect()
        }
        None => Vec::new(),
    }
}

/// Puts the ranks' sizes into `summary`; a share holds its own rows' bonds, so the model's
/// bonds and pairs are the sums over the ranks.
fn with_ranks(summary: &mut RunSummary, model: &Model, ranks: Option<Ranks>) {
    if let Some(r) = ranks
        .as_ref()
        .filter(|_| model.rows != (0..model.cloud.n_body))
    {
        summary.bonds = r.bonds.iter().sum();
        summary.pairs = r.pairs.iter().sum();
    }
    summary.ranks = ranks;
}

/// A time-loop error keyed to the case: a non-finite temperature names the key that most
/// likely caused it ([`likely_cause`]).
fn run_error(case: &Case, model: &Model, e: Error) -> Error {
    match e {
        Error::Core(CoreError::NonFinite { node, time }) => {
            let p = model.cloud.pos[node];
            case.error(
                likely_cause(case, model, node, time),
                format!(
                    "temperature became non-finite near ({}, {}, {}) by t = {time:e} s; this key most likely caused it (else check the source, boundary values and time.dt)",
                    p.x, p.y, p.z
                ),
            )
            .into()
        }
        other => keyed(case, other),
    }
}

/// Wall-clock times of a run, s.
struct Timing {
    /// Building the model and planning the time loop.
    setup_seconds: f64,
    /// The time loop, output and references included.
    run_seconds: f64,
    /// Solving a `[reference.fem]` before the time loop.
    fem_seconds: f64,
}

/// The run.json of a finished run (without its initial energy, history and origin).
fn summary(
    case: &Case,
    model: &Model,
    schedule: &Schedule,
    engine: &Engine,
    stats: RunStats,
    writer: OutputWriter,
    timing: Timing,
) -> RunSummary {
    let implicit = engine.implicit();
    let dt = schedule.dt;
    RunSummary {
        status: "complete".into(),
        title: case.title.clone(),
        case: case.path.display().to_string(),
        solver: "peridynamics".into(),
        nodes: model.cloud.n_body,
        fictitious_nodes: model.cloud.n_fictitious(),
        bonds: model.bonds,
        pairs: model.conductance.nnz(),
        steps: stats.steps,
        // implicit runs: the step taken (adaptive: the first; 0 for steady) and, for
        // comparison, Euler's bound
        dt: match (implicit, schedule.adaptive) {
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
        fields: writer.fields,
        initial_energy: 0.0,
        energy: writer.energy,
        setup_seconds: timing.setup_seconds,
        wall_seconds: timing.run_seconds - writer.reference_seconds - timing.fem_seconds,
        reference_seconds: writer.reference_seconds + timing.fem_seconds,
        threads: rayon::current_num_threads(),
        consistency: model.correction,
        step_storage: (model.step != StepStorage::default()).then(|| model.step.name()),
        reference: writer.comparisons,
        implicit: implicit.map(|st| st.stats),
        history: None,
        settings: case.settings.clone(),
        origin: None,
        ranks: None,
    }
}

/// What a run writes at each output time into its (staged) directory: `field_<k>.csv` and
/// `field_<k>.vtu` with the flux, the damage and the case's reference, and the comparison
/// with that reference; it keeps what run.json lists.
pub struct OutputWriter<'a> {
    case: &'a Case,
    model: &'a Model,
    out: &'a Path,
    cutters: Vec<crate::crack::Cutter>,
    /// The case's reference, resolved ([`resolve_reference`]).
    pub reference: Option<ReferenceSpec>,
    /// Energy of the body at each output written, J.
    pub energy: Vec<f64>,
    /// Field files written (`field_<k>.csv`, names only).
    pub fields: Vec<String>,
    /// Comparisons with the reference, one per output written.
    pub comparisons: Vec<crate::output::Comparison>,
    /// Time spent evaluating and comparing with the reference, s.
    pub reference_seconds: f64,
    /// The body rows of each rank of a distributed run (empty: a serial run), one piece each
    /// of the parallel VTK files.
    pub pieces: Vec<std::ops::Range<usize>>,
    /// `(time, VTK file)` of each output written, for `fields.pvd`.
    series: Vec<(f64, String)>,
}

impl<'a> OutputWriter<'a> {
    /// Resolves the case's reference (a `[reference.fem]` is solved into `out/fem/`).
    pub fn new(case: &'a Case, model: &'a Model, out: &'a Path) -> Result<Self> {
        Ok(OutputWriter {
            case,
            model,
            out,
            cutters: crack_cutters(&model.cloud, &case.spec.cracks),
            reference: resolve_reference(case, out)?,
            energy: Vec::new(),
            fields: Vec::new(),
            comparisons: Vec::new(),
            reference_seconds: 0.0,
            pieces: Vec::new(),
            series: Vec::new(),
        })
    }

    /// Writes output `k` (from 0) at time `t` (s): temperature `th` of every node (°C), the
    /// flux through `conductance` (W/K) and the body's energy `e` (J).
    pub fn write(
        &mut self,
        k: usize,
        t: f64,
        th: &[f64],
        conductance: &crate::operator::Conductance,
        e: f64,
    ) -> Result<()> {
        let flux = conductance.flux(&self.model.cloud, th);
        self.write_with_flux(k, t, th, &flux, e)
    }

    /// [`OutputWriter::write`] with the heat flux of every body node given, W/m².
    pub fn write_with_flux(
        &mut self,
        k: usize,
        t: f64,
        th: &[f64],
        flux: &[crate::math::Vector],
        e: f64,
    ) -> Result<()> {
        let damage = self.model.damage_at(t);
        self.write_fields(k, t, th, (flux, &damage), e)
    }

    /// [`OutputWriter::write_with_flux`] with the damage of every body node given too
    /// (`nodal`: flux, W/m², and damage).
    pub fn write_fields(
        &mut self,
        k: usize,
        t: f64,
        th: &[f64],
        nodal: (&[crate::math::Vector], &[f64]),
        e: f64,
    ) -> Result<()> {
        let (case, model, out) = (self.case, self.model, self.out);
        let (flux, damage) = nodal;
        self.energy.push(e);
        let path = field_path(out, k + 1);
        let classical = match &self.reference {
            Some(r) => {
                let started = Instant::now();
                let classical = classical_at(&model.cloud, &r.source, t, &self.cutters)?;
                let tips = tips_at(&self.cutters, t);
                let c = compare(&model.cloud, th, &classical, r, t, &tips);
                let measures = [c.max_abs_diff, c.mean_sq_rel_diff, c.l2_rel_line, c.epsilon];
                if measures.iter().any(|v| !v.is_finite()) {
                    // finite values whose squares overflow: never an exact match
                    return Err(case.error(
                        "reference",
                        format!(
                            "the comparison with the reference overflows at t = {t} s (max |diff| = {:e}); its values are too large",
                            c.max_abs_diff
                        ),
                    )
                    .into());
                }
                self.comparisons.push(c);
                self.reference_seconds += started.elapsed().as_secs_f64();
                Some(classical)
            }
            None => None,
        };
        let f = Fields {
            theta: th,
            damage,
            flux,
            reference: classical.as_deref(),
        };
        write_atomic_with(&path, |w| field_csv(w, &model.cloud, &f))?;
        let vtk = self.write_vtk(k + 1, &f)?;
        self.series.push((t, vtk));
        write_atomic(&pvd_path(out), series_pvd(&self.series).as_bytes())?;
        self.fields.push(
            path.file_name()
                .expect("file")
                .to_string_lossy()
                .into_owned(),
        );
        Ok(())
    }
}

impl OutputWriter<'_> {
    /// Writes the VTK file of output `k` (from 1): `field_<k>.vtu`, or for a distributed run
    /// one piece per rank and `field_<k>.pvtu` over them; its name.
    fn write_vtk(&self, k: usize, f: &Fields) -> Result<String> {
        let (cloud, out) = (&self.model.cloud, self.out);
        if self.pieces.is_empty() {
            write_atomic_with(&vtu_path(out, k), |w| field_vtu(w, cloud, f))?;
            return Ok(format!("field_{k}.vtu"));
        }
        let dir = piece_path(out, k, 0);
        let dir = dir.parent().expect("a piece's directory");
        std::fs::create_dir_all(dir).map_err(|error| IoError::Io {
            path: dir.to_path_buf(),
            error,
        })?;
        let mut names = Vec::with_capacity(self.pieces.len());
        for (r, rows) in self.pieces.iter().enumerate() {
            let piece = |w: &mut dyn std::io::Write| field_vtu_rows(w, cloud, f, rows.clone());
            write_atomic_with(&piece_path(out, k, r), piece)?;
            names.push(format!("field_{k}/piece_{r}.vtu"));
        }
        let pvtu = field_pvtu(&names, f.reference.is_some());
        write_atomic(&pvtu_path(out, k), pvtu.as_bytes())?;
        Ok(format!("field_{k}.pvtu"))
    }
}

/// The recorder of the case's `[history]` (None without one), with the analytical reference
/// beside it when the case has one, and its first sample, θ0 at t = 0.
fn recorder<'a>(
    case: &Case,
    model: &Model,
    reference: Option<&'a ReferenceSpec>,
    theta0: &[f64],
) -> Option<Recorder<'a>> {
    let analytic = match reference.map(|r| &r.source) {
        Some(ReferenceSource::Analytic(a)) => Some(a),
        _ => None,
    };
    let mut r = Recorder::new(case.history.as_ref()?, &model.cloud, analytic);
    r.record(0.0, theta0);
    Some(r)
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
