//! Micro-conductivity kernels and partial volumes: the only home of their constants.
//!
//! A node's micro-conductance for a bond of length r is `c_i(r) = C_i w(r/δ_i) / r^p`
//! (theory §2.1), with `C_i = 2 d k_i / ∫_{H_i} w(r/δ_i) r^(2−p) dV` so that a smooth
//! field in a full horizon gives the classical conductivity k_i. p = 2 with the constant or
//! the triangular/conical profile is Bobaru & Duangpanya's (2010, eqs. 16–17; 2012
//! §2.3); p = 1 with the constant profile is Wang, Oterkus & Oterkus's (eq. 18).

use serde::{Deserialize, Serialize};

/// Relative round-off below which a partial-volume factor β counts as zero (see
/// [`Kernel::coverage`]).
pub const ROUNDOFF: f64 = 1e-9;

/// Shape w(r/δ) of the micro-conductivity inside the horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Profile {
    /// w = 1 (Bobaru & Duangpanya 2010, eq. 16; Bobaru & Duangpanya 2012 §2.3.1; Wang, Oterkus &
    /// Oterkus, eq. 18).
    Constant,
    /// w = 1 − r/δ: "triangular" in 1D (Bobaru & Duangpanya 2010, eq. 17), "conical" in 2D/3D
    /// (Bobaru & Duangpanya 2012 §2.3.2).
    #[serde(alias = "triangular")]
    Conical,
}

/// How much of a neighbour's volume lies inside a horizon (theory §2.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartialVolume {
    /// β = 1 for r ≤ δ, else 0 (non-uniform m-convergence, Bobaru & Duangpanya 2012 §3.3).
    AllOrNothing,
    /// Bobaru & Duangpanya 2012 Algorithm 1: β falls linearly over δ ± Δ_j/2; with the conical
    /// profile w is evaluated at the centroid of the covered part (lines 6 and 9).
    Algorithm1,
}

/// Which integral of the horizon fixes the normalisation C_i.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Calibration {
    /// Exact integration over the full horizon (theory §2.1).
    #[default]
    Continuum,
    /// The midpoint sum over the node's own lattice (cell-centred, spacing Δ_i, the same
    /// partial volumes), so that the discrete bulk operator has conductivity k exactly. The
    /// midpoint rule misses the node's own cell: 1/m of the moment in 1D (12.5 % at m = 4),
    /// which the p = i term of Bobaru & Duangpanya 2010 (eq. 18) restores; this does it for every
    /// kernel.
    Lattice,
}

/// A micro-conductivity kernel: exponent p, profile and partial-volume rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kernel {
    /// Exponent p of 1/r^p: 2 (Bobaru & Duangpanya 2010, 2012; PCS2022)
    /// or 1 (Wang, Oterkus & Oterkus).
    pub p: u8,
    /// Profile w.
    pub profile: Profile,
    /// Partial-volume rule.
    pub partial_volume: PartialVolume,
    /// Normalisation by exact integration or by the lattice sum.
    pub calibration: Calibration,
}

/// Measure of the unit sphere's "surface" in d dimensions: 2 (1D), 2π (2D), 4π (3D).
fn sphere_measure(dim: usize) -> f64 {
    match dim {
        1 => 2.0,
        2 => 2.0 * std::f64::consts::PI,
        _ => 4.0 * std::f64::consts::PI,
    }
}

impl Kernel {
    /// ∫ over a d-ball of radius δ of w(r/δ) r^(2−p) dA, in units of length^(d+2−p)
    /// (without the cross-section or thickness; exact integration).
    pub fn moment(&self, dim: usize, delta: f64) -> f64 {
        let q = (2 - self.p as i32 + dim as i32) as f64; // ∫_0^δ w r^(q−1) dr
        let radial = match self.profile {
            Profile::Constant => delta.powf(q) / q,
            Profile::Conical => delta.powf(q) * (1.0 / q - 1.0 / (q + 1.0)),
        };
        sphere_measure(dim) * radial
    }

    /// Normalisation C_i (theory §2.1) for conductivity `k` (W/(m·K)), horizon `delta` (m)
    /// and out-of-plane measure `tau` (cross-section area in 1D, thickness in 2D, 1 in 3D).
    pub fn normalisation(&self, dim: usize, k: f64, delta: f64, tau: f64) -> f64 {
        2.0 * dim as f64 * k / (tau * self.moment(dim, delta))
    }

