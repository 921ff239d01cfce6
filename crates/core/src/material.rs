//! Materials, their enthalpy–temperature relation (theory §6, PCS2022
//! (doi:10.1007/s42102-022-00092-3), eqs. 1–3) and the bond-conductivity rule at interfaces (theory
//! §2.4).

use serde::{Deserialize, Serialize};

/// A conducting material; with `phase_change` its properties are those of the melted phase.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Thermal conductivity k (λ_m of the melted phase), W/(m·K).
    pub conductivity: f64,
    /// Density ρ (ρ_m), kg/m³.
    pub density: f64,
    /// Specific heat c (C_m), J/(kg·K).
    pub specific_heat: f64,
    /// Freezing/melting at one temperature (PCS2022 §2.1); None for a
    /// linear material.
    #[serde(default)]
    pub phase_change: Option<PhaseChange>,
}

/// Whether any of `materials` freezes or melts (a phase-change run).
pub fn any_phase_change(materials: &[Material]) -> bool {
    materials.iter().any(|m| m.phase_change.is_some())
}

/// `[material.<name>.phase_change]`: the frozen phase and the latent heat (PCS2022,
/// eqs. 1–3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseChange {
    /// Phase-change temperature T_f, °C (or K).
    pub temperature: f64,
    /// Specific latent heat L, J/kg.
    pub latent_heat: f64,
    /// Fraction Π of the volume that changes phase (default 1).
    #[serde(default = "one")]
    pub fraction: f64,
    /// Conductivity λ_f of the frozen phase, W/(m·K).
    pub frozen_conductivity: f64,
    /// Density ρ_f of the frozen phase (default: the melted density), kg/m³.
    #[serde(default)]
    pub frozen_density: Option<f64>,
    /// Specific heat C_f of the frozen phase, J/(kg·K).
    pub frozen_specific_heat: f64,
}

fn one() -> f64 {
    1.0
}

/// The enthalpy per unit volume H(θ) ↔ θ(H) relation of one material (theory §6), with
/// H = ρ_f C_f θ below T_f (H = ρcθ for a linear material). Precomputed for the time loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Enthalpy {
    /// ρ_f C_f (ρc for a linear material), J/(m³·K).
    frozen_capacity: f64,
    /// ρ_m C_m, J/(m³·K).
    melted_capacity: f64,
    /// T_f (+∞ for a linear material: always "frozen").
    t_f: f64,
    /// H at the start of the plateau, ρ_f C_f T_f, J/m³.
    h_solid: f64,
    /// H at the end of the plateau, ρ_f C_f T_f + ρ_f Π L, J/m³.
    h_liquid: f64,
    /// λ_f, W/(m·K).
    k_frozen: f64,
    /// λ_m, W/(m·K).
    k_melted: f64,
}

impl Enthalpy {
    /// Temperature at enthalpy `h` (PCS2022, eq. 3), °C.
    #[inline]
    pub fn temperature(&self, h: f64) -> f64 {
        if h < self.h_solid {
            h / self.frozen_capacity
        } else if h <= self.h_liquid {
            self.t_f
        } else {
            self.t_f + (h - self.h_liquid) / self.melted_capacity
        }
    }

    /// Enthalpy at temperature `t`, J/m³; at T_f exactly, the frozen end of the plateau.
    #[inline]
    pub fn enthalpy(&self, t: f64) -> f64 {
        if t <= self.t_f {
            self.frozen_capacity * t
        } else {
            self.h_liquid + self.melted_capacity * (t - self.t_f)
        }
    }

    /// Conductivity at enthalpy `h` (PCS2022, eq. 1: the mean of λ_f
    /// and λ_m on the plateau), W/(m·K).
    #[inline]
    pub fn conductivity(&self, h: f64) -> f64 {
        if h < self.h_solid {
            self.k_frozen
        } else if h <= self.h_liquid {
            0.5 * (self.k_frozen + self.k_melted)
        } else {
            self.k_melted
        }
    }

    /// Melted fraction at enthalpy `h`: 0 frozen, 1 melted, linear across the plateau.
    pub fn melted_fraction(&self, h: f64) -> f64 {
        if self.h_liquid > self.h_solid {
            ((h - self.h_solid) / (self.h_liquid - self.h_solid)).clamp(0.0, 1.0)
        } else if h < self.h_solid {
            0.0
        } else {
            1.0
        }
    }

    /// Largest conductivity of any phase, W/(m·K).
    pub fn max_conductivity(&self) -> f64 {
        self.k_frozen.max(self.k_melted)
    }

    /// Smallest volumetric heat capacity of any phase, J/(m³·K).
    pub fn min_capacity(&self) -> f64 {
        self.frozen_capacity.min(self.melted_capacity)
    }
}

/// What a material property must be, with the phrase its error message uses.
#[derive(Debug, Clone, Copy)]
enum Requirement {
    /// A positive normal number (subnormal values make ρc or 1/(Vρc) underflow or overflow).
    Positive,
    /// Any finite number.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// In [0, 1].
    Fraction,
}

impl Requirement {
    /// Whether `v` meets the requirement.
    fn holds(self, v: f64) -> bool {
        match self {
            Requirement::Positive => v.is_normal() && v > 0.0,
            Requirement::Finite => v.is_finite(),
            Requirement::NonNegative => v.is_finite() && v >= 0.0,
            Requirement::Fraction => (0.0..=1.0).contains(&v),
        }
    }

