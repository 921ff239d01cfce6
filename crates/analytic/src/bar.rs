//! Bars: the 1D series of Bobaru & Duangpanya 2010, both ends held (eq. 33; Wang, Oterkus &
//! Oterkus §4.1), the left end insulated from a two-step initial field (eq. 38) and the left
//! end held with a gradient at the right (eq. 43; Bobaru & Duangpanya 2012, eq. 18 with 0),
//! each written in s = x − x0 along the bar.

use crate::series::{decaying, modes, odd_modes};
use crate::Reference;
use std::f64::consts::PI;

impl Reference {
    /// A [`Reference::BarFixedEnds`] at x, t: the linear steady state plus the sine series
    /// (Bobaru & Duangpanya 2010, eq. 33), °C.
    pub(crate) fn bar_fixed_ends(&self, x: f64, t: f64) -> f64 {
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
    pub(crate) fn bar_insulated_left(&self, x: f64, t: f64) -> f64 {
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
    pub(crate) fn bar_fixed_flux(&self, x: f64, t: f64) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The fixed-flux bar reproduces its initial and boundary data (tolerance from truncation).
    #[test]
    fn bar_fixed_flux_meets_its_data() {
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
    }
}
