//! Exact invariants: energy conservation, symmetry of K, linear fields, serial == parallel,
//! and the explicit stability bound.
#![allow(clippy::needless_range_loop)] // index loops mirror the formulas

use crate::common::case::CaseToml;
use peritherm::case::Case;
use peritherm::gather::{ColumnIndex, Precision, StepStorage};
use peritherm::model::Model;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use peritherm::weights::Order;

/// A two-region dual-horizon plate 2 × 1: k = Δ1/Δ2 = 0.5, m = δ1/δ2 = 2/3 (so neither
/// spacing nor horizon is uniform), free (insulated) surfaces.
fn dual_horizon_case(faces: &str, calibration: &str) -> Case {
    CaseToml::new(2)
        .domain("[0.0, 0.0]", "[2.0, 1.0]")
        .domain_key("thickness = 0.1")
        .region("fine", "spacing = 0.025", 4.0)
        .region_key("max = [0.8, 1.0]")
        .region("coarse", "spacing = 0.05", 3.0)
        .region_key("min = [0.8, 0.0]")
        .material("m", 2.0, 300.0, 0.5)
        .section(&format!("[kernel]\np = 1\ncalibration = \"{calibration}\""))
        .section(faces)
        .initial("sin(7*x) + 3*cos(5*y) + x*y")
        .time_key("integrator = \"euler\"")
        .case("dual_horizon.toml")
}

/// Energy Σ V ρc θ stays constant over 1000 Euler steps on an insulated, non-uniform,
/// dual-horizon cloud, with K in f64 and with K rounded to f32 (`kernel.precision = "f32"`).
/// Tolerance 1e-12 relative: the bond sum cancels pairwise (K_ij = K_ji bit for bit, and so
/// are their f32 roundings), leaving only summation round-off.
#[test]
fn energy_is_conserved_with_dual_horizon() {
    let storages = [
        StepStorage::default(),
        StepStorage {
            columns: ColumnIndex::Packed,
            precision: Precision::F32,
        },
    ];
    for (integ, storage) in [Integrator::Euler, Integrator::Rk4]
        .into_iter()
        .flat_map(|i| storages.map(|s| (i, s)))
    {
        let case = dual_horizon_case("", "continuum");
        let model = Model::build(&case.spec).unwrap();
        // a twentieth of the stable step, so that the field still varies after 1000 steps
        let dt = choose_dt(&model, integ, None).unwrap() / 20.0;
        let mut theta = model.theta0.clone();
        let e0 = model.energy(&theta);
        let mut st = Explicit::new(&model, integ.try_into().unwrap());
        st.set_storage(storage);
        for s in 0..1000 {
            st.step(&mut theta, s as f64 * dt, dt);
        }
        let e1 = model.energy(&theta);
        let spread = theta.iter().cloned().fold(f64::MIN, f64::max)
            - theta.iter().cloned().fold(f64::MAX, f64::min);
        assert!(
            spread > 0.1,
            "the field must still vary for the test to mean anything"
        );
        assert!(
            ((e1 - e0) / e0).abs() <= 1e-12,
            "{integ:?} {}: drift {}",
            storage.name(),
            (e1 - e0) / e0
        );
    }
}

/// K_ij == K_ji exactly for every body pair, with variable spacing and horizon, and the
/// directed bonds really are asymmetric (some j ∈ H_i with i ∉ H_j).
#[test]
fn conductance_is_symmetric_and_bonds_are_directed() {
    let spec = dual_horizon_case("", "lattice").spec;
    let model = Model::build(&spec).unwrap();
    let k = &model.conductance;
    let h = &peritherm::horizons::Horizons::build(&model.cloud, &spec.kernel);
    let mut one_way = 0;
    for i in 0..k.n_rows() {
        for b in k.offsets[i]..k.offsets[i + 1] {
            let j = k.cols[b] as usize;
            assert_eq!(k.vals[b], k.get(j, i), "K[{i},{j}]");
            assert!(k.vals[b] > 0.0);
        }
        for b in h.row(i) {
            let j = h.targets[b] as usize;
            if !h.targets[h.row(j)].contains(&(i as u32)) {
                one_way += 1;
            }
        }
    }
    assert!(one_way > 0, "a dual-horizon cloud must have one-way bonds");
}

