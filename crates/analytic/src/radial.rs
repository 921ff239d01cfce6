//! Radial series about the origin: the sphere with its surface held (PCS2022,
//! doi:10.1007/s42102-022-00092-3, §3.2), the disc (a cylinder along z in 3D) with its edge
//! held, on the zeros of J0 (Abramowitz & Stegun 9.5.12), and the steady annulus with both
//! circles held.

use crate::series::{decaying, modes};
use crate::Reference;
use std::f64::consts::PI;

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

impl Reference {
    /// A [`Reference::SphereFixedSurface`] at (x, y, z), t: the radial sine series, °C.
    pub(crate) fn sphere(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
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

    /// A [`Reference::DiscFixedEdge`] at x, y, t: the Bessel series of [`disc`] at
    /// r = √(x² + y²), °C.
    pub(crate) fn disc_fixed_edge(&self, x: f64, y: f64, t: f64) -> f64 {
        let Reference::DiscFixedEdge {
            radius,
            diffusivity: a,
            edge,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        edge + (initial - edge) * disc(x.hypot(y), radius, a, t)
    }

    /// A [`Reference::AnnulusSteady`] at x, y: the logarithmic profile between the circles, °C.
    pub(crate) fn annulus_steady(&self, x: f64, y: f64) -> f64 {
        let Reference::AnnulusSteady {
            inner_radius: ri,
            outer_radius: ro,
            inner,
            outer,
        } = *self
        else {
            return f64::NAN;
        };
        let r = x.hypot(y);
        inner + (outer - inner) * (r / ri).ln() / (ro / ri).ln()
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
}
