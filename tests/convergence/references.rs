//! References exported by other codes: CSV tables read, checked and interpolated at the nodes.

use crate::common::case::CaseToml;
use peritherm::case::{Case, ReferenceSource};
use peritherm::model::Model;
use peritherm::report::classical_at;
use std::fmt::Write as _;
use std::path::Path;

/// A 2D square held at 0 °C from 40 °C (Bobaru & Duangpanya 2012 Example 1, coarse), its reference
/// given by `reference` (TOML lines of the `[reference]` table).
fn square(reference: &str) -> String {
    let mut c = CaseToml::new(2)
        .domain("[0.0, 0.0]", "[1.0, 1.0]")
        .region("square", "cells = [32, 32]", 3.0)
        .material("m", 1.14, 1.0, 1.0);
    for face in ["x_min", "x_max", "y_min", "y_max"] {
        c = c.section(&format!(
            "[boundary.{face}]\ntype = \"temperature\"\nvalue = 0.0"
        ));
    }
    c.section(&format!("[reference]\n{reference}"))
        .initial_value(40.0)
        .end(0.1)
        .time_key("outputs = [0.05, 0.1]")
        .text()
}

const SERIES: &str = r#"[reference.solution]
kind = "square_fixed_edges"
x0 = 0.0
y0 = 0.0
length = 1.0
diffusivity = 1.14
edge = 0.0
initial = 40.0"#;

/// The series of `SERIES` written as a CSV table on an n × n grid of the square (corners
/// included), at `times`, columns in another order than the reader's.
fn series_csv(n: usize, times: &[f64]) -> String {
    let r = match Case::parse(&square(SERIES), Path::new("square.toml"))
        .unwrap()
        .reference
        .unwrap()
        .source
    {
        ReferenceSource::Analytic(r) => r,
        _ => unreachable!("SERIES is an analytical reference"),
    };
    let mut s = String::from("# the square series\nx,y,time,temperature\n");
    for &t in times {
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                writeln!(s, "{x},{y},{t},{}", r.eval(x, y, 0.0, t)).unwrap();
            }
        }
    }
    s
}

/// A table of the square series on a 101 × 101 grid (points other than the 32 × 32 nodes),
/// interpolated at the nodes, reproduces the series there within 0.02 °C: the local linear
/// least-squares fit errs by about h²|∇²θ|/8 ≈ 0.01² × 500 / 8 ≈ 0.006 °C at t = 0.05 s
/// (θ ≈ 25 °C·sin πx sin πy, so |∇²θ| ≈ 2π²·25). A run with the table writes the comparisons
/// into run.json just as with the series.
#[test]
fn a_table_interpolates_like_the_series() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ref.csv"), series_csv(101, &[0.05, 0.1])).unwrap();
    let series = Case::parse(&square(SERIES), &dir.path().join("a.toml")).unwrap();
    let table = Case::parse(
        &square("file = \"ref.csv\"\nline_y = 0.5"),
        &dir.path().join("b.toml"),
    )
    .unwrap();
    let model = Model::build(&series.spec).unwrap();
    for t in [0.05, 0.1] {
        let a = classical_at(
            &model.cloud,
            &series.reference.as_ref().unwrap().source,
            t,
            &[],
        )
        .unwrap();
        let b = classical_at(
            &model.cloud,
            &table.reference.as_ref().unwrap().source,
            t,
            &[],
        )
        .unwrap();
        let worst = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!("t = {t}: table against series at the nodes: {worst:.2e} °C");
        assert!(worst < 0.02, "t = {t}: {worst} °C");
    }
    let out = tempfile::tempdir().unwrap();
    let s = peritherm::run::run_case(&table, out.path(), |_, _| {}).unwrap();
    assert_eq!(s.reference.len(), 2);
    assert!(s.reference.iter().all(|c| c.line_nodes == 32 * 2));
    let json = std::fs::read_to_string(out.path().join("run.json")).unwrap();
    assert!(json.contains("l2_rel_line"));
}