/// A linear field produces no flow at nodes whose horizon is full and uniform (tolerance
/// 1e-9 of the flow scale: round-off over a symmetric lattice sum).
#[test]
fn linear_field_is_steady_in_the_bulk() {
    let case = dual_horizon_case("", "continuum");
    let model = Model::build(&case.spec).unwrap();
    let c = &model.cloud;
    let theta: Vec<f64> = c.pos.iter().map(|p| 3.0 * p.x - 2.0 * p.y + 1.0).collect();
    let mut flow = vec![0.0; c.n_body];
    model.conductance.apply(&theta, &mut flow);
    let scale = model.conductance.diag.iter().cloned().fold(0.0, f64::max) * 0.2;
    let mut checked = 0;
    for i in 0..c.n_body {
        let p = c.pos[i];
        let reach = c.horizon[i] + c.spacing[i];
        // no bond of i reaches the other region or a free surface (largest reach 0.2)
        let far_from_interface = (p.x - 0.8).abs() > 0.2 + reach;
        let inside = p.x > reach && p.x < 2.0 - reach && p.y > reach && p.y < 1.0 - reach;
        if inside && far_from_interface {
            assert!(flow[i].abs() < 1e-9 * scale, "node {i} at {p}: {}", flow[i]);
            checked += 1;
        }
    }
    assert!(checked > 10);
}

/// Mirrored layers holding 1 + 3x on the x faces of the 2 × 1 plate, insulated in y.
const MIRROR_FACES: &str = r#"
[boundary.x_min]
type = "temperature"
method = "mirror"
value = 1.0
[boundary.x_max]
type = "temperature"
method = "mirror"
value = 7.0
[boundary.y_min]
type = "insulated"
[boundary.y_max]
type = "insulated"
"#;

/// With mirrored fictitious layers (Dirichlet on x, insulated on y) a linear field in x is
/// steady at every body node, including those at the faces and corners (same tolerance).
#[test]
fn mirror_layers_keep_a_linear_field_steady_everywhere() {
    let case = dual_horizon_case(MIRROR_FACES, "lattice");
    let mut spec = case.spec.clone();
    let peritherm::model::Geometry::Box(g) = &mut spec.geometry else {
        panic!("a box case")
    };
    g.regions.truncate(1);
    g.regions[0].max[0] = 2.0;
    g.regions[0].cells[0] = 80;
    spec.initial =
        peritherm::model::Initial::Field(peritherm::expr::Expr::parse("1 + 3*x").unwrap());
    let model = Model::build(&spec).unwrap();
    let mut theta = model.theta0.clone();
    model.boundary.apply(&model.cloud, &mut theta, 0.0);
    let mut flow = vec![0.0; model.cloud.n_body];
    model.conductance.apply(&theta, &mut flow);
    let scale = model.conductance.diag.iter().cloned().fold(0.0, f64::max) * 0.1;
    for (i, f) in flow.iter().enumerate() {
        assert!(
            f.abs() < 1e-9 * scale,
            "node {i} at {}: {f}",
            model.cloud.pos[i]
        );
    }
}

/// The dual-horizon plate with every lattice refined 2× (7040 body nodes, several tasks of
/// [`peritherm::operator::ROW_CHUNK`] rows), with the given faces.
fn refined_dual_horizon(faces: &str) -> Model {
    let model = Model::build(&refined_dual_horizon_spec(faces)).unwrap();
    assert!(model.cloud.n_body > 3 * peritherm::operator::ROW_CHUNK);
    model
}

/// The spec of [`refined_dual_horizon`].
fn refined_dual_horizon_spec(faces: &str) -> peritherm::model::ModelSpec {
    let mut spec = dual_horizon_case(faces, "lattice").spec;
    let peritherm::model::Geometry::Box(g) = &mut spec.geometry else {
        panic!("a box case")
    };
    for r in &mut g.regions {
        r.cells[0] *= 2;
        r.cells[1] *= 2;
    }
    spec
}

