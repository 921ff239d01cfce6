//! Enthalpy form and phase change (theory §6; PCS2022
//! (doi:10.1007/s42102-022-00092-3)): the enthalpy stepper against the linear one, energy
//! conservation with phase change in symmetric bodies, and planar freezing against Neumann's
//! solution.

use crate::common::case::CaseToml;
use crate::common::figures::Table;
use peritherm::analytic::{neumann_front, Reference};
use peritherm::case::Case;
use peritherm::model::Model;
use peritherm::solve::enthalpy::Enthalpic;
use peritherm::solve::explicit::{choose_dt, Explicit, ExplicitScheme, Integrator};
use std::path::Path;

/// The phase-change checks (docs/validation.md).
const PHASE: Table = Table {
    name: "phase_checks",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases phase::",
    columns: &["check", "measured", "criterion"],
    keys: &[
        "enthalpy stepper vs linear stepper, a material that never changes phase (1D mirror/flux/source; 2D axisymmetric flux/convection)",
        "energy Σ V H, ice in water, insulated (free faces), axisymmetric 2D and spherical 1D",
        "planar freezing (Δ = 5 mm, −10 °C face, +5 °C water, 48 h) against Neumann's front",
        "`cases/pipe_freezing.toml` (the axisymmetric phase-change paper §3.3) against a radial finite-volume enthalpy solve (2 mm cells) at 1, 2, 3 days",
    ],
    timed: &[],
};

/// Relative tolerance of a physical figure of these checks on another machine: explicit steppers
/// give the same bits at any thread count, so only a printed digit may move.
const PHYSICAL: f64 = 1e-6;
/// Relative tolerance of a round-off figure (a difference or drift of 1e-14): it measures the
/// summation order, which another compiler or instruction set may change; its criterion is the
/// bound that matters.
const ROUND_OFF: f64 = 10.0;

/// With `phase` a phase change that never happens (T_f far above every temperature, frozen
/// properties equal to the melted ones), which switches the model to the enthalpy stepper
/// without changing the physics.
const NO_PHASE_CHANGE: &str = "[material.m.phase_change]\ntemperature = 1e9\nlatent_heat = 3e5\n\
                               frozen_conductivity = 2.0\nfrozen_specific_heat = 1500.0";

/// Geometries covering every path of the stepper: planar 1D with mirror temperature and flux
/// layers and a source; 2D axisymmetric with a free axis, mirror flux, mirror convection,
/// surface convection and a nodal temperature.
fn geometry(which: usize) -> CaseToml {
    match which {
        0 => CaseToml::new(1)
            .domain("[0.0]", "[1.0]")
            .region("body", "spacing = 0.02", 3.0)
            .section(
                "[boundary.x_min]\ntype = \"temperature\"\nmethod = \"mirror\"\n\
                 value = \"20*(1 - exp(-t/50))\"\n\
                 [boundary.x_max]\ntype = \"flux\"\nvalue = 150.0\n\
                 [source]\nvalue = \"2000*x\"",
            )
            .initial("5*sin(3*x)"),
        _ => CaseToml::new(2)
            .key("symmetry = \"axisymmetric\"")
            .domain("[0.0, 0.0]", "[0.5, 0.4]")
            .region("body", "spacing = 0.02", 3.0)
            .section(
                "[boundary.x_max]\ntype = \"flux\"\nvalue = -300.0\n\
                 [boundary.y_min]\ntype = \"convection\"\nmethod = \"mirror\"\nh = 40.0\n\
                 ambient = 30.0\n\
                 [boundary.y_max]\ntype = \"convection\"\nh = 25.0\nambient = -10.0",
            )
            .initial("10*x + 20*y*y"),
    }
}

fn case(which: usize, phase: bool) -> Case {
    let mut c = geometry(which).material("m", 2.0, 900.0, 1500.0);
    if phase {
        c = c.section(NO_PHASE_CHANGE);
    }
    c.end(100.0)
        .time_key("integrator = \"euler\"")
        .case("enthalpy.toml")
}

