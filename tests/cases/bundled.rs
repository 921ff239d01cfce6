//! Every bundled case parses, passes the validation path of `check` and `run`
//! ([`peritherm::prepare`]: budget, model, semantic checks, and the plan of the time loop
//! inside `run_model`), honours its own stability bound and runs a few steps (each model is
//! built once and reused for the run), and gives the same files distributed over 2 and 3
//! ranks ([`crate::distributed`]).

use peritherm::case::Case;
use peritherm::run::run_model;
use std::path::Path;

#[test]
fn every_case_builds_and_starts() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 13, "{names:?}");
    for path in names {
        let started = std::time::Instant::now();
        let mut case = Case::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let model =
            peritherm::prepare::build(&case, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        let bound = case.integrator.stable_dt(&model);
        if let Some(dt) = case.dt {
            assert!(
                dt <= bound,
                "{}: dt {dt} above the bound {bound}",
                path.display()
            );
        }
        // a few steps only: the full runs are the README's benchmark table; adaptive cases
        // (time.tolerance) run to a thousandth of their first output
        let adaptive = case.tolerance.is_some();
        let dt = if adaptive {
            case.outputs[0] * 1e-3
        } else {
            case.dt.unwrap_or(0.9 * bound)
        };
        case.outputs = vec![3.0 * dt];
        // a FEM reference would be solved in full first: tests/convergence/references.rs covers
        // that path
        if case
            .reference
            .as_ref()
            .is_some_and(|r| matches!(r.source, peritherm::case::ReferenceSource::Fem(_)))
        {
            case.reference = None;
        }
        let out = tempfile::tempdir().unwrap();
        let s = run_model(&case, &model, out.path(), started, |_, _| {}).unwrap();
        if adaptive {
            let st = s.implicit.expect("adaptive counters");
            assert!(s.steps >= 1 && st.accepted == s.steps, "{}", path.display());
        } else {
            assert_eq!(s.steps, 3, "{}", path.display());
        }
        assert!(out.path().join("field_1.csv").exists());
        let serial_seconds = started.elapsed().as_secs_f64();
        // and distributed over 2 and 3 ranks, the same bits
        crate::distributed::same_as_serial(&case, &model, out.path(), serial_seconds);
        eprintln!(
            "{}: {serial_seconds:.1} s, {:.1} s with the distributed runs",
            path.display(),
            started.elapsed().as_secs_f64()
        );
    }
}
