//! The series references of the mesh-convergence suite (`box_fixed_faces`, `disc_fixed_edge`
//! in src/analytic.rs) against independent finite-difference solves (tests/common/heat_fd.rs).
//!
//! Tolerances: the finite differences are second order in h (mirrored ghosts at the faces,
//! an exact second difference inside), so on a grid and its refinement by 2 their distance
//! to the exact solution must fall by about 4; we require a fall by at least 3 (a series that
//! is wrong by more than the FD error stops the fall) and, on the finer grid, a largest
//! difference below 1e-3 θ0: the FD error at these h (the θ0-to-0 jump at the held faces at
//! t = 0 makes it largest there) measured 2.5e-5 θ0 (rectangle), 1.9e-4 θ0 (box) and
//! 3.5e-6 θ0 (disc) when this test was written, so a 5× margin on the worst.

mod common;

use common::heat_fd::{disc_fd, BoxFd};
use peritherm::analytic::{AxisEnds, Reference};

const THETA0: f64 = 100.0;
const T: f64 = 0.01;

/// Largest |FD − series| over the cells of a box solve, °C.
fn box_error(fd: &BoxFd, series: &Reference) -> f64 {
    let theta = fd.solve(1.0, THETA0, T);
    (0..theta.len())
        .map(|k| {
            let [x, y, z] = fd.centre(k);
            (theta[k] - series.eval(x, y, z, T)).abs()
        })
        .fold(0.0, worst)
}

/// The larger of two differences; NaN (a blown-up solve) wins.
fn worst(m: f64, e: f64) -> f64 {
    if m.is_nan() || e.is_nan() {
        f64::NAN
    } else {
        m.max(e)
    }
}

/// Asserts the FD-to-series distances of a grid and its refinement (see the module comment).
fn assert_converges(what: &str, coarse: f64, fine: f64) {
    eprintln!("{what}: max |FD − series| = {coarse:.3e} → {fine:.3e} °C");
    assert!(
        coarse.is_finite() && fine.is_finite() && fine > 0.0,
        "{what}: {coarse} → {fine}"
    );
    assert!(fine <= 1e-3 * THETA0, "{what}: {fine} °C on the finer grid");
    assert!(
        coarse >= 3.0 * fine,
        "{what}: {coarse} → {fine}: no second-order fall"
    );
}

/// The rectangle of the suite: x held at both ends, y held at 0 and insulated at 0.5.
#[test]
fn rectangle_series_matches_finite_differences() {
    let series = Reference::BoxFixedFaces {
        min: vec![0.0, 0.0],
        size: vec![1.0, 0.5],
        ends: vec![AxisEnds::FixedBoth, AxisEnds::FixedLow],
        diffusivity: 1.0,
        edge: 0.0,
        initial: THETA0,
    };
    let errors: Vec<f64> = [1, 2]
        .map(|m| {
            let fd = BoxFd {
                cells: vec![100 * m, 50 * m],
                size: vec![1.0, 0.5],
                held: vec![[true, true], [true, false]],
            };
            box_error(&fd, &series)
        })
        .to_vec();
    assert_converges("rectangle", errors[0], errors[1]);
}

/// A 3D box with every kind of axis: both faces held, the low one held, the high one held.
#[test]
fn box_series_matches_finite_differences() {
    let series = Reference::BoxFixedFaces {
        min: vec![0.0, 0.0, 0.0],
        size: vec![1.0, 0.5, 0.75],
        ends: vec![AxisEnds::FixedBoth, AxisEnds::FixedLow, AxisEnds::FixedHigh],
        diffusivity: 1.0,
        edge: 0.0,
        initial: THETA0,
    };
    let errors: Vec<f64> = [1, 2]
        .map(|m| {
            let fd = BoxFd {
                cells: vec![40 * m, 20 * m, 30 * m],
                size: vec![1.0, 0.5, 0.75],
                held: vec![[true, true], [true, false], [false, true]],
            };
            box_error(&fd, &series)
        })
        .to_vec();
    assert_converges("box", errors[0], errors[1]);
}

/// The disc of the suite (radius 0.5 m, edge held) against radial finite volumes.
#[test]
fn disc_series_matches_finite_volumes() {
    let series = Reference::DiscFixedEdge {
        radius: 0.5,
        diffusivity: 1.0,
        edge: 0.0,
        initial: THETA0,
    };
    let errors: Vec<f64> = [200, 400]
        .map(|n| {
            disc_fd(n, 0.5, 1.0, THETA0, T)
                .into_iter()
                .map(|(r, theta)| {
                    // the radius along a diagonal: the series depends on r only
                    let c = r / 2f64.sqrt();
                    (theta - series.eval(c, c, 0.3, T)).abs()
                })
                .fold(0.0, worst)
        })
        .to_vec();
    assert_converges("disc", errors[0], errors[1]);
}