/// "Materials without phase change behave exactly as before": the enthalpy stepper on a
/// material whose phase never changes gives the linear stepper's temperatures. Tolerance 1e-12
/// relative to the field's range: the two differ only in rounding (K scaled by λ̄ per bond
/// instead of once, H = ρcθ instead of θ).
#[test]
fn enthalpy_form_equals_the_linear_form_without_phase_change() {
    let mut measured = Vec::new();
    for which in 0..2 {
        let linear = Model::build(&case(which, false).spec).unwrap();
        let enth = Model::build(&case(which, true).spec).unwrap();
        assert!(linear.enthalpy.is_none() && enth.enthalpy.is_some());
        let dt = choose_dt(&linear, Integrator::Euler, None).unwrap();
        let dt_enth = choose_dt(&enth, Integrator::Euler, None).unwrap();
        assert!((dt - dt_enth).abs() < 1e-12 * dt, "{dt} vs {dt_enth}");
        let mut a = linear.theta0.clone();
        let mut b = enth.theta0.clone();
        let mut lin = Explicit::new(&linear, ExplicitScheme::Euler);
        let mut ent = Enthalpic::new(&enth, Integrator::Euler).unwrap();
        for s in 0..400 {
            let t = s as f64 * dt;
            lin.step(&mut a, t, dt);
            ent.step(&mut b, t, dt);
        }
        let range = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = a
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        println!("geometry {which}: max |Δθ| = {diff:.3e} of {range:.3e}");
        assert!(range > 1.0);
        assert!(diff <= 1e-12 * range, "geometry {which}: {diff:e}");
        measured.push(format!("{diff:.0e} of {range:.0} °C"));
    }
    let cells = [
        PHASE.keys[0],
        &format!("max difference {}", measured.join(", ")),
        "1e-12 relative",
    ];
    PHASE.row(&cells, ROUND_OFF);
}

/// Total enthalpy Σ V_i H_i (ring or shell volumes) is conserved by phase change in an
/// insulated symmetric body: ice at −5 °C in water at 60 °C, axisymmetric 2D and spherical
/// 1D, free faces. Tolerance 1e-12 relative: λ̄_ij = λ̄_ji and K_ij = K_ji, so the bond sum
/// cancels pairwise; only summation round-off remains.
#[test]
fn energy_is_conserved_with_phase_change_in_symmetric_bodies() {
    let bodies = [
        CaseToml::new(2)
            .key("symmetry = \"axisymmetric\"")
            .domain("[0.0, 0.0]", "[0.1, 0.1]")
            .region("ice", "spacing = 0.005", 3.0)
            .region_key("max = [0.04, 0.04]")
            .region_key("initial = -5.0")
            .region("water beside", "spacing = 0.005", 3.0)
            .region_key("min = [0.04, 0.0]")
            .region_key("max = [0.1, 0.04]")
            .region_key("initial = 60.0")
            .region("water above", "spacing = 0.005", 3.0)
            .region_key("min = [0.0, 0.04]")
            .region_key("initial = 60.0"),
        CaseToml::new(1)
            .key("symmetry = \"spherical\"")
            .domain("[0.0]", "[0.1]")
            .region("ice", "spacing = 0.002", 3.0)
            .region_key("max = [0.03]")
            .region_key("initial = -5.0")
            .region("water", "spacing = 0.002", 3.0)
            .region_key("min = [0.03]")
            .region_key("initial = 60.0"),
    ];
    let mut drifts = Vec::new();
    for body in bodies {
        let case = body
            .material("water", 0.6, 1000.0, 4182.0)
            .section(
                "[material.water.phase_change]\ntemperature = 0.0\nlatent_heat = 333e3\n\
                 frozen_conductivity = 2.14\nfrozen_specific_heat = 2060.0",
            )
            .end(100.0)
            .case("ice.toml");
        let model = Model::build(&case.spec).unwrap();
        let dt = choose_dt(&model, Integrator::Euler, None).unwrap();
        let mut theta = model.theta0.clone();
        let mut st = Enthalpic::new(&model, Integrator::Euler).unwrap();
        st.step(&mut theta, 0.0, dt);
        let e0 = st.energy();
        let scale: f64 = st
            .enthalpy()
            .iter()
            .zip(&model.cloud.volume)
            .map(|(h, v)| (h * v).abs())
            .sum();
        for s in 1..300 {
            st.step(&mut theta, s as f64 * dt, dt);
        }
        let melted = st.melted_fraction();
        let partly = melted.iter().filter(|&&f| f > 0.0 && f < 1.0).count();
        let drift = (st.energy() - e0).abs() / scale;
        println!(
            "{}: {partly} nodes on the plateau, drift {drift:.2e}",
            case.spec.symmetry.name()
        );
        assert!(partly > 0, "the test must cross the phase change");
        assert!(drift < 1e-12, "{drift:e}");
        drifts.push(if drift == 0.0 {
            "0".into()
        } else {
            format!("{drift:.0e}")
        });
    }
    let cells = [
        PHASE.keys[1],
        &format!("drift {}", drifts.join(", ")),
        "1e-12 relative",
    ];
    PHASE.row(&cells, ROUND_OFF);
}

