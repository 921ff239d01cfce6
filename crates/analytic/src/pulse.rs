//! Pulses (Wang, Oterkus & Oterkus, Thermal diffusion analysis by using dual horizon
//! peridynamics): the bar whose end follows A t e^(−rt) (§4.2, Duhamel's theorem over the sine
//! modes), the metal film heated by a femtosecond laser pulse (§4.4, Qiu & Tien's source: the
//! cosine series of the insulated slab, each mode's time integral in closed form) and the
//! plate with that pulsed edge and a split initial field (§4.5, the Duhamel solution plus a
//! separable product).

use crate::series::{axis_factor, decaying, modes, terms, AxisEnds};
use crate::Reference;
use peritherm_core::math::Point;
use std::f64::consts::PI;

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

    /// A [`Reference::BarPulseLeft`] at x, t: [`pulse_left`] in s = x − x0, °C.
    pub(crate) fn bar_pulse_left(&self, x: f64, t: f64) -> f64 {
        let Reference::BarPulseLeft {
            x0,
            length: l,
            diffusivity: a,
            amplitude: amp,
            rate: r,
        } = *self
        else {
            return f64::NAN;
        };
        pulse_left(x - x0, l, a, amp, r, t)
    }

    /// A [`Reference::PlatePulseSplit`] at x, y, t: the pulse and slab factors of x and the
    /// split factor of y, °C.
    pub(crate) fn plate_pulse_split(&self, x: f64, y: f64, t: f64) -> f64 {
        let (pulse, fx) = self.split_factors_x(x, t);
        pulse + fx * self.split_factor_y(y, t)
    }

    /// [`Reference::eval_many`] of a [`Reference::PlatePulseSplit`] from its factors, each
    /// evaluated once per distinct x and per distinct y (°C); `None` for other references.
    pub(crate) fn eval_separable(&self, points: &[Point], t: f64) -> Option<Vec<f64>> {
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

    /// A [`Reference::FilmLaserPulse`] at x, t (the cosine series of [`LaserPulse`]), °C.
    pub(crate) fn laser_film(&self, x: f64, t: f64) -> f64 {
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

    /// The pulsed bar reproduces its boundary data: the held end follows A t e^(−rt), the far end
    /// is still cold (tolerance from truncation).
    #[test]
    fn bar_pulse_left_meets_its_data() {
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
}
