//! Consistent bond weights (crates/core/src/weights) on gmsh meshes of every element kind: quadratic
//! fields integrated exactly, K symmetric and positive, energy conserved, the explicit bound
//! still stable. The meshes are meshes/moments_*.msh (triangles, unstructured quadrangles,
//! mixed, graded 4×, tetrahedra; the hexahedra of moments_hex.msh are the open case below).

use crate::common::case::CaseToml;
use crate::common::figures::Table;
use peritherm::model::Model;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use peritherm::weights::{self, Order};
use std::path::{Path, PathBuf};

const MESHES: [(&str, usize); 5] = [
    ("moments_tri.msh", 2),
    ("moments_quad.msh", 2),
    ("moments_mixed.msh", 2),
    ("moments_graded.msh", 2),
    ("moments_tet.msh", 3),
];

/// The lowest level of each family of the mesh-convergence suite (boundary group `held`).
const SUITE: [(&str, usize); 5] = [
    ("conv_rect_tri_L1.msh", 2),
    ("conv_rect_quad_L1.msh", 2),
    ("conv_graded_L1.msh", 2),
    ("conv_disc_L1.msh", 2),
    ("conv_cube_tet_L1.msh", 3),
];

/// A case on `file` with conductivity 2, the group `wall` given `wall` (a TOML table body).
fn model(file: &str, dim: usize, wall: &str, initial: &str, order: Option<&str>) -> Model {
    model_on(file, dim, ("wall", wall), initial, order)
}

