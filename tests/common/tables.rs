//! Figure tables whose rows more than one test binary measures (see [`super::figures::Table`]),
//! and the formatting of their cells.

use super::figures::Table;

/// The checks of the axisymmetric and spherical bodies (docs/validation.md), measured by the
/// peridynamic tests of `tests/cases/symmetry.rs` and the FEM tests of
/// `tests/convergence/fem.rs`.
pub const SYMMETRY_CHECKS: Table = Table {
    name: "symmetry_checks",
    command: "PERITHERM_RECORD=1 cargo test --release --test cases symmetry:: && PERITHERM_RECORD=1 cargo test --release --test convergence -- fem::symmetric_steady fem::sphere_converges",
    columns: &["check", "measured", "criterion"],
    keys: &[
        "PD axisymmetric 1D steady wall, Δ = (b − a)/40, /80, /160",
        "PD axisymmetric 2D steady wall, Δ = (b − a)/40, /80, /160",
        "PD spherical 1D steady wall, Δ = (b − a)/40, /80, /160",
        "PD axisymmetric 1D wall, radial flux against −k dθ/dr, Δ = (b − a)/80, /160",
        "PD axisymmetric 2D wall, radial flux against −k dθ/dr, Δ = (b − a)/80, /160",
        "PD cooling sphere, ε against the series at t = 2 s, Δ = R/20, R/40, R/80",
        "PD cooling sphere, ε against the series at t = 5 s, Δ = R/20, R/40, R/80",
        "PD cooling sphere, ε against the series at t = 10 s, Δ = R/20, R/40, R/80",
        "PD insulated axisymmetric body, 500 Euler steps",
        "PD insulated axisymmetric body, 500 Rk4 steps",
        "FEM axisymmetric 1D, held, h = (b − a)/20 … /160",
        "FEM axisymmetric 2D, held, h = (b − a)/20 … /160",
        "FEM axisymmetric 1D, flux, h = (b − a)/20 … /160",
        "FEM axisymmetric 1D, convection, h = (b − a)/20 … /160",
        "FEM spherical, held, h = (b − a)/20 … /160",
        "FEM spherical, flux, h = (b − a)/20 … /160",
        "FEM cooling sphere at t = 10 s, h = R/40 … R/320",
    ],
    timed: &[],
};

/// Figures `v` as `a, b, c` with `digits` significant digits in scientific notation.
pub fn sci_list(v: &[f64], digits: usize) -> String {
    let s: Vec<String> = v.iter().map(|x| format!("{x:.digits$e}")).collect();
    s.join(", ")
}

/// Rates `v` as `a, b` with two decimals.
pub fn rate_list(v: &[f64]) -> String {
    let s: Vec<String> = v.iter().map(|x| format!("{x:.2}")).collect();
    s.join(", ")
}

/// Errors at halved spacings with their observed rates, the cell of every convergence row:
/// `a, b, c UNIT, rates x, y` (`unit` with its leading space, or empty).
pub fn errors_and_rates(errors: &[f64], unit: &str) -> String {
    let r = rates(errors);
    format!("{}{unit}, rates {}", sci_list(errors, 2), rate_list(&r))
}

/// Observed rates log2(e_k / e_{k+1}) of errors at halved spacings.
pub fn rates(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}