/// One region of 128 × 64 cells on the 2 × 1 plate (Δ = 2⁻⁶, so lattice offsets are exact and
/// rows repeat bit for bit: K compresses into stencils), with the given faces.
fn uniform_plate(faces: &str) -> Model {
    let mut spec = dual_horizon_case(faces, "lattice").spec;
    let peritherm::model::Geometry::Box(g) = &mut spec.geometry else {
        panic!("a box case")
    };
    g.regions.truncate(1);
    g.regions[0].max[0] = 2.0;
    g.regions[0].cells = [128, 64, 1];
    let model = Model::build(&spec).unwrap();
    assert!(model.cloud.n_body > 3 * peritherm::operator::ROW_CHUNK);
    model
}

/// The parallel assembly gives, bit for bit, K_ij = w_ij + w_ji (w_ij alone, or w_ji alone, for
/// one-way bonds) with sorted columns and row sums in column order, on a dual-horizon cloud
/// with fictitious layers (one-way bonds at the horizon change) and on a uniform one (none).
#[test]
fn assembly_matches_a_pairwise_reference() {
    for model in [
        refined_dual_horizon(MIRROR_FACES),
        uniform_plate(MIRROR_FACES),
    ] {
        assembly_check(&model);
    }
}

fn assembly_check(model: &Model) {
    let spec = dual_horizon_case("", "lattice").spec;
    let c = &model.cloud;
    let h = &peritherm::horizons::Horizons::build(c, &spec.kernel);
    let w = peritherm::operator::directed_weights(
        c,
        h,
        &spec.kernel,
        &model.conductivity,
        spec.bond_rule,
    );
    let k = peritherm::operator::Conductance::assemble(c, h, &w);
    // K_ij = w_ij first, then + w_ji: the order the assembly adds them in
    let mut rows: Vec<std::collections::BTreeMap<u32, f64>> = vec![Default::default(); c.n_body];
    for (i, row) in rows.iter_mut().enumerate() {
        for b in h.row(i) {
            row.insert(h.targets[b], w[b]);
        }
    }
    let mut one_way = 0;
    for j in 0..h.len() {
        for b in h.row(j) {
            let i = h.targets[b] as usize;
            if i >= c.n_body {
                continue;
            }
            let e = rows[i].entry(j as u32).or_insert_with(|| {
                one_way += 1;
                0.0
            });
            *e = if *e == 0.0 { w[b] } else { *e + w[b] };
        }
    }
    for (i, row) in rows.iter().enumerate() {
        let r = k.offsets[i]..k.offsets[i + 1];
        let cols: Vec<u32> = row.keys().copied().collect();
        let vals: Vec<f64> = row.values().copied().collect();
        assert_eq!(k.cols[r.clone()], cols[..], "row {i}");
        assert_eq!(k.vals[r], vals[..], "row {i}");
        assert_eq!(k.diag[i], vals.iter().sum::<f64>(), "row {i}");
    }
    let uniform = model
        .cloud
        .horizon
        .iter()
        .all(|&d| d == model.cloud.horizon[0]);
    assert_eq!(
        one_way > 0,
        !uniform,
        "one-way bonds exactly where horizons differ"
    );
}

/// The parallel gather gives bit-identical results to the serial loop.
#[test]
fn serial_and_parallel_products_agree_exactly() {
    let model = refined_dual_horizon("");
    let mut a = vec![0.0; model.cloud.n_body];
    let mut b = a.clone();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| model.conductance.apply(&model.theta0, &mut a));
    model.conductance.apply_serial(&model.theta0, &mut b);
    assert_eq!(a, b);
}

/// Nodal Dirichlet on x_min (driven nodes), mirrored layers on y, convection on x_max.
const MIXED_FACES: &str = r#"
[boundary.x_min]
type = "temperature"
value = "1 + y"
[boundary.y_min]
type = "temperature"
method = "mirror"
value = 2.0
[boundary.y_max]
type = "insulated"
"#;

/// Convection on x_max (a load: the Euler step takes its rates-then-update path).
const CONVECTION_FACE: &str = r#"
[boundary.x_max]
type = "convection"
h = 50.0
ambient = 4.0
"#;

