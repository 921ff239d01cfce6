//! The mesh-convergence suite of issue 14 on gmsh default meshes (meshes/conv_<family>_L1..3,
//! cases/conv_<family>.toml): each family is run at its three test levels through the library
//! and its volume-weighted relative L2 error against the series is measured at the end time.
//!
//! Targets, from issue 14 ("Done when"), not loosened: on every family the relative L2 error
//! falls with an observed rate of at least 1.5 per refinement at fixed δ/Δ, the rate
//! log(e_(l−1)/e_l)/log(h_(l−1)/h_l) with h = (Σ V_i/N)^(1/d) measured on the cloud; and on the
//! finest 2D level the PD error is within 3× the error of the P1 FEM (`peritherm fem`) on the
//! same mesh against the same series. The FEM errors of the 3D family are left to
//! scripts/mesh-convergence.sh (the target names 2D only).

use peritherm::case::Case;
use peritherm::fem::{run_fem, FemOptions};
use peritherm::run::run_case;
use std::path::Path;

/// Observed convergence rate required per refinement (issue 14).
const MIN_RATE: f64 = 1.5;
/// Largest PD/FEM error ratio on the finest 2D level (issue 14).
const MAX_FEM_RATIO: f64 = 3.0;
/// The levels the test runs (a 4th level is in the script's table only).
const LEVELS: [usize; 3] = [1, 2, 3];

