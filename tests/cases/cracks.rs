//! Cracks: bond cutting, damage, the heat-flux vector, and the Bobaru & Duangpanya 2012 crack plate
//! against an independent finite-difference solution.
#![allow(clippy::needless_range_loop)] // index loops mirror the formulas

use peritherm::case::Case;
use peritherm::gather::{ColumnIndex, Precision, StepStorage};
use peritherm::model::Model;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use std::path::PathBuf;

use crate::common::case::CaseToml;
use crate::common::fd::CrackPlate;
use crate::common::figures::Table;

/// The crack plates against finite differences (docs/validation.md).
const CRACK_FD: Table = Table {
    name: "crack_fd",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases cracks::",
    columns: &[
        "crack plate",
        "max abs diff vs FD outside the 2δ tip discs (°C)",
        "the test's bound (°C)",
    ],
    keys: &[
        "crack_plate at 0.5 s, against the classical transient at 0.5 s",
        "crack_plate at steady state (run on to 3 s), against the classical steady solution",
        "the classical solution itself, from 0.5 s to steady",
        "crack_plate_refined (gmsh triangles) at 0.5 s",
        "dh_crack_plate_k2_m1 (dual horizon, 25000 nodes) at 0.5 s",
        "dh_crack_plate_k1_m1 (uniform, 40000 nodes) at 0.5 s",
        "dh_crack_plate_k2_m1 against dh_crack_plate_k1_m1 at 0.5 s",
    ],
    timed: &[],
};

/// Relative tolerance of the crack plates' figures on another machine: the PD runs are explicit
/// (the same bits at any thread count), the finite differences a sparse Cholesky solve whose
/// round-off depends on the threads, far below 1e-6 of a difference of 0.1 °C.
const FD_REL_TOL: f64 = 1e-6;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Where the test cases pretend to live (relative paths in them resolve from `cases/`).
fn in_cases() -> PathBuf {
    root().join("cases/test.toml")
}

/// The body node at (x, y, z) (within 1e-9 m).
fn node_at(model: &Model, x: f64, y: f64, z: f64) -> usize {
    let c = &model.cloud;
    let p = peritherm::math::Point::new(x, y, z);
    (0..c.n_body)
        .find(|&i| (c.pos[i] - p).norm() < 1e-9)
        .unwrap_or_else(|| panic!("no node at {p:?}"))
}

fn run_steps(model: &Model, steps: usize, dt: f64) -> Vec<f64> {
    let mut theta = model.theta0.clone();
    let mut st = Explicit::new(model, ExplicitScheme::Euler);
    for s in 0..steps {
        st.step(&mut theta, s as f64 * dt, dt);
    }
    theta
}

