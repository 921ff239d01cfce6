//! peritherm-analytic: the classical (local) series solutions of the papers' benchmarks, the
//! references a case compares its run with.
//!
//! All are separation-of-variables series of the heat equation θ_t = α ∇²θ: along one axis
//! (written in the coordinate s = x − x0 along the bar), products of such slabs over the axes
//! of a rectangle or box, and radial series of a sphere and a disc. One file per family:
//! `series` (the modes and slabs they share), `bar` (1D bars), `rect` (rectangles and
//! boxes), `radial` (sphere, disc, annulus, Bessel zeros), `phase` (Neumann freezing) and
//! `pulse` (the pulsed bar, the laser film, the split plate); this file keeps the
//! [`Reference`] a case names and its dispatch. It sits on `peritherm-core` (its `math`
//! types) and below `peritherm-io`, which reads a reference from the case file; it reads and
//! writes no file.
#![warn(missing_docs)]

mod bar;
mod phase;
mod pulse;
mod radial;
mod rect;
mod series;

pub use phase::{neumann_front, neumann_root};
pub use radial::bessel_j0_zeros;
pub use series::AxisEnds;

use peritherm_core::math::Point;
use serde::{Deserialize, Serialize};

/// A classical reference solution with its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Reference {
    /// Both ends held, constant initial temperature (Bobaru & Duangpanya 2010, eq. 33; Wang,
    /// Oterkus & Oterkus §4.1).
    BarFixedEnds {
        /// Coordinate of the left end, m.
        x0: f64,
        /// Length L, m.
        length: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ at s = 0, °C.
        left: f64,
        /// θ at s = L, °C.
        right: f64,
        /// Initial θ, °C.
        initial: f64,
    },
    /// Left end insulated, right end held, two-step initial field (Bobaru & Duangpanya 2010, eq.
    /// 38).
    BarInsulatedLeft {
        /// Coordinate of the left end, m.
        x0: f64,
        /// Length L, m.
        length: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ at s = L, °C.
        right: f64,
        /// Initial θ on s < L/2, °C.
        initial_left: f64,
        /// Initial θ on s > L/2, °C.
        initial_right: f64,
    },
    /// Left end held, gradient θ_s given at the right end (Bobaru & Duangpanya 2010, eq. 43; Bobaru
    /// & Duangpanya 2012, eq. 18 with 0).
    BarFixedFlux {
        /// Coordinate of the left end, m.
        x0: f64,
        /// Length L, m.
        length: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ at s = 0, °C.
        left: f64,
        /// θ_s at s = L, K/m (q/κ).
        gradient: f64,
        /// Initial θ, °C.
        initial: f64,
    },
    /// Left end at A t e^(−r t), right end insulated, initial 0 (Wang, Oterkus & Oterkus §4.2,
    /// Duhamel).
    BarPulseLeft {
        /// Coordinate of the left end, m.
        x0: f64,
        /// Length L, m.
        length: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// Amplitude A, K/s.
        amplitude: f64,
        /// Rate r, 1/s.
        rate: f64,
    },
    /// Square with all edges held, constant initial temperature (Bobaru & Duangpanya 2012 Example
    /// 1).
    SquareFixedEdges {
        /// Coordinates of the lower-left corner, m.
        x0: f64,
        /// See `x0`.
        y0: f64,
        /// Side L, m.
        length: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// Edge temperature, °C.
        edge: f64,
        /// Initial θ, °C.
        initial: f64,
    },
    /// Sphere of radius R about the origin, surface held, uniform initial temperature
    /// (PCS2022, doi:10.1007/s42102-022-00092-3, §3.2): θ = θ_s + (θ_0
    /// − θ_s)(2R/(πr)) Σ (−1)^(n+1)/n sin(nπr/R) e^(−α n²π² t/R²), r = √(x² + y² + z²) (the radius
    /// of a 1D radial model is x).
    SphereFixedSurface {
        /// Radius R, m.
        radius: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ on the surface, °C (or K).
        surface: f64,
        /// Initial θ, °C (or K).
        initial: f64,
    },
    /// Neumann's solution of planar freezing (theory §6): a liquid at `initial` > T_f
    /// fills s = x − x0 > 0 and the face s = 0 is held at `surface` < T_f from t = 0. The
    /// front is at X(t) = 2λ√(α_f t) ([`neumann_front`]); one density for both phases.
    NeumannFreezing {
        /// Coordinate of the cooled face, m.
        x0: f64,
        /// θ of the face, °C (or K).
        surface: f64,
        /// Initial θ of the liquid, °C (or K).
        initial: f64,
        /// Freezing temperature T_f, °C (or K).
        freezing: f64,
        /// Latent heat L, J/kg.
        latent_heat: f64,
        /// Density ρ of both phases, kg/m³.
        density: f64,
        /// λ_f, W/(m·K).
        frozen_conductivity: f64,
        /// C_f, J/(kg·K).
        frozen_specific_heat: f64,
        /// λ_m, W/(m·K).
        melted_conductivity: f64,
        /// C_m, J/(kg·K).
        melted_specific_heat: f64,
    },
    /// A rectangle [x0, x0 + a] × [y0, y0 + b] (or box × [z0, z0 + c], or bar) with every face
    /// either held at `edge` or insulated, uniform initial θ0: θ = θ_edge + (θ0 − θ_edge)
    /// Π_axes u(s_axis, t), u the unit slab series of each axis ([`AxisEnds`]).
    BoxFixedFaces {
        /// Lower corner (x0, y0[, z0]), m: one number per axis of the box (1 to 3).
        min: Vec<f64>,
        /// Side lengths (a, b[, c]), m: one per axis.
        size: Vec<f64>,
        /// How each axis is bounded at its low and high faces: one per axis.
        ends: Vec<AxisEnds>,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ on the held faces, °C.
        edge: f64,
        /// Initial θ, °C.
        initial: f64,
    },
    /// Disc of radius R about the origin (a cylinder along z in 3D), edge held, uniform
    /// initial θ0: θ = θ_s + (θ0 − θ_s) Σ 2/(λ_n J1(λ_n)) J0(λ_n r/R) e^(−α λ_n² t/R²),
    /// λ_n the zeros of J0 ([`bessel_j0_zeros`]), r = √(x² + y²).
    DiscFixedEdge {
        /// Radius R, m.
        radius: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// θ on the edge r = R, °C.
        edge: f64,
        /// Initial θ, °C.
        initial: f64,
    },
    /// A slab [x0, x0 + L] insulated at both faces, from θ = 0, heated by the volumetric source
    /// s = 0.94 J0 (1 − R)/(t0 l) · e^(−(x − x0)/l − a|t − 2t0|/t0), W/m³ (a femtosecond laser
    /// pulse absorbed in a metal film: Qiu & Tien's source, Wang, Oterkus & Oterkus, Thermal
    /// diffusion analysis by using dual horizon peridynamics, §4.4): the cosine series of the
    /// insulated slab, each mode's time integral in closed form.
    FilmLaserPulse {
        /// Coordinate of the irradiated face, m.
        x0: f64,
        /// Thickness L of the film along x, m.
        length: f64,
        /// Diffusivity α = k/(ρc), m²/s.
        diffusivity: f64,
        /// Volumetric heat capacity ρc, J/(m³·K).
        heat_capacity: f64,
        /// Laser fluence J0, J/m².
        fluence: f64,
        /// Reflectivity R of the face, in [0, 1).
        reflectivity: f64,
        /// Radiation penetration depth l, m.
        depth: f64,
        /// Pulse duration t0 (full width at half maximum), s; the peak is at 2t0.
        duration: f64,
        /// Shape parameter a of the pulse's exponential decay, dimensionless.
        shape: f64,
    },
    /// The plate [x0, x0 + L] × [y0, y0 + W] with the edge x = x0 at A t e^(−rt), the other
    /// edges insulated, from `below` for y < `split` and `above` for y > `split` (Wang,
    /// Oterkus & Oterkus §4.5): the Duhamel solution of `bar_pulse_left` plus the split field
    /// diffusing with x = x0 held at 0, a separable product X(x, t) Y(y, t) of a slab series
    /// (sine modes, held at x0, insulated at x0 + L, from 1) and a cosine series in y.
    PlatePulseSplit {
        /// Coordinate of the held edge, m.
        x0: f64,
        /// Coordinate of the lower edge, m.
        y0: f64,
        /// Side L along x, m.
        length: f64,
        /// Side W along y, m.
        width: f64,
        /// Diffusivity α, m²/s.
        diffusivity: f64,
        /// Amplitude A of the held edge's A t e^(−rt), K/s.
        amplitude: f64,
        /// Rate r, 1/s.
        rate: f64,
        /// The y of the step in the initial field, m (within [y0, y0 + W]).
        split: f64,
        /// Initial θ for y < split, °C.
        below: f64,
        /// Initial θ for y > split, °C.
        above: f64,
    },
    /// Steady conduction in a ring about the origin with both circles held:
    /// θ = θ_i + (θ_o − θ_i) ln(r/r_i)/ln(r_o/r_i) (independent of t).
    AnnulusSteady {
        /// Inner radius r_i, m.
        inner_radius: f64,
        /// Outer radius r_o, m.
        outer_radius: f64,
        /// θ on the inner circle, °C.
        inner: f64,
        /// θ on the outer circle, °C.
        outer: f64,
    },
}

