//! The series references of the mesh-convergence suite (`box_fixed_faces`, `disc_fixed_edge`
//! in crates/analytic/src/rect.rs and radial.rs), and of the laser film and the split thermal
//! shock (`film_laser_pulse`, `plate_pulse_split`, crates/analytic/src/pulse.rs), against independent finite-difference solves
//! (tests/common/heat_fd.rs).
//!
//! Tolerances: the finite differences are second order in h (mirrored ghosts at the faces,
//! an exact second difference inside), so on a grid and its refinement by 2 their distance
//! to the exact solution must fall by about 4; we require a fall by at least 3 (a series that
//! is wrong by more than the FD error stops the fall) and, on the finer grid, a largest
//! difference below 1e-3 θ0: the FD error at these h (the θ0-to-0 jump at the held faces at
//! t = 0 makes it largest there) measured 2.5e-5 θ0 (rectangle), 1.9e-4 θ0 (box) and
//! 3.5e-6 θ0 (disc) when this test was written, so a 5× margin on the worst.

use crate::common::heat_fd::{disc_fd, plate_held_left_fd, slab_source_fd, BoxFd};
use peritherm::analytic::{AxisEnds, Reference};
use peritherm::math::Point;
use peritherm::series::SeriesCheck;

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

/// The laser-heated film of Wang, Oterkus & Oterkus §4.4 (`film_laser_pulse`, the cosine
/// series with each mode's time integral in closed form) against finite volumes of the same
/// 1D slab (insulated ends, the source at the cell centres, explicit Euler; its error is
/// O(h²) in space and O(Δt) ∝ h² in time), at the pulse's peak 0.2 ps, 0.5 ps and 1 ps.
/// Tolerances as in the module comment, relative to the largest temperature of the run
/// (the FD error on 200 cells measured 2.1e-4 of it when this test was written: the
/// tolerance is 1e-3, a 5× margin); the FD fall must be at least 3 between 100 and 200 cells.
#[test]
fn laser_series_matches_finite_differences() {
    let (l, k, rho_c) = (2e-8, 315.0, 2.5e6);
    let (j0, r, depth, t0, a) = (13.4, 0.93, 15.3e-9, 100e-15, 1.992);
    let alpha = k / rho_c;
    let series = Reference::FilmLaserPulse {
        x0: 0.0,
        length: l,
        diffusivity: alpha,
        heat_capacity: rho_c,
        fluence: j0,
        reflectivity: r,
        depth,
        duration: t0,
        shape: a,
    };
    let q = |s: f64, t: f64| {
        0.94 * j0 * (1.0 - r) / (t0 * depth) * (-s / depth - a * (t - 2.0 * t0).abs() / t0).exp()
            / rho_c
    };
    let times = [2e-13, 5e-13, 1e-12];
    let peak = times
        .iter()
        .map(|&t| series.eval(0.0, 0.0, 0.0, t))
        .fold(0.0, f64::max);
    assert!(peak > 10.0 && peak < 20.0, "peak {peak} °C");
    let series = &series;
    let errors: Vec<f64> = [100, 200]
        .map(|n| {
            slab_source_fd(n, l, alpha, q, &times)
                .iter()
                .zip(times)
                .flat_map(|(cells, t)| {
                    cells
                        .iter()
                        .map(move |&(s, theta)| (theta - series.eval(s, 0.7, 0.0, t)).abs())
                })
                .fold(0.0, worst)
                / peak
        })
        .to_vec();
    eprintln!(
        "laser: max |FD − series| / peak = {:.3e} → {:.3e}",
        errors[0], errors[1]
    );
    assert!(errors[1] <= 1e-3, "{errors:?}");
    assert!(
        errors[0] >= 3.0 * errors[1],
        "{errors:?}: no second-order fall"
    );
}

/// The split thermal shock of Wang, Oterkus & Oterkus §4.5 (`plate_pulse_split`: the Duhamel
/// series in x plus the product of a sine series in x and a cosine series in y) against a 2D
/// finite-difference solve of the whole problem (the edge x = −5 at 5t·e^(−2t), the others
/// insulated, 0.5 °C below y = 0 and 0 above) at 3 s. Tolerances as in the module comment,
/// relative to the split 0.5 °C: the FD error on 200² cells measured 6.3e-5 of it when this
/// test was written; the tolerance is 1e-3 (the largest boundary value is 0.92 °C, so 1e-3 of
/// 0.5 °C is far below what a plot shows), and the fall must be at least 3.
#[test]
fn split_plate_series_matches_finite_differences() {
    let series = Reference::PlatePulseSplit {
        x0: -5.0,
        y0: -5.0,
        length: 10.0,
        width: 10.0,
        diffusivity: 1.0,
        amplitude: 5.0,
        rate: 2.0,
        split: 0.0,
        below: 0.5,
        above: 0.0,
    };
    assert_eq!(series.check(), None);
    let t = 3.0;
    let errors: Vec<f64> = [100, 200]
        .map(|n| {
            let fd = plate_held_left_fd(
                [n, n],
                [10.0, 10.0],
                1.0,
                |_, y| if y < 5.0 { 0.5 } else { 0.0 },
                |t| 5.0 * t * (-2.0 * t).exp(),
                t,
            )
            .into_iter()
            .map(|([x, y], theta)| (Point::new(x - 5.0, y - 5.0, 0.0), theta));
            let (pts, fd): (Vec<Point>, Vec<f64>) = fd.unzip();
            let exact = series.eval_many(&pts, t);
            fd.iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, worst)
                / 0.5
        })
        .to_vec();
    eprintln!(
        "split plate: max |FD − series| / 0.5 °C = {:.3e} → {:.3e}",
        errors[0], errors[1]
    );
    assert!(errors[1] <= 1e-3, "{errors:?}");
    assert!(
        errors[0] >= 3.0 * errors[1],
        "{errors:?}: no second-order fall"
    );
    // eval_many (each factor once per distinct x and y) is eval at every point
    let pts: Vec<_> = [(-4.9, 2.0), (0.3, -0.1), (4.99, -4.99), (0.3, 2.0)]
        .iter()
        .map(|&(x, y)| Point::new(x, y, 0.0))
        .collect();
    for (p, v) in pts.iter().zip(series.eval_many(&pts, t)) {
        assert_eq!(v, series.eval(p.x, p.y, 0.0, t));
    }
}
