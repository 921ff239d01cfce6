//! Coarse versions of the papers' benchmarks against their classical series solutions.
//! Each test states the paper's figure it must meet and why its tolerance is what it is.

use peritherm::case::Case;
use peritherm::output::Comparison;
use peritherm::report::{classical_at, compare};
use peritherm::run::run_case;
use std::path::Path;

/// Loads a bundled case and applies `edits` (key → replacement line) to its text.
fn case_with(name: &str, edits: &[(&str, &str)]) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    Case::parse(&text, &path).unwrap()
}

/// Runs a case into a temporary directory and returns its comparisons with the reference.
fn run(case: &Case) -> Vec<Comparison> {
    let dir = tempfile::tempdir().unwrap();
    let s = run_case(case, dir.path(), |_, _| {}).unwrap();
    s.reference
}

/// Bobaru & Duangpanya 2010 Example 3 at δ = 3L/200 (m = 4, 267 nodes) must already beat the
/// paper's eq 45 = 3.43e-5, which the paper reached with a 4× smaller horizon (δ = 3L/800).
#[test]
fn bar_flux_beats_bobaru_duangpanya_2010_eq45() {
    let case = case_with(
        "bar_flux.toml",
        &[
            ("cells = [1067]", "cells = [267]"),
            ("0.011780972450961724", "0.04712388980384690"),
        ],
    );
    let r = run(&case);
    let last = r.last().unwrap();
    assert!(
        last.mean_sq_rel_diff <= 3.43e-5,
        "eq 45 = {:e}",
        last.mean_sq_rel_diff
    );
}

/// Bobaru & Duangpanya 2010 Examples 1 and 2: δ-convergence of eq 13 at t = 8 s between δ = 3L/100
/// and 3L/200 at m = 4; the paper reports rates ≈ 1.0 and 1.5 for eq 45 (a squared measure, so ≥
/// 0.5 for our unsquared one); we require a rate ≥ 0.5, and eq 13 at δ = 3L/200 below the levels
/// measured when this test was written (0.0316 and 0.0101) plus 10 %.
#[test]
fn bars_converge_in_delta() {
    for (name, level) in [
        ("bar_dirichlet.toml", 0.035),
        ("bar_insulated_left.toml", 0.0111),
    ] {
        let mut errs = Vec::new();
        for (cells, radius) in [("cells = [267]", "0.3"), ("cells = [533]", "0.15")] {
            let case = case_with(
                name,
                &[
                    ("cells = [1067]", cells),
                    ("radius = 0.0375", &format!("radius = {radius}")),
                ],
            );
            errs.push(run(&case).last().unwrap().l2_rel_line);
        }
        let rate = (errs[0] / errs[1]).log2();
        eprintln!("{name}: eq13 {errs:?}, rate {rate}");
        assert!(rate >= 0.5, "{name}: rate {rate} ({errs:?})");
        assert!(errs[1] < level, "{name}: {errs:?}");
    }
}

/// Bobaru & Duangpanya 2012 Example 2 at δ = 13L/120 (61 × 61 nodes, m = 6.5): eq 13 along y = 0.5
/// at or below Table 1's first column (0.15741, 0.11342, 0.07517) at every time.
#[test]
fn square_one_hot_edge_meets_table1() {
    let case = case_with(
        "square_one_hot_edge.toml",
        &[("cells = [120, 120]", "cells = [60, 60]")],
    );
    let r = run(&case);
    let paper = [0.15741, 0.11342, 0.07517];
    for (c, p) in r.iter().zip(paper) {
        eprintln!("t = {}: eq13 = {} (paper {p})", c.time, c.l2_rel_line);
        assert!(
            c.l2_rel_line <= p,
            "t = {}: {} > {p}",
            c.time,
            c.l2_rel_line
        );
    }
}

/// Bobaru & Duangpanya 2012 Example 1 at δ = 13L/120 with Δ = L/64 (m = 6.93): eq 13 along y = 0.5
/// small, and the solution decays like the classical one (tolerance: Bobaru & Duangpanya 2012 Fig.
/// 12 shows eq 13 of a few 1e-2 at this horizon).
#[test]
fn square_dirichlet_follows_the_series() {
    let case = case_with(
        "square_dirichlet.toml",
        &[
            ("cells = [256, 256]", "cells = [64, 64]"),
            ("0.027083333333333334", "0.10833333333333334"),
        ],
    );
    let r = run(&case);
    for c in &r {
        eprintln!("t = {}: eq13 = {}", c.time, c.l2_rel_line);
        assert!(c.l2_rel_line < 0.05, "t = {}: {}", c.time, c.l2_rel_line);
    }
}