/// Planar freezing: water at +5 °C, the face x = 0 held at −10 °C by a mirrored layer. The front
/// (where half of a node's latent heat is gone) follows Neumann's X(t) = 2λ√(α_f t) within two node
/// spacings at every hour of two days (the criterion). Δ = 5 mm, δ = 3Δ, constant kernel
/// (as in PCS2022); the far face (0.6 m, ~4 liquid diffusion lengths
/// away) is held at +5 °C.
#[test]
fn planar_freezing_follows_the_neumann_front() {
    let case = CaseToml::new(1)
        .domain("[0.0]", "[0.6]")
        .region("body", "spacing = 0.005", 3.0)
        .section("[kernel]\ncalibration = \"lattice\"")
        .material("water", 0.6, 1000.0, 4182.0)
        .section(
            "[material.water.phase_change]\ntemperature = 273.15\nlatent_heat = 333e3\n\
             frozen_conductivity = 2.14\nfrozen_specific_heat = 2060.0\n\
             [boundary.x_min]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 263.15\n\
             [boundary.x_max]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 278.15",
        )
        .initial_value(278.15)
        .end(172800.0)
        .case("freezing.toml");
    let model = Model::build(&case.spec).unwrap();
    let neumann = Reference::NeumannFreezing {
        x0: 0.0,
        surface: 263.15,
        initial: 278.15,
        freezing: 273.15,
        latent_heat: 333e3,
        density: 1000.0,
        frozen_conductivity: 2.14,
        frozen_specific_heat: 2060.0,
        melted_conductivity: 0.6,
        melted_specific_heat: 4182.0,
    };
    let hours: Vec<f64> = (1..=48).map(|h| h as f64 * 3600.0).collect();
    let dt = choose_dt(&model, Integrator::Euler, None).unwrap();
    let mut theta = model.theta0.clone();
    let mut st = Enthalpic::new(&model, Integrator::Euler).unwrap();
    let mut worst: f64 = 0.0;
    let spacing = 0.005;
    let x: Vec<f64> = model.cloud.pos[..model.cloud.n_body]
        .iter()
        .map(|p| p.x)
        .collect();
    let mut t = 0.0;
    for &to in &hours {
        while t < to - 1e-9 {
            let h = dt.min(to - t);
            st.step(&mut theta, t, h);
            t += h;
        }
        // the front: where the melted fraction passes ½, between the nodes either side
        let f = st.melted_fraction();
        let k = f.iter().position(|&v| v > 0.5).expect("liquid remains");
        assert!(k > 0, "the face node froze");
        let front = x[k - 1] + (0.5 - f[k - 1]) / (f[k] - f[k - 1]) * (x[k] - x[k - 1]);
        let exact = neumann_front(&neumann, t).unwrap();
        worst = worst.max((front - exact).abs());
        if (to as u64).is_multiple_of(43200) {
            println!(
                "t = {} h: front {front:.4} m, Neumann {exact:.4} m",
                to / 3600.0
            );
        }
    }
    println!(
        "largest front error {worst:.4} m ({:.2} spacings)",
        worst / spacing
    );
    let last = neumann_front(&neumann, t).unwrap();
    assert!(last > 20.0 * spacing, "the front must travel many spacings");
    assert!(worst <= 2.0 * spacing, "{worst}");
    let measured = format!(
        "largest front error {:.1} mm = {:.2} Δ",
        1e3 * worst,
        worst / spacing
    );
    PHASE.row(&[PHASE.keys[2], &measured, "2Δ"], PHYSICAL);
}

/// Water's T(H) and λ(H) of PCS2022, eqs 1–3, written out again for the
/// reference below.
fn water_state(h: f64) -> (f64, f64) {
    let (cf, cm, tf, l) = (2060.0e3, 4182.0e3, 273.15, 333e6);
    if h < cf * tf {
        (h / cf, 2.14)
    } else if h <= cf * tf + l {
        (tf, 0.5 * (2.14 + 0.6))
    } else {
        (tf + (h - cf * tf - l) / cm, 0.6)
    }
}