/// The unit square (Δ = 0.02, δ = 3Δ), k = ρc = 1, with an explicit Euler time loop.
fn unit_square() -> CaseToml {
    CaseToml::new(2)
        .domain("[0.0, 0.0]", "[1.0, 1.0]")
        .region("r", "spacing = 0.02", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .time_key("integrator = \"euler\"")
}

fn halves(conductance: f64, correction: bool) -> (f64, f64, f64) {
    let model = unit_square()
        .section(&format!(
            "[kernel]\ncrack_correction = {correction}\n\
             [[crack]]\npoints = [[-0.5, 0.5003], [0.4, 0.5003], [1.5, 0.5003]]\n\
             conductance = {conductance}"
        ))
        .initial("y > 0.5")
        .model(in_cases());
    let dt = choose_dt(&model, Integrator::Euler, None).unwrap();
    let theta = run_steps(&model, 500, dt);
    let energy_of = |th: &[f64], upper: bool| -> f64 {
        (0..model.cloud.n_body)
            .filter(|&i| (model.cloud.pos[i].y > 0.5) == upper)
            .map(|i| model.cloud.volume[i] * model.capacity[i] * th[i])
            .sum()
    };
    (
        energy_of(&model.theta0, true),
        energy_of(&theta, true),
        energy_of(&theta, false),
    )
}

/// An insulated crack across the whole body (a polyline with an interior vertex) lets no
/// heat through: each half keeps its energy to round-off (1e-12 of the total), with and
/// without the crack correction (which rescales the bonds beside the crack). With μ = 0.5
/// the same crack does pass heat, so the test can fail.
#[test]
fn an_insulated_crack_splits_the_body() {
    for correction in [false, true] {
        let (u0, u, l) = halves(0.0, correction);
        assert!((u - u0).abs() < 1e-12 * u0, "upper {u0} -> {u}");
        assert!(l.abs() < 1e-12 * u0, "lower got {l}");
        let (_, u, l) = halves(0.5, correction);
        assert!(l > 1e-3 * u, "a conducting crack passes heat: {l}");
    }
}

/// The PD heat flux (theory §8) equals −k∇θ for a linear field at every bulk node
/// (horizon clear of the free faces), in 2D and 3D. Tolerance 1e-10 relative: with the
/// lattice calibration the half-horizon moment is k exactly, leaving round-off.
#[test]
fn flux_is_minus_k_grad_theta_for_a_linear_field() {
    for (dim, min, max) in [
        (2, "[0.0, 0.0]", "[1.0, 1.0]"),
        (3, "[0.0, 0.0, 0.0]", "[0.5, 0.5, 0.5]"),
    ] {
        let model = CaseToml::new(dim)
            .domain(min, max)
            .region("r", "spacing = 0.05", 3.0)
            .material("m", 2.5, 1.0, 1.0)
            .section("[kernel]\ncalibration = \"lattice\"")
            .initial("3 + 2*x - 5*y + 7*z")
            .model(in_cases());
        let q = model.conductance.flux(&model.cloud, &model.theta0);
        let grad = [2.0, -5.0, if dim == 3 { 7.0 } else { 0.0 }];
        let c = &model.cloud;
        let mut checked = 0;
        for i in 0..c.n_body {
            let clear = (0..dim).all(|a| {
                let p = c.pos[i][a];
                p - c.min[a] > c.horizon[i] + c.spacing[i]
                    && c.max[a] - p > c.horizon[i] + c.spacing[i]
            });
            if !clear {
                continue;
            }
            checked += 1;
            for a in 0..3 {
                let expected = -2.5 * grad[a];
                assert!(
                    (q[i][a] - expected).abs() <= 1e-10 * 2.5 * 7.0,
                    "{dim}D node {i}: q = {:?}",
                    q[i]
                );
            }
        }
        assert!(checked > 0, "{dim}D: no bulk node");
    }
}

/// The bundled Bobaru & Duangpanya 2012 Example 3 crack plate (with the crack correction) against
/// the classical solution of the same problem (finite differences on 3 × 3 cells per PD node, so
/// that every node sits on a cell centre; `common::fd`), at every node outside the 2δ discs around
/// the crack tips:
/// - at 0.5 s against the classical transient at 0.5 s: within 1 °C;
/// - run on to its steady state (3 s) against the classical steady solution: within 1 °C
///   (measured figures: validation/crack_fd.json).
///
/// The 1 °C bound is about twice the PD discretisation error at δ = 13L/240 (Bobaru & Duangpanya
/// 2012's own figures show differences of this size against ABAQUS). The paper calls 0.5 s steady;
/// it is not quite: the classical solution itself still moves by more than 2 °C between 0.5 s and
/// its steady state at the middle of the crack faces, which this test also checks so that the
/// transient-to-transient comparison stays justified. The gmsh refined-zone crack plate
/// (cases/crack_plate_refined.toml: default triangles, consistent bond weights, crack correction)
/// against the classical solution at 0.5 s (finite differences as above) outside the 2δ discs
/// around the crack tips (δ = 3 × 1.25e-4 m there): within 0.5 °C (the lattice plates are within
/// 0.47–0.76 °C; this mesh was 1.07 °C with the kernel's own weights).
///
/// Triangle centroids do not sit on finite-difference cell centres, so the reference is
/// interpolated bilinearly between cell centres (never across the crack). Taking the nearest
/// cell's value instead adds up to |∇θ|·h_FD/√2 of sampling error, which reached 0.55 °C
/// beside the crack tips (and 0.35 °C at twice the resolution): an error of the
/// reference's sampling, not of the peridynamic solution. Doubling the finite-difference
/// resolution (720 cells per side) moves the measured figure from 0.234 to 0.176 °C, so the
/// reference's own error at 360 cells is below 0.06 °C.
#[test]
fn refined_zone_crack_plate_matches_finite_differences() {
    let mut c = Case::load(&root().join("cases/crack_plate_refined.toml")).unwrap();
    c.outputs = vec![0.5];
    c.end = 0.5;
    c.reference = None;
    let out = tempfile::tempdir().unwrap();
    peritherm::run::run_case(&c, out.path(), |_, _| {}).unwrap();
    let plate = CrackPlate {
        n: 360,
        a: 0.01,
        c: 0.005,
        theta_top: 100.0,
    };
    let transient = plate.transient(114.0 / 1e6, 1e-3, 0.5);
    let delta = 3.0 * 1.25e-4;
    let rows = peritherm::output::read_field(&out.path().join("field_1.csv")).unwrap();
    let mut worst: f64 = 0.0;
    for (p, t) in rows.pos.iter().zip(&rows.theta) {
        if [-0.005, 0.005]
            .iter()
            .all(|tx| (p.x - tx).hypot(p.y) >= 2.0 * delta)
        {
            worst = worst.max((t - plate.interpolate(&transient, p.x, p.y)).abs());
        }
    }
    eprintln!("refined crack plate: max |θ_PD − θ_FD| outside the tip discs {worst:.3} °C");
    assert!(worst < 0.5, "max difference {worst} °C at 0.5 s");
    let key = CRACK_FD.keys[3];
    CRACK_FD.row(&[key, &format!("{worst:.3}"), "0.5"], FD_REL_TOL);
}

#[test]
fn crack_plate_matches_finite_differences() {
    let mut c = Case::load(&root().join("cases/crack_plate.toml")).unwrap();
    c.outputs = vec![0.5, 3.0];
    c.end = 3.0;
    c.reference = None; // compared with finite differences here, not with the case's FEM
    let out = tempfile::tempdir().unwrap();
    peritherm::run::run_case(&c, out.path(), |_, _| {}).unwrap();
    let model = Model::build(&c.spec).unwrap();
    let plate = CrackPlate {
        n: 360,
        a: 0.01,
        c: 0.005,
        theta_top: 100.0,
    };
    let alpha = 114.0 / 1e6;
    let transient = plate.transient(alpha, 1e-3, 0.5);
    let steady = plate.steady();
    let delta = 13.0 * 0.02 / 240.0;
    let worst = |field: &str, fd: &[f64]| {
        let rows = peritherm::output::read_field(&out.path().join(field)).unwrap();
        let mut worst: f64 = 0.0;
        for (p, t) in rows.pos.iter().zip(&rows.theta) {
            let near_tip = [-0.005, 0.005]
                .iter()
                .any(|tx| (p.x - tx).hypot(p.y) < 2.0 * delta);
            if !near_tip {
                worst = worst.max((t - plate.at(fd, p.x, p.y)).abs());
            }
        }
        worst
    };
    let moved = transient
        .iter()
        .zip(&steady)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let (at_half, at_steady) = (
        worst("field_1.csv", &transient),
        worst("field_2.csv", &steady),
    );
    eprintln!(
        "crack plate, max |θ_PD − θ_FD| outside the tip discs: {at_half:.3} °C at 0.5 s, \
         {at_steady:.3} °C steady; the classical field moves {moved:.2} °C after 0.5 s"
    );
    assert!(at_half < 1.0, "at 0.5 s: max difference {at_half} °C");
    assert!(at_steady < 1.0, "steady: max difference {at_steady} °C");
    assert!(
        moved > 2.0,
        "the classical field moves {moved} °C after 0.5 s"
    );
    let rows = [(at_half, "1"), (at_steady, "1"), (moved, "above 2")];
    for (key, (v, bound)) in CRACK_FD.keys.iter().zip(rows) {
        CRACK_FD.row(&[key, format!("{v:.3}").as_str(), bound], FD_REL_TOL);
    }
    // the heat flux (columns qx, qy) is finite everywhere and at the tips a few times the
    // far-field flux k·200 °C/2 cm = 1.14e6 W/m² (measured: 3.9e6 at the node by the tip)
    let text = std::fs::read_to_string(out.path().join("field_2.csv")).unwrap();
    let mut tip_flux: f64 = 0.0;
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let q = v[9].hypot(v[10]);
        assert!(q.is_finite());
        if (v[0].abs() - 0.005).hypot(v[1]) < 2e-4 {
            tip_flux = tip_flux.max(q);
        }
    }
    assert!(
        tip_flux > 1.14e6 && tip_flux < 1e7,
        "flux at the tips {tip_flux:e} W/m²"
    );
    let cl = &model.cloud;
    let damage = model.damage_at(3.0);
    for i in 0..cl.n_body {
        let p = cl.pos[i];
        let d = damage[i];
        if p.y.abs() > delta + cl.spacing[i] || p.x.abs() > 0.005 + delta + cl.spacing[i] {
            assert_eq!(d, 0.0, "no crack within reach of {p:?}");
        } else if p.x.abs() < 0.004 && p.y.abs() < cl.spacing[i] {
            assert!(d > 0.3 && d < 0.6, "beside the crack {p:?}: damage {d}");
        }
    }
}