/// A reference Euler or RK4 run built from the serial product alone (no fused kernel), so that
/// the fused, chunked step is checked against the plain formula.
fn serial_reference(model: &Model, integ: Integrator, dt: f64, steps: usize) -> Vec<f64> {
    let nb = model.cloud.n_body;
    let rate = |theta: &[f64], t: f64| -> Vec<f64> {
        let mut r = vec![0.0; nb];
        model.conductance.apply_serial(theta, &mut r);
        for i in 0..nb {
            r[i] *= model.inv_heat_capacity[i];
        }
        model
            .boundary
            .add_loads(&model.cloud, &model.capacity, theta, t, &mut r);
        for i in 0..nb {
            if model.boundary.driven[i] {
                r[i] = 0.0;
            }
        }
        r
    };
    let mut theta = model.theta0.clone();
    for s in 0..steps {
        let t = s as f64 * dt;
        match integ {
            Integrator::Euler => {
                let r = rate(&theta, t);
                for i in 0..nb {
                    theta[i] += dt * r[i];
                }
            }
            _ => {
                let mut stage = theta.clone();
                let mut ks: Vec<Vec<f64>> = Vec::new();
                for (c, tc) in [
                    (0.0, t),
                    (0.5, t + 0.5 * dt),
                    (0.5, t + 0.5 * dt),
                    (1.0, t + dt),
                ] {
                    if let Some(k) = ks.last() {
                        for i in 0..nb {
                            stage[i] = theta[i] + c * dt * k[i];
                        }
                        model.boundary.apply(&model.cloud, &mut stage, tc);
                    }
                    ks.push(rate(&stage, tc));
                }
                for i in 0..nb {
                    theta[i] += dt / 6.0 * (ks[0][i] + 2.0 * (ks[1][i] + ks[2][i]) + ks[3][i]);
                }
            }
        }
        model.boundary.apply(&model.cloud, &mut theta, t + dt);
    }
    theta
}

/// Explicit runs on 1 and 2 threads, through the plain CSR rows, the stencils of K or the
/// packed columns ([`peritherm::packed`]), give the same temperatures bit for bit, and agree with a plain serial implementation of the same
/// scheme to 1e-12 relative (the kernels sum a row in another order than the serial product:
/// round-off only), for Euler with and without loads and for RK4, with driven, fictitious and
/// convective nodes.
#[test]
fn explicit_runs_agree_serial_and_parallel() {
    let mut stencils_seen = false;
    for (faces, integ, lattice) in [
        (MIXED_FACES.to_string(), Integrator::Euler, false),
        (MIXED_FACES.to_string(), Integrator::Euler, true),
        (
            format!("{MIXED_FACES}{CONVECTION_FACE}"),
            Integrator::Euler,
            true,
        ),
        (MIXED_FACES.to_string(), Integrator::Rk4, false),
    ] {
        let model = if lattice {
            uniform_plate(&faces)
        } else {
            refined_dual_horizon(&faces)
        };
        assert!(model.boundary.driven.iter().any(|&d| d));
        assert!(model.cloud.n_fictitious() > 0);
        let dt = choose_dt(&model, integ, None).unwrap();
        let steps = 60;
        let packed = StepStorage {
            columns: ColumnIndex::Packed,
            precision: Precision::F64,
        };
        let run_with = |threads: usize, stencils: bool, storage: StepStorage| -> Vec<f64> {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut theta = model.theta0.clone();
                let mut st = Explicit::new(&model, integ.try_into().unwrap());
                st.set_storage(storage);
                let used = st.set_stencils(stencils);
                assert!(!used || stencils);
                for s in 0..steps {
                    st.step(&mut theta, s as f64 * dt, dt);
                }
                theta
            })
        };
        let run = |threads, stencils| run_with(threads, stencils, StepStorage::default());
        let one = run(1, false);
        assert_eq!(one, run(2, false), "{integ:?}: 1 and 2 threads differ");
        assert_eq!(one, run_with(1, false, packed), "{integ:?}: packed differs");
        assert_eq!(
            one,
            run_with(2, false, packed),
            "{integ:?}: packed, 2 threads"
        );
        if integ == Integrator::Euler {
            let mut st = Explicit::new(&model, integ.try_into().unwrap());
            stencils_seen |= st.set_stencils(true);
            assert!(
                !lattice || st.set_stencils(true),
                "a lattice repeats its rows"
            );
            assert_eq!(one, run(1, true), "{integ:?}: stencils differ from CSR");
            assert_eq!(one, run(2, true), "{integ:?}: stencils on 2 threads differ");
        }
        let reference = serial_reference(&model, integ, dt, steps);
        let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let moved = (0..model.cloud.n_body)
            .map(|i| (reference[i] - model.theta0[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            moved > 1e-3 * scale,
            "the field must change for the test to mean anything"
        );
        for (i, (a, b)) in one.iter().zip(&reference).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "{integ:?} node {i}: fused {a} vs serial {b}"
            );
        }
    }
    assert!(stencils_seen, "the lattice plate must use stencils");
}