/// [`model`] with the boundary group named `group.0`.
fn model_on(
    file: &str,
    dim: usize,
    group: (&str, &str),
    initial: &str,
    order: Option<&str>,
) -> Model {
    let (name, wall) = group;
    let consistency = order.map_or(String::new(), |o| format!("consistency = \"{o}\"\n"));
    let case = CaseToml::new(dim)
        .mesh(&format!("../meshes/{file}"))
        .region("body", "", 3.0)
        .material("m", 2.0, 1.0, 1.0)
        .section(&format!("[kernel]\n{consistency}"))
        .section(&format!("[boundary.{name}]\n{wall}"))
        .initial(initial)
        .time_key("integrator = \"euler\"")
        .case("tests/weights.toml");
    Model::build(&case.spec).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// θ = 1 + 2x − 3y + z + 3x² − 2xy + 1.5y² + 0.5z² + yz, and its Laplacian (9 in 3D, 9 in 2D:
/// the z terms vanish on z = 0 but 0.5z² still adds 1 in 3D).
fn quadratic(p: &peritherm::math::Point, dim: usize) -> (f64, f64) {
    let (x, y, z) = (p.x, p.y, p.z);
    let t =
        1.0 + 2.0 * x - 3.0 * y + z + 3.0 * x * x - 2.0 * x * y + 1.5 * y * y + 0.5 * z * z + y * z;
    (t, if dim == 3 { 10.0 } else { 9.0 })
}

/// Largest |Σ_j K_ij (θ_j − θ_i) − V_i k ∇²θ| / (V_i k (|∇²θ| + |∇θ|/δ_i)) over the nodes the
/// correction met, θ quadratic and evaluated at every node (fictitious ones included).
#[allow(clippy::needless_range_loop)] // flow, positions and marks are indexed by node
fn quadratic_error(m: &Model, dim: usize) -> (f64, usize) {
    let theta: Vec<f64> = m.cloud.pos.iter().map(|p| quadratic(p, dim).0).collect();
    let mut flow = vec![0.0; m.cloud.n_body];
    m.conductance.apply(&theta, &mut flow);
    let mut worst = 0.0f64;
    let mut count = 0;
    for i in 0..m.cloud.n_body {
        let selected = m.consistent[i] || m.correction.is_none();
        if !selected {
            continue;
        }
        count += 1;
        let (_, lap) = quadratic(&m.cloud.pos[i], dim);
        let vk = m.cloud.volume[i] * 2.0;
        let scale = vk * (lap + 10.0 / m.cloud.horizon[i]);
        worst = worst.max((flow[i] - vk * lap).abs() / scale);
    }
    (worst, count)
}

/// With mirrored insulated walls every node has a complete horizon: the corrected operator is
/// V_i k ∇²θ for a quadratic θ at every node of every mesh kind (tolerance 1e-8 of the scale:
/// the moments are met to 1e-10 relative), where the kernel's own weights miss by > 1e-3.
#[test]
fn quadratic_fields_are_integrated_exactly_on_every_mesh_kind() {
    for (file, dim) in MESHES {
        let wall = "type = \"insulated\"";
        let m = model(file, dim, wall, "0", None);
        let c = m.correction.expect("meshes are corrected by default");
        assert_eq!(c.uncorrected, 0, "{file}: {c:?}");
        assert_eq!(c.corrected, m.cloud.n_body, "{file}: {c:?}");
        assert!(c.min_ratio > 0.0, "{file}: {c:?}");
        let (after, n) = quadratic_error(&m, dim);
        assert_eq!(n, m.cloud.n_body);
        assert!(after < 1e-8, "{file}: {after:e}");
        let plain = model(file, dim, wall, "0", Some("none"));
        let (before, _) = quadratic_error(&plain, dim);
        assert!(
            before > 1e-3,
            "{file}: the kernel alone already exact? {before:e}"
        );
    }
}

/// With free walls (no fictitious nodes) the corrected K is symmetric bit for bit with every
/// entry positive, an Euler run at 0.99 of the stable bound stays bounded by the initial
/// maximum for 10⁴ steps (positive weights: each step is a convex combination), and the
/// energy is conserved to 1e-12 relative: on every mesh kind and on the suite's families.
#[test]
fn consistent_weights_are_symmetric_positive_stable_and_conservative() {
    // the suite's meshes leave facets in no group (insulated by default): free them too
    let free = "type = \"free\"";
    let free_all = "type = \"free\"\n[boundary.\"(no group)\"]\ntype = \"free\"";
    let kinds = MESHES.iter().map(|&(f, d)| (f, d, "wall", free));
    for (file, dim, group, wall) in
        kinds.chain(SUITE.iter().map(|&(f, d)| (f, d, "held", free_all)))
    {
        let m = model_on(
            file,
            dim,
            (group, wall),
            "2 + sin(40*x)*cos(37*y) + z",
            None,
        );
        let c = m.correction.unwrap();
        // every node of the coarsest cube lies within δ of a (free) face: nothing to correct,
        // the kernel's own weights are checked there
        let coarse_cube = file == "conv_cube_tet_L1.msh";
        assert!(c.corrected > 0 || coarse_cube, "{file}: {c:?}");
        assert_eq!(m.cloud.n_fictitious(), 0, "{file}");
        let k = &m.conductance;
        for i in 0..k.n_rows() {
            for b in k.offsets[i]..k.offsets[i + 1] {
                let j = k.cols[b] as usize;
                assert!(k.vals[b] > 0.0, "{file}");
                assert_eq!(k.vals[b].to_bits(), k.get(j, i).to_bits(), "{file}");
            }
        }
        let dt = 0.99 * choose_dt(&m, Integrator::Euler, None).unwrap();
        let mut theta = m.theta0.clone();
        let top = theta.iter().cloned().fold(f64::MIN, f64::max);
        let bottom = theta.iter().cloned().fold(f64::MAX, f64::min);
        let e0 = m.energy(&theta);
        let mut st = Explicit::new(&m, ExplicitScheme::Euler);
        for s in 0..10_000 {
            st.step(&mut theta, s as f64 * dt, dt);
        }
        let hi = theta.iter().cloned().fold(f64::MIN, f64::max);
        let lo = theta.iter().cloned().fold(f64::MAX, f64::min);
        assert!(
            hi <= top + 1e-9 && lo >= bottom - 1e-9,
            "{file}: {lo}..{hi}"
        );
        let e = m.energy(&theta);
        assert!(((e - e0) / e0).abs() <= 1e-12, "{file}: {e} vs {e0}");
    }
}

/// A direct factor of the Newton matrix that would not fit in memory is left to CG
/// (`weights::correct_within` with no room), which reaches the same weights: every pair
/// conductance within 1e-6 relative of the direct solve's (both meet the moments to 1e-10
/// relative; the pairs are not unique, the Newton iterates are the same up to round-off at
/// this size), with more CG iterations.
#[test]
fn a_factor_that_does_not_fit_is_left_to_cg() {
    let wall = "type = \"insulated\"";
    let corrected = model("moments_tri.msh", 2, wall, "0", None);
    let plain = model("moments_tri.msh", 2, wall, "0", Some("none"));
    let solve = |room: Option<f64>| {
        let mut k = plain.conductance.clone();
        let sel = &corrected.consistent;
        let order = Order::Quadratic;
        let (c, met) =
            weights::correct_within(&mut k, &plain.cloud, sel, &plain.conductivity, order, room);
        assert!(c.after < 1e-10 && met == *sel, "{room:?}: {c:?}");
        (k.vals, c.iterations)
    };
    let (direct, direct_cg) = solve(None);
    let (cg, cg_only) = solve(Some(0.0));
    assert!(
        cg_only > direct_cg,
        "CG {cg_only} against {direct_cg} iterations"
    );
    for (a, b) in direct.iter().zip(&cg) {
        assert!(
            (a - b).abs() <= 1e-6 * a.abs().max(1e-300),
            "{a:e} against {b:e}"
        );
    }
}

/// The weights are the same bits on 1 and 2 threads, through the direct factor and through
/// CG alone, in 2D and 3D: every sum of the correction has a fixed order and its
/// factorisations are sequential (an exact invariant: no tolerance).
#[test]
fn consistent_weights_are_the_same_bits_for_any_thread_count() {
    let wall = "type = \"insulated\"";
    for (file, dim) in [("moments_tri.msh", 2), ("moments_tet.msh", 3)] {
        let corrected = model(file, dim, wall, "0", None);
        let plain = model(file, dim, wall, "0", Some("none"));
        let solve = |threads: usize, room: Option<f64>| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut k = plain.conductance.clone();
            let (sel, order) = (&corrected.consistent, Order::Quadratic);
            pool.install(|| {
                weights::correct_within(&mut k, &plain.cloud, sel, &plain.conductivity, order, room)
            });
            k.vals
        };
        for room in [None, Some(0.0)] {
            assert!(
                solve(1, room) == solve(2, room),
                "{file}, factor room {room:?}: 1 and 2 threads differ"
            );
        }
    }
}

