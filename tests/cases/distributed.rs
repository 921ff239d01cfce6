//! A distributed run gives the serial run's files, bit for bit: ranks simulated by threads of
//! one process ([`InProcessLink`], the protocol of the MPI build without MPI), each building its
//! share of the model where the case allows it. Called for every
//! bundled case by [`crate::bundled`]; the MPI build's own tests run the same under `mpiexec`.

use crate::common::case::CaseToml;
use crate::common::runs::{field_files_differ_by, same_field_files};
use peritherm::case::Case;
use peritherm::model::Model;
use peritherm::prepare::{build_rank, shares, Options};
use peritherm::run::run_ranked;
use peritherm::solve::exchange::{InProcessLink, RankPlan};
use std::path::Path;
use std::time::Instant;

/// Runs `case` over `ranks` in-process ranks into `out`; rank 0's summary. Each rank builds
/// its share of the model when the case allows it ([`peritherm::prepare::build_rank`]), else
/// they share the whole `model`, as the MPI ranks would each build it.
pub fn run_in_process(
    case: &Case,
    model: &Model,
    ranks: usize,
    out: &Path,
) -> peritherm::output::RunSummary {
    let links = InProcessLink::group(ranks, model.cloud.len());
    let whole = RankPlan::all(model, ranks);
    let summaries: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = links
            .into_iter()
            .zip(whole)
            .map(|(link, plan)| {
                s.spawn(move || {
                    let started = Instant::now();
                    if !shares(case) {
                        let ex = link.with_plan(plan);
                        return run_ranked(case, model, out, started, &ex, |_, _| {});
                    }
                    let (share, plan) = build_rank(case, &Options::default(), &link)?;
                    let ex = link.with_plan(plan);
                    run_ranked(case, &share, out, started, &ex, |_, _| {})
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut summaries = summaries.into_iter();
    let first = summaries.next().unwrap().unwrap_or_else(|e| panic!("{e}"));
    for other in summaries {
        assert!(other.unwrap_or_else(|e| panic!("{e}")).is_none());
    }
    first.expect("rank 0 writes the summary")
}

/// Runs `case` distributed over 2 and 3 in-process ranks and checks the fields against the
/// serial run in `serial_dir` (run.json lists them): explicit runs bit for bit, fixed-step
/// implicit and steady runs (distributed CG against the serial direct solve) within
/// [`IMPLICIT_AGREEMENT`]. Adaptive runs, which every rank steps whole, run over 2 ranks
/// when their serial run took under a second (`serial_seconds`): bit for bit.
pub fn same_as_serial(case: &Case, model: &Model, serial_dir: &Path, serial_seconds: f64) {
    let serial = peritherm::output::RunSummary::read(serial_dir).unwrap();
    let replicated = case.tolerance.is_some();
    let ranks: &[usize] = match (replicated, serial_seconds < 1.0) {
        (false, _) => &[2, 3],
        (true, true) => &[2],
        (true, false) => &[],
    };
    let exact = !case.integrator.is_implicit();
    for &ranks in ranks {
        let out = tempfile::tempdir().unwrap();
        let s = run_in_process(case, model, ranks, out.path());
        let r = s.ranks.as_ref().expect("ranks in run.json");
        assert_eq!(r.size, ranks);
        assert_eq!(r.nodes.iter().sum::<usize>(), model.cloud.n_body);
        let setup = if shares(case) { "share" } else { "whole" };
        assert_eq!(r.setup, setup, "{}", case.path.display());
        // the shares' bonds add up to the whole model's
        assert_eq!(r.bonds.iter().sum::<usize>(), model.bonds);
        assert_eq!((s.bonds, s.pairs), (serial.bonds, serial.pairs));
        let what = format!(
            "{} on {ranks} ranks ({}, {setup})",
            case.path.display(),
            r.mode
        );
        let read = peritherm::output::RunSummary::read(out.path()).unwrap();
        if exact || r.mode == "replicated" {
            same_field_files(serial_dir, out.path(), &serial.fields, &what);
            // both as run.json has them (serde_json's parse of a float may differ in its last
            // bit from the value written, the same way for both)
            assert_eq!(read.energy, serial.energy, "{what}");
            continue;
        }
        let d = field_files_differ_by(serial_dir, out.path(), &serial.fields);
        assert!(d <= IMPLICIT_AGREEMENT, "{what}: fields differ by {d:e}");
        // the energies are Σ V ρc θ of these temperatures: where θ changes sign, as in the
        // crack plates, they cancel down to 1e-10 J, so they are not compared relative to
        // themselves
        assert_eq!(read.energy.len(), serial.energy.len(), "{what}");
    }
}

/// Relative agreement of a distributed implicit or steady run with the serial one (per
/// quantity, of its largest magnitude in the serial run): the 1e-12. The distributed
/// run solves by CG to [`peritherm::solve::implicit::DISTRIBUTED_CG_TOLERANCE`] (1e-15
/// relative residual, or until round-off stalls it), the serial by a direct factorisation;
/// both err by round-off times the condition number of cM + A.
const IMPLICIT_AGREEMENT: f64 = 1e-12;

/// Fixed-step implicit schemes and the steady solve, distributed over 2 and 3 ranks (each
/// building its share, solving by block-Jacobi CG), against the serial run within
/// [`IMPLICIT_AGREEMENT`]: a dual-horizon plate (spacings 0.02 and 0.05) with a held face, a
/// convective one, insulated ones and a source.
#[test]
fn implicit_and_steady_runs_distribute() {
    for (integrator, dt) in [
        ("backward_euler", 0.05),
        ("crank_nicolson", 0.05),
        ("bdf2", 0.05),
        ("steady", 0.0),
    ] {
        let mut toml = CaseToml::new(2)
            .domain("[0.0, 0.0]", "[1.0, 0.5]")
            .region("fine", "spacing = 0.02", 3.0)
            .region_key("max = [0.4, 0.5]")
            .region("coarse", "spacing = 0.05", 3.0)
            .region_key("min = [0.4, 0.0]")
            .material("m", 2.0, 300.0, 0.5)
            .section("[boundary.x_min]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 1.0")
            .section("[boundary.x_max]\ntype = \"convection\"\nh = 5.0\nambient = 0.0")
            .section("[source]\nvalue = \"10*x*y\"")
            .initial("sin(7*x) + 3*cos(5*y)")
            .end(0.5)
            .time_key(&format!("integrator = \"{integrator}\""))
            .time_key("outputs = [0.25, 0.5]");
        if dt > 0.0 {
            toml = toml.time_key(&format!("dt = {dt}"));
        }
        let case = toml.case("implicit_ranks.toml");
        let model = Model::build(&case.spec).unwrap();
        let serial = tempfile::tempdir().unwrap();
        peritherm::run::run_model(&case, &model, serial.path(), Instant::now(), |_, _| {}).unwrap();
        let summary = peritherm::output::RunSummary::read(serial.path()).unwrap();
        for ranks in [2, 3] {
            let out = tempfile::tempdir().unwrap();
            let s = run_in_process(&case, &model, ranks, out.path());
            let r = s.ranks.as_ref().unwrap();
            assert_eq!(
                (r.mode.as_str(), r.setup.as_str()),
                ("rows", "share"),
                "{integrator}"
            );
            let d = field_files_differ_by(serial.path(), out.path(), &summary.fields);
            eprintln!("{integrator} on {ranks} ranks: fields within {d:.1e}");
            assert!(
                d <= IMPLICIT_AGREEMENT,
                "{integrator} on {ranks} ranks: {d:e}"
            );
        }
    }
}

/// A case whose system is asymmetric across ranks (a gmsh triangulation without consistent
/// weights: the held side's mirror images are interpolated) cannot be solved by distributed
/// CG: the ranks find the asymmetry between their shares' rows by comparing the pairs they
/// hold with one another's, build the whole model instead and step it on every rank, which
/// gives the serial run's bits.
#[test]
fn an_asymmetric_implicit_case_runs_whole_on_every_rank() {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/conv_rect_tri_L1.msh");
    let case = CaseToml::new(2)
        .mesh(&mesh.display().to_string())
        .region("body", "", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .section("[kernel]\nconsistency = \"none\"")
        .section("[boundary.held]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 0.0")
        .initial_value(1.0)
        .end(0.01)
        .time_key("integrator = \"backward_euler\"\ndt = 0.005")
        .case("asymmetric.toml");
    assert!(shares(&case));
    let model = Model::build(&case.spec).unwrap();
    let serial = tempfile::tempdir().unwrap();
    let s =
        peritherm::run::run_model(&case, &model, serial.path(), Instant::now(), |_, _| {}).unwrap();
    let out = tempfile::tempdir().unwrap();
    let d = run_in_process(&case, &model, 2, out.path());
    let r = d.ranks.as_ref().unwrap();
    assert_eq!((r.mode.as_str(), r.setup.as_str()), ("replicated", "whole"));
    same_field_files(
        serial.path(),
        out.path(),
        &s.fields,
        "asymmetric.toml on 2 ranks",
    );
}