    /// Midpoint-rule analogue of [`Kernel::moment`]: Σ over the cubic lattice of spacing `h`
    /// around a node of w(at/δ) r^(2−p) β h^d, with this kernel's partial volumes.
    pub fn lattice_moment(&self, dim: usize, delta: f64, h: f64) -> f64 {
        let reach = self.reach(delta, h);
        let n = (reach / h).ceil() as i64;
        let (ny, nz) = (if dim >= 2 { n } else { 0 }, if dim >= 3 { n } else { 0 });
        let mut sum = 0.0;
        for k in -nz..=nz {
            for j in -ny..=ny {
                for i in -n..=n {
                    if i == 0 && j == 0 && k == 0 {
                        continue;
                    }
                    let r = h * ((i * i + j * j + k * k) as f64).sqrt();
                    let (beta, at) = self.coverage(r, delta, h);
                    if beta > 0.0 {
                        // w r^(2-p) = micro(1, r, at, δ) · r²
                        sum += self.micro(1.0, r, at, delta) * r * r * beta;
                    }
                }
            }
        }
        sum * h.powi(dim as i32)
    }

    /// Normalisation C_i by this kernel's calibration, for a node of spacing `h`.
    pub fn calibrated(&self, dim: usize, k: f64, delta: f64, tau: f64, h: f64) -> f64 {
        match self.calibration {
            Calibration::Continuum => self.normalisation(dim, k, delta, tau),
            Calibration::Lattice => {
                2.0 * dim as f64 * k / (tau * self.lattice_moment(dim, delta, h))
            }
        }
    }

    /// Partial-volume factor β of a neighbour at distance `r` with spacing `dj`
    /// inside the horizon `delta`, and the distance at which w is evaluated. A neighbour
    /// whose β would be below [`ROUNDOFF`] is outside (β = 0): such a β is the round-off of
    /// coordinates (a gmsh node one bit from the lattice's), and it would decide which pairs
    /// exist.
    pub fn coverage(&self, r: f64, delta: f64, dj: f64) -> (f64, f64) {
        match self.partial_volume {
            PartialVolume::AllOrNothing => (if r <= delta { 1.0 } else { 0.0 }, r),
            PartialVolume::Algorithm1 => {
                if r <= delta - 0.5 * dj {
                    (1.0, r)
                } else if r <= delta + 0.5 * dj * (1.0 - 2.0 * ROUNDOFF) {
                    let beta = (delta + 0.5 * dj - r) / dj;
                    let at = match self.profile {
                        Profile::Constant => r,
                        Profile::Conical if r <= delta => r - dj * (1.0 - beta) / 2.0,
                        Profile::Conical => delta - dj * beta / 2.0,
                    };
                    (beta, at)
                } else {
                    (0.0, r)
                }
            }
        }
    }

    /// Largest distance at which a neighbour of spacing `dj` can still count.
    pub fn reach(&self, delta: f64, dj: f64) -> f64 {
        match self.partial_volume {
            PartialVolume::AllOrNothing => delta,
            PartialVolume::Algorithm1 => delta + 0.5 * dj,
        }
    }

