//! Implicit schemes and the steady solve (theory §4): temporal orders against an RK4
//! reference, steady state against the explicit run and exact/classical solutions, energy
//! conservation, refusals, serial == parallel.

use crate::common::case::CaseToml;
use crate::common::figures::Table;
use peritherm::case::Case;
use peritherm::error::CoreError;
use peritherm::model::Model;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use peritherm::solve::implicit::{Adaptive, Implicit, Options, Ordering, Scheme, Solver};
use std::path::Path;

/// The implicit and adaptive integrators' checks (docs/validation.md).
const IMPLICIT: Table = Table {
    name: "implicit_checks",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases implicit::",
    columns: &["check (1D bar, against RK4 at a quarter of its stable step)", "measured", "criterion"],
    keys: &[
        "observed temporal orders at Δt = 0.02, 0.01, 0.005 s",
        "adaptive Crank–Nicolson: worst output error / tol at tol = 1e-3, 1e-4, 1e-5",
        "adaptive BDF2: worst output error / tol at tol = 1e-3, 1e-4, 1e-5",
        "after a boundary jump: adaptive Crank–Nicolson at tol 1e-4 against the fixed step of the same accuracy",
    ],
    timed: &[],
};

/// Relative tolerance of these figures on another machine: the factorisations split their work
/// by the thread count, so the fields move by round-off, and an adaptive run may then accept a
/// step more or less (counts and errors move by a few per cent, never by the criteria's margins).
const IMPLICIT_REL_TOL: f64 = 0.05;

