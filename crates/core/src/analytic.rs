//! Classical (local) series solutions of the papers' benchmarks, for comparison.
//!
//! All are separation-of-variables series of the heat equation θ_t = α ∇²θ: along one axis
//! (written in the coordinate s = x − x0 along the bar), products of such slabs over the axes
//! of a rectangle or box, and radial series of a sphere and a disc.

use crate::math::Point;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The two ends of one axis of a [`Reference::BoxFixedFaces`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisEnds {
    /// Both faces of the axis held: the slab series on [0, L].
    FixedBoth,
    /// The low face held, the high face insulated: a slab of length 2L at s.
    FixedLow,
    /// The low face insulated, the high face held: a slab of length 2L at s + L.
    FixedHigh,
    /// Both faces insulated: the axis contributes a factor 1.
    Insulated,
}

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

/// Number of series terms so that e^(−α λ_n² t) < e^(−40) beyond, with λ_n = c n.
fn terms(alpha: f64, t: f64, c: f64) -> usize {
    let n = if t > 0.0 {
        (40.0 / (alpha * t)).sqrt() / c
    } else {
        f64::INFINITY
    };
    (n.ceil() as usize + 2).clamp(200, 200_000)
}

/// The modes n = 1, 2, … of a series with λ_n = c n, as many as [`terms`] asks: (n, λ_n), λ in
/// the unit of c.
fn modes(alpha: f64, t: f64, c: f64) -> impl Iterator<Item = (usize, f64)> {
    (1..=terms(alpha, t, c)).map(move |n| (n, c * n as f64))
}

/// The modes n = 1, 2, … of a series with λ_n = c (2n − 1), as many as [`terms`] asks for
/// the spacing 2c: (n, λ_n), λ in the unit of c.
fn odd_modes(alpha: f64, t: f64, c: f64) -> impl Iterator<Item = (usize, f64)> {
    (1..=terms(alpha, t, 2.0 * c)).map(move |n| (n, c * (2 * n - 1) as f64))
}

/// `start + Σ term(n, λ_n) e^(−α λ_n² t)` over the `modes` (n, λ_n), summed in their order:
/// the decaying modes of a separation-of-variables series (α in m²/s, t in s, λ in 1/m).
fn decaying(
    start: f64,
    alpha: f64,
    t: f64,
    modes: impl Iterator<Item = (usize, f64)>,
    term: impl Fn(usize, f64) -> f64,
) -> f64 {
    modes.fold(start, |sum, (n, lam)| {
        sum + term(n, lam) * (-alpha * lam * lam * t).exp()
    })
}

/// (4/π) Σ_{m odd} sin(mπs/L)/m e^(−α m²π² t/L²): the unit solution of a slab held at 0.
fn slab(s: f64, l: f64, alpha: f64, t: f64) -> f64 {
    let c = PI / l;
    let odd = (1..=terms(alpha, t, c))
        .step_by(2)
        .map(|m| (m, c * m as f64));
    4.0 / PI * decaying(0.0, alpha, t, odd, |m, lam| (lam * s).sin() / m as f64)
}

/// The unit solution of one axis of a [`Reference::BoxFixedFaces`] at s ∈ [0, L] (1 inside
/// at t = 0, 0 on the held faces).
fn axis_factor(ends: AxisEnds, s: f64, l: f64, alpha: f64, t: f64) -> f64 {
    let s = s.clamp(0.0, l);
    match ends {
        AxisEnds::FixedBoth => slab(s, l, alpha, t),
        // the slab [0, 2L] held at both ends is symmetric about L: insulated there
        AxisEnds::FixedLow => slab(s, 2.0 * l, alpha, t),
        AxisEnds::FixedHigh => slab(s + l, 2.0 * l, alpha, t),
        AxisEnds::Insulated => 1.0,
    }
}

/// The first `n` positive zeros of the Bessel function J0, in increasing order: Newton's
/// method (J0' = −J1) from McMahon's asymptotic expansion β + 1/(8β) − 31/(384β³) +
/// 3779/(15360β⁵), β = (n − ¼)π (Abramowitz & Stegun 9.5.12), to 1e-15 relative.
pub fn bessel_j0_zeros(n: usize) -> Vec<f64> {
    (1..=n)
        .map(|k| {
            let b = (k as f64 - 0.25) * PI;
            let mut z =
                b + 1.0 / (8.0 * b) - 31.0 / (384.0 * b.powi(3)) + 3779.0 / (15360.0 * b.powi(5));
            for _ in 0..50 {
                let step = libm::j0(z) / libm::j1(z);
                z += step;
                if step.abs() <= 1e-15 * z {
                    break;
                }
            }
            z
        })
        .collect()
}

/// The unit solution of a disc of radius R with its edge held at 0, at radius r: Σ
/// 2/(λ_n J1(λ_n)) J0(λ_n r/R) e^(−α λ_n² t/R²), to the terms with e^(−α λ_n² t/R²) ≥ e^(−40).
fn disc(r: f64, radius: f64, alpha: f64, t: f64) -> f64 {
    let rho = (r / radius).clamp(0.0, 1.0);
    if t <= 0.0 {
        return if rho < 1.0 { 1.0 } else { 0.0 };
    }
    let tau = alpha * t / (radius * radius);
    // λ_n ≈ (n − ¼)π: the last term needed has λ_n² τ ≥ 40
    let n = ((40.0 / tau).sqrt() / PI + 0.25).ceil() as usize + 2;
    bessel_j0_zeros(n.clamp(4, 100_000))
        .into_iter()
        .map(|l| 2.0 / (l * libm::j1(l)) * libm::j0(l * rho) * (-l * l * tau).exp())
        .sum()
}

/// Neumann's root λ and the frozen and melted diffusivities (α_f, α_m) of a
/// [`Reference::NeumannFreezing`]: λ solves
/// e^(−λ²)/erf λ − (λ_m/λ_f)√(α_f/α_m) (T_i − T_f)/(T_f − T_s) e^(−λ²α_f/α_m)/erfc(λ√(α_f/α_m))
/// = λ√π L/(C_f (T_f − T_s)) (Carslaw & Jaeger §11.2), found by bisection to 1e-14.
/// `None` for another reference.
pub fn neumann_root(r: &Reference) -> Option<(f64, f64, f64)> {
    let Reference::NeumannFreezing {
        surface,
        initial,
        freezing,
        latent_heat,
        density,
        frozen_conductivity: kf,
        frozen_specific_heat: cf,
        melted_conductivity: km,
        melted_specific_heat: cm,
        ..
    } = *r
    else {
        return None;
    };
    let (af, am) = (kf / (density * cf), km / (density * cm));
    let nu = (af / am).sqrt();
    let stefan = cf * (freezing - surface) / latent_heat;
    let f = |l: f64| {
        (-l * l).exp() / libm::erf(l)
            - km / kf * nu * (initial - freezing) / (freezing - surface) * (-l * l * nu * nu).exp()
                / libm::erfc(l * nu)
            - l * PI.sqrt() / stefan
    };
    let (mut lo, mut hi) = (1e-12, 10.0);
    while hi - lo > 1e-14 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some((0.5 * (lo + hi), af, am))
}

/// Front position x0 + 2λ√(α_f t) of a [`Reference::NeumannFreezing`] at time `t`, m.
pub fn neumann_front(r: &Reference, t: f64) -> Option<f64> {
    let (l, af, _) = neumann_root(r)?;
    let Reference::NeumannFreezing { x0, .. } = *r else {
        return None;
    };
    Some(x0 + 2.0 * l * (af * t).sqrt())
}

impl Reference {
    /// The gold film of `cases/laser_film.toml` (Wang, Oterkus & Oterkus §4.4, Qiu & Tien's
    /// data): L = 20 nm, α = 1.26e-4 m²/s, ρc = 2.5e6 J/(m³·K), J0 = 13.4 J/m², R = 0.93,
    /// l = 15.3 nm, t0 = 100 fs, a = 1.992; a worked example shared by the tests.
    pub fn laser_film_example() -> Reference {
        Reference::FilmLaserPulse {
            x0: 0.0,
            length: 2e-8,
            diffusivity: 1.26e-4,
            heat_capacity: 2.5e6,
            fluence: 13.4,
            reflectivity: 0.93,
            depth: 15.3e-9,
            duration: 100e-15,
            shape: 1.992,
        }
    }

    /// The 10 × 10 m plate of `cases/thermal_shock_split.toml` (Wang, Oterkus & Oterkus §4.5:
    /// α = 1 m²/s, A = 5 K/s, r = 2 1/s) with its initial step at y = `split` m from `below` to
    /// `above` °C; a worked example shared by the tests.
    pub fn split_plate_example(split: f64, below: f64, above: f64) -> Reference {
        Reference::PlatePulseSplit {
            x0: -5.0,
            y0: -5.0,
            length: 10.0,
            width: 10.0,
            diffusivity: 1.0,
            amplitude: 5.0,
            rate: 2.0,
            split,
            below,
            above,
        }
    }

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

    /// [`Reference::eval_many`] of a [`Reference::PlatePulseSplit`] from its factors, each
    /// evaluated once per distinct x and per distinct y (°C); `None` for other references.
    fn eval_separable(&self, points: &[Point], t: f64) -> Option<Vec<f64>> {
        use rayon::prelude::*;
        use std::collections::HashMap;
        let Reference::PlatePulseSplit { .. } = self else {
            return None;
        };
        let distinct = |a: usize| {
            let mut v: Vec<f64> = points.iter().map(|p| p[a]).collect();
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| a.to_bits() == b.to_bits());
            v
        };
        let (xs, ys) = (distinct(0), distinct(1));
        let fx: HashMap<u64, (f64, f64)> = xs
            .par_iter()
            .map(|&x| (x.to_bits(), self.split_factors_x(x, t)))
            .collect();
        let fy: HashMap<u64, f64> = ys
            .par_iter()
            .map(|&y| (y.to_bits(), self.split_factor_y(y, t)))
            .collect();
        Some(
            points
                .iter()
                .map(|p| {
                    let (pulse, x) = fx[&p.x.to_bits()];
                    pulse + x * fy[&p.y.to_bits()]
                })
                .collect(),
        )
    }

    /// The x factors of a [`Reference::PlatePulseSplit`] at x, t: the Duhamel solution of
    /// the held edge (°C) and the unit slab factor X (held at x0, insulated at x0 + L).
    fn split_factors_x(&self, x: f64, t: f64) -> (f64, f64) {
        let Reference::PlatePulseSplit {
            x0,
            length: l,
            diffusivity: a,
            amplitude,
            rate,
            ..
        } = *self
        else {
            return (f64::NAN, f64::NAN);
        };
        let s = (x - x0).clamp(0.0, l);
        (
            pulse_left(s, l, a, amplitude, rate, t),
            axis_factor(AxisEnds::FixedLow, s, l, a, t),
        )
    }

    /// The y factor of a [`Reference::PlatePulseSplit`] at y, t: the step `below`/`above` at
    /// `split` diffusing between insulated edges (cosine series), °C.
    fn split_factor_y(&self, y: f64, t: f64) -> f64 {
        let Reference::PlatePulseSplit {
            y0,
            width: w,
            diffusivity: a,
            split,
            below,
            above,
            ..
        } = *self
        else {
            return f64::NAN;
        };
        let (s, c) = ((y - y0).clamp(0.0, w), split - y0);
        let mean = (below * c + above * (w - c)) / w;
        decaying(mean, a, t, modes(a, t, PI / w), |n, lam| {
            let b = 2.0 * (below - above) * (lam * c).sin() / (n as f64 * PI);
            b * (lam * s).cos()
        })
    }

    /// The classical temperature at the point (x, y, z), m, and time t, s, °C.
    pub fn eval(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        match *self {
            Reference::FilmLaserPulse { .. } => self.laser_film(x, t),
            Reference::PlatePulseSplit { .. } => {
                let (pulse, fx) = self.split_factors_x(x, t);
                pulse + fx * self.split_factor_y(y, t)
            }
            Reference::BoxFixedFaces {
                ref min,
                ref size,
                ref ends,
                diffusivity: a,
                edge,
                initial,
            } => {
                let u = (0..ends.len().min(3))
                    .map(|k| axis_factor(ends[k], [x, y, z][k] - min[k], size[k], a, t));
                edge + (initial - edge) * u.product::<f64>()
            }
            Reference::DiscFixedEdge {
                radius,
                diffusivity: a,
                edge,
                initial,
            } => edge + (initial - edge) * disc(x.hypot(y), radius, a, t),
            Reference::SphereFixedSurface { .. } => self.sphere(x, y, z, t),
            Reference::NeumannFreezing { .. } => self.neumann(x, t),
            Reference::AnnulusSteady {
                inner_radius: ri,
                outer_radius: ro,
                inner,
                outer,
            } => {
                let r = x.hypot(y);
                inner + (outer - inner) * (r / ri).ln() / (ro / ri).ln()
            }
            Reference::BarFixedEnds { .. } => self.bar_fixed_ends(x, t),
            Reference::BarInsulatedLeft { .. } => self.bar_insulated_left(x, t),
            Reference::BarFixedFlux { .. } => self.bar_fixed_flux(x, t),
            Reference::BarPulseLeft {
                x0,
                length: l,
                diffusivity: a,
                amplitude: amp,
                rate: r,
            } => pulse_left(x - x0, l, a, amp, r, t),
            Reference::SquareFixedEdges {
                x0,
                y0,
                length: l,
                diffusivity: a,
                edge,
                initial,
            } => edge + (initial - edge) * slab(x - x0, l, a, t) * slab(y - y0, l, a, t),
        }
    }

    /// A [`Reference::FilmLaserPulse`] at x, t (the cosine series of [`LaserPulse`]), °C.
    fn laser_film(&self, x: f64, t: f64) -> f64 {
        let Reference::FilmLaserPulse {
            x0,
            length,
            diffusivity,
            heat_capacity,
            fluence,
            reflectivity,
            depth,
            duration,
            shape,
        } = *self
        else {
            return f64::NAN;
        };
        let pulse = LaserPulse {
            length,
            diffusivity,
            heat_capacity,
            fluence,
            reflectivity,
            depth,
            duration,
            shape,
        };
        pulse.eval((x - x0).clamp(0.0, length), t)
    }

    /// A [`Reference::SphereFixedSurface`] at (x, y, z), t: the radial sine series, °C.
    fn sphere(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        let Reference::SphereFixedSurface {
            radius: rs,
            diffusivity: a,
            surface,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        let r = x.hypot(y).hypot(z).min(rs);
        let sum = decaying(0.0, a, t, modes(a, t, PI / rs), |n, lam| {
            let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
            // sin(λr)/(λr) → 1 at the centre
            let sinc = if lam * r < 1e-8 {
                1.0
            } else {
                (lam * r).sin() / (lam * r)
            };
            2.0 * sign * sinc
        });
        surface + (initial - surface) * sum
    }

    /// A [`Reference::NeumannFreezing`] at x, t: the erf profile behind the front and the
    /// erfc profile ahead of it, °C.
    fn neumann(&self, x: f64, t: f64) -> f64 {
        let Reference::NeumannFreezing {
            x0,
            surface,
            initial,
            freezing,
            ..
        } = *self
        else {
            return f64::NAN;
        };
        let (l, af, am) = neumann_root(self).expect("a Neumann reference");
        let s = (x - x0).max(0.0);
        if t <= 0.0 {
            return if s > 0.0 { initial } else { surface };
        }
        if s < 2.0 * l * (af * t).sqrt() {
            surface + (freezing - surface) * libm::erf(s / (2.0 * (af * t).sqrt())) / libm::erf(l)
        } else {
            let nu = (af / am).sqrt();
            initial
                + (freezing - initial) * libm::erfc(s / (2.0 * (am * t).sqrt()))
                    / libm::erfc(l * nu)
        }
    }

    /// A [`Reference::BarFixedEnds`] at x, t: the linear steady state plus the sine series
    /// (Bobaru & Duangpanya 2010, eq. 33), °C.
    fn bar_fixed_ends(&self, x: f64, t: f64) -> f64 {
        let Reference::BarFixedEnds {
            x0,
            length: l,
            diffusivity: a,
            left,
            right,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        let s = x - x0;
        let steady = left + (right - left) * s / l;
        decaying(steady, a, t, modes(a, t, PI / l), |n, lam| {
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            let b = 2.0 / (n as f64 * PI) * (initial * (1.0 - sign) - left + right * sign);
            b * (lam * s).sin()
        })
    }

    /// A [`Reference::BarInsulatedLeft`] at x, t: the odd cosine modes from the two-step
    /// initial field (Bobaru & Duangpanya 2010, eq. 38), °C.
    fn bar_insulated_left(&self, x: f64, t: f64) -> f64 {
        let Reference::BarInsulatedLeft {
            x0,
            length: l,
            diffusivity: a,
            right,
            initial_left,
            initial_right,
        } = *self
        else {
            return f64::NAN;
        };
        let s = x - x0;
        let odd = odd_modes(a, t, PI / (2.0 * l));
        decaying(right, a, t, odd, |_, lam| {
            let cn = 2.0 / (l * lam)
                * ((initial_left - right) * (lam * l / 2.0).sin()
                    + (initial_right - right) * ((lam * l).sin() - (lam * l / 2.0).sin()));
            cn * (lam * s).cos()
        })
    }

    /// A [`Reference::BarFixedFlux`] at x, t: the linear steady state plus the odd sine modes
    /// (Bobaru & Duangpanya 2010, eq. 43), °C.
    fn bar_fixed_flux(&self, x: f64, t: f64) -> f64 {
        let Reference::BarFixedFlux {
            x0,
            length: l,
            diffusivity: a,
            left,
            gradient: g,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        let s = x - x0;
        let odd = odd_modes(a, t, PI / (2.0 * l));
        decaying(left + g * s, a, t, odd, |n, lam| {
            let alt = if n % 2 == 1 { 1.0 } else { -1.0 };
            let b = 2.0 / l * ((initial - left) / lam - g * alt / (lam * lam));
            b * (lam * s).sin()
        })
    }
}

/// θ at s of a bar [0, L] whose end s = 0 follows A t e^(−rt) and whose end s = L is
/// insulated, from θ = 0 (Duhamel's theorem over the sine modes), °C.
fn pulse_left(s: f64, l: f64, a: f64, amp: f64, r: f64, t: f64) -> f64 {
    let g = amp * t * (-r * t).exp();
    let c = PI / (2.0 * l);
    let nmax = terms(a, t, 2.0 * c).max(4000);
    (1..=nmax)
        .map(|n| c * (2 * n - 1) as f64)
        .fold(g, |sum, lam| {
            let an = 2.0 / (l * lam);
            sum - an * duhamel(amp, r, a * lam * lam, t) * (lam * s).sin()
        })
}

/// The parameters of a [`Reference::FilmLaserPulse`] (units there).
struct LaserPulse {
    length: f64,
    diffusivity: f64,
    heat_capacity: f64,
    fluence: f64,
    reflectivity: f64,
    depth: f64,
    duration: f64,
    shape: f64,
}

impl LaserPulse {
    /// θ at depth s ∈ [0, L] and time t: Σ_n e_n cos(λ_n s) (s0/ρc) I(αλ_n², t), with
    /// e^(−s/l) = Σ e_n cos(λ_n s), λ_n = nπ/L, and I the pulse's time integral
    /// ([`pulse_integral`]), °C. Terms are summed until the bound 4L³/(3lαπ⁴N³) of the tail
    /// (|e_n| ≤ 4/(Llλ_n²), I ≤ 1/(αλ_n²)) is below 1e-12 of the mean term.
    fn eval(&self, s: f64, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        let (l, d, a) = (self.length, self.depth, self.diffusivity);
        let s0 = 0.94 * self.fluence * (1.0 - self.reflectivity) / (self.duration * d);
        let (peak, tau) = (2.0 * self.duration, self.duration / self.shape);
        let far = (-l / d).exp();
        let e0 = d / l * (1.0 - far);
        let i0 = pulse_integral(0.0, peak, tau, t);
        let mut sum = e0 * i0;
        let tail = 4.0 * l.powi(3) / (3.0 * d * a * PI.powi(4));
        let n = (tail / (1e-12 * e0 * i0)).cbrt().ceil();
        let n = if n.is_finite() { n as usize } else { 200_000 };
        for k in 1..=n.clamp(200, 200_000) {
            let lam = k as f64 * PI / l;
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            let en = 2.0 * d / l * (1.0 - sign * far) / (1.0 + lam * lam * d * d);
            sum += en * (lam * s).cos() * pulse_integral(a * lam * lam, peak, tau, t);
        }
        s0 / self.heat_capacity * sum
    }
}

/// ∫_0^t e^(−μ(t−u)) e^(−|u − t_p|/τ) du, s: in closed form on each side of the peak t_p.
fn pulse_integral(mu: f64, peak: f64, tau: f64, t: f64) -> f64 {
    // ∫_0^T e^(−μ(T−u)) e^(u/τ) du · e^(−T/τ) = (1 − e^(−(μ + 1/τ)T))/(μ + 1/τ)
    let rising = |t: f64| {
        let k = mu + 1.0 / tau;
        ((t - peak) / tau).exp() * -(-k * t).exp_m1() / k
    };
    if t <= peak {
        return rising(t);
    }
    let big_t = t - peak;
    let nu = mu - 1.0 / tau;
    // (1 − e^(−νT))/ν, → T as ν → 0
    let phi = if (nu * big_t).abs() < 1e-8 {
        big_t * (1.0 - 0.5 * nu * big_t)
    } else {
        -(-nu * big_t).exp_m1() / nu
    };
    (-mu * big_t).exp() * rising(peak) + (-big_t / tau).exp() * phi
}

/// ∫_0^t e^(−μ(t−τ)) g'(τ) dτ for g = A τ e^(−rτ).
fn duhamel(amp: f64, r: f64, mu: f64, t: f64) -> f64 {
    let nu = mu - r;
    if (nu * t).abs() > 1e-3 {
        let er = (-r * t).exp();
        let em = (-mu * t).exp();
        amp * ((er - em) / nu - r * (er * (nu * t - 1.0) + em) / (nu * nu))
    } else {
        // Simpson's rule where the closed form cancels
        let n = 2000;
        let h = t / n as f64;
        let f = |tau: f64| (-mu * (t - tau)).exp() * amp * (-r * tau).exp() * (1.0 - r * tau);
        let mut s = f(0.0) + f(t);
        for i in 1..n {
            s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sphere series against an independent radial finite-difference solve of
    /// u = rθ (u_t = α u_rr, u(0) = 0, u(R) = Rθ_s): 400 intervals, explicit steps of
    /// 0.25 h²/α, at t = 0.02 and 0.1 R²/α. The FD error is O(h²) ≈ 1e-4 of the jump
    /// θ_0 − θ_s here, so 2e-3 of the jump bounds the comparison.
    #[test]
    fn sphere_series_matches_a_radial_solve() {
        let (rs, a, ts, t0) = (0.1, 400.0 / (8920.0 * 385.0), 300.0, 1000.0);
        let sphere = Reference::SphereFixedSurface {
            radius: rs,
            diffusivity: a,
            surface: ts,
            initial: t0,
        };
        let n = 400;
        let h = rs / n as f64;
        let dt = 0.25 * h * h / a;
        let mut u: Vec<f64> = (0..=n).map(|i| i as f64 * h * t0).collect();
        u[n] = rs * ts;
        let mut t = 0.0;
        for t_check in [0.02 * rs * rs / a, 0.1 * rs * rs / a] {
            while t < t_check - 1e-12 {
                let step = dt.min(t_check - t);
                let old = u.clone();
                for i in 1..n {
                    u[i] = old[i] + a * step / (h * h) * (old[i - 1] - 2.0 * old[i] + old[i + 1]);
                }
                t += step;
            }
            for i in [1, n / 4, n / 2, 3 * n / 4] {
                let r = i as f64 * h;
                let fd = u[i] / r;
                let series = sphere.eval(r, 0.0, 0.0, t);
                assert!(
                    (fd - series).abs() < 2e-3 * (t0 - ts),
                    "t = {t}, r = {r}: FD {fd}, series {series}"
                );
            }
        }
        // the centre is finite and the surface is held
        assert!(sphere.eval(0.0, 0.0, 0.0, 1.0).is_finite());
        assert!((sphere.eval(rs, 0.0, 0.0, 1.0) - ts).abs() < 1e-9 * t0);
    }

    /// The midpoint values printed by Bobaru & Duangpanya 2010 at t = 8 s (±0.005 °C: the paper
    /// prints 2 decimals).
    #[test]
    fn bobaru_duangpanya_2010_midpoints() {
        let ex1 = Reference::BarFixedEnds {
            x0: 0.0,
            length: 10.0,
            diffusivity: 1.14,
            left: 0.0,
            right: 0.0,
            initial: 100.0,
        };
        assert!(
            (ex1.eval(5.0, 0.0, 0.0, 8.0) - 51.75).abs() < 0.005,
            "{}",
            ex1.eval(5.0, 0.0, 0.0, 8.0)
        );
        let ex2 = Reference::BarInsulatedLeft {
            x0: 0.0,
            length: 10.0,
            diffusivity: 1.14,
            right: 100.0,
            initial_left: 60.0,
            initial_right: 0.0,
        };
        assert!(
            (ex2.eval(5.0, 0.0, 0.0, 8.0) - 53.06).abs() < 0.005,
            "{}",
            ex2.eval(5.0, 0.0, 0.0, 8.0)
        );
    }

    /// Each series reproduces its initial and boundary data (tolerance from truncation).
    #[test]
    fn series_meet_their_data() {
        let ex3 = Reference::BarFixedFlux {
            x0: 0.0,
            length: PI,
            diffusivity: 1.14,
            left: 20.0,
            gradient: 3.0,
            initial: 0.0,
        };
        assert!(ex3.eval(1.0, 0.0, 0.0, 1e-6).abs() < 1e-2);
        assert!((ex3.eval(0.0, 0.0, 0.0, 0.5) - 20.0).abs() < 1e-9);
        let h = 1e-5;
        let grad = (ex3.eval(PI, 0.0, 0.0, 0.5) - ex3.eval(PI - h, 0.0, 0.0, 0.5)) / h;
        assert!((grad - 3.0).abs() < 1e-3, "{grad}");
        let shock = Reference::BarPulseLeft {
            x0: -5.0,
            length: 10.0,
            diffusivity: 1.0,
            amplitude: 5.0,
            rate: 2.0,
        };
        let t: f64 = 0.8;
        assert!((shock.eval(-5.0, 0.0, 0.0, t) - 5.0 * t * (-2.0 * t).exp()).abs() < 1e-9);
        assert!(shock.eval(4.0, 0.0, 0.0, 0.3).abs() < 1e-6);
        let sq = Reference::SquareFixedEdges {
            x0: 0.0,
            y0: 0.0,
            length: 1.0,
            diffusivity: 1.14,
            edge: 0.0,
            initial: 40.0,
        };
        assert!((sq.eval(0.5, 0.5, 0.0, 1e-7) - 40.0).abs() < 1e-3);
        assert!(sq.eval(0.0, 0.3, 0.0, 0.01).abs() < 1e-12);
    }

    /// The Duhamel series against a fine explicit finite-difference solve (tolerance 2e-3 °C
    /// from the FD grid h = 0.05, Δt = 1e-3).
    #[test]
    fn pulse_series_matches_finite_differences() {
        let (l, a) = (10.0, 1.0);
        let n = 200;
        let h = l / n as f64;
        let dt = 0.2 * h * h / a;
        let steps = (3.0 / dt).round() as usize;
        let dt = 3.0 / steps as f64;
        let mut u = vec![0.0; n + 1];
        let mut next = u.clone();
        for s in 0..steps {
            let t = (s + 1) as f64 * dt;
            for i in 1..n {
                next[i] = u[i] + a * dt / (h * h) * (u[i - 1] - 2.0 * u[i] + u[i + 1]);
            }
            next[n] = u[n] + a * dt / (h * h) * 2.0 * (u[n - 1] - u[n]);
            next[0] = 5.0 * t * (-2.0 * t).exp();
            std::mem::swap(&mut u, &mut next);
        }
        let r = Reference::BarPulseLeft {
            x0: 0.0,
            length: l,
            diffusivity: a,
            amplitude: 5.0,
            rate: 2.0,
        };
        for i in (0..=n).step_by(10) {
            let e = r.eval(i as f64 * h, 0.0, 0.0, 3.0);
            assert!(
                (e - u[i]).abs() < 2e-3,
                "x = {}: {} vs {}",
                i as f64 * h,
                e,
                u[i]
            );
        }
    }

    /// The zeros of J0: J0 vanishes there to round-off, they interlace with the zeros of J1
    /// (J1 changes sign between consecutive ones), their spacing tends to π, and the first
    /// is A&S Table 9.5's 2.404825557695773 (to 1e-14).
    #[test]
    fn bessel_zeros_are_zeros() {
        let z = bessel_j0_zeros(400);
        assert!((z[0] - 2.404825557695773).abs() < 1e-14, "{}", z[0]);
        for w in z.windows(2) {
            assert!(w[1] > w[0]);
            assert!(libm::j1(w[0]) * libm::j1(w[1]) < 0.0);
        }
        for &x in &z {
            // |J0| near a zero is |J1(x)|·|x − zero|: round-off of x is 1e-16 x
            assert!(libm::j0(x).abs() < 1e-15 * x.max(1.0), "J0({x})");
        }
        assert!((z[399] - z[398] - PI).abs() < 1e-5);
    }

    /// The disc series meets its data: the edge is held, the initial field is uniform (the
    /// series Σ 2J0(λr/R)/(λJ1(λ)) → 1 inside as t → 0, to 1e-3 at t = 1e-6 R²/α away from
    /// the edge), the field is radial and it decays as the first mode e^(−λ1²αt/R²) late.
    #[test]
    fn disc_series_meets_its_data() {
        let d = Reference::DiscFixedEdge {
            radius: 0.5,
            diffusivity: 2.0,
            edge: 10.0,
            initial: 60.0,
        };
        assert!((d.eval(0.5, 0.0, 0.0, 0.01) - 10.0).abs() < 1e-12);
        assert!((d.eval(0.0, -0.5, 0.0, 0.01) - 10.0).abs() < 1e-12);
        for r in [0.0, 0.1, 0.3, 0.45] {
            assert!((d.eval(r, 0.0, 0.0, 1e-6 * 0.25 / 2.0) - 60.0).abs() < 1e-3 * 50.0);
        }
        let (a, b) = (d.eval(0.3, 0.0, 0.0, 0.02), d.eval(0.18, 0.24, 5.0, 0.02));
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        let l1 = bessel_j0_zeros(1)[0];
        let late = |t: f64| d.eval(0.0, 0.0, 0.0, t) - 10.0;
        let ratio = late(0.2) / late(0.1);
        let mode = (-l1 * l1 * 2.0 * 0.1 / 0.25).exp();
        assert!((ratio / mode - 1.0).abs() < 1e-6, "{ratio} vs {mode}");
    }

    /// The box series meets its data: held faces at the edge value, a zero normal derivative
    /// at insulated faces (one-sided difference, h = 1e-6), the initial value inside at small
    /// t, an insulated axis contributing nothing, and the product of per-axis slab factors.
    #[test]
    fn box_series_meets_its_data() {
        let ends = vec![AxisEnds::FixedBoth, AxisEnds::FixedLow, AxisEnds::FixedHigh];
        let b = Reference::BoxFixedFaces {
            min: vec![1.0, -1.0, 0.0],
            size: vec![2.0, 1.0, 0.5],
            ends,
            diffusivity: 0.5,
            edge: -5.0,
            initial: 20.0,
        };
        let t = 0.02;
        for p in [
            [1.0, -0.5, 0.2],
            [3.0, -0.5, 0.2],
            [2.0, -1.0, 0.2],
            [2.0, -0.5, 0.5],
        ] {
            assert!((b.eval(p[0], p[1], p[2], t) + 5.0).abs() < 1e-9, "{p:?}");
        }
        let h = 1e-6;
        let dy = (b.eval(2.0, 0.0, 0.2, t) - b.eval(2.0, -h, 0.2, t)) / h;
        let dz = (b.eval(2.0, -0.5, h, t) - b.eval(2.0, -0.5, 0.0, t)) / h;
        assert!(dy.abs() < 1e-3 && dz.abs() < 1e-3, "{dy} {dz}");
        assert!((b.eval(2.0, -0.5, 0.25, 1e-9) - 20.0).abs() < 1e-6);
        let x_only = Reference::BoxFixedFaces {
            min: vec![1.0, -1.0],
            size: vec![2.0, 1.0],
            ends: vec![AxisEnds::FixedBoth, AxisEnds::Insulated],
            diffusivity: 0.5,
            edge: 0.0,
            initial: 1.0,
        };
        let bar = Reference::BarFixedEnds {
            x0: 1.0,
            length: 2.0,
            diffusivity: 0.5,
            left: 0.0,
            right: 0.0,
            initial: 1.0,
        };
        for x in [1.1, 1.7, 2.5] {
            let (u, v) = (x_only.eval(x, 7.0, 0.0, t), bar.eval(x, 0.0, 0.0, t));
            assert!((u - v).abs() < 1e-12, "{u} vs {v}");
        }
        assert_eq!(x_only.depends_on(), [true, false, false]);
        assert_eq!(b.depends_on(), [true, true, true]);
    }

    /// The laser series meets its data: zero at t = 0, insulated faces (the slope there below
    /// 1e-5 of the interior's scale θ(0)/l), and its
    /// heat ∫ρcθ dx equals the absorbed energy s0·l(1 − e^(−L/l))·∫g dt (Simpson over 400
    /// points of the series against the closed form, 1e-9 relative: the mode n = 0 carries
    /// all of it, so this checks e_0 and the time integral; the higher modes are checked
    /// against finite differences in tests/convergence/series.rs).
    #[test]
    fn laser_series_meets_its_data() {
        let film = Reference::laser_film_example();
        let Reference::FilmLaserPulse {
            length: l,
            heat_capacity: rho_c,
            fluence,
            reflectivity,
            depth,
            duration: t0,
            shape: a,
            ..
        } = film
        else {
            unreachable!("the laser example is a laser film")
        };
        assert_eq!(film.eval(0.0, 0.0, 0.0, 0.0), 0.0);
        for t in [1e-13, 2e-13, 7e-13] {
            // second-order one-sided slopes (−3θ0 + 4θ1 − θ2)/2h, h = 1e-4 L: their error
            // h²θ‴/3 is below 1e-6 of the scale θ(0)/l of the slope inside
            let h = 1e-4 * l;
            let scale = film.eval(0.0, 0.0, 0.0, t) / depth;
            let th = |x: f64| film.eval(x, 0.0, 0.0, t);
            let low = (-3.0 * th(0.0) + 4.0 * th(h) - th(2.0 * h)) / (2.0 * h);
            let high = (3.0 * th(l) - 4.0 * th(l - h) + th(l - 2.0 * h)) / (2.0 * h);
            for slope in [low, high] {
                assert!(slope.abs() <= 1e-5 * scale, "t {t}: {slope} of {scale}");
            }
            let n = 400;
            let f = |k: usize| film.eval(k as f64 * l / n as f64, 0.0, 0.0, t);
            let mut sum = f(0) + f(n);
            for k in 1..n {
                sum += f(k) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            let heat = rho_c * sum * l / (3.0 * n as f64);
            let s0 = 0.94 * fluence * (1.0 - reflectivity) / (t0 * depth);
            let exact =
                s0 * depth * (1.0 - (-l / depth).exp()) * pulse_integral(0.0, 2.0 * t0, t0 / a, t);
            assert!(
                (heat / exact - 1.0).abs() < 1e-9,
                "t {t}: {heat} vs {exact}"
            );
        }
        // the time integral against Simpson's rule of its definition, on both sides of the peak
        for (mu, t) in [
            (0.0, 1e-13),
            (3e13, 1.5e-13),
            (3e13, 6e-13),
            (1.99e13, 9e-13),
        ] {
            let (peak, tau) = (2e-13, 5.02e-14);
            let g = |u: f64| (-mu * (t - u)).exp() * (-(u - peak).abs() / tau).exp();
            let n = 200_000;
            let h = t / n as f64;
            let mut sum = g(0.0) + g(t);
            for k in 1..n {
                sum += g(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            let simpson = sum * h / 3.0;
            let closed = pulse_integral(mu, peak, tau, t);
            // the kink at the peak costs Simpson O(h²) there: 1e-8 relative
            assert!(
                (closed / simpson - 1.0).abs() < 1e-8,
                "{closed} vs {simpson}"
            );
        }
    }

    /// The split-plate series meets its data: the held edge follows A t e^(−rt), the other
    /// edges are insulated (one-sided differences, h = 1e-6 m), the initial split is there at
    /// small t away from the step, and with equal halves it is `bar_pulse_left` plus the
    /// uniform field times the slab factor.
    #[test]
    fn split_series_meets_its_data() {
        let split = |below: f64, above: f64| Reference::split_plate_example(0.0, below, above);
        let p = split(0.5, 0.0);
        let t: f64 = 3.0;
        let g = 5.0 * t * (-2.0 * t).exp();
        assert!((p.eval(-5.0, 1.3, 0.0, t) - g).abs() < 1e-9);
        let h = 1e-6;
        let dx = (p.eval(5.0, 1.0, 0.0, t) - p.eval(5.0 - h, 1.0, 0.0, t)) / h;
        let dy0 = (p.eval(1.0, -5.0 + h, 0.0, t) - p.eval(1.0, -5.0, 0.0, t)) / h;
        let dy1 = (p.eval(1.0, 5.0, 0.0, t) - p.eval(1.0, 5.0 - h, 0.0, t)) / h;
        assert!(
            dx.abs() < 1e-5 && dy0.abs() < 1e-5 && dy1.abs() < 1e-5,
            "{dx} {dy0} {dy1}"
        );
        assert!((p.eval(0.0, -2.0, 0.0, 1e-6) - 0.5).abs() < 1e-3);
        assert!(p.eval(0.0, 2.0, 0.0, 1e-6).abs() < 1e-3);
        let uniform = split(0.5, 0.5);
        let bar = Reference::BarPulseLeft {
            x0: -5.0,
            length: 10.0,
            diffusivity: 1.0,
            amplitude: 5.0,
            rate: 2.0,
        };
        for x in [-4.0, 0.5, 4.9] {
            let slab = axis_factor(AxisEnds::FixedLow, x + 5.0, 10.0, 1.0, t);
            let want = bar.eval(x, 0.0, 0.0, t) + 0.5 * slab;
            assert!((uniform.eval(x, 3.3, 0.0, t) - want).abs() < 1e-12);
        }
    }

    fn water_freezing() -> Reference {
        Reference::NeumannFreezing {
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
        }
    }

    /// The Neumann solution satisfies what defines it: T = T_f on both sides of the front and
    /// the Stefan condition λ_f ∂T/∂x|₋ − λ_m ∂T/∂x|₊ = ρ L dX/dt there (central differences
    /// with h = 1e-7 m: truncation ~1e-9 relative; tolerance 1e-5 relative).
    #[test]
    fn neumann_solution_meets_the_stefan_condition() {
        let r = water_freezing();
        let t = 36_000.0;
        let x = super::neumann_front(&r, t).unwrap();
        let h = 1e-7;
        assert!((r.eval(x - 1e-12, 0.0, 0.0, t) - 273.15).abs() < 1e-6);
        assert!((r.eval(x + 1e-12, 0.0, 0.0, t) - 273.15).abs() < 1e-6);
        let gs = (r.eval(x - h, 0.0, 0.0, t) - r.eval(x - 3.0 * h, 0.0, 0.0, t)) / (2.0 * h);
        let gl = (r.eval(x + 3.0 * h, 0.0, 0.0, t) - r.eval(x + h, 0.0, 0.0, t)) / (2.0 * h);
        let lhs = 2.14 * gs - 0.6 * gl;
        let dt = 1.0;
        let v = (super::neumann_front(&r, t + dt).unwrap()
            - super::neumann_front(&r, t - dt).unwrap())
            / (2.0 * dt);
        let rhs = 1000.0 * 333e3 * v;
        assert!((lhs - rhs).abs() < 1e-5 * rhs, "{lhs} vs {rhs}");
        // far away the liquid is untouched, at the face the surface temperature holds
        assert!((r.eval(5.0, 0.0, 0.0, t) - 278.15).abs() < 1e-9);
        assert!((r.eval(0.0, 0.0, 0.0, t) - 263.15).abs() < 1e-12);
    }
}