/// The bucket-grid search and the k-d tree give the same neighbour lists, bit for bit, on a
/// dual-horizon cloud (spacing ratio 2) with fictitious layers, where the grid is used.
#[test]
fn neighbour_search_grid_equals_tree() {
    let model = refined_dual_horizon(MIRROR_FACES);
    let kernel = dual_horizon_case("", "lattice").spec.kernel;
    let a = peritherm::horizons::Horizons::build_with(&model.cloud, &kernel, true);
    let b = peritherm::horizons::Horizons::build_with(&model.cloud, &kernel, false);
    assert!(peritherm::horizons::Horizons::grid_applies(
        &model.cloud,
        &kernel
    ));
    assert_eq!(a.offsets, b.offsets);
    assert_eq!(a.targets, b.targets);
    assert_eq!(a.n_bonds(), model.bonds);
}

/// A rank's rows searched alone ([`Horizons::build_rows_with`], grid and k-d tree, 1 to 4
/// ranks) are the whole search's rows, and so is every row whose horizon holds one of them
/// (the margin the assembly reads: dual horizon, fictitious layers).
#[test]
fn a_ranks_search_holds_its_rows_and_their_margin() {
    use peritherm::horizons::Horizons;
    use peritherm::partition::Partition;
    let model = refined_dual_horizon(MIRROR_FACES);
    let kernel = dual_horizon_case("", "lattice").spec.kernel;
    let whole = &Horizons::build(&model.cloud, &kernel);
    let row = |h: &Horizons, i: usize| h.targets[h.row(i)].to_vec();
    for grid in [true, false] {
        for ranks in 1..=4 {
            let partition = Partition::by_estimate(&model.cloud, ranks);
            for r in 0..ranks {
                let rows = partition.range(r);
                let h = Horizons::build_rows_with(&model.cloud, &kernel, rows.clone(), grid);
                let mut needed: Vec<usize> = rows.clone().collect();
                for j in 0..whole.len() {
                    let t = &whole.targets[whole.row(j)];
                    if t.iter().any(|&i| rows.contains(&(i as usize))) {
                        needed.push(j);
                    }
                }
                for i in needed {
                    assert_eq!(
                        row(&h, i),
                        row(whole, i),
                        "grid {grid}, {ranks} ranks, row {i}"
                    );
                }
            }
        }
    }
}

/// The Gershgorin bound of theory §4 is safe and not far from the truth: Euler at the
/// bound stays bounded; Euler at 1.2× the true limit 2/λ_max (power iteration) blows up;
/// a user Δt above the bound is refused with the bound in the message.
#[test]
fn time_step_bound() {
    let model = Model::build(&dual_horizon_case("", "continuum").spec).unwrap();
    let n = model.cloud.n_body;
    // power iteration on A = M⁻¹ L (free nodes), shifted to its largest magnitude
    let mut v: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { 1.0 } else { -0.7 })
        .collect();
    let mut lambda = 0.0;
    let mut w = vec![0.0; n];
    for _ in 0..3000 {
        model.conductance.apply(&v, &mut w);
        let mut norm = 0.0;
        for i in 0..n {
            w[i] *= -model.inv_heat_capacity[i];
            norm += w[i] * w[i];
        }
        let norm = norm.sqrt();
        let vn = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        lambda = norm / vn;
        for i in 0..n {
            v[i] = w[i] / norm;
        }
    }
    let bound = Integrator::Euler.stable_dt(&model);
    let exact = 2.0 / lambda;
    assert!(
        bound <= exact * (1.0 + 1e-6),
        "bound {bound} vs exact {exact}"
    );
    assert!(
        bound > 0.25 * exact,
        "bound {bound} is too pessimistic vs {exact}"
    );
    let amplitude = |dt: f64| {
        let mut theta = model.theta0.clone();
        let mut st = Explicit::new(&model, ExplicitScheme::Euler);
        for s in 0..400 {
            st.step(&mut theta, s as f64 * dt, dt);
        }
        theta[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()))
    };
    let a0 = model.theta0[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(amplitude(bound) <= a0 * (1.0 + 1e-9));
    assert!(amplitude(1.2 * exact) > 1e3 * a0);
    let err = choose_dt(&model, Integrator::Euler, Some(2.0 * bound))
        .unwrap_err()
        .to_string();
    assert!(err.contains("exceeds the stable bound"), "{err}");
}