/// A 1D bar, 100 nodes, δ = 3Δ, the left end following θ = 5t·e^(−2t) through a mirrored layer,
/// the right end insulated (mirrored layer): a smooth transient.
fn bar(left: &str, right: &str, initial: &str) -> Case {
    CaseToml::new(1)
        .domain("[0.0]", "[1.0]")
        .region("bar", "spacing = 0.01", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .section("[kernel]\np = 2\ncalibration = \"lattice\"")
        .section(&format!("[boundary.x_min]\n{left}"))
        .section(&format!("[boundary.x_max]\n{right}"))
        .initial(initial)
        .time_key("integrator = \"rk4\"")
        .case("bar.toml")
}

/// A 2D plate 1 × 0.5 of two regions with the same lattice (Δ = 0.025, δ = 3Δ), the faces
/// given by `faces`, a non-uniform initial field.
fn plate(faces: &str) -> Case {
    CaseToml::new(2)
        .domain("[0.0, 0.0]", "[1.0, 0.5]")
        .domain_key("thickness = 0.1")
        .region("fine", "spacing = 0.025", 3.0)
        .region_key("max = [0.5, 0.5]")
        .region("coarse", "spacing = 0.025", 3.0)
        .region_key("min = [0.5, 0.0]")
        .material("m", 2.0, 300.0, 0.5)
        .section("[kernel]\np = 1\ncalibration = \"lattice\"")
        .section(faces)
        .initial("sin(7*x) + 3*cos(5*y) + x*y")
        .time_key("integrator = \"euler\"")
        .case("plate.toml")
}

const INSULATED: &str = r#"
[boundary.x_min]
type = "insulated"
[boundary.x_max]
type = "insulated"
[boundary.y_min]
type = "insulated"
[boundary.y_max]
type = "insulated"
"#;

/// Body temperatures at `t_end` from an implicit run.
fn implicit(model: &Model, scheme: Scheme, dt: f64, t_end: f64, options: Options) -> Vec<f64> {
    let mut theta = model.theta0.clone();
    let mut st = Implicit::new(model, scheme, options).unwrap();
    st.run(&mut theta, 0.0, dt, &[t_end], |_, _, _, _| Ok(()), |_| {})
        .unwrap();
    theta.truncate(model.cloud.n_body);
    theta
}

/// Body temperatures at `t_end` from an explicit RK4 run with step `dt`.
fn rk4(model: &Model, dt: f64, t_end: f64) -> Vec<f64> {
    let mut theta = model.theta0.clone();
    let mut st = Explicit::new(model, ExplicitScheme::Rk4);
    st.run(&mut theta, 0.0, dt, &[t_end], |_, _, _, _| Ok(()), |_| {})
        .unwrap();
    theta.truncate(model.cloud.n_body);
    theta
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// BE, CN and BDF2 converge to the RK4 solution with orders 1, 2, 2. The reference is RK4 at
/// a quarter of its stable step (its error, O(dt⁴) ~ 1e-15, is far below the implicit errors,
/// 1e-3…1e-6); the spatial operator is the same, so the differences are purely temporal.
/// Orders from h = 0.02, 0.01, 0.005 s to t = 1 s (far above the explicit stable step); the
/// thresholds 0.9 / 1.8 leave 10 % for the pre-asymptotic range.
#[test]
fn temporal_orders_against_rk4() {
    let case = bar(
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = \"5*t*exp(-2*t)\"",
        "type = \"insulated\"",
        "0",
    );
    let model = Model::build(&case.spec).unwrap();
    let dt_ref = choose_dt(&model, Integrator::Rk4, None).unwrap() / 4.0;
    let reference = rk4(&model, dt_ref, 1.0);
    let mut measured = Vec::new();
    for (scheme, name, order) in [
        (Scheme::BackwardEuler, "backward Euler", 0.9),
        (Scheme::CrankNicolson, "Crank–Nicolson", 1.8),
        (Scheme::Bdf2, "BDF2", 1.8),
    ] {
        let errors: Vec<f64> = [0.02, 0.01, 0.005]
            .iter()
            .map(|&h| {
                max_diff(
                    &implicit(&model, scheme, h, 1.0, Options::default()),
                    &reference,
                )
            })
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!("{scheme:?}: errors {errors:?}, orders {orders:.3?}");
        assert!(
            orders.iter().all(|&p| p >= order),
            "{scheme:?}: observed orders {orders:?} below {order} (errors {errors:?})"
        );
        let o: Vec<String> = orders.iter().map(|p| format!("{p:.2}")).collect();
        measured.push(format!("{name} {}", o.join(", ")));
    }
    let cells = [IMPLICIT.keys[0], &measured.join("; "), "≥ 0.9, 1.8, 1.8"];
    IMPLICIT.row(&cells, IMPLICIT_REL_TOL);
}

/// Nodal Dirichlet (driven nodes) and Bobaru & Duangpanya 2010's flux relation (slaved nodes) are
/// eliminated correctly: CN and BDF2 at h = 0.0025 s agree with RK4 to 1e-4 °C (their time error at
/// this step is ~1e-6 °C on the mirrored bar above; a wrong elimination errs by O(1) °C).
#[test]
fn nodal_and_relation_constraints_match_rk4() {
    let case = bar(
        "type = \"temperature\"\nvalue = \"5*t*exp(-2*t)\"",
        "type = \"flux\"\nmethod = \"relation\"\nvalue = 3.0",
        "0",
    );
    let model = Model::build(&case.spec).unwrap();
    let dt_ref = choose_dt(&model, Integrator::Rk4, None).unwrap() / 4.0;
    let reference = rk4(&model, dt_ref, 1.0);
    for scheme in [Scheme::CrankNicolson, Scheme::Bdf2] {
        let st = Implicit::new(&model, scheme, Options::default()).unwrap();
        assert!(st.system().len() < model.cloud.n_body);
        let d = max_diff(
            &implicit(&model, scheme, 0.0025, 1.0, Options::default()),
            &reference,
        );
        println!("{scheme:?}: {d:e}");
        assert!(d <= 1e-4, "{scheme:?}: {d:e}");
    }
}

/// Steady state of a bar held at 0 and 100 °C through mirrored layers: the linear profile
/// (mirrored layers reproduce linear fields exactly; tolerance 1e-9 °C, round-off of a
/// 100-node solve), and the explicit RK4 run taken to t = 5 s (50 time constants
/// L²/(π²α); e^(−50) of a 100 °C transient is below 1e-20) to 1e-9 °C.
#[test]
fn steady_equals_linear_profile_and_long_explicit_run() {
    let case = bar(
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = 0.0",
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = 100.0",
        "50*sin(3*x)",
    );
    let model = Model::build(&case.spec).unwrap();
    let mut theta = model.theta0.clone();
    let mut st = Implicit::new(&model, Scheme::Bdf2, Options::default()).unwrap();
    assert!(st.system().symmetric, "asymmetry {}", st.system().asymmetry);
    st.steady(&mut theta, &[1.0], |_, _, _, _| Ok::<_, CoreError>(()))
        .unwrap();
    let nb = model.cloud.n_body;
    let linear = (0..nb)
        .map(|i| (theta[i] - 100.0 * model.cloud.pos[i].x).abs())
        .fold(0.0, f64::max);
    assert!(linear <= 1e-9, "steady vs linear: {linear:e}");
    let dt = choose_dt(&model, Integrator::Rk4, None).unwrap();
    let long = rk4(&model, dt, 5.0);
    let d = max_diff(&theta[..nb], &long);
    assert!(d <= 1e-9, "steady vs explicit at 5 s: {d:e}");
}

/// The annulus of `cases/annulus_steady.toml` (gmsh ring, layers mirrored across chords: A is
/// nonsymmetric, so this exercises the LU path) against its logarithmic steady profile: no
/// worse than the explicit run's 0.107 °C max abs diff (README table), which is the spatial
/// error of the PD model itself; tolerance +5 %.
#[test]
fn steady_annulus_against_logarithmic_profile() {
    let mut case = Case::load(Path::new("cases/annulus_steady.toml")).unwrap();
    case.integrator = Integrator::Steady;
    let dir = std::env::temp_dir().join(format!("peritherm_steady_{}", std::process::id()));
    let summary = peritherm::run::run_case(&case, &dir, |_, _| {}).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let worst = summary
        .reference
        .iter()
        .map(|c| c.max_abs_diff)
        .fold(0.0, f64::max);
    println!("annulus steady: max abs diff {worst:.4e} °C");
    assert!(worst > 0.0 && worst <= 0.107 * 1.05, "{worst}");
    assert_eq!(summary.integrator, "steady");
}

/// An insulated plate with mirrored layers on every face and no source: A is symmetric and
/// Σ V ρc θ stays constant to round-off (1e-12 relative) under BE, CN and BDF2, while the
/// field changes. (Where A is not symmetric, e.g. the dual-horizon plates whose spacing
/// changes at the faces, asymmetry 1.3e-3 for `dh_plate_k0.5_m1`, the mirrored layers do not
/// conserve energy exactly, explicit or implicit.)
#[test]
fn energy_is_conserved_by_implicit_schemes() {
    let case = plate(INSULATED);
    let model = Model::build(&case.spec).unwrap();
    let st = Implicit::new(&model, Scheme::BackwardEuler, Options::default()).unwrap();
    let sys = st.system();
    assert!(sys.symmetric, "asymmetry {:e}", sys.asymmetry);
    let e0 = model.energy(&model.theta0);
    for scheme in [Scheme::BackwardEuler, Scheme::CrankNicolson, Scheme::Bdf2] {
        let theta = implicit(&model, scheme, 0.5, 20.0, Options::default());
        let e1 = model.energy(&theta);
        assert!(max_diff(&theta, &model.theta0[..model.cloud.n_body]) > 0.1);
        assert!(
            ((e1 - e0) / e0).abs() <= 1e-12,
            "{scheme:?}: drift {:e}",
            (e1 - e0) / e0
        );
    }
}

/// Growing cracks change K as the tips pass: the implicit path refuses them with one line
/// naming the file and `time.integrator`. An implicit run without `time.dt` is refused too.
#[test]
fn refusals_name_file_and_key() {
    let text = r#"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
[[region]]
name = "r"
spacing = 0.05
horizon = { factor = 3 }
[material.m]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[[crack]]
points = [[0.2, 0.5], [0.8, 0.5]]
speed = 0.1
[boundary.y_max]
type = "temperature"
method = "mirror"
value = 1.0
[time]
end = 1.0
dt = 0.1
integrator = "crank_nicolson"
"#;
    let case = Case::parse(text, Path::new("growing.toml")).unwrap();
    let dir = std::env::temp_dir().join(format!("peritherm_refuse_{}", std::process::id()));
    let e = peritherm::run::run_case(&case, &dir, |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("growing.toml: time.integrator:") && e.contains("growing cracks"),
        "{e}"
    );
    assert!(!e.contains('\n'));
    let no_dt = text.replace("dt = 0.1\n", "").replace("speed = 0.1\n", "");
    let case = Case::parse(&no_dt, Path::new("nodt.toml")).unwrap();
    let e = peritherm::run::run_case(&case, &dir, |_, _| {})
        .unwrap_err()
        .to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(e.starts_with("nodt.toml: time.dt:"), "{e}");
}

/// Serial and parallel runs (rayon products, faer's parallel kernels) agree to 1e-12 relative,
/// for the direct solver and for conjugate gradients.
#[test]
fn serial_equals_parallel() {
    let case = plate(
        r#"
[boundary.x_min]
type = "temperature"
method = "mirror"
value = "sin(t)"
[boundary.y_max]
type = "insulated"
"#,
    );
    let model = Model::build(&case.spec).unwrap();
    for solver in [Solver::Direct, Solver::Cg] {
        let run = |parallel| {
            let o = Options {
                solver,
                parallel,
                ..Options::default()
            };
            implicit(&model, Scheme::CrankNicolson, 0.1, 2.0, o)
        };
        let (s, p) = (run(false), run(true));
        let scale = s.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let d = max_diff(&s, &p);
        assert!(d <= 1e-12 * scale, "{solver:?}: {d:e} of {scale:e}");
    }
}

/// The implicit solvers' costs per case (docs/performance.md, "Implicit solver choices").
const SOLVERS: Table = Table {
    name: "implicit_solvers",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases implicit::per_solve_direct_vs_cg -- --ignored",
    columns: &[
        "case and linear solver (Crank–Nicolson)",
        "Δt",
        "unknowns",
        "nnz(L)",
        "factorisation (s)",
        "solves",
        "per solve (s)",
        "CG iterations",
    ],
    keys: &[
        "dh_crack_plate_k1_m1_implicit, direct, nested dissection",
        "dh_crack_plate_k1_m1_implicit, direct, AMD",
        "dh_crack_plate_k1_m1_implicit, Jacobi CG",
        "thermal_shock_k1_m1_implicit, direct, nested dissection",
        "thermal_shock_k1_m1_implicit, direct, AMD",
        "thermal_shock_k1_m1_implicit, Jacobi CG",
    ],
    timed: &[4, 6],
};

/// Relative tolerance of the solver counts (fill, iterations) on another machine: the
/// orderings and CG are deterministic, but the factorisations split their work by the thread
/// count, so an iteration count may move by one.
const SOLVERS_REL_TOL: f64 = 0.05;

/// Per-solve cost of the direct solver (two orderings) against Jacobi-PCG on the two study
/// cases at the Δt of their implicit variants; records [`SOLVERS`] (minutes).
#[test]
#[ignore]
fn per_solve_direct_vs_cg() {
    for (file, dt, steps) in [
        ("dh_crack_plate_k1_m1_implicit", 0.01, 10),
        ("thermal_shock_k1_m1_implicit", 0.05, 4),
    ] {
        let case = Case::load(Path::new(&format!("cases/{file}.toml"))).unwrap();
        let dt = case.dt.unwrap_or(dt);
        let model = Model::build(&case.spec).unwrap();
        for (solver, ordering, name) in [
            (
                Solver::Direct,
                Ordering::NestedDissection,
                "direct, nested dissection",
            ),
            (Solver::Direct, Ordering::Amd, "direct, AMD"),
            (Solver::Cg, Ordering::Amd, "Jacobi CG"),
        ] {
            let o = Options {
                solver,
                ordering,
                ..Options::default()
            };
            let mut theta = model.theta0.clone();
            let mut st = Implicit::new(&model, Scheme::CrankNicolson, o).unwrap();
            let end = [dt * steps as f64];
            st.run(&mut theta, 0.0, dt, &end, |_, _, _, _| Ok(()), |_| {})
                .unwrap();
            let s = st.stats;
            // CG factorises nothing
            let (fill, factorising) = match solver {
                Solver::Cg => ("-".into(), "-".into()),
                _ => (
                    format!("{:.3e}", s.factor_entries as f64),
                    format!("{:.2}", s.factor_seconds),
                ),
            };
            let cells = [
                format!("{file}, {name}"),
                format!("{dt} s"),
                st.system().len().to_string(),
                fill,
                factorising,
                s.solves.to_string(),
                format!("{:.4}", s.solve_seconds / s.solves as f64),
                s.cg_iterations.to_string(),
            ];
            SOLVERS.row(&cells, SOLVERS_REL_TOL);
        }
    }
}

/// The asymmetry of the eliminated system matrix A (docs/validation.md).
const ASYMMETRY: Table = Table {
    name: "asymmetry",
    command:
        "PERITHERM_RECORD=1 cargo test --release --test cases implicit::asymmetry_of_a -- --ignored",
    columns: &[
        "case",
        "max |A_ij − A_ji| / max A_ii",
        "solved as symmetric",
    ],
    keys: &[
        "annulus_steady",
        "dh_plate_k0.5_m1",
        "bar_flux",
        "crack_plate_refined",
        "dh_crack_plate_k2_m1",
    ],
    timed: &[],
};

/// Records [`ASYMMETRY`] for a few bundled cases: where the mirrors and relations of the
/// boundary break the symmetry of A, and by how much (a minute).
#[test]
#[ignore]
fn asymmetry_of_a() {
    for name in ASYMMETRY.keys {
        let case = Case::load(Path::new(&format!("cases/{name}.toml"))).unwrap();
        let model = Model::build(&case.spec).unwrap();
        let sys = peritherm::solve::implicit::System::build(&model).unwrap();
        let cells = [
            name.to_string(),
            format!("{:.1e}", sys.asymmetry),
            if sys.symmetric { "yes" } else { "no" }.to_string(),
        ];
        // the asymmetry is a property of the model: the same bits on any machine up to `exp`
        ASYMMETRY.row(&cells, 0.01);
    }
}

/// Body temperatures at each output time of an adaptive run, and its counters.
fn adaptive(
    model: &Model,
    scheme: Scheme,
    tolerance: f64,
    outputs: &[f64],
    options: Options,
) -> (Vec<Vec<f64>>, peritherm::solve::implicit::ImplicitStats) {
    let mut theta = model.theta0.clone();
    let mut st = Implicit::new(model, scheme, options).unwrap();
    let mut fields = Vec::new();
    let nb = model.cloud.n_body;
    let a = Adaptive {
        tolerance,
        first: None,
        max: None,
    };
    st.run_adaptive(
        &mut theta,
        0.0,
        &a,
        outputs,
        |_, _, th, _| {
            fields.push(th[..nb].to_vec());
            Ok::<_, CoreError>(())
        },
        |_, _| {},
    )
    .unwrap();
    (fields, st.stats)
}

/// Body temperatures at each output time of an RK4 run at a quarter of its stable step: the
/// time-converged semi-discrete solution (its error, O(dt⁴) ~ 1e-15 °C, is far below every
/// tolerance used here).
fn rk4_outputs(model: &Model, outputs: &[f64]) -> Vec<Vec<f64>> {
    let dt = choose_dt(model, Integrator::Rk4, None).unwrap() / 4.0;
    let mut theta = model.theta0.clone();
    let mut st = Explicit::new(model, ExplicitScheme::Rk4);
    let nb = model.cloud.n_body;
    let mut fields = Vec::new();
    st.run(
        &mut theta,
        0.0,
        dt,
        outputs,
        |_, _, th, _| {
            fields.push(th[..nb].to_vec());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    fields
}

/// Largest max-norm difference over the outputs.
fn worst(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| max_diff(x, y))
        .fold(0.0, f64::max)
}

/// The adaptive error follows the tolerance (Crank–Nicolson and BDF2, direct solver). The bar
/// of [`temporal_orders_against_rk4`] (left end 5t·e^(−2t), mirrored), outputs at 0.3, 0.55
/// and 1 s, which the steps do not land on (Hermite dense output), against RK4 at a quarter
/// of its stable step (time-converged, error ~1e-15 °C). The tolerance bounds the local error
/// per step, so the global error may exceed it by the accumulation over the steps: measured
/// worst error / tolerance at tol = 1e-3, 1e-4, 1e-5: CN 1.0, 2.5, 6.2; BDF2 2.4, 5.3, 12
/// (it grows like tol^(−1/3): per-step control). Asserted: ≤ 20·tol (margin 1.7× on BDF2 at
/// 1e-5), and tol 1e-3 → 1e-5 divides the error by at least 10 (measured 16× CN, 20× BDF2).
#[test]
fn adaptive_error_follows_the_tolerance() {
    let case = bar(
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = \"5*t*exp(-2*t)\"",
        "type = \"insulated\"",
        "0",
    );
    let model = Model::build(&case.spec).unwrap();
    let outputs = [0.3, 0.55, 1.0];
    let reference = rk4_outputs(&model, &outputs);
    for (key, scheme) in [(1, Scheme::CrankNicolson), (2, Scheme::Bdf2)] {
        let errors: Vec<f64> = [1e-3, 1e-4, 1e-5]
            .iter()
            .map(|&tol| {
                let (fields, s) = adaptive(&model, scheme, tol, &outputs, Options::default());
                let e = worst(&fields, &reference);
                println!(
                    "{scheme:?} tol {tol:e}: error {e:.3e} ({:.2} tol), {} accepted, {} rejected, {} solves",
                    e / tol,
                    s.accepted,
                    s.rejected,
                    s.solves
                );
                assert!(e <= 20.0 * tol, "{scheme:?} tol {tol:e}: error {e:e}");
                e
            })
            .collect();
        assert!(
            errors[0] >= 10.0 * errors[2],
            "{scheme:?}: errors {errors:?} do not fall with the tolerance"
        );
        let ratios: Vec<String> = errors
            .iter()
            .zip([1e-3, 1e-4, 1e-5])
            .map(|(e, tol)| format!("{:.1}", e / tol))
            .collect();
        let criterion = "≤ 20, falling with tol";
        let cells = [IMPLICIT.keys[key], &ratios.join(" / "), criterion];
        IMPLICIT.row(&cells, IMPLICIT_REL_TOL);
    }
}

/// A boundary jump at t = 0 (the bar at 0 °C, its left end held at 1 °C through a mirrored
/// layer from t = 0, as the crack plate's faces), outputs at 2e-3 s (early: the layer is a
/// few nodes thick) and 0.2 s. Adaptive Crank–Nicolson at tol = 1e-4 with the automatic
/// solver choice (CG on the small steps) against fixed-Δt Crank–Nicolson (Rannacher start)
/// that meets the same accuracy at every output; reference RK4 as above (measured figures:
/// validation/implicit_checks.json). At the first output alone fixed Δt can be cheaper, since
/// per-step error control resolves the start-up layer that the later smoothing would forgive;
/// the adaptive gain is that the step then grows. Asserted: the adaptive error ≤ 2·tol, at most
/// a fifth of the solves.
#[test]
fn adaptive_steps_pay_after_a_boundary_jump() {
    let case = bar(
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = 1.0",
        "type = \"insulated\"",
        "0",
    );
    let model = Model::build(&case.spec).unwrap();
    let outputs = [2e-3, 0.2];
    let reference = rk4_outputs(&model, &outputs);
    let tol = 1e-4;
    let auto = Options {
        solver: Solver::Auto,
        ..Options::default()
    };
    let (fields, s) = adaptive(&model, Scheme::CrankNicolson, tol, &outputs, auto);
    let e = worst(&fields, &reference);
    println!(
        "adaptive: error {e:.3e}, {} solves ({} by CG), {} factorisations",
        s.solves, s.cg_solves, s.factorisations
    );
    assert!(e <= 2.0 * tol, "adaptive error {e:e}");
    let mut fixed = None;
    for dt in [4e-4, 2e-4, 1e-4, 5e-5] {
        let mut theta = model.theta0.clone();
        let mut st = Implicit::new(&model, Scheme::CrankNicolson, Options::default()).unwrap();
        let mut fields = Vec::new();
        st.run(
            &mut theta,
            0.0,
            dt,
            &outputs,
            |_, _, th, _| {
                fields.push(th[..model.cloud.n_body].to_vec());
                Ok(())
            },
            |_| {},
        )
        .unwrap();
        let ef = worst(&fields, &reference);
        println!(
            "fixed Δt {dt:e}: error {ef:.3e}, {} solves",
            st.stats.solves
        );
        if ef <= e {
            fixed = Some((dt, st.stats.solves));
            break;
        }
    }
    let (dt, fixed) = fixed.expect("a fixed step down to 5e-5 s reaches the adaptive accuracy");
    assert!(
        5 * s.solves <= fixed,
        "adaptive {} solves against fixed {fixed}",
        s.solves
    );
    let measured = format!(
        "adaptive {e:.1e} °C with {} solves ({} by CG); fixed Δt {dt:e} s, {fixed} solves",
        s.solves, s.cg_solves
    );
    let criterion = "error ≤ 2 tol, at most a fifth of the fixed step's solves";
    IMPLICIT.row(&[IMPLICIT.keys[3], &measured, criterion], IMPLICIT_REL_TOL);
}

/// An insulated plate (mirrored layers, symmetric A) with a constant source s = 7 W/m³:
/// Σ V ρc θ = E0 + s·V·t at every output of adaptive backward Euler, Crank–Nicolson and BDF2
/// (direct solver) to 1e-12 relative, as at fixed steps. Each scheme conserves the energy
/// step by step (BDF2 with its interpolated history too, the energy of a Hermite interpolant
/// of a linear-in-time energy being exact), and the Hermite output is exact for it.
#[test]
fn adaptive_steps_conserve_energy() {
    let case = plate(&format!("{INSULATED}\n[source]\nvalue = 7.0\n"));
    let model = Model::build(&case.spec).unwrap();
    let e0 = model.energy(&model.theta0);
    let volume = 1.0 * 0.5 * 0.1;
    let outputs = [0.7, 3.0, 20.0];
    for scheme in [Scheme::BackwardEuler, Scheme::CrankNicolson, Scheme::Bdf2] {
        let (fields, s) = adaptive(&model, scheme, 1e-3, &outputs, Options::default());
        assert!(s.accepted > 3 && s.max_step > s.min_step, "{s:?}");
        for (theta, &t) in fields.iter().zip(&outputs) {
            let expected = e0 + 7.0 * volume * t;
            let drift = (model.energy(theta) - expected) / e0.abs();
            assert!(drift.abs() <= 1e-12, "{scheme:?} at {t}: drift {drift:e}");
        }
        assert!(max_diff(&fields[2], &model.theta0[..model.cloud.n_body]) > 0.1);
    }
}

/// `time.tolerance` and `time.dt_max` are refused with one line naming the file and the key:
/// non-positive or non-finite values, explicit or steady integrators, phase change, dt_max
/// without tolerance, a first step above dt_max.
#[test]
fn adaptive_keys_are_checked() {
    let base = bar("type = \"insulated\"", "type = \"insulated\"", "0");
    assert!(base.tolerance.is_none());
    let text = |time: &str, material: &str| {
        format!(
            "dimension = 1\n[domain]\nmin = [0.0]\nmax = [1.0]\n[[region]]\nname = \"bar\"\nspacing = 0.01\nhorizon = {{ factor = 3 }}\n[material.m]\nconductivity = 1.0\ndensity = 1.0\nspecific_heat = 1.0\n{material}[time]\nend = 1.0\n{time}\n"
        )
    };
    let ok = Case::parse(
        &text(
            "integrator = \"bdf2\"\ntolerance = 1e-4\ndt = 1e-3\ndt_max = 0.05",
            "",
        ),
        Path::new("a.toml"),
    )
    .unwrap();
    assert_eq!(
        (ok.tolerance, ok.dt, ok.dt_max),
        (Some(1e-4), Some(1e-3), Some(0.05))
    );
    let phase = "[material.m.phase_change]\ntemperature = 0.5\nlatent_heat = 10.0\nfrozen_conductivity = 1.0\nfrozen_specific_heat = 1.0\n";
    for (time, material, key, words) in [
        (
            "integrator = \"crank_nicolson\"\ntolerance = 0.0",
            "",
            "time.tolerance",
            "positive",
        ),
        (
            "integrator = \"crank_nicolson\"\ntolerance = -1e-3",
            "",
            "time.tolerance",
            "positive",
        ),
        (
            "integrator = \"crank_nicolson\"\ntolerance = nan",
            "",
            "time.tolerance",
            "positive",
        ),
        (
            "integrator = \"crank_nicolson\"\ntolerance = inf",
            "",
            "time.tolerance",
            "positive",
        ),
        (
            "integrator = \"euler\"\ntolerance = 1e-3",
            "",
            "time.tolerance",
            "not of euler",
        ),
        (
            "integrator = \"rk4\"\ntolerance = 1e-3",
            "",
            "time.tolerance",
            "not of rk4",
        ),
        ("tolerance = 1e-3", "", "time.tolerance", "not of rk4"),
        (
            "integrator = \"steady\"\ntolerance = 1e-3",
            "",
            "time.tolerance",
            "not of steady",
        ),
        (
            "integrator = \"backward_euler\"\ntolerance = 1e-3",
            phase,
            "time.tolerance",
            "phase change",
        ),
        (
            "integrator = \"bdf2\"\ndt = 0.01\ndt_max = 0.1",
            "",
            "time.dt_max",
            "time.tolerance",
        ),
        (
            "integrator = \"bdf2\"\ntolerance = 1e-3\ndt_max = 0.0",
            "",
            "time.dt_max",
            "positive",
        ),
        (
            "integrator = \"bdf2\"\ntolerance = 1e-3\ndt = 0.2\ndt_max = 0.1",
            "",
            "time.dt",
            "exceeds",
        ),
    ] {
        let e = Case::parse(&text(time, material), Path::new("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!("bad.toml: {key}:")) && e.contains(words) && !e.contains('\n'),
            "{time}: {e}"
        );
    }
}

/// An adaptive run through `run_case` needs no `time.dt` and reports its counters in
/// run.json: accepted steps (= `steps`), rejected steps, solves, factorisations.
#[test]
fn adaptive_run_reports_its_counters() {
    let mut case = bar(
        "type = \"temperature\"\nmethod = \"mirror\"\nvalue = 1.0",
        "type = \"insulated\"",
        "0",
    );
    case.integrator = Integrator::Bdf2;
    case.tolerance = Some(1e-3);
    case.outputs = vec![0.01, 0.1];
    let dir = tempfile::tempdir().unwrap();
    let summary = peritherm::run::run_case(&case, dir.path(), |_, _| {}).unwrap();
    let read = peritherm::output::RunSummary::read(dir.path()).unwrap();
    let st = read.implicit.expect("implicit counters in run.json");
    assert_eq!(st.accepted, summary.steps);
    assert!(st.accepted > 10 && st.solves >= st.accepted && st.tolerance == 1e-3);
    assert!(st.solves == st.accepted + st.rejected, "{st:?}");
    assert_eq!(summary.dt, st.first_step);
    assert_eq!(read.fields.len(), 2);
}

/// The automatic solver choice of adaptive runs against the direct solver alone.
const SOLVER_CHOICE: Table = Table {
    name: "adaptive_solver_choice",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases implicit::adaptive_auto_vs_direct -- --ignored",
    columns: &[
        "adaptive Crank–Nicolson, dh_crack_plate_k1_m1, tol 1e-3",
        "steps",
        "solves (by CG, CG iterations)",
        "factorisations",
        "factorising (s)",
        "whole run (s)",
    ],
    keys: &["solver = auto", "solver = direct"],
    timed: &[4, 5],
};

/// The automatic solver choice against the direct solver alone on the adaptive crack plate;
/// records [`SOLVER_CHOICE`] (about a minute).
#[test]
#[ignore]
fn adaptive_auto_vs_direct() {
    let case = Case::load(Path::new("cases/dh_crack_plate_k1_m1_adaptive.toml")).unwrap();
    let model = Model::build(&case.spec).unwrap();
    for (solver, name) in [(Solver::Auto, "auto"), (Solver::Direct, "direct")] {
        let o = Options {
            solver,
            ..Options::default()
        };
        let started = std::time::Instant::now();
        let (_, s) = adaptive(&model, Scheme::CrankNicolson, 1e-3, &case.outputs, o);
        let cells = [
            format!("solver = {name}"),
            s.accepted.to_string(),
            format!("{} ({}, {})", s.solves, s.cg_solves, s.cg_iterations),
            s.factorisations.to_string(),
            format!("{:.2}", s.factor_seconds),
            format!("{:.2}", started.elapsed().as_secs_f64()),
        ];
        SOLVER_CHOICE.row(&cells, IMPLICIT_REL_TOL);
    }
}