/// Tables with missing columns, the wrong dimension, missing output times or too small a
/// region fail with one line naming the file and what is wrong.
#[test]
fn bad_tables_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("c.toml");
    let text = square("file = \"ref.csv\"");
    let fails = |csv: &str| {
        std::fs::write(dir.path().join("ref.csv"), csv).unwrap();
        Case::parse(&text, &case).unwrap_err().to_string()
    };
    let e = fails("time,x,temperature\n0.05,0,1\n");
    assert!(e.contains("ref.csv: header: missing column `y`"), "{e}");
    let e = fails("time,x,y,z,temperature\n0.05,0,0,0,1\n");
    assert!(
        e.contains("ref.csv: header: has a `z` column but the case is 2D"),
        "{e}"
    );
    let e = fails(&series_csv(5, &[0.05]));
    assert!(
        e.contains("c.toml: reference.file:")
            && e.contains("no rows at t = 0.1 s (it has t = 0.05)"),
        "{e}"
    );
    let e = Case::parse(&square("file = \"missing.csv\""), &case)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("missing.csv") && e.contains("cannot read"),
        "{e}"
    );
    let e = Case::parse(&square(&format!("file = \"ref.csv\"\n{SERIES}")), &case)
        .unwrap_err()
        .to_string();
    assert!(e.contains("reference: give exactly one of"), "{e}");
    // a table of the lower half only does not cover the nodes of the upper half
    let half: String = series_csv(11, &[0.05, 0.1])
        .lines()
        .filter(|l| {
            !l.starts_with(|c: char| c.is_ascii_digit()) || {
                let y: f64 = l.split(',').nth(1).unwrap().parse().unwrap();
                y <= 0.5
            }
        })
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.path().join("ref.csv"), half).unwrap();
    let c = Case::parse(&text, &case).unwrap();
    let model = Model::build(&c.spec).unwrap();
    let e = classical_at(&model.cloud, &c.reference.unwrap().source, 0.05, &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("ref.csv: t = 0.05: does not cover the node at"),
        "{e}"
    );
}

/// `[reference.fem]` solves the case with the built-in FEM first (into `<out>/fem/`) and
/// compares the PD run with it. On the coarse square (32 × 32 nodes, δ = 3Δ) the PD error
/// against the series is 1.04 / 0.81 °C at t = 0.05 / 0.1 s and the FEM's (quads of h = 1/32,
/// Crank–Nicolson) 0.046 / 0.023 °C (both measured with `peritherm run` and `peritherm fem`),
/// so judged against the FEM the PD run must show the same max difference to within the FEM
/// error plus the interpolation of its field at the PD nodes: 0.2 °C.
#[test]
fn a_fem_reference_is_solved_and_compared() {
    let dir = tempfile::tempdir().unwrap();
    let with = |reference: &str| {
        let case = Case::parse(&square(reference), &dir.path().join("f.toml")).unwrap();
        let out = tempfile::tempdir().unwrap();
        let s = peritherm::run::run_case(&case, out.path(), |_, _| {}).unwrap();
        (s, out)
    };
    let (fem, out) = with("[reference.fem]\nh = 0.03125\nscheme = \"crank_nicolson\"");
    assert!(out.path().join("fem/run.json").exists());
    let (series, _) = with(SERIES);
    assert_eq!(fem.reference.len(), 2);
    for (f, s) in fem.reference.iter().zip(&series.reference) {
        eprintln!(
            "t = {}: PD against FEM {:.3} °C, against the series {:.3} °C",
            f.time, f.max_abs_diff, s.max_abs_diff
        );
        assert!((f.max_abs_diff - s.max_abs_diff).abs() < 0.2, "{f:?} {s:?}");
    }
    let e = Case::parse(
        &square("[reference.fem]\nh = -1.0"),
        &dir.path().join("f.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("reference.fem.h: must be a positive number"),
        "{e}"
    );
}