/// An independent classical reference for PCS2022 §3.3: a radial
/// finite-volume enthalpy solve (cells of width `dr` on [r0, r1], harmonic face conductivities, the
/// extracted flux `q` through the inner face, the outer face held at `outer` half a cell away),
/// forward Euler at half its stability limit. Returns the temperatures at each of `times`.
fn radial_freezing(r0: f64, r1: f64, dr: f64, q: f64, outer: f64, times: &[f64]) -> Vec<Vec<f64>> {
    use std::f64::consts::PI;
    let n = ((r1 - r0) / dr).round() as usize;
    let r: Vec<f64> = (0..n).map(|i| r0 + (i as f64 + 0.5) * dr).collect();
    let vol: Vec<f64> = r.iter().map(|&ri| 2.0 * PI * ri * dr).collect();
    let face: Vec<f64> = (0..=n).map(|i| 2.0 * PI * (r0 + i as f64 * dr)).collect();
    let cm = 4182.0e3;
    let h_of = |t: f64| 2060.0e3 * 273.15 + 333e6 + cm * (t - 273.15);
    let mut h = vec![h_of(outer); n];
    let dt = 0.5 * dr * dr * 2060.0e3 / (2.0 * 2.14);
    let (mut t, mut out) = (0.0, Vec::new());
    let mut flow = vec![0.0; n];
    let mut state = vec![(0.0, 0.0); n];
    for &to in times {
        while t < to - 1e-9 {
            let step = dt.min(to - t);
            for (s, &v) in state.iter_mut().zip(&h) {
                *s = water_state(v);
            }
            flow.iter_mut().for_each(|f| *f = 0.0);
            flow[0] += q * face[0];
            for i in 0..n - 1 {
                let (ta, ka) = state[i];
                let (tb, kb) = state[i + 1];
                let g = 2.0 * ka * kb / (ka + kb) * face[i + 1] / dr;
                flow[i] += g * (tb - ta);
                flow[i + 1] -= g * (tb - ta);
            }
            let (tl, kl) = state[n - 1];
            flow[n - 1] += kl * face[n] / (0.5 * dr) * (outer - tl);
            for i in 0..n {
                h[i] += step * flow[i] / vol[i];
            }
            t += step;
        }
        out.push(r.iter().zip(&h).map(|(_, &v)| water_state(v).0).collect());
    }
    out
}

/// PCS2022 §3.3, freezing around a pipe (the bundled case, 1D
/// axisymmetric): against the radial finite-volume enthalpy reference with 2 mm cells at 1, 2 and 3
/// days. Measures: ε of its eq 27 ≤ 0.5% (the criterion for the symmetric cases) and the
/// ice front (T = T_f crossing) within two node spacings.
#[test]
fn pipe_freezing_matches_a_radial_finite_volume_reference() {
    let case = Case::load(Path::new("cases/pipe_freezing.toml")).unwrap();
    let model = Model::build(&case.spec).unwrap();
    let nb = model.cloud.n_body;
    let x: Vec<f64> = model.cloud.pos[..nb].iter().map(|p| p.x).collect();
    let dr = 2e-3;
    let fv = radial_freezing(0.1, 1.1, dr, -1000.0, 281.15, &case.outputs);
    let mut theta = model.theta0.clone();
    let mut st = Enthalpic::new(&model, Integrator::Euler).unwrap();
    let mut k = 0;
    let (mut eps_all, mut fronts_pd, mut fronts_fv) = (Vec::new(), Vec::new(), Vec::new());
    let front = |xs: &[f64], th: &[f64]| -> f64 {
        let i = th.iter().position(|&v| v > 273.15).expect("water remains");
        xs[i - 1] + (273.15 - th[i - 1]) / (th[i] - th[i - 1]) * (xs[i] - xs[i - 1])
    };
    st.run(
        &mut theta,
        0.0,
        case.dt.unwrap(),
        &case.outputs,
        |_, t, th, _, _| {
            let reference = &fv[k];
            k += 1;
            // FV cell centres are every dr from 0.1005: interpolate linearly at the PD nodes
            let at = |r: f64| {
                let s = ((r - 0.1) / dr - 0.5).clamp(0.0, (reference.len() - 1) as f64);
                let i = (s.floor() as usize).min(reference.len() - 2);
                let w = s - i as f64;
                reference[i] * (1.0 - w) + reference[i + 1] * w
            };
            let exact: Vec<f64> = x.iter().map(|&r| at(r)).collect();
            let rms = (x
                .iter()
                .enumerate()
                .map(|(i, _)| (th[i] - exact[i]).powi(2))
                .sum::<f64>()
                / nb as f64)
                .sqrt();
            let eps = rms / exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let xs_fv: Vec<f64> = (0..reference.len())
                .map(|i| 0.1 + (i as f64 + 0.5) * dr)
                .collect();
            let (f_pd, f_fv) = (front(&x, &th[..nb]), front(&xs_fv, reference));
            println!(
                "t = {} d: ε = {:.3}%, front PD {f_pd:.4} m, FV {f_fv:.4} m",
                t / 86400.0,
                100.0 * eps
            );
            assert!(eps <= 0.005, "ε = {eps}");
            assert!((f_pd - f_fv).abs() <= 2.0 * 0.01, "front {f_pd} vs {f_fv}");
            eps_all.push(format!("{:.2} %", 100.0 * eps));
            fronts_pd.push(format!("{f_pd:.3}"));
            fronts_fv.push(format!("{f_fv:.3}"));
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    let measured = format!(
        "ε (the paper's eq. 27) {}; ice front {} m against {} m",
        eps_all.join(", "),
        fronts_pd.join(" / "),
        fronts_fv.join(" / ")
    );
    let criterion = "ε ≤ 0.5 %, front within 2Δ";
    PHASE.row(&[PHASE.keys[3], &measured, criterion], PHYSICAL);
}
