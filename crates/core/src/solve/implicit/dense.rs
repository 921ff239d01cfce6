//! Dense output: the cubic Hermite interpolant of a step, for output times inside it.

use super::adaptive::Past;
use super::Implicit;
use crate::error::{Error, Result};
use crate::operator::Conductance;

impl Implicit<'_> {
    /// Cubic Hermite interpolant at s ∈ [0, 1] of a step of length h from (a, a') to (b, b').
    pub(super) fn hermite(
        a: &[f64],
        da: &[f64],
        b: &[f64],
        db: &[f64],
        h: f64,
        s: f64,
        out: &mut [f64],
    ) {
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10) = (2.0 * s3 - 3.0 * s2 + 1.0, (s3 - 2.0 * s2 + s) * h);
        let (h01, h11) = (3.0 * s2 - 2.0 * s3, (s3 - s2) * h);
        for r in 0..out.len() {
            out[r] = h00 * a[r] + h10 * da[r] + h01 * b[r] + h11 * db[r];
        }
    }

    /// Writes `next` (the interpolated unknowns) into `theta` and sets the constrained nodes
    /// at time t.
    pub(super) fn scatter_from_next(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        std::mem::swap(&mut self.u, &mut self.next);
        let done = self.scatter(theta, t);
        std::mem::swap(&mut self.u, &mut self.next);
        done
    }

    /// Calls `on_output(k, t, θ, K)` for the outputs from `next` on that the accepted step
    /// of length `h` (s) reaching `past.t` covers, with θ from its Hermite interpolant; returns
    /// the next output not reached.
    pub(super) fn dense_outputs<E: From<Error>>(
        &mut self,
        theta: &mut [f64],
        past: &Past,
        h: f64,
        outputs: &[f64],
        mut next: usize,
        on_output: &mut impl FnMut(usize, f64, &[f64], &Conductance) -> std::result::Result<(), E>,
    ) -> std::result::Result<usize, E> {
        while next < outputs.len() && outputs[next] <= past.t + 1e-12 * h {
            let to = outputs[next];
            let s = ((to - past.t_prev) / h).clamp(0.0, 1.0);
            Self::hermite(
                &self.u_prev,
                &self.d_prev,
                &self.u,
                &self.d_now,
                h,
                s,
                &mut self.next,
            );
            self.scatter_from_next(theta, to)?;
            on_output(next, to, theta, &self.model.conductance)?;
            next += 1;
        }
        Ok(next)
    }
}
