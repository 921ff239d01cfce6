//! Clouds from gmsh meshes: identical clouds from ASCII and binary files, exact volumes,
//! the built-in generator reproduced, energy conservation with graded horizons and cracks,
//! mirrored layers on curved boundaries, bond cutting at re-entrant corners and cracks, and
//! the case-file errors of the `[mesh]` schema.
#![allow(clippy::needless_range_loop)] // index loops mirror the formulas

use crate::common::case::CaseToml;
use peritherm::case::Case;
use peritherm::cloud::mesh::{MeshGeometry, MeshRegion};
use peritherm::cloud::{Cloud, HorizonRule};
use peritherm::gmsh;
use peritherm::horizons::Horizons;
use peritherm::model::Model;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The cloud of a mesh file with one region per body group (δ = 3Δ), no fictitious layer.
fn cloud_of(file: &Path, tau: f64) -> Cloud {
    let mesh = gmsh::read(file).unwrap_or_else(|e| panic!("{e}"));
    let dim = mesh.dim();
    let regions = (0..mesh.groups.len())
        .filter(|&g| mesh.groups[g].dim == dim)
        .map(|g| MeshRegion {
            name: mesh.groups[g].name.clone(),
            group: g,
            horizon: HorizonRule::Factor(3.0),
            material: 0,
        })
        .collect();
    let geometry = MeshGeometry {
        mesh: Arc::new(mesh),
        scale: 1.0,
        tau,
        regions,
        horizon_ratio: None,
    };
    geometry.generate(&[], 0.0).unwrap()
}

/// Where the test cases pretend to live: in `cases/`, so mesh paths read `../meshes/...`.
fn in_cases() -> PathBuf {
    root().join("cases/test.toml")
}

