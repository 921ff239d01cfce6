//! Axial and spherical symmetry (PCS2022 §2.2–2.3; theory §7).
//!
//! A symmetric model is computed on a planar cloud: the x coordinate is the radius r and, for
//! an axisymmetric 2D model, y is the axial coordinate z. Each node stands for a ring
//! (axisymmetric) or a shell (spherical). Its true volume is its planar measure times
//! [`Symmetry::volume_factor`] (2πr or 4πr²), and each pair conductance is the planar one
//! times [`Symmetry::pair_factor`]. Dividing a pair factor by a node's volume factor gives
//! the shape factors of PCS2022, Ω (eq. 10) and Ω_sp (eq. 21), so the
//! per-node balance is exactly the paper's eq. (23) while K stays symmetric and energy is
//! conserved.

use serde::{Deserialize, Serialize};

/// Symmetry of the modelled body (`geometry.symmetry` in a case).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Symmetry {
    /// No symmetry: 1D bars, 2D plates of thickness h, 3D bodies.
    #[default]
    Planar,
    /// Bodies of revolution about the z axis: x = r (1D) or (x, y) = (r, z) (2D).
    Axisymmetric,
    /// Spherical symmetry: x = r (1D only).
    Spherical,
}

impl Symmetry {
    /// Name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Symmetry::Planar => "planar",
            Symmetry::Axisymmetric => "axisymmetric",
            Symmetry::Spherical => "spherical",
        }
    }

    /// True for the axisymmetric and spherical models.
    pub fn is_symmetric(&self) -> bool {
        *self != Symmetry::Planar
    }

    /// Dimensions of the planar cloud this symmetry allows.
    pub fn allows_dimension(&self, dim: usize) -> bool {
        match self {
            Symmetry::Planar => true,
            Symmetry::Axisymmetric => dim == 1 || dim == 2,
            Symmetry::Spherical => dim == 1,
        }
    }

    /// True volume per planar measure of a node at radius `r`: 1, 2πr or 4πr² (m⁰, m, m²).
    #[inline]
    pub fn volume_factor(&self, r: f64) -> f64 {
        self.pair_factor(r, r)
    }

    /// Factor multiplying the planar pair conductance of nodes at radii `ri` and `rj`:
    /// 1, 2π·2 ri rj/(ri + rj) or 4π·3 ri² rj²/(ri² + ri rj + rj²). Symmetric in (ri, rj);
    /// divided by [`Symmetry::volume_factor`]`(ri)` it is Ω(rj, ri) of PCS2022
    /// (doi:10.1007/s42102-022-00092-3), eq. (10) or Ω_sp(rj, ri) of eq. (21).
    #[inline]
    pub fn pair_factor(&self, ri: f64, rj: f64) -> f64 {
        use std::f64::consts::PI;
        // the same operations in the same order either way, so that the factor is symmetric
        // bit for bit (a product's value depends on its association order)
        let (ri, rj) = if ri <= rj { (ri, rj) } else { (rj, ri) };
        match self {
            Symmetry::Planar => 1.0,
            Symmetry::Axisymmetric => 2.0 * PI * 2.0 * ri * rj / (ri + rj),
            Symmetry::Spherical => {
                4.0 * PI * 3.0 * ri * ri * rj * rj / (ri * ri + ri * rj + rj * rj)
            }
        }
    }

    /// The shape factor (PCS2022) of a bond from a node at `r` to one
    /// at `r_other`: Ω = 2r'/(r' + r) (eq. 10) or Ω_sp = 3r'²/(r² + r r' + r'²) (eq. 21); 1 when
    /// planar.
    pub fn shape_factor(&self, r_other: f64, r: f64) -> f64 {
        self.pair_factor(r, r_other) / self.volume_factor(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_factors_are_the_papers() {
        let (r, rp) = (0.3, 0.45);
        let ax = Symmetry::Axisymmetric.shape_factor(rp, r);
        assert!((ax - 2.0 * rp / (rp + r)).abs() < 1e-15);
        let sp = Symmetry::Spherical.shape_factor(rp, r);
        assert!((sp - 3.0 * rp * rp / (r * r + r * rp + rp * rp)).abs() < 1e-15);
        assert_eq!(Symmetry::Planar.shape_factor(rp, r), 1.0);
        // Ω → 1 for neighbours at the same radius
        for s in [Symmetry::Axisymmetric, Symmetry::Spherical] {
            assert!((s.shape_factor(r, r) - 1.0).abs() < 1e-15);
            assert_eq!(s.pair_factor(r, rp), s.pair_factor(rp, r));
        }
    }

    #[test]
    fn volume_factors_are_ring_and_shell_measures() {
        use std::f64::consts::PI;
        let r = 0.2;
        assert!((Symmetry::Axisymmetric.volume_factor(r) - 2.0 * PI * r).abs() < 1e-15);
        assert!((Symmetry::Spherical.volume_factor(r) - 4.0 * PI * r * r).abs() < 1e-15);
    }
}
