//! The machinery the series share: how many modes to sum, the decaying sum of a
//! separation-of-variables series of θ_t = α θ_ss, the unit slab held at 0 at both faces
//! (a sine series over the odd modes) and the unit factor of one axis of a box
//! ([`AxisEnds`]), on which the bars, boxes and split plate build.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The two ends of one axis of a [`Reference::BoxFixedFaces`](crate::Reference::BoxFixedFaces).
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

/// Number of series terms so that e^(−α λ_n² t) < e^(−40) beyond, with λ_n = c n.
pub(crate) fn terms(alpha: f64, t: f64, c: f64) -> usize {
    let n = if t > 0.0 {
        (40.0 / (alpha * t)).sqrt() / c
    } else {
        f64::INFINITY
    };
    (n.ceil() as usize + 2).clamp(200, 200_000)
}

/// The modes n = 1, 2, … of a series with λ_n = c n, as many as [`terms`] asks: (n, λ_n), λ in
/// the unit of c.
pub(crate) fn modes(alpha: f64, t: f64, c: f64) -> impl Iterator<Item = (usize, f64)> {
    (1..=terms(alpha, t, c)).map(move |n| (n, c * n as f64))
}

/// The modes n = 1, 2, … of a series with λ_n = c (2n − 1), as many as [`terms`] asks for
/// the spacing 2c: (n, λ_n), λ in the unit of c.
pub(crate) fn odd_modes(alpha: f64, t: f64, c: f64) -> impl Iterator<Item = (usize, f64)> {
    (1..=terms(alpha, t, 2.0 * c)).map(move |n| (n, c * (2 * n - 1) as f64))
}

/// `start + Σ term(n, λ_n) e^(−α λ_n² t)` over the `modes` (n, λ_n), summed in their order:
/// the decaying modes of a separation-of-variables series (α in m²/s, t in s, λ in 1/m).
pub(crate) fn decaying(
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
pub(crate) fn slab(s: f64, l: f64, alpha: f64, t: f64) -> f64 {
    let c = PI / l;
    let odd = (1..=terms(alpha, t, c))
        .step_by(2)
        .map(|m| (m, c * m as f64));
    4.0 / PI * decaying(0.0, alpha, t, odd, |m, lam| (lam * s).sin() / m as f64)
}

/// The unit solution of one axis of a [`Reference::BoxFixedFaces`](crate::Reference::BoxFixedFaces) at s ∈ [0, L] (1 inside
/// at t = 0, 0 on the held faces).
pub(crate) fn axis_factor(ends: AxisEnds, s: f64, l: f64, alpha: f64, t: f64) -> f64 {
    let s = s.clamp(0.0, l);
    match ends {
        AxisEnds::FixedBoth => slab(s, l, alpha, t),
        // the slab [0, 2L] held at both ends is symmetric about L: insulated there
        AxisEnds::FixedLow => slab(s, 2.0 * l, alpha, t),
        AxisEnds::FixedHigh => slab(s + l, 2.0 * l, alpha, t),
        AxisEnds::Insulated => 1.0,
    }
}