impl Reference {
    /// Which of x, y, z the solution varies with.
    pub fn depends_on(&self) -> [bool; 3] {
        match self {
            Reference::SquareFixedEdges { .. }
            | Reference::PlatePulseSplit { .. }
            | Reference::AnnulusSteady { .. }
            | Reference::DiscFixedEdge { .. } => [true, true, false],
            Reference::SphereFixedSurface { .. } => [true, true, true],
            Reference::BoxFixedFaces { ends, .. } => {
                let mut d = [false; 3];
                for (a, e) in ends.iter().enumerate().take(3) {
                    d[a] = *e != AxisEnds::Insulated;
                }
                d
            }
            _ => [true, false, false],
        }
    }

    /// The classical temperature at every point, evaluating each distinct point once (only
    /// the coordinates the solution depends on count; in parallel), °C.
    pub fn eval_many(&self, points: &[Point], t: f64) -> Vec<f64> {
        use rayon::prelude::*;
        use std::collections::HashMap;
        if let Some(values) = self.eval_separable(points, t) {
            return values;
        }
        let dep = self.depends_on();
        let bits = |v: f64, a: usize| if dep[a] { v.to_bits() } else { 0 };
        let key = |p: &Point| (bits(p.x, 0), bits(p.y, 1), bits(p.z, 2));
        let mut index: HashMap<(u64, u64, u64), usize> = HashMap::new();
        let mut unique = Vec::new();
        let slots: Vec<usize> = points
            .iter()
            .map(|p| {
                *index.entry(key(p)).or_insert_with(|| {
                    unique.push(*p);
                    unique.len() - 1
                })
            })
            .collect();
        let values: Vec<f64> = unique
            .par_iter()
            .map(|p: &Point| self.eval(p.x, p.y, p.z, t))
            .collect();
        slots.into_iter().map(|s| values[s]).collect()
    }

    /// The classical temperature at the point (x, y, z), m, and time t, s, °C.
    pub fn eval(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        match self {
            Reference::BarFixedEnds { .. } => self.bar_fixed_ends(x, t),
            Reference::BarInsulatedLeft { .. } => self.bar_insulated_left(x, t),
            Reference::BarFixedFlux { .. } => self.bar_fixed_flux(x, t),
            Reference::BarPulseLeft { .. } => self.bar_pulse_left(x, t),
            Reference::SquareFixedEdges { .. } => self.square_fixed_edges(x, y, t),
            Reference::BoxFixedFaces { .. } => self.box_fixed_faces(x, y, z, t),
            Reference::SphereFixedSurface { .. } => self.sphere(x, y, z, t),
            Reference::DiscFixedEdge { .. } => self.disc_fixed_edge(x, y, t),
            Reference::AnnulusSteady { .. } => self.annulus_steady(x, y),
            Reference::NeumannFreezing { .. } => self.neumann(x, t),
            Reference::FilmLaserPulse { .. } => self.laser_film(x, t),
            Reference::PlatePulseSplit { .. } => self.plate_pulse_split(x, y, t),
        }
    }
}
