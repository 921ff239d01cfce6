//! Phase change: Neumann's solution of planar freezing (theory §6; Carslaw & Jaeger §11.2),
//! the erf profile of the frozen layer behind the front X(t) = 2λ√(α_f t) and the erfc profile
//! of the liquid ahead of it, one density for both phases.

use crate::Reference;
use std::f64::consts::PI;

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
    /// A [`Reference::NeumannFreezing`] at x, t: the erf profile behind the front and the
    /// erfc profile ahead of it, °C.
    pub(crate) fn neumann(&self, x: f64, t: f64) -> f64 {
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
}

#[cfg(test)]
mod tests {
    use super::*;

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
