//! Materials and the bond-conductivity rule at interfaces (formulation §2.4).

use serde::{Deserialize, Serialize};

/// A linear conducting material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Thermal conductivity k, W/(m·K).
    pub conductivity: f64,
    /// Density ρ, kg/m³.
    pub density: f64,
    /// Specific heat c, J/(kg·K).
    pub specific_heat: f64,
}

impl Material {
    /// Volumetric heat capacity ρc, J/(m³·K).
    pub fn capacity(&self) -> f64 {
        self.density * self.specific_heat
    }
    /// Diffusivity k/(ρc), m²/s.
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / self.capacity()
    }
}

/// How a bond between two materials takes its conductivity (formulation §2.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BondRule {
    /// 2 k_a k_b / (k_a + k_b) (seed 001, default).
    #[default]
    Harmonic,
    /// min(k_a, k_b) (seed 003, composites).
    Lower,
    /// (k_a + k_b) / 2.
    Arithmetic,
}

impl BondRule {
    /// The bond conductivity for end conductivities `a` and `b`, W/(m·K).
    pub fn combine(&self, a: f64, b: f64) -> f64 {
        if a == b {
            return a;
        }
        match self {
            BondRule::Harmonic => 2.0 * a * b / (a + b),
            BondRule::Lower => a.min(b),
            BondRule::Arithmetic => 0.5 * (a + b),
        }
    }
}
