//! Step counts of a fixed step between output times: arithmetic that the integrators, the
//! stepping interface and the run loop share.

/// Steps from `t` to `to` (s) when no step may exceed `dt` (s); a relative 1e-12 slack keeps
/// round-off from adding a step.
pub fn steps_between(t: f64, to: f64, dt: f64) -> u64 {
    ((to - t) / dt * (1.0 - 1e-12)).ceil().max(0.0) as u64
}

/// Number of steps from `t0` to each output time (s) with steps no longer than `dt` (s).
pub fn count_steps(t0: f64, outputs: &[f64], dt: f64) -> u64 {
    let mut t = t0;
    let mut n = 0;
    for &to in outputs {
        n += steps_between(t, to, dt);
        t = to;
    }
    n
}