/// The linear order zeroes first moments only: a linear field is steady, a quadratic one is
/// not integrated exactly (the second moments keep the quadrature bias).
#[test]
fn the_linear_order_leaves_second_moments_alone() {
    let m = model(
        "moments_tri.msh",
        2,
        "type = \"insulated\"",
        "0",
        Some("linear"),
    );
    assert!(m.correction.unwrap().after < 1e-10);
    let (err, _) = quadratic_error(&m, 2);
    assert!(err > 1e-4, "{err:e}");
    assert_eq!(Order::default(), Order::Quadratic);
}

/// Extruded hexahedra (moments_hex.msh, 6 layers): OPEN. The correction meets the moments at
/// 523 of 594 nodes and leaves 71 out; a linear program over the same pairs (nonnegative,
/// symmetric K) has no solution there at all: layers 0.1 apart against horizons of
/// 0.26–0.29 leave too few pairs in z. The mesh is not refused, and the nodes left out are
/// counted with how far from exact they stay. This test pins that report (it fails, and
/// should be tightened, once the hexahedra are corrected).
#[test]
fn hexahedra_left_out_nodes_are_reported_not_refused() {
    let m = model("moments_hex.msh", 3, "type = \"insulated\"", "0", None);
    let c = m.correction.unwrap();
    assert!(c.uncorrected > 0 && c.worst_uncorrected > 0.0, "{c:?}");
    assert_eq!(c.corrected + c.uncorrected, m.cloud.n_body, "{c:?}");
    assert!(c.after < 1e-10 && c.min_ratio > 0.0, "{c:?}");
    let met = m.consistent.iter().filter(|&&x| x).count();
    assert_eq!(met, c.corrected);
}

/// Every body group of `file` (under meshes/) as a region with δ = 3Δ, one material, no
/// boundary named (so every boundary takes the default, an insulating mirrored layer), the
/// default kernel: the consistent weights are on. Also the set-up's memory estimate, bytes.
fn default_model(file: &Path) -> Result<(Model, f64), String> {
    let mesh = peritherm::gmsh::read(file).map_err(|e| e.to_string())?;
    let dim = mesh.dim();
    let body = mesh.groups.iter().filter(|g| g.dim == dim);
    let toml = body
        .fold(CaseToml::new(dim), |t, g| t.region(&g.name, "", 3.0))
        .mesh(&file.display().to_string())
        .material("m", 1.0, 1.0, 1.0)
        .initial_value(1.0)
        .end(1.0);
    let case = peritherm::case::Case::parse(&toml.text(), Path::new("every_mesh.toml"))
        .map_err(|e| e.to_string())?;
    let model = Model::build(&case.spec).map_err(|e| e.to_string())?;
    Ok((model, case.budget.bytes))
}

/// The committed meshes of meshes/ with at most `max_bytes` bytes (all: usize::MAX).
fn committed_meshes(max_bytes: u64) -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "msh"))
        .filter(|p| std::fs::metadata(p).unwrap().len() <= max_bytes)
        .collect();
    files.sort();
    files
}