/// The family's case on the mesh of `level`.
fn case_at(family: &str, level: usize) -> Case {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("cases").join(format!("conv_{family}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let from = format!("file = \"../meshes/conv_{family}_L2.msh\"");
    assert!(text.contains(&from), "{} has no `{from}`", path.display());
    let to = format!("file = \"../meshes/conv_{family}_L{level}.msh\"");
    Case::parse(&text.replacen(&from, &to, 1), &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Mean spacing h = (Σ V_i / (τ N))^(1/d) of the case's cloud, m, and its node count.
fn spacing(case: &Case) -> (f64, usize) {
    let cloud = case.spec.geometry.bare_cloud().unwrap();
    let n = cloud.n_body;
    let measure: f64 = cloud.volume[..n].iter().sum::<f64>() / cloud.tau;
    ((measure / n as f64).powf(1.0 / cloud.dim as f64), n)
}

/// The relative L2 error of PD (and, when `fem`, of the P1 FEM) at the case's end time.
fn errors(case: &Case, fem: bool) -> (f64, Option<f64>) {
    let dir = tempfile::tempdir().unwrap();
    let pd = run_case(case, dir.path(), |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let e = pd
        .reference
        .last()
        .expect("the case has a series")
        .l2_rel_volume;
    let f = fem.then(|| {
        let out = dir.path().join("fem");
        let s = run_fem(case, &out, &FemOptions::default(), |_, _| {})
            .unwrap_or_else(|e| panic!("{e}"));
        s.reference
            .last()
            .expect("the case has a series")
            .l2_rel_volume
    });
    (e, f)
}

/// Runs `family` at the test levels and asserts the targets of issue 14.
fn converges(family: &str, two_d: bool) {
    let mut rows: Vec<(f64, usize, f64)> = Vec::new();
    let mut fem = None;
    for &level in &LEVELS {
        let case = case_at(family, level);
        let (h, n) = spacing(&case);
        let finest = level == *LEVELS.last().unwrap();
        let (e, f) = errors(&case, two_d && finest);
        eprintln!("{family} L{level}: {n} nodes, h = {h:.3e} m, PD relative L2 = {e:.3e}");
        if let Some(f) = f {
            eprintln!(
                "{family} L{level}: P1 FEM relative L2 = {f:.3e}, PD/FEM = {:.2}",
                e / f
            );
            fem = Some((e, f));
        }
        rows.push((h, n, e));
    }
    let mut failures = Vec::new();
    for w in rows.windows(2) {
        let ((h0, _, e0), (h1, n1, e1)) = (w[0], w[1]);
        let rate = (e0 / e1).ln() / (h0 / h1).ln();
        eprintln!("{family}: rate {rate:.2} to {n1} nodes");
        if rate.is_nan() || rate < MIN_RATE {
            failures.push(format!("rate {rate:.2} < {MIN_RATE} ({e0:.3e} → {e1:.3e})"));
        }
    }
    if let Some((e, f)) = fem {
        if e.is_nan() || e > MAX_FEM_RATIO * f {
            failures.push(format!(
                "finest level: PD {e:.3e} > {MAX_FEM_RATIO} × FEM {f:.3e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{family}: {}", failures.join("; "));
}

/// Rectangle of gmsh default triangles, three sides held, one free.
#[test]
#[ignore = "passes (docs/mesh-convergence.md) but takes minutes on 2 cores; run with --ignored"]
fn rect_tri_converges() {
    converges("rect_tri", true);
}

/// The same rectangle of gmsh quadrangles (recombined triangles).
#[test]
#[ignore = "passes (docs/mesh-convergence.md) but takes minutes on 2 cores; run with --ignored"]
fn rect_quad_converges() {
    converges("rect_quad", true);
}

/// The rectangle graded to a refined zone 4× finer (dual horizon across the transition).
#[test]
fn graded_converges() {
    converges("graded", true);
}

/// A disc (curved held boundary) of gmsh default triangles.
#[test]
#[ignore = "passes (docs/mesh-convergence.md) but takes minutes on 2 cores; run with --ignored"]
fn disc_converges() {
    converges("disc", true);
}

/// The unit cube of gmsh default tetrahedra, all faces held.
#[test]
#[ignore = "passes (docs/mesh-convergence-3d.md) but L3 (36 k tetrahedra) takes about 15 min on 2 cores; run with --ignored"]
fn cube_tet_converges() {
    converges("cube_tet", false);
}

/// `peritherm sweep --vary mesh.file=...` runs the levels of a family (the script's path):
/// one row per level whose h and relative L2 error are the ones measured here on the same
/// cloud and written to the level's run.json, and a convergence plot against h.
#[test]
fn sweep_varies_the_mesh_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<String> = [1, 2]
        .iter()
        .map(|l| format!("../meshes/conv_rect_quad_L{l}.msh"))
        .collect();
    let o = crate::common::cli::command()
        .arg("sweep")
        .arg(root.join("cases/conv_rect_quad.toml"))
        .arg("--vary")
        .arg(format!("mesh.file={}", files.join(",")))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    for (level, row) in [1, 2].iter().zip(&rows) {
        let (h, n) = spacing(&case_at("rect_quad", *level));
        let h_row: f64 = row[col("h_mean")].parse().unwrap();
        assert!((h_row / h - 1.0).abs() < 1e-9, "L{level}: h {h_row} vs {h}");
        assert_eq!(row[col("nodes")], n.to_string());
        let run = peritherm::output::RunSummary::read(&dir.path().join(row[0])).unwrap();
        let e: f64 = row[col("l2_rel")].parse().unwrap();
        let want = run.reference.last().unwrap().l2_rel_volume;
        assert!(
            e > 0.0 && (e / want - 1.0).abs() < 1e-9,
            "L{level}: {e} vs {want}"
        );
    }
    assert!(dir.path().join("convergence_h_t1.png").exists());
}

/// `kernel.precision = "f32"` on the graded gmsh family at its three test levels: the field at
/// the end time differs from the f64 run's by at most 1e-6 relative (volume-weighted L2; the
/// issue's bound). Rounding each K_ij to f32 perturbs it by at most 2⁻²⁴ ≈ 6e-8 relative; the
/// sums are still formed in f64, so the field moves by round-off of that size, not more.
#[test]
fn f32_conductances_keep_the_field_within_1e_6() {
    use peritherm::gather::{ColumnIndex, Precision, StepStorage};
    use peritherm::model::Model;
    use peritherm::solve::explicit::{choose_dt, steps_between, Explicit};
    for &level in &LEVELS {
        let case = case_at("graded", level);
        let model = Model::build(&case.spec).unwrap();
        let dt = choose_dt(&model, case.integrator, case.dt).unwrap();
        let scheme = case.integrator.try_into().unwrap();
        let run = |precision| {
            let mut st = Explicit::new(&model, scheme);
            st.set_storage(StepStorage {
                columns: ColumnIndex::Packed,
                precision,
            });
            let mut theta = model.theta0.clone();
            let steps = steps_between(0.0, case.end, dt);
            let h = case.end / steps as f64;
            for s in 0..steps {
                st.step(&mut theta, s as f64 * h, h);
            }
            theta
        };
        let (a, b) = (run(Precision::F64), run(Precision::F32));
        let v = &model.cloud.volume;
        let n = model.cloud.n_body;
        let diff: f64 = (0..n).map(|i| v[i] * (a[i] - b[i]).powi(2)).sum();
        let norm: f64 = (0..n).map(|i| v[i] * a[i].powi(2)).sum();
        let rel = (diff / norm).sqrt();
        eprintln!("graded L{level}: {n} nodes, f32 against f64: {rel:.2e} relative L2");
        assert!(
            norm > 0.0 && rel > 0.0,
            "the f32 run must differ, and the field not vanish"
        );
        assert!(rel <= 1e-6, "L{level}: f32 moves the field by {rel:e}");
    }
}