/// A growing crack cuts each pair when its tip passes the crossing point: at
/// start + (x_cross − initial_length)/speed, pairs crossing the initial length at once,
/// pairs the tip never reaches never. The stepper cuts them in place at that moment, K
/// stays symmetric, and energy is conserved to round-off across the cuts.
#[test]
fn growing_crack_cuts_bonds_when_its_tip_passes() {
    let model = unit_square()
        .section(
            "[[crack]]\npoints = [[0.0, 0.5003], [0.6, 0.5003], [1.0, 0.5003]]\n\
             speed = 0.1\nstart = 0.2\ninitial_length = 0.1",
        )
        .initial("y > 0.5")
        .model(in_cases());
    let c = &model.cloud;
    assert!(!model.growth.is_empty());
    let k0 = &model.conductance;
    let mut checked = 0;
    for cut in &model.growth {
        for (row, e) in cut.entries.into_iter().flatten() {
            let (a, b) = (c.pos[row], c.pos[k0.cols[e] as usize]);
            // where the bond crosses y = 0.5003
            let x = a.x + (b.x - a.x) * (0.5003 - a.y) / (b.y - a.y);
            let expected = 0.2 + (x - 0.1) / 0.1;
            assert!(
                (cut.time - expected).abs() < 1e-9,
                "{a:?}-{b:?}: {} vs {expected}",
                cut.time
            );
            assert!(x > 0.1);
            checked += 1;
        }
    }
    assert!(checked > 50);
    // pairs crossing the initial length are cut from the start
    let (i, j) = (
        node_at(&model, 0.05, 0.49, 0.0),
        node_at(&model, 0.05, 0.51, 0.0),
    );
    assert_eq!(k0.get(i, j), 0.0);
    // the pair at x = 0.41 is cut at 0.2 + 0.31/0.1 = 3.3 s: run past 0.5 s and check it is
    // intact, then past 3.3 s and check it is cut
    let (i, j) = (
        node_at(&model, 0.41, 0.49, 0.0),
        node_at(&model, 0.41, 0.51, 0.0),
    );
    let intact = k0.get(i, j);
    assert!(intact > 0.0);
    let tc = model
        .growth
        .iter()
        .find(|cut| {
            cut.entries
                .iter()
                .flatten()
                .any(|&(r, e)| r == i && k0.cols[e] as usize == j)
        })
        .unwrap()
        .time;
    assert!((tc - 3.3).abs() < 1e-9);
    let dt = choose_dt(&model, Integrator::Euler, None).unwrap();
    // K's own rows, the packed columns (the same bits), and the packed columns with K in f32
    // (each cut entry rounded again: energy still conserved to round-off)
    let mut fields = Vec::new();
    for (columns, precision) in [
        (ColumnIndex::U32, Precision::F64),
        (ColumnIndex::Packed, Precision::F64),
        (ColumnIndex::Packed, Precision::F32),
    ] {
        let mut theta = model.theta0.clone();
        let e0 = model.energy(&theta);
        let mut st = Explicit::new(&model, ExplicitScheme::Euler);
        st.set_storage(StepStorage { columns, precision });
        let mut t = 0.0;
        while t < 3.4 {
            st.step(&mut theta, t, dt);
            t += dt;
            let now = st.conductance().get(i, j);
            assert_eq!(now, if t - dt >= tc { 0.0 } else { intact }, "t = {t}");
            assert_eq!(now, st.conductance().get(j, i));
        }
        let drift = (model.energy(&theta) - e0).abs() / e0.abs();
        assert!(
            drift < 1e-12,
            "{columns:?} {precision:?}: energy drift {drift:e}"
        );
        fields.push(theta);
    }
    assert_eq!(fields[0], fields[1], "packed columns change the bits");
    assert_ne!(fields[0], fields[2], "f32 K must be read");
    assert!(model.damage_at(3.4)[i] > model.damage_at(0.0)[i]);
}