/// The linear-consistency correction (crates/core/src/weights, order linear) keeps K symmetric bit for bit
/// and positive, conserves energy to round-off, and makes a linear field steady at every body
/// node of a dual-horizon cloud with mirrored layers, interface included. Tolerance 1e-9 of
/// the flow scale (the moments are met to 1e-10 relative).
#[test]
fn linear_consistency_correction_is_exact_and_conservative() {
    let case = dual_horizon_case(MIRROR_FACES, "lattice");
    let mut spec = case.spec.clone();
    spec.initial =
        peritherm::model::Initial::Field(peritherm::expr::Expr::parse("1 + 3*x").unwrap());
    let plain = Model::build(&spec).unwrap();
    spec.consistency = Order::Linear;
    let model = Model::build(&spec).unwrap();
    let c = model.correction.unwrap();
    assert!(
        c.before > 1e-3,
        "the uncorrected interface must be inconsistent: {}",
        c.before
    );
    assert!(c.after < 1e-10, "{c:?}");
    assert!(c.min_ratio > 0.5, "{c:?}");
    let k = &model.conductance;
    for i in 0..k.n_rows() {
        for b in k.offsets[i]..k.offsets[i + 1] {
            let j = k.cols[b] as usize;
            if j < k.n_rows() {
                assert_eq!(k.vals[b], k.get(j, i));
            }
        }
    }
    let flows = |m: &Model| {
        let mut theta = m.theta0.clone();
        m.boundary.apply(&m.cloud, &mut theta, 0.0);
        let mut flow = vec![0.0; m.cloud.n_body];
        m.conductance.apply(&theta, &mut flow);
        let scale = m.conductance.diag.iter().cloned().fold(0.0, f64::max) * 0.1;
        flow.iter().fold(0.0f64, |a, f| a.max(f.abs())) / scale
    };
    assert!(
        flows(&plain) > 1e-3,
        "without the correction the interface is not steady"
    );
    assert!(flows(&model) < 1e-9, "{}", flows(&model));
    // energy on the same cloud with free surfaces
    let mut free = dual_horizon_case("", "lattice").spec;
    free.consistency = Order::Linear;
    let m = Model::build(&free).unwrap();
    let dt = choose_dt(&m, Integrator::Euler, None).unwrap() / 20.0;
    let mut theta = m.theta0.clone();
    let e0 = m.energy(&theta);
    let mut st = Explicit::new(&m, ExplicitScheme::Euler);
    for s in 0..1000 {
        st.step(&mut theta, s as f64 * dt, dt);
    }
    assert!(((m.energy(&theta) - e0) / e0).abs() <= 1e-12);
}

/// A 3D box with two regions (k = 0.5) and conical p = 2 kernel: volumes sum to the box,
/// K is symmetric and an RK4 run conserves energy (tolerance 1e-12 relative).
#[test]
fn three_dimensional_boxes_conserve_energy() {
    let m = CaseToml::new(3)
        .domain("[0.0, 0.0, 0.0]", "[0.4, 0.2, 0.2]")
        .region("fine", "spacing = 0.02", 3.0)
        .region_key("max = [0.2, 0.2, 0.2]")
        .region("coarse", "spacing = 0.04", 2.0)
        .region_key("min = [0.2, 0.0, 0.0]")
        .material("m", 1.0, 1.0, 1.0)
        .section("[kernel]\nprofile = \"conical\"")
        .initial("x*x + sin(20*y) + z")
        .model("box.toml");
    assert!((m.cloud.body_volume() - 0.4 * 0.2 * 0.2).abs() < 1e-15);
    assert_eq!(m.cloud.n_body, 10 * 10 * 10 + 5 * 5 * 5);
    let k = &m.conductance;
    for i in 0..k.n_rows() {
        for b in k.offsets[i]..k.offsets[i + 1] {
            assert_eq!(k.vals[b], k.get(k.cols[b] as usize, i));
        }
    }
    let dt = choose_dt(&m, Integrator::Rk4, None).unwrap() / 10.0;
    let mut theta = m.theta0.clone();
    let e0 = m.energy(&theta);
    let mut st = Explicit::new(&m, ExplicitScheme::Rk4);
    for s in 0..200 {
        st.step(&mut theta, s as f64 * dt, dt);
    }
    assert!(((m.energy(&theta) - e0) / e0).abs() <= 1e-12);
}