/// Wang, Oterkus & Oterkus (dual-horizon paper) §4.1, the dual-horizon plates at a 2.5× coarser
/// spacing (Δ1 = 2.5e-4 m), as bundled (lattice calibration and linear-consistency correction):
/// every node within 1 % of the 10 °C span of the classical solution at 5 ms, the paper's figure to
/// meet.
#[test]
fn dual_horizon_plates_within_one_percent() {
    for (name, d1, d2, dt) in [
        ("dh_plate_k1_m1.toml", "2.5e-4", "2.5e-4", "6e-7"),
        ("dh_plate_k1_m2.toml", "2.5e-4", "2.5e-4", "6e-7"),
        ("dh_plate_k0.5_m1.toml", "2.5e-4", "5e-4", "6e-7"),
        ("dh_plate_k0.5_m0.5.toml", "2.5e-4", "5e-4", "6e-7"),
    ] {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("cases")
                .join(name),
        )
        .unwrap();
        let s1 = text
            .lines()
            .find(|l| l.starts_with("spacing"))
            .unwrap()
            .to_string();
        let s2 = text
            .lines()
            .filter(|l| l.starts_with("spacing"))
            .nth(1)
            .unwrap()
            .to_string();
        let mut case = case_with(name, &[]);
        let edited = text
            .replacen(&s1, &format!("spacing = {d1}"), 1)
            .replacen(&s2, &format!("spacing = {d2}"), 1)
            .replace("dt = 1e-7", &format!("dt = {dt}"));
        case = Case::parse(&edited, &case.path).unwrap();
        let last = run(&case).pop().unwrap();
        eprintln!("{name}: max |diff| at 5 ms = {}", last.max_abs_diff);
        assert!(last.max_abs_diff <= 0.1, "{name}: {}", last.max_abs_diff);
    }
}

/// Wang, Oterkus & Oterkus §4.2 thermal shock at Δ = 0.1 m (k = 0.5, m = 0.5 at Δ1 = 0.1, Δ2 =
/// 0.2): against the Duhamel series at 3 and 6 s within 2 % of the peak boundary value 0.92 °C.
#[test]
fn thermal_shock_follows_duhamel() {
    let case = case_with(
        "thermal_shock_k0.5_m0.5.toml",
        &[
            ("spacing = 0.02", "spacing = 0.1"),
            ("spacing = 0.04", "spacing = 0.2"),
            ("dt = 3.75e-4", "dt = 3.75e-3"),
        ],
    );
    for c in run(&case) {
        eprintln!("t = {}: max |diff| = {}", c.time, c.max_abs_diff);
        assert!(
            c.max_abs_diff < 0.02 * 0.92,
            "t = {}: {}",
            c.time,
            c.max_abs_diff
        );
    }
}

/// Comparison measures are those of theory §9 (checked on a hand-made field).
#[test]
fn measures_follow_the_formulas() {
    let case = case_with(
        "bar_dirichlet.toml",
        &[
            ("cells = [1067]", "cells = [10]"),
            ("radius = 0.0375", "radius = 3.0"),
        ],
    );
    let model = peritherm::model::Model::build(&case.spec).unwrap();
    let r = case.reference.as_ref().unwrap();
    let exact = classical_at(&model.cloud, &r.source, 1.0, &[]).unwrap();
    let pd: Vec<f64> = exact.iter().map(|e| e * 1.01).collect();
    let mut r = r.clone();
    r.line_y = None;
    r.probe = Some(peritherm::math::Point::new(5.4, 0.0, 0.0));
    let c = compare(&model.cloud, &pd, &exact, &r, 1.0, &[]);
    let probe = c.probe.unwrap();
    assert!(
        (probe.x - 5.5).abs() < 1e-12 && (probe.peridynamic / probe.classical - 1.01).abs() < 1e-12
    );
    assert!((c.mean_sq_rel_diff - 1e-4).abs() < 1e-12);
    assert!((c.l2_rel_line - 1e-2).abs() < 1e-12);
}