    /// Micro-conductance c = C w(at/δ) / r^p, W/(K·m⁶): K_ij = V_i V_j c is in W/K.
    pub fn micro(&self, c_norm: f64, r: f64, at: f64, delta: f64) -> f64 {
        let w = match self.profile {
            Profile::Constant => 1.0,
            Profile::Conical => (1.0 - at / delta).max(0.0),
        };
        let rp = if self.p == 1 { r } else { r * r };
        c_norm * w / rp
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn kern(p: u8, profile: Profile) -> Kernel {
        Kernel {
            p,
            profile,
            partial_volume: PartialVolume::Algorithm1,
            calibration: Calibration::Continuum,
        }
    }

    /// Every normalisation printed in the papers, derived from the formula (tolerance: round-off).
    #[test]
    fn normalisations_match_the_papers() {
        let (k, d, a) = (1.7, 0.3, 0.2);
        let close = |x: f64, y: f64| assert!((x - y).abs() <= 1e-13 * y.abs(), "{x} vs {y}");
        // Bobaru & Duangpanya 2010, eq. 16: k0 = κ/δ (per cross-section A)
        close(
            kern(2, Profile::Constant).normalisation(1, k, d, a),
            k / d / a,
        );
        // Bobaru & Duangpanya 2010, eq. 17: k1 = 2κ/δ
        close(
            kern(2, Profile::Conical).normalisation(1, k, d, a),
            2.0 * k / d / a,
        );
        // Bobaru & Duangpanya 2012 §2.3.1: 4κ/(πδ²) per thickness h
        close(
            kern(2, Profile::Constant).normalisation(2, k, d, a),
            4.0 * k / (PI * d * d * a),
        );
        // Bobaru & Duangpanya 2012 §2.3.2: 12κ/(πδ²)
        close(
            kern(2, Profile::Conical).normalisation(2, k, d, a),
            12.0 * k / (PI * d * d * a),
        );
        // Wang, Oterkus & Oterkus, eq. 18: 6k/(πhδ³)
        close(
            kern(1, Profile::Constant).normalisation(2, k, d, a),
            6.0 * k / (PI * a * d.powi(3)),
        );
        // 3D p = 1: 6k/(πδ⁴); 3D constant p = 2: 9k/(2πδ³)
        close(
            kern(1, Profile::Constant).normalisation(3, k, d, 1.0),
            6.0 * k / (PI * d.powi(4)),
        );
        close(
            kern(2, Profile::Constant).normalisation(3, k, d, 1.0),
            9.0 * k / (2.0 * PI * d.powi(3)),
        );
    }

    /// The normalisation makes ∫ c(r) ξ_x² dV / 2 = k for a quadratic field, checked by
    /// independent numerical quadrature over the ball (tolerance 1e-3 from the quadrature).
    #[test]
    fn normalisation_reproduces_conductivity_by_quadrature() {
        let (k, d) = (2.5, 1.0);
        for dim in 1..=3 {
            for (p, prof) in [
                (2, Profile::Constant),
                (2, Profile::Conical),
                (1, Profile::Constant),
            ] {
                let ker = kern(p, prof);
                let c = ker.normalisation(dim, k, d, 1.0);
                let n = if dim == 3 { 120 } else { 600 };
                let h = 2.0 * d / n as f64;
                let mut sum = 0.0;
                let range = |i: usize| -d + (i as f64 + 0.5) * h;
                let ny = if dim >= 2 { n } else { 1 };
                let nz = if dim >= 3 { n } else { 1 };
                for i in 0..n {
                    for j in 0..ny {
                        for l in 0..nz {
                            let x = range(i);
                            let y = if dim >= 2 { range(j) } else { 0.0 };
                            let z = if dim >= 3 { range(l) } else { 0.0 };
                            let r = (x * x + y * y + z * z).sqrt();
                            if r <= d && r > 0.0 {
                                sum += ker.micro(c, r, r, d) * x * x * h.powi(dim as i32);
                            }
                        }
                    }
                }
                let got = 0.5 * sum;
                assert!(
                    (got - k).abs() < 1e-2 * k,
                    "dim {dim} p {p} {prof:?}: {got}"
                );
            }
        }
    }

    /// The lattice moment tends to the exact moment as m = δ/Δ grows (the missing self cell
    /// shrinks like 1/m^d), and in 1D at m = 4 it is exactly 7/8 of it (β = 1/2 at r = δ).
    #[test]
    fn lattice_moment_converges_to_the_integral() {
        let k = kern(2, Profile::Constant);
        let ratio = k.lattice_moment(1, 1.0, 0.25) / k.moment(1, 1.0);
        assert!((ratio - 7.0 / 8.0).abs() < 1e-12, "{ratio}");
        for dim in 2..=3 {
            for (p, prof) in [
                (2, Profile::Constant),
                (2, Profile::Conical),
                (1, Profile::Constant),
            ] {
                let k = kern(p, prof);
                let coarse =
                    (k.lattice_moment(dim, 1.0, 1.0 / 3.0) / k.moment(dim, 1.0) - 1.0).abs();
                let fine =
                    (k.lattice_moment(dim, 1.0, 1.0 / 12.0) / k.moment(dim, 1.0) - 1.0).abs();
                assert!(
                    fine < 0.02 && fine < coarse,
                    "dim {dim} p {p} {prof:?}: {coarse} -> {fine}"
                );
            }
        }
    }

    #[test]
    fn algorithm1_coverage() {
        let k = kern(2, Profile::Conical);
        assert_eq!(k.coverage(0.5, 1.0, 0.2), (1.0, 0.5));
        let (b, at) = k.coverage(0.95, 1.0, 0.2);
        assert!((b - 0.75).abs() < 1e-12 && (at - (0.95 - 0.2 * 0.25 / 2.0)).abs() < 1e-12);
        let (b, at) = k.coverage(1.05, 1.0, 0.2);
        assert!((b - 0.25).abs() < 1e-12 && (at - (1.0 - 0.2 * 0.25 / 2.0)).abs() < 1e-12);
        assert_eq!(k.coverage(1.2, 1.0, 0.2).0, 0.0);
        // a neighbour one round-off inside the outer edge is outside, one ten times further in is
        // not
        assert_eq!(k.coverage(1.1 - 1e-12, 1.0, 0.2).0, 0.0);
        assert!(k.coverage(1.1 - 1e-8, 1.0, 0.2).0 > 0.0);
    }
}