/// Where the horizon jumps abruptly (here by 4×) a first-order correction of K would need
/// negative conductances; the exponential form keeps every pair positive and still makes the
/// moments exact (tolerance: the solver's 1e-10), so such clouds are no longer refused.
#[test]
fn abrupt_horizon_jumps_are_corrected_with_positive_conductances() {
    let mut spec = dual_horizon_case(MIRROR_FACES, "lattice").spec;
    let peritherm::model::Geometry::Box(g) = &mut spec.geometry else {
        panic!("a box case")
    };
    g.regions[0].horizon = peritherm::cloud::HorizonRule::Factor(1.5);
    spec.consistency = Order::Linear;
    let c = Model::build(&spec).unwrap().correction.unwrap();
    assert!(c.min_ratio > 0.0 && c.after < 1e-10, "{c:?}");
    assert_eq!(c.uncorrected, 0, "{c:?}");
}

/// Each rank's share of a dual-horizon model with fictitious layers ([`Model::build_share`],
/// 1 to 5 ranks) holds the rows of K of its range with the bits of the whole model's (columns,
/// values, row sums) and nothing else, its bonds add up to the whole model's, and the halo it
/// plans alone equals the one planned from the whole model. Exact: the same sums in the same
/// order.
#[test]
fn a_share_holds_the_whole_models_rows_bit_for_bit() {
    use peritherm::horizons::Horizons;
    use peritherm::partition::{own_halo, publishers, rule_sources};
    use peritherm::solve::exchange::RankPlan;
    let spec = refined_dual_horizon_spec(MIRROR_FACES);
    assert!(Model::shareable(&spec));
    let whole = Model::build(&spec).unwrap();
    let k = &whole.conductance;
    for ranks in 1..=5 {
        let plans = RankPlan::all(&whole, ranks);
        let mut bonds = 0;
        for (rank, plan) in plans.iter().enumerate() {
            let (share, partition) = Model::build_share(&spec, ranks, rank).unwrap();
            assert_eq!(partition, plan.partition);
            let rows = partition.range(rank);
            assert_eq!(share.rows, rows);
            let s = &share.conductance;
            assert_eq!(s.nnz(), k.offsets[rows.end] - k.offsets[rows.start]);
            for i in 0..whole.cloud.n_body {
                let (a, b) = (
                    s.offsets[i]..s.offsets[i + 1],
                    k.offsets[i]..k.offsets[i + 1],
                );
                if !rows.contains(&i) {
                    assert!(a.is_empty() && s.diag[i] == 0.0, "{ranks} ranks: row {i}");
                    continue;
                }
                assert_eq!(s.cols[a.clone()], k.cols[b.clone()], "row {i}");
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&s.vals[a]), bits(&k.vals[b]), "row {i}");
                assert_eq!(s.diag[i].to_bits(), k.diag[i].to_bits(), "row {i}");
            }
            // a share counts its bonds as a search of its rows alone does
            let census = Horizons::census(&share.cloud, &spec.kernel, std::slice::from_ref(&rows));
            assert_eq!(share.bonds, census[0].bonds, "{ranks} ranks, rank {rank}");
            bonds += share.bonds;
            // the halo a share plans alone is the one of the whole model (sends aside)
            let sources = rule_sources(share.cloud.len(), &share.boundary.linear_rules());
            let nb = share.cloud.n_body;
            let publish = publishers(&sources, nb, &partition).swap_remove(rank);
            let own = own_halo(s, &sources, nb, &partition, rank, publish);
            assert_eq!(
                (&own.recv, &own.publish),
                (&plan.halo.recv, &plan.halo.publish)
            );
        }
        let all = Horizons::build(&whole.cloud, &spec.kernel).n_bonds();
        assert_eq!((bonds, whole.bonds), (all, all), "{ranks} ranks");
    }
}