/// The set-up of the consistent weights on every committed mesh (docs/performance.md).
const EVERY_MESH: Table = Table {
    name: "every_mesh",
    command: "PERITHERM_RECORD=1 cargo test --release --test properties weights::no_committed_mesh_is_refused_large_ones_included -- --ignored",
    columns: &[
        "mesh",
        "body nodes",
        "corrected",
        "left out (worst relative moment error)",
        "K'/K from .. to",
        "Newton / CG iterations",
        "model built in (s)",
        "peak resident (GB)",
        "estimated (GB)",
    ],
    keys: &[
        "annulus.msh",
        "block_refined.msh",
        "conv_cube_tet_L1.msh",
        "conv_cube_tet_L2.msh",
        "conv_cube_tet_L3.msh",
        "conv_cube_tet_L4.msh",
        "conv_disc_L1.msh",
        "conv_disc_L2.msh",
        "conv_disc_L3.msh",
        "conv_disc_L4.msh",
        "conv_graded_L1.msh",
        "conv_graded_L2.msh",
        "conv_graded_L3.msh",
        "conv_graded_L4.msh",
        "conv_rect_quad_L1.msh",
        "conv_rect_quad_L2.msh",
        "conv_rect_quad_L3.msh",
        "conv_rect_quad_L4.msh",
        "conv_rect_tri_L1.msh",
        "conv_rect_tri_L2.msh",
        "conv_rect_tri_L3.msh",
        "conv_rect_tri_L4.msh",
        "crack_plate_refined.msh",
        "crack_plate_uniform.msh",
        "dh_plate_k0.5.msh",
        "dh_plate_k1.msh",
        "l_shape.msh",
        "moments_graded.msh",
        "moments_hex.msh",
        "moments_mixed.msh",
        "moments_quad.msh",
        "moments_tet.msh",
        "moments_tri.msh",
        "pipe_heating_d0.01.msh",
        "pipe_heating_d0.02.msh",
        "pipe_heating_d0.04.msh",
        "pipe_heating_fem.msh",
    ],
    timed: &[6, 7],
};

/// Relative tolerance of the counts and ratios on another machine: the Newton iterations and
/// parallel sums are the same bits at any thread count, but another CPU's `exp` may differ in
/// its last bit and an iteration count may then move by one or two.
const EVERY_MESH_REL_TOL: f64 = 0.05;

/// Forgets the process's peak resident set so far, so that [`peritherm::bench::peak_rss`]
/// measures from here (Linux; elsewhere a no-op).
fn reset_peak_resident() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Builds every mesh in `files` with the default settings; none may be refused, and every
/// node the correction leaves out is counted (corrected + left out = body nodes). Each mesh's
/// row of [`EVERY_MESH`] is recorded or checked.
fn assert_none_refused(files: &[PathBuf]) {
    assert!(!files.is_empty());
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        reset_peak_resident();
        let start = std::time::Instant::now();
        let (m, estimate) = default_model(f).unwrap_or_else(|e| panic!("{name}: refused: {e}"));
        let seconds = start.elapsed().as_secs_f64();
        let c = m.correction.expect("mesh cases are corrected by default");
        assert!(
            c.corrected + c.uncorrected <= m.cloud.n_body,
            "{name}: {c:?}"
        );
        let cells = [
            name.clone(),
            m.cloud.n_body.to_string(),
            c.corrected.to_string(),
            format!("{} ({:.1e})", c.uncorrected, c.worst_uncorrected),
            format!("{:.1e} .. {:.1e}", c.min_ratio, c.max_ratio),
            format!("{} / {}", c.newton, c.iterations),
            format!("{seconds:.0}"),
            peritherm::bench::peak_rss().map_or("-".into(), |b| format!("{:.1}", b as f64 / 1e9)),
            format!("{:.1}", estimate / 1e9),
        ];
        eprintln!("{}", cells.join(" | "));
        EVERY_MESH.row(&cells, EVERY_MESH_REL_TOL);
    }
}

/// No mesh of meshes/ up to 80 kB (11 of 37, each below 2 000 nodes) is refused with the
/// default settings (no boundary named). The larger ones are built by the bundled cases and
/// the convergence tests, and all of them by the ignored test below.
#[test]
fn no_committed_mesh_is_refused() {
    assert_none_refused(&committed_meshes(80_000));
}

/// The same for every mesh of meshes/, the largest levels of the convergence suite included
/// (the 26 meshes up to 1 MB took 7.5 minutes on 2 cores under load 7; the four 4.5–12.5 MB
/// level-4 meshes take longer: `cargo test --release --test weights -- --ignored`).
#[test]
#[ignore]
fn no_committed_mesh_is_refused_large_ones_included() {
    assert_none_refused(&committed_meshes(u64::MAX));
}