/// A 3D crack given as a planar polygon (a square in the plane z = 0.5 covering
/// 0.2 ≤ x, y ≤ 0.6) cuts the bonds through it and no others: damage is positive next to it
/// and zero beside it, and a node pair straddling it has K = 0.
#[test]
fn a_planar_polygon_cuts_3d_bonds() {
    let cube = |points: &str| {
        CaseToml::new(3)
            .domain("[0.0, 0.0, 0.0]", "[1.0, 1.0, 1.0]")
            .region("r", "spacing = 0.1", 2.0)
            .material("m", 1.0, 1.0, 1.0)
            .section(&format!("[[crack]]\npoints = {points}"))
    };
    let model = cube("[[0.2, 0.2, 0.5], [0.6, 0.2, 0.5], [0.6, 0.6, 0.5], [0.2, 0.6, 0.5]]")
        .model(in_cases());
    let find = |x: f64, y: f64, z: f64| node_at(&model, x, y, z);
    let (a, b) = (find(0.35, 0.45, 0.45), find(0.35, 0.45, 0.55));
    assert_eq!(model.conductance.get(a, b), 0.0);
    let (a2, b2) = (find(0.85, 0.45, 0.45), find(0.85, 0.45, 0.55));
    assert!(model.conductance.get(a2, b2) > 0.0);
    let d = model.damage_at(0.0);
    assert!(d[a] > 0.2, "damage {}", d[a]);
    assert_eq!(d[a2], 0.0);
    let bad = cube("[[0.2, 0.2, 0.5], [0.6, 0.2, 0.5], [0.6, 0.6, 0.5], [0.2, 0.6, 0.7]]");
    let e = Case::parse(&bad.text(), &in_cases())
        .unwrap_err()
        .to_string();
    assert!(e.contains("crack[0].points") && e.contains("planar"), "{e}");
}