fn case_error(text: &str) -> String {
    match Case::parse(text, &root().join("cases/test.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The same mesh saved as ASCII and as binary gives bit-identical clouds.
#[test]
fn ascii_and_binary_give_identical_clouds() {
    let a = cloud_of(&root().join("tests/data/square_tri_ascii.msh"), 0.1);
    let b = cloud_of(&root().join("tests/data/square_tri_binary.msh"), 0.1);
    assert!(a.n_body > 200);
    assert_eq!(a.pos, b.pos);
    assert_eq!(a.volume, b.volume);
    assert_eq!(a.spacing, b.spacing);
    assert_eq!(a.horizon, b.horizon);
}

/// Node volumes sum to the domain's measure × τ. Tolerance 1e-12 relative: the element
/// measures are exact for straight-sided elements, leaving summation round-off.
#[test]
fn node_volumes_sum_to_the_domain_measure() {
    let cases = [
        ("tests/data/square_tri_ascii.msh", 0.1, 0.1),
        ("tests/data/square_quad.msh", 1.0, 1.0),
        ("tests/data/line.msh", 0.01, 0.01),
        ("tests/data/cube_hex.msh", 1.0, 1.0),
        ("tests/data/cube_tet.msh", 1.0, 1.0),
        ("meshes/dh_plate_k0.5.msh", 0.001, 1e-4 * 0.001),
        ("meshes/crack_plate_refined.msh", 1.0, 4e-4),
        ("meshes/l_shape.msh", 2.0, 3e-4 * 2.0),
        ("meshes/block_refined.msh", 1.0, 1e-6),
    ];
    for (file, tau, measure) in cases {
        let c = cloud_of(&root().join(file), tau);
        let rel = (c.body_volume() - measure).abs() / measure;
        assert!(
            rel < 1e-12,
            "{file}: {} vs {measure} ({rel:e})",
            c.body_volume()
        );
        for i in 0..c.n_body {
            let expected = (c.volume[i] / tau).powf(1.0 / c.dim as f64);
            assert!(
                (c.spacing[i] - expected).abs() <= 1e-12 * expected,
                "{file}"
            );
        }
    }
}

/// Nodes are stored in space-filling-curve order: consecutive nodes are close in space
/// (on average within two spacings; a random order would put them ~L/2 apart).
#[test]
fn nodes_follow_a_space_filling_curve() {
    let c = cloud_of(&root().join("meshes/crack_plate_refined.msh"), 1.0);
    let n = c.n_body;
    let mean_step: f64 = (1..n)
        .map(|i| (c.pos[i] - c.pos[i - 1]).norm())
        .sum::<f64>()
        / n as f64;
    let mean_dx: f64 = c.spacing.iter().sum::<f64>() / n as f64;
    assert!(mean_step < 2.0 * mean_dx, "{mean_step} vs Δ {mean_dx}");
}

fn run_steps(model: &Model, steps: usize, dt: f64) -> Vec<f64> {
    let mut theta = model.theta0.clone();
    let mut st = Explicit::new(model, ExplicitScheme::Euler);
    let mut t = 0.0;
    for _ in 0..steps {
        st.step(&mut theta, t, dt);
        t += dt;
    }
    theta
}

/// Structured quads from gmsh give the built-in generator's dual-horizon plate: after 2000
/// steps (with the consistency correction and mirrored layers) every node agrees with the
/// box model's node at the same place. Tolerance 1e-9 °C on a 10 °C span: quad areas equal
/// the lattice's cell areas only to round-off, which moves β and C in the last bits.
#[test]
fn gmsh_quads_reproduce_the_box_generator() {
    let gm = Case::load(&root().join("cases/dh_plate_gmsh_k0.5_m1.toml")).unwrap();
    let bx = Case::load(&root().join("cases/dh_plate_k0.5_m1.toml")).unwrap();
    let (mg, mb) = (
        Model::build(&gm.spec).unwrap(),
        Model::build(&bx.spec).unwrap(),
    );
    assert_eq!(mg.cloud.n_body, mb.cloud.n_body);
    let dt = gm.dt.unwrap();
    let (tg, tb) = (run_steps(&mg, 2000, dt), run_steps(&mb, 2000, dt));
    let key = |p: &peritherm::math::Point| ((p.x * 1e7).round() as i64, (p.y * 1e7).round() as i64);
    let mut by_pos = std::collections::HashMap::new();
    for i in 0..mb.cloud.n_body {
        by_pos.insert(key(&mb.cloud.pos[i]), tb[i]);
    }
    let mut worst: f64 = 0.0;
    for i in 0..mg.cloud.n_body {
        let other = by_pos[&key(&mg.cloud.pos[i])];
        worst = worst.max((tg[i] - other).abs());
    }
    assert!(
        tg.iter().take(mg.cloud.n_body).any(|&t| t > 1.0),
        "heat arrived"
    );
    assert!(worst < 1e-9, "max difference {worst:e} °C");
}

/// The refined crack plate mesh, insulated, with the crack; horizons graded by
/// `mesh.horizon_ratio = 1.3` when `graded`.
fn graded_cracked(graded: bool) -> Case {
    let mut c = CaseToml::new(2)
        .mesh("../meshes/crack_plate_refined.msh")
        .mesh_key("thickness = 1e-4");
    if graded {
        c = c.mesh_key("horizon_ratio = 1.3");
    }
    c.region("zone", "", 3.0)
        .region("far", "", 4.0)
        .material("m", 114.0, 1e6, 1.0)
        .section("[[crack]]\ngroup = \"crack\"")
        .section(
            "[boundary.top]\ntype = \"free\"\n[boundary.bottom]\ntype = \"free\"\n\
             [boundary.left]\ntype = \"free\"\n[boundary.right]\ntype = \"free\"",
        )
        .initial("100*sin(300*x) + 50*cos(200*y) + 1e4*x*y")
        .time_key("integrator = \"euler\"")
        .case(in_cases())
}

/// Energy is conserved to 1e-12 relative over 1000 Euler steps on an insulated gmsh cloud
/// whose horizon varies node to node (graded, two horizon rules) and which has a crack:
/// K stays symmetric bit for bit, so the bond sum cancels pairwise up to summation round-off.
#[test]
fn energy_is_conserved_on_a_graded_cracked_cloud() {
    let c = graded_cracked(true);
    let model = Model::build(&c.spec).unwrap();
    let (lo, hi) = model.cloud.horizon[..model.cloud.n_body]
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &d| (a.min(d), b.max(d)));
    assert!(hi > 3.0 * lo, "horizons vary: {lo} .. {hi}");
    let k = &model.conductance;
    for i in 0..model.cloud.n_body {
        for e in k.offsets[i]..k.offsets[i + 1] {
            assert_eq!(k.vals[e], k.get(k.cols[e] as usize, i), "K symmetric");
        }
    }
    let dt = choose_dt(&model, Integrator::Euler, None).unwrap() / 2.0;
    let e0 = model.energy(&model.theta0);
    let theta = run_steps(&model, 1000, dt);
    let scale: f64 = (0..model.cloud.n_body)
        .map(|i| (model.cloud.volume[i] * model.capacity[i] * model.theta0[i]).abs())
        .sum();
    let drift = (model.energy(&theta) - e0).abs() / scale;
    assert!(drift < 1e-12, "relative drift {drift:e}");
    let moved = (0..model.cloud.n_body).any(|i| (theta[i] - model.theta0[i]).abs() > 1.0);
    assert!(moved, "the field evolved");
}

/// No bond joins two body nodes of the two arms of the L across its re-entrant notch; without
/// the boundary cut such pairs would be within a horizon of each other. (The unnamed sides are
/// insulated through mirrored layers by default: their fictitious nodes lie in the notch.)
#[test]
fn no_bond_crosses_the_re_entrant_notch() {
    let model = CaseToml::new(2)
        .mesh("../meshes/l_shape.msh")
        .region("plate", "", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .model(in_cases());
    let c = &model.cloud;
    let in_notch = |p: &peritherm::math::Point| p.x > 0.01 + 1e-9 && p.y > 0.01 + 1e-9;
    let crosses = |i: usize, j: usize| {
        (1..20).any(|s| {
            let t = s as f64 / 20.0;
            in_notch(&(c.pos[i] + (c.pos[j] - c.pos[i]) * t))
        })
    };
    let k = &model.conductance;
    let mut close_pairs = 0;
    for i in 0..c.n_body {
        for e in k.offsets[i]..k.offsets[i + 1] {
            let j = k.cols[e] as usize;
            assert!(
                !(j < c.n_body && k.vals[e] > 0.0 && crosses(i, j)),
                "bond {i}-{j} leaves the body"
            );
        }
        for j in 0..c.n_body {
            if (c.pos[j] - c.pos[i]).norm() < c.horizon[i] && crosses(i, j) {
                close_pairs += 1;
            }
        }
    }
    assert!(
        close_pairs > 0,
        "no pair within a horizon across the notch: the test is void"
    );
}

/// Runs the bundled case `name` to time `t` and returns its largest difference from the
/// case's classical reference there, °C.
fn max_diff_at(name: &str, t: f64) -> f64 {
    let mut c = Case::load(&root().join(format!("cases/{name}.toml"))).unwrap();
    c.outputs = vec![t];
    c.end = t;
    let out = tempfile::tempdir().unwrap();
    let s = peritherm::run::run_case(&c, out.path(), |_, _| {}).unwrap();
    s.reference[0].max_abs_diff
}

/// Fictitious layers mirrored across curved (chord) boundaries: the ring held at 100 °C
/// inside and 0 °C outside reaches the logarithmic steady profile. Measured 0.11 °C; the
/// tolerance 0.25 °C (0.25 % of the span) covers the chords of 2.5e-4 m standing in for the
/// circles and the quadrature of triangles.
#[test]
fn annulus_reaches_the_logarithmic_profile() {
    let max = max_diff_at("annulus_steady", 1e-4);
    assert!(max < 0.25, "max |θ − θ_c| = {max}");
}

/// The 3D gmsh block (tetrahedra, refined sub-block, mirrored layers on all faces) follows
/// the 1D series of a slab held at 100 and 0 °C. Measured 1.12 °C at t = 1 s; the tolerance
/// 2 °C (2 % of the span) covers tetrahedra of quality down to 0.3 and the 2.5× size jump at
/// the sub-block, where no consistency correction is possible (it would need negative K).
#[test]
fn refined_block_follows_the_slab_series() {
    let max = max_diff_at("block_refined", 1.0);
    assert!(max < 2.0, "max |θ − θ_c| = {max}");
}

/// Case-file errors of the mesh schema name the key.
#[test]
fn mesh_case_errors_name_the_key() {
    let base = |region: &str, extra: &str| {
        format!(
            r#"
dimension = 2
[mesh]
file = "../meshes/l_shape.msh"
[[region]]
name = "{region}"
horizon = {{ factor = 3 }}
[material.m]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[time]
end = 1.0
{extra}
"#
        )
    };
    let e = case_error(&base("body", ""));
    assert!(e.contains("region[0].name") && e.contains("plate"), "{e}");
    let e = case_error(&base("plate", "[boundary.front]\ntype = \"insulated\""));
    assert!(e.contains("boundary.front") && e.contains("\"top\""), "{e}");
    let e = case_error(&base("plate", "[[crack]]\ngroup = \"tip\""));
    assert!(e.contains("crack[0].group"), "{e}");
    let e = case_error(&base(
        "plate",
        "[domain]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]",
    ));
    assert!(e.contains("not both"), "{e}");
    let e = case_error(&base("plate", "").replace("l_shape.msh", "missing.msh"));
    assert!(e.contains("mesh.file") && e.contains("missing.msh"), "{e}");
    let e = case_error(&base("plate", "").replace("dimension = 2", "dimension = 3"));
    assert!(e.contains("dimension"), "{e}");
    let e = case_error(&base("plate", "").replace("[[region]]", "[[region]]\nspacing = 0.1"));
    assert!(e.contains("region[0].spacing"), "{e}");
    let e = case_error(&base("plate", "").replace("l_shape.msh", "../tests/data/msh22.msh"));
    assert!(e.contains("MSH 4.1") && e.contains("mesh.file"), "{e}");
}

/// The exposed areas of a boundary set (used by convection) add up to the set's length × τ,
/// and each belongs to a node of the element behind the facet (tolerance: round-off).
#[test]
fn exposed_areas_add_up_to_the_boundary() {
    let model = CaseToml::new(2)
        .mesh("../meshes/l_shape.msh")
        .mesh_key("thickness = 0.003")
        .region("plate", "", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .model(in_cases());
    let peritherm::cloud::Sides::Mesh(sides) = &model.cloud.sides else {
        panic!("a mesh cloud")
    };
    for (name, length) in [
        ("top", 0.02),
        ("left", 0.02),
        ("right", 0.02),
        ("bottom", 0.02),
    ] {
        let s = sides.names.iter().position(|n| n == name).unwrap();
        let exposed = model.cloud.exposed(s);
        let total: f64 = exposed.iter().map(|e| e.1).sum();
        assert!((total - length * 0.003).abs() < 1e-15, "{name}: {total}");
        for (i, _) in exposed {
            let d = model.cloud.set_distance(&model.cloud.pos[i], s);
            assert!(
                d < model.cloud.spacing[i],
                "{name}: node {i} at {d} from its facet"
            );
        }
    }
}

/// `mesh.horizon_ratio` grades the horizons: no node's δ exceeds the ratio times that of any
/// of its nearest neighbours, and no δ grows (the grading only lowers coarse horizons).
#[test]
fn horizon_grading_limits_the_ratio_between_neighbours() {
    let graded = Model::build(&graded_cracked(true).spec).unwrap().cloud;
    let plain = Model::build(&graded_cracked(false).spec).unwrap().cloud;
    let index = peritherm::spatial::PointIndex::new(&graded.pos[..graded.n_body]);
    let mut lowered = 0;
    for i in 0..graded.n_body {
        assert!(graded.horizon[i] <= plain.horizon[i]);
        if graded.horizon[i] < plain.horizon[i] {
            lowered += 1;
        }
        for (j, _) in index.nearest(&graded.pos[i], 9) {
            assert!(graded.horizon[j] <= 1.3 * graded.horizon[i] * (1.0 + 1e-12));
        }
    }
    assert!(lowered > 100, "the grading acted on {lowered} nodes");
}

/// A linear field is steady on gmsh clouds of every dimension with mirrored layers: lines
/// (1D), triangles (2D, with the linear-consistency correction), hexahedra (3D). The held
/// sets carry the field's own values, the others are insulated (the gradient runs along
/// them) or, in 3D, partly left without a set: free faces along the gradient keep a linear
/// field too on a lattice. Tolerance 1e-8 °C/s against rates of order 10 °C/s without the layers: the CG
/// solve of the correction stops at 1e-12 relative, the rest is round-off.
#[test]
fn linear_fields_are_steady_on_mesh_clouds() {
    let setups = [
        ("line.msh", 1, "bar", "left", "right", "", ""),
        (
            "square_tri_ascii.msh",
            2,
            "plate",
            "left",
            "right",
            "bottom",
            "top",
        ),
        (
            "cube_hex_faces.msh",
            3,
            "block",
            "x_min",
            "x_max",
            "y_min",
            "z_max",
        ),
    ];
    for (file, dim, region, lo, hi, ins1, ins2) in setups {
        let mut text = CaseToml::new(dim)
            .mesh(&format!("../tests/data/{file}"))
            .region(region, "", 3.0)
            .material("m", 2.0, 1.0, 1.0)
            .section(&format!(
                "[kernel]\ncalibration = \"lattice\"\nlinear_consistency = {}",
                dim == 2
            ))
            .initial("3 + 10*x")
            .time_key("integrator = \"euler\"");
        for (set, kind) in [(lo, "hold"), (hi, "hold"), (ins1, "ins"), (ins2, "ins")] {
            if set.is_empty() {
                continue;
            }
            text = text.section(&if kind == "hold" {
                format!("[boundary.{set}]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = \"3 + 10*x\"\n")
            } else {
                format!("[boundary.{set}]\ntype = \"insulated\"\n")
            });
        }
        let model =
            Model::build(&text.case(in_cases()).spec).unwrap_or_else(|e| panic!("{file}: {e}"));
        let dt = choose_dt(&model, Integrator::Euler, None).unwrap();
        let theta = run_steps(&model, 1, dt);
        let worst = (0..model.cloud.n_body)
            .map(|i| (theta[i] - model.theta0[i]).abs() / dt)
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "{file}: largest rate {worst:e} °C/s");
    }
}

/// The neighbour lists of a graded 3D gmsh cloud (`block_refined`: tetrahedra, a 2.5× jump of
/// element size, per-node horizons, mirrored layers) equal a brute-force search over all node
/// pairs with the same inclusion rule (partial-volume coverage β > 0, no bond between two
/// fictitious nodes), row by row, for both the bucket grid and the k-d tree. Exact: both
/// sides evaluate the same rule on the same distances.
#[test]
fn graded_3d_mesh_neighbours_equal_a_brute_force_search() {
    let c = Case::load(&root().join("cases/block_refined.toml")).unwrap();
    let model = Model::build(&c.spec).unwrap();
    let (cloud, kernel) = (&model.cloud, &c.spec.kernel);
    let (n, nb) = (cloud.len(), cloud.n_body);
    let spread = cloud.horizon.iter().cloned().fold(0.0, f64::max)
        / cloud.horizon.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(spread > 2.0, "horizons vary by {spread}×");
    let brute: Vec<Vec<u32>> = (0..n)
        .map(|i| {
            (0..n)
                .filter(|&j| {
                    let r = (cloud.pos[j] - cloud.pos[i]).norm();
                    j != i
                        && !(i >= nb && j >= nb)
                        && kernel.coverage(r, cloud.horizon[i], cloud.spacing[j]).0 > 0.0
                })
                .map(|j| j as u32)
                .collect()
        })
        .collect();
    for grid in [true, false] {
        let h = Horizons::build_with(cloud, kernel, grid);
        for (i, want) in brute.iter().enumerate() {
            assert_eq!(&h.targets[h.row(i)], &want[..], "grid {grid}, row {i}");
        }
    }
    assert_eq!(model.bonds, brute.iter().map(Vec::len).sum::<usize>());
}

/// Every committed mesh (meshes/ and the test fixtures that are meant to be valid) passes the
/// integrity checks of `gmsh::read` (duplicated, overlapping, inverted or degenerate elements,
/// repeated node tags, two groups of one dimension and name): the checks refuse no mesh gmsh
/// wrote.
#[test]
fn every_committed_mesh_passes_the_integrity_checks() {
    let mut files: Vec<PathBuf> = ["meshes", "tests/data"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root().join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "msh"))
        .collect();
    files.sort();
    // the fixtures that are invalid on purpose (tests/data/make_fixtures.py)
    let invalid = ["msh22", "no_groups", "second_order", "unmeshed"];
    let mut read = 0;
    for f in &files {
        let stem = f.file_stem().unwrap().to_string_lossy();
        if invalid.contains(&stem.as_ref()) {
            continue;
        }
        gmsh::read(f).unwrap_or_else(|e| panic!("{e}"));
        read += 1;
    }
    assert!(read >= 45, "only {read} meshes found");
}