    /// The phrase after "must be" in the error message.
    fn phrase(self) -> &'static str {
        match self {
            Requirement::Positive => "a positive number",
            Requirement::Finite => "finite",
            Requirement::NonNegative => "finite and ≥ 0",
            Requirement::Fraction => "in [0, 1]",
        }
    }
}

impl Material {
    /// Every checked property as (key, value, requirement), in the order they are checked.
    fn requirements(&self) -> Vec<(&'static str, f64, Requirement)> {
        use Requirement::*;
        let mut checks = vec![
            ("conductivity", self.conductivity, Positive),
            ("density", self.density, Positive),
            ("specific_heat", self.specific_heat, Positive),
        ];
        if let Some(p) = self.phase_change {
            let rho = p.frozen_density.unwrap_or(self.density);
            checks.extend([
                ("phase_change.temperature", p.temperature, Finite),
                ("phase_change.latent_heat", p.latent_heat, NonNegative),
                ("phase_change.fraction", p.fraction, Fraction),
                (
                    "phase_change.frozen_conductivity",
                    p.frozen_conductivity,
                    Positive,
                ),
                ("phase_change.frozen_density", rho, Positive),
                (
                    "phase_change.frozen_specific_heat",
                    p.frozen_specific_heat,
                    Positive,
                ),
            ]);
        }
        checks
    }

    /// Checks every property: `Err((key, message))` names the offending key, e.g.
    /// `phase_change.latent_heat`.
    pub fn check(&self) -> Result<(), (String, String)> {
        let failed = self.requirements().into_iter().find(|c| !c.2.holds(c.1));
        if let Some((key, v, requirement)) = failed {
            // tiny and huge values in exponent form (a subnormal's digits fill a screen)
            let v = if v != 0.0 && !(1e-6..1e9).contains(&v.abs()) {
                format!("{v:e}")
            } else {
                format!("{v}")
            };
            let what = requirement.phrase();
            return Err((key.to_string(), format!("must be {what}, got {v}")));
        }
        // each factor may be normal while ρc or k/(ρc) is not
        let (c, d) = (self.capacity(), self.diffusivity());
        if !(c.is_normal() && d.is_normal()) {
            return Err((
                "specific_heat".to_string(),
                format!("gives ρc = {c:e} J/(m³·K) and k/(ρc) = {d:e} m²/s, outside the range of doubles"),
            ));
        }
        Ok(())
    }

    /// The material's enthalpy relation (theory §6).
    pub fn enthalpy(&self) -> Enthalpy {
        match self.phase_change {
            None => Enthalpy {
                frozen_capacity: self.capacity(),
                melted_capacity: self.capacity(),
                t_f: f64::INFINITY,
                h_solid: f64::INFINITY,
                h_liquid: f64::INFINITY,
                k_frozen: self.conductivity,
                k_melted: self.conductivity,
            },
            Some(p) => {
                let rho_f = p.frozen_density.unwrap_or(self.density);
                let frozen_capacity = rho_f * p.frozen_specific_heat;
                let h_solid = frozen_capacity * p.temperature;
                Enthalpy {
                    frozen_capacity,
                    melted_capacity: self.capacity(),
                    t_f: p.temperature,
                    h_solid,
                    h_liquid: h_solid + rho_f * p.fraction * p.latent_heat,
                    k_frozen: p.frozen_conductivity,
                    k_melted: self.conductivity,
                }
            }
        }
    }

    /// Volumetric heat capacity ρc, J/(m³·K).
    pub fn capacity(&self) -> f64 {
        self.density * self.specific_heat
    }
    /// Diffusivity k/(ρc), m²/s.
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / self.capacity()
    }
}

/// How a bond between two materials takes its conductivity (theory §2.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BondRule {
    /// 2 k_a k_b / (k_a + k_b) (PCS2022, default).
    #[default]
    Harmonic,
    /// min(k_a, k_b) (Bobaru & Duangpanya 2012, composites).
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

#[cfg(test)]
mod tests {
    use super::*;

    fn water() -> Material {
        Material {
            conductivity: 0.6,
            density: 1000.0,
            specific_heat: 4182.0,
            phase_change: Some(PhaseChange {
                temperature: 273.15,
                latent_heat: 333e3,
                fraction: 1.0,
                frozen_conductivity: 2.14,
                frozen_density: None,
                frozen_specific_heat: 2060.0,
            }),
        }
    }

    #[test]
    fn enthalpy_and_temperature_are_inverse_off_the_plateau() {
        let e = water().enthalpy();
        for t in [200.0, 273.0, 273.2, 300.0, 373.15] {
            assert!((e.temperature(e.enthalpy(t)) - t).abs() < 1e-9 * t, "{t}");
        }
        // PCS2022, eq. 3: the plateau is ρ_f Π L wide and sits at T_f
        let hs = 1000.0 * 2060.0 * 273.15;
        assert_eq!(e.temperature(hs + 0.5 * 1000.0 * 333e3), 273.15);
        assert!((e.temperature(hs + 1000.0 * 333e3 + 4182.0e3) - 274.15).abs() < 1e-9);
        assert_eq!(e.conductivity(hs + 1.0), 0.5 * (2.14 + 0.6));
        assert_eq!(e.conductivity(hs - 1.0), 2.14);
    }

    #[test]
    fn a_linear_material_is_h_equals_rho_c_theta() {
        let m = Material {
            phase_change: None,
            ..water()
        };
        let e = m.enthalpy();
        for t in [-50.0, 0.0, 20.0, 1e4] {
            assert_eq!(e.enthalpy(t), m.capacity() * t);
            assert_eq!(e.conductivity(e.enthalpy(t)), 0.6);
        }
    }
}
