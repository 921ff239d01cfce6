//! Exact invariants of the boundary conditions of theory §3: each rule reproduces the
//! field it is built for, and the loads add exactly the energy they should.

use crate::common::case::CaseToml;
use peritherm::model::Model;
use peritherm::solve::explicit::{Explicit, ExplicitScheme};

/// A 2D plate 1 × 0.5 (thickness 0.1) with the given boundary tables and initial field.
fn plate(placement: &str, faces: &str, initial: &str) -> Model {
    CaseToml::new(2)
        .domain("[0.0, 0.0]", "[1.0, 0.5]")
        .domain_key("thickness = 0.1")
        .domain_key(&format!("placement = \"{placement}\""))
        .region("plate", "spacing = 0.025", 3.5)
        .material("m", 2.0, 4.0, 0.5)
        .section("[kernel]\ncalibration = \"lattice\"")
        .section(faces)
        .initial(initial)
        .model("plate.toml")
}

/// Largest |Σ_j K_ij (θ_j − θ_i)| over free body nodes after the boundary is applied,
/// relative to the largest row sum of K times the field's range.
fn max_free_flow(m: &Model, t: f64) -> f64 {
    let mut theta = m.theta0.clone();
    m.boundary.apply(&m.cloud, &mut theta, t);
    let mut flow = vec![0.0; m.cloud.n_body];
    m.conductance.apply(&theta, &mut flow);
    let scale = m.conductance.diag.iter().cloned().fold(0.0, f64::max);
    (0..m.cloud.n_body)
        .filter(|&i| !m.boundary.driven[i])
        .map(|i| flow[i].abs() / scale)
        .fold(0.0, f64::max)
}

/// Mirror layers: a field linear in x with θ = 1 at x = 0 (Dirichlet) and gradient 3 at
/// x = 1 (flux q = k·3 = 6 into the body), insulated in y, is steady at every node
/// (tolerance 1e-12: round-off of the bond sums).
#[test]
fn mirror_temperature_and_flux_layers_are_exact_for_linear_fields() {
    let faces = r#"
[boundary.x_min]
type = "temperature"
method = "mirror"
value = 1.0
[boundary.x_max]
type = "flux"
method = "mirror"
value = 6.0
[boundary.y_min]
type = "insulated"
[boundary.y_max]
type = "insulated"
"#;
    let m = plate("cell", faces, "1 + 3*x");
    assert!(max_free_flow(&m, 0.0) < 1e-12, "{}", max_free_flow(&m, 0.0));
    // and the flux sign matters: the opposite flux is not steady
    let m = plate(
        "cell",
        &faces.replace("value = 6.0", "value = -6.0"),
        "1 + 3*x",
    );
    assert!(max_free_flow(&m, 0.0) > 1e-3);
}

/// Naive layers hold every fictitious node at θ_b(t), here a function of t.
#[test]
fn naive_layers_take_the_boundary_value() {
    let faces = r#"
[boundary.x_min]
type = "temperature"
method = "naive"
value = "2 + t"
"#;
    let m = plate("cell", faces, "0");
    let mut theta = m.theta0.clone();
    m.boundary.apply(&m.cloud, &mut theta, 0.5);
    assert!(m.cloud.n_fictitious() > 0);
    for v in &theta[m.cloud.n_body..] {
        assert_eq!(*v, 2.5);
    }
}

/// Bobaru & Duangpanya 2012 §3.2 nodal flux relation on nodes on the boundary: with the lattice
/// calibration the inward half-horizon sum gives exactly k ∂θ/∂n, so the relation keeps a linear
/// field with gradient q/k unchanged (tolerance 1e-12 relative).
#[test]
fn nodal_flux_relation_keeps_the_matching_linear_field() {
    let faces = r#"
[boundary.x_max]
type = "flux"
method = "relation"
value = 6.0
"#;
    let m = plate("boundary", faces, "1 + 3*x");
    let mut theta = m.theta0.clone();
    m.boundary.apply(&m.cloud, &mut theta, 0.0);
    let mut n = 0;
    for (i, p) in m.cloud.pos.iter().enumerate().take(m.cloud.n_body) {
        if m.boundary.driven[i] {
            let exact = 1.0 + 3.0 * p.x;
            // corner nodes see a truncated half-horizon along y; interior face nodes are exact
            let y = p.y;
            if y > 0.1 && y < 0.4 {
                assert!(
                    (theta[i] - exact).abs() < 1e-12 * exact,
                    "{} vs {exact}",
                    theta[i]
                );
                n += 1;
            }
        }
    }
    assert!(n > 5);
}

/// Bobaru & Duangpanya 2010 eq 22 in 1D: the nodes within δ of the end follow the anchor with
/// gradient q/k.
#[test]
fn bar_flux_relation_sets_the_gradient() {
    let m = CaseToml::new(1)
        .domain("[0.0]", "[1.0]")
        .region("bar", "cells = [40]", 4.0)
        .material("m", 2.0, 1.0, 1.0)
        .section("[boundary.x_max]\ntype = \"flux\"\nmethod = \"relation\"\nvalue = 6.0")
        .model("bar.toml");
    let mut theta = vec![5.0; m.cloud.len()];
    m.boundary.apply(&m.cloud, &mut theta, 0.0);
    let driven: Vec<usize> = (0..m.cloud.n_body)
        .filter(|&i| m.boundary.driven[i])
        .collect();
    assert_eq!(driven.len(), 4, "m = 4 nodes within δ of the end");
    for &i in &driven {
        let d = m.cloud.pos[i].x - m.cloud.pos[35].x;
        assert!((theta[i] - (5.0 + 3.0 * d)).abs() < 1e-12);
    }
}

/// Convection adds dE/dt = h A (T∞ − θ) through the face, and a source s adds s V: one
/// Euler step from a uniform field, where bond flows vanish (tolerance 1e-12 relative).
#[test]
fn convection_and_sources_add_the_right_energy() {
    let faces = r#"
[boundary.y_max]
type = "convection"
h = 10.0
ambient = 30.0
[source]
value = 7.0
"#;
    let m = plate("cell", faces, "20");
    let mut theta = m.theta0.clone();
    let e0 = m.energy(&theta);
    let dt = 1e-4;
    Explicit::new(&m, ExplicitScheme::Euler).step(&mut theta, 0.0, dt);
    let area = 1.0 * 0.1; // face length × thickness
    let volume = 1.0 * 0.5 * 0.1;
    let expected = dt * (10.0 * area * (30.0 - 20.0) + 7.0 * volume);
    let got = m.energy(&theta) - e0;
    assert!(
        (got - expected).abs() < 1e-12 * expected.abs().max(e0),
        "{got} vs {expected}"
    );
}