/// Wang, Oterkus & Oterkus (dual-horizon paper) §4.3: the dual-horizon crack plate with a coarse
/// outer region ((k, m) = (2, 1), 25000 nodes) agrees with the classical solution at 0.5 s (finite
/// differences, bilinear between cell centres, never across the crack) as well as the uniform fine
/// run ((1, 1), 40000 nodes) does, outside the 2δ discs around the crack tips: both within 1 °C
/// (the PD discretisation at δ = 3Δ beside the crack faces; the bound is the one of
/// `crack_plate_matches_finite_differences`), and within 0.2 °C of each other (at the region
/// interface). Measured figures: validation/crack_fd.json.
#[test]
fn dual_horizon_crack_plate_matches_finite_differences() {
    let plate = CrackPlate {
        n: 360,
        a: 0.01,
        c: 0.005,
        theta_top: 100.0,
    };
    let fd = plate.transient(114.0 / 1e6, 1e-3, 0.5);
    let two_delta = 2.0 * 3.0 * 1e-4;
    let mut fields = Vec::new();
    for name in ["dh_crack_plate_k2_m1", "dh_crack_plate_k1_m1"] {
        let mut c = Case::load(&root().join(format!("cases/{name}.toml"))).unwrap();
        c.outputs = vec![0.5];
        c.reference = None; // compared with finite differences here, not with the case's FEM
        let out = tempfile::tempdir().unwrap();
        let s = peritherm::run::run_case(&c, out.path(), |_, _| {}).unwrap();
        let rows = peritherm::output::read_field(&out.path().join("field_1.csv")).unwrap();
        let mut worst: f64 = 0.0;
        for (p, t) in rows.pos.iter().zip(&rows.theta) {
            let near_tip = [-0.005, 0.005]
                .iter()
                .any(|tx| (p.x - tx).hypot(p.y) < two_delta);
            if !near_tip {
                worst = worst.max((t - plate.interpolate(&fd, p.x, p.y)).abs());
            }
        }
        eprintln!(
            "{name}: {} nodes, max |θ_PD − θ_FD| = {worst:.3} °C",
            s.nodes
        );
        assert!(worst < 1.0, "{name}: max difference {worst} °C");
        let key = CRACK_FD.keys[4 + fields.len()];
        CRACK_FD.row(&[key, &format!("{worst:.3}"), "1"], FD_REL_TOL);
        fields.push((s.nodes, rows, c));
    }
    let (coarse, fine) = (&fields[0], &fields[1]);
    assert!(coarse.0 < fine.0);
    let cloud = fine.2.spec.geometry.bare_cloud().unwrap();
    let cracks = peritherm::model::crack_cutters(&cloud, &fine.2.spec.cracks);
    let tips = peritherm::crack::tips_at(&cracks, 0.5);
    assert_eq!(tips.len(), 2);
    let d = peritherm::report::field_difference(
        2,
        (&coarse.1.pos, &coarse.1.theta),
        (&fine.1.pos, &fine.1.theta),
        &cracks,
        (&tips, two_delta),
    );
    eprintln!("(2, 1) against (1, 1): max {:.3} °C", d.max_abs);
    assert!(d.max_abs < 0.2, "(2, 1) against (1, 1): {} °C", d.max_abs);
    let cells = [CRACK_FD.keys[6], &format!("{:.3}", d.max_abs), "0.2"];
    CRACK_FD.row(&cells, FD_REL_TOL);
}
