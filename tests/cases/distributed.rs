//! A distributed run gives the serial run's files, bit for bit: ranks simulated by threads of
//! one process ([`InProcessLink`], the protocol of the MPI build without MPI), each building its
//! share of the model where the case allows it. Called for every
//! bundled case by [`crate::bundled`]; the MPI build's own tests run the same under `mpiexec`.

use crate::common::runs::same_field_files;
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
/// serial run in `serial_dir` (run.json lists them). The implicit steppers, which are not
/// distributed (each rank steps the whole model), run over 2 ranks when their serial run took
/// under a second (`serial_seconds`): the protocol around them is the same for all.
pub fn same_as_serial(case: &Case, model: &Model, serial_dir: &Path, serial_seconds: f64) {
    let serial = peritherm::output::RunSummary::read(serial_dir).unwrap();
    let explicit = !case.integrator.is_implicit();
    let ranks: &[usize] = match (explicit, serial_seconds < 1.0) {
        (true, _) => &[2, 3],
        (false, true) => &[2],
        (false, false) => &[],
    };
    for &ranks in ranks {
        let out = tempfile::tempdir().unwrap();
        let s = run_in_process(case, model, ranks, out.path());
        let r = s.ranks.as_ref().expect("ranks in run.json");
        assert_eq!(r.size, ranks);
        assert_eq!(r.nodes.iter().sum::<usize>(), model.cloud.n_body);
        let setup = if shares(case) { "share" } else { "whole" };
        assert_eq!(r.setup, setup, "{}", case.path.display());
        // the shares' bonds add up to the whole model's
        assert_eq!(r.bonds.iter().sum::<usize>(), model.horizons.n_bonds());
        assert_eq!((s.bonds, s.pairs), (serial.bonds, serial.pairs));
        let what = format!(
            "{} on {ranks} ranks ({}, {setup})",
            case.path.display(),
            r.mode
        );
        same_field_files(serial_dir, out.path(), &serial.fields, &what);
        // both as run.json has them (serde_json's parse of a float may differ in its last bit
        // from the value written, the same way for both)
        let read = peritherm::output::RunSummary::read(out.path()).unwrap();
        assert_eq!(read.energy, serial.energy, "{what}");
    }
}
