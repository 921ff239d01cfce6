//! Adaptive Δt: local error estimates per scheme and the step controller on a ladder of
//! rungs (case key `time.tolerance`, theory §4).

use super::linear::Guess;
use super::{Implicit, Scheme, System};
use crate::error::{Error, Result};
use crate::operator::Conductance;
use crate::solve::stepper::RunStats;

/// Adaptive Δt of [`Implicit::run_adaptive`].
#[derive(Debug, Clone, Copy)]
pub struct Adaptive {
    /// Local error estimate allowed per step, max over the unknowns, K.
    pub tolerance: f64,
    /// First step, s (None: tolerance over the largest initial rate |θ'(0)|, or a
    /// ten-thousandth of the last output time if nothing moves at t0).
    pub first: Option<f64>,
    /// Largest step, the top of the ladder, s (None: a tenth of the last output time).
    pub max: Option<f64>,
}

/// Share of the tolerance allowed to the error of a CG solution in adaptive runs.
pub(super) const CG_SHARE: f64 = 1e-3;
/// Safety factor of the step controller (dimensionless).
pub(super) const SAFETY: f64 = 0.9;
/// Accepted steps on a rung before the step may grow to the next (hysteresis).
pub(super) const HYSTERESIS: u32 = 3;
/// Most rungs one accepted step may climb (growth cap 2² = 4).
pub(super) const GROWTH_RUNGS: u32 = 2;
/// Most rungs one rejection may go down (factor 2^−5).
pub(super) const MAX_CUT: u32 = 5;
/// Most halvings of the ladder's top step before the run gives up.
pub(super) const MAX_RUNG: u32 = 60;

/// Where an adaptive run stands: the accepted steps, the time reached and the two before it,
/// s, and the last step, s.
#[derive(Debug, Clone, Copy)]
pub(super) struct Past {
    /// Steps accepted so far.
    pub(super) accepted: u64,
    /// Time reached, s.
    pub(super) t: f64,
    /// Time one accepted step back, s.
    pub(super) t_prev: f64,
    /// Time two accepted steps back, s.
    pub(super) t_prev2: f64,
    /// Length of the last accepted step, s.
    pub(super) h_prev: f64,
}

/// The ladder of steps h_k = h_max·2^(−k), s, and the rung in use.
struct Ladder {
    /// The top step h_max, s.
    top: f64,
    /// The rung in use.
    k: u32,
    /// Steps accepted on it since the last change.
    on_rung: u32,
}

impl Ladder {
    /// The ladder under `top` (s) on its largest rung not above the step `first` (s).
    fn new(top: f64, first: f64) -> Ladder {
        Ladder {
            top,
            k: ((top / first).log2() - 1e-9).ceil().max(0.0) as u32,
            on_rung: 0,
        }
    }

    /// The step of rung `k`, s.
    fn rung(&self, k: u32) -> f64 {
        self.top * 0.5f64.powi(k as i32)
    }

    /// After a rejection: as many rungs down as the ideal step ratio asks (at least one, at
    /// most [`MAX_CUT`]).
    fn descend(&mut self, ideal: f64) {
        self.on_rung = 0;
        let cut = if ideal.is_finite() && ideal > 0.0 {
            (-ideal.log2()).ceil().clamp(1.0, MAX_CUT as f64) as u32
        } else {
            MAX_CUT
        };
        self.k += cut;
    }

    /// After an acceptance: climb whole rungs, one when the ideal step is twice this one and
    /// [`HYSTERESIS`] steps were accepted here, up to [`GROWTH_RUNGS`] at once when it is 4×
    /// or more (BDF2 one at a time, needing two steps on the rung: θ(t − 2h) is then stored).
    fn climb(&mut self, ideal: f64, scheme: Scheme) {
        let (cap, wait) = match scheme {
            Scheme::Bdf2 => (1, if ideal >= 4.0 { 2 } else { HYSTERESIS }),
            _ => (GROWTH_RUNGS, if ideal >= 4.0 { 1 } else { HYSTERESIS }),
        };
        if ideal >= 2.0 && self.on_rung >= wait && self.k > 0 {
            let up = (ideal.log2().floor() as u32).min(cap).min(self.k);
            self.k -= up;
            self.on_rung = 0;
        }
    }
}

impl Implicit<'_> {
    /// θ' = M⁻¹(f − A v) into `out` (K/s).
    pub(super) fn derivative(sys: &System, v: &[f64], f: &[f64], out: &mut [f64], parallel: bool) {
        sys.combine(0.0, 1.0, v, out, parallel);
        for ((o, fr), m) in out.iter_mut().zip(f).zip(&sys.mass) {
            *o = (*o + fr) / m;
        }
    }
    /// One backward-Euler solve `(cM + A)θ = cM·v + f(t1)` into `next`, from v = `next` (which
    /// also starts CG) or else `u`; f(t1) is left in `f_next`.
    pub(super) fn be_into_next(&mut self, t1: f64, c: f64, from_next: bool) -> Result<()> {
        self.forcing_into_next(t1);
        self.rhs_mass(c, from_next);
        let guess = if from_next {
            self.cg[0].copy_from_slice(&self.next);
            Guess::Preset
        } else {
            Guess::U
        };
        self.solve(c, guess)?;
        std::mem::swap(&mut self.next, &mut self.rhs);
        Ok(())
    }

    /// `rhs = c·M·v + f_next` (W) with v = `next` or `u`.
    pub(super) fn rhs_mass(&mut self, c: f64, from_next: bool) {
        let v = if from_next { &self.next } else { &self.u };
        for (((o, vr), m), f) in self
            .rhs
            .iter_mut()
            .zip(v)
            .zip(&self.sys.mass)
            .zip(&self.f_next)
        {
            *o = c * m * vr + f;
        }
    }

    /// One attempted step of length h from (t, u) to t + h; the result goes to `next` and
    /// `d_next` (θ' there), f(t + h) to `f_next`. Returns the local error estimate (K, max
    /// over the unknowns) and the order p it scales with (est ∝ h^(p+1)).
    ///
    /// Estimates: backward Euler `(h/2)·‖θ'ₙ₊₁ − θ'ₙ‖` (its local error h²θ''/2, θ'' by the
    /// difference of the directly evaluated derivatives; Hairer & Wanner, *Solving ODEs II*,
    /// §IV.8); Crank–Nicolson's Rannacher start (two backward-Euler half steps) the same at
    /// half the weight, `(h/4)·‖θ'₁ − θ'₀‖`; Crank–Nicolson the TR–AB2 estimate of Gresho &
    /// Sani (*Incompressible Flow and the FEM*, vol. 1, §3.16.4; Gresho, Griffiths & Silvester,
    /// SIAM J. Sci. Comput. 30, 2008): AB2 predictor θᵖ = θₙ + (hₙ/2)[(2 + hₙ/hₙ₋₁)θ'ₙ −
    /// (hₙ/hₙ₋₁)θ'ₙ₋₁] and dₙ₊₁ = (θₙ₊₁ − θᵖ)/(3(1 + hₙ₋₁/hₙ)), θ' = M⁻¹(f − Aθ) evaluated
    /// directly; BDF2 Milne's device (Hairer, Nørsett & Wanner, *Solving ODEs I*, §III.7;
    /// Brenan, Campbell & Petzold, *DAEs*, §5.2): the quadratic through the last three
    /// accepted values extrapolated to tₙ₊₁ errs by C_p h³θ''', BDF2 by −(2/9)h³θ''', so the
    /// local error is (2/9)/(C_p + 2/9)·‖θₙ₊₁ − θᵖ‖ (2/11 for equal steps).
    ///
    /// BDF2 here has a fixed leading coefficient, `(3/2)θₙ₊₁ − 2θₙ + (1/2)θ(tₙ − h) =
    /// h M⁻¹(f − Aθₙ₊₁)`, with θ(tₙ − h) an accepted value or the Hermite interpolant of the
    /// last step when the step changed (the interpolation strategy of Brenan, Campbell &
    /// Petzold §5.2): its matrix 1.5M/h + A depends on h alone, so each rung of the ladder
    /// has one factorisation.
    pub(super) fn attempt(&mut self, past: &Past, h: f64) -> Result<(f64, u32)> {
        let first = past.accepted == 0;
        match self.scheme {
            Scheme::BackwardEuler | Scheme::Bdf2
                if first || self.scheme == Scheme::BackwardEuler =>
            {
                self.attempt_euler(past.t, h)
            }
            Scheme::CrankNicolson if first => self.attempt_rannacher(past.t, h),
            Scheme::CrankNicolson => self.attempt_cn(past.t, h, past.h_prev),
            // BDF2 (backward Euler took the first arm)
            Scheme::BackwardEuler | Scheme::Bdf2 => self.attempt_bdf2(past, h),
        }
    }

    /// A backward-Euler step with its estimate `(h/2)·‖θ'ₙ₊₁ − θ'ₙ‖` (order 1).
    fn attempt_euler(&mut self, t: f64, h: f64) -> Result<(f64, u32)> {
        let par = self.options.parallel;
        let n = self.u.len();
        let t1 = t + h;
        self.be_into_next(t1, 1.0 / h, false)?;
        Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
        for r in 0..n {
            self.pred[r] = 0.5 * h * (self.d_next[r] - self.d_now[r]);
        }
        Ok((self.estimate(), 1))
    }

    /// Crank–Nicolson's Rannacher start-up: two backward-Euler half steps (the matrix of CN),
    /// estimate `(h/4)·‖θ'₁ − θ'₀‖` (order 1).
    fn attempt_rannacher(&mut self, t: f64, h: f64) -> Result<(f64, u32)> {
        let par = self.options.parallel;
        let n = self.u.len();
        let t1 = t + h;
        self.be_into_next(t + 0.5 * h, 2.0 / h, false)?;
        self.be_into_next(t1, 2.0 / h, true)?;
        Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
        for r in 0..n {
            self.pred[r] = 0.25 * h * (self.d_next[r] - self.d_now[r]);
        }
        Ok((self.estimate(), 1))
    }

    /// A Crank–Nicolson step with the TR–AB2 estimate (order 2).
    fn attempt_cn(&mut self, t: f64, h: f64, h_prev: f64) -> Result<(f64, u32)> {
        let par = self.options.parallel;
        let n = self.u.len();
        let t1 = t + h;
        let w = h / h_prev;
        for r in 0..n {
            self.pred[r] = self.u[r] + 0.5 * h * ((2.0 + w) * self.d_now[r] - w * self.d_prev[r]);
        }
        self.forcing_into_next(t1);
        // (2M/h + A)θₙ₊₁ = (2M/h − A)θₙ + fₙ + fₙ₊₁ = 2M/h θₙ + M θ'ₙ + fₙ₊₁
        for r in 0..n {
            let m = self.sys.mass[r];
            self.rhs[r] = m * (2.0 / h * self.u[r] + self.d_now[r]) + self.f_next[r];
        }
        self.cg[0].copy_from_slice(&self.pred);
        self.solve(2.0 / h, Guess::Preset)?;
        std::mem::swap(&mut self.next, &mut self.rhs);
        Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
        let w = 1.0 / (3.0 * (1.0 + h_prev / h));
        for r in 0..n {
            self.pred[r] = w * (self.next[r] - self.pred[r]);
        }
        Ok((self.estimate(), 2))
    }

    /// A BDF2 step of fixed leading coefficient with Milne's estimate (order 2).
    fn attempt_bdf2(&mut self, past: &Past, h: f64) -> Result<(f64, u32)> {
        let par = self.options.parallel;
        let n = self.u.len();
        let t1 = past.t + h;
        self.bdf2_history(past, h)?;
        let cp = self.bdf2_predictor(past, h);
        self.forcing_into_next(t1);
        for r in 0..n {
            let m = self.sys.mass[r];
            self.rhs[r] = m / h * (2.0 * self.u[r] - 0.5 * self.hist[r]) + self.f_next[r];
        }
        self.cg[0].copy_from_slice(&self.pred);
        self.solve(1.5 / h, Guess::Preset)?;
        std::mem::swap(&mut self.next, &mut self.rhs);
        Self::derivative(&self.sys, &self.next, &self.f_next, &mut self.d_next, par);
        let cc = 2.0 / 9.0;
        let w = cc / (cp + cc);
        for r in 0..n {
            self.pred[r] = w * (self.next[r] - self.pred[r]);
        }
        Ok((self.estimate(), 2))
    }

    /// θ(t − h) into `hist`: an accepted value or the Hermite interpolant of the last step.
    fn bdf2_history(&mut self, past: &Past, h: f64) -> Result<()> {
        let (t, t_prev, t_prev2) = (past.t, past.t_prev, past.t_prev2);
        let back = t - h;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * h;
        if close(back, t_prev) {
            self.hist.copy_from_slice(&self.u_prev);
        } else if past.accepted >= 2 && close(back, t_prev2) {
            self.hist.copy_from_slice(&self.u_prev2);
        } else if back > t_prev {
            Self::hermite(
                &self.u_prev,
                &self.d_prev,
                &self.u,
                &self.d_now,
                t - t_prev,
                (back - t_prev) / (t - t_prev),
                &mut self.hist,
            );
        } else {
            return Err(Error::Solver {
                message: format!(
                    "BDF2 step {h:e} s at t = {t:e} s reaches behind the stored history (internal)"
                ),
            });
        }
        Ok(())
    }

    /// The BDF2 predictor into `pred`: the quadratic through the last three accepted values
    /// (or, after the start, through θ₀, θ'₀ and θ₁), extrapolated to t + h. Returns its error
    /// constant C_p.
    fn bdf2_predictor(&mut self, past: &Past, h: f64) -> f64 {
        let (t, t_prev, t_prev2) = (past.t, past.t_prev, past.t_prev2);
        let n = self.u.len();
        let t1 = t + h;
        if past.accepted >= 2 {
            let (t1r, t2r) = ((t_prev - t) / h, (t_prev2 - t) / h);
            let l0 = (1.0 - t1r) * (1.0 - t2r) / (t1r * t2r);
            let l1 = (1.0 - t2r) / (t1r * (t1r - t2r));
            let l2 = (1.0 - t1r) / (t2r * (t2r - t1r));
            for r in 0..n {
                self.pred[r] = l0 * self.u[r] + l1 * self.u_prev[r] + l2 * self.u_prev2[r];
            }
            (1.0 - t1r) * (1.0 - t2r) / 6.0
        } else {
            let h0 = t - t_prev;
            let x = t1 - t_prev;
            for r in 0..n {
                let a = (self.u[r] - self.u_prev[r] - self.d_prev[r] * h0) / (h0 * h0);
                self.pred[r] = self.u_prev[r] + self.d_prev[r] * x + a * x * x;
            }
            let t0r = (t_prev - t) / h;
            (1.0 - t0r) * (1.0 - t0r) / 6.0
        }
    }

    /// Max norm of the error estimate in `pred` (K).
    pub(super) fn estimate(&self) -> f64 {
        self.pred.iter().fold(0.0, |m: f64, v| m.max(v.abs()))
    }

    /// Integrates from `t0` with steps chosen from a local error estimate (see
    /// `Implicit::attempt`) and calls `on_output(k, t, θ, K)` at each output time with θ there
    /// from the cubic Hermite interpolant of the step that covers it (θ and θ' at both ends:
    /// fourth-order accurate, so the steps need not land on the outputs); `progress(accepted,
    /// t)` after each accepted step.
    ///
    /// **Step control.** Steps are rungs h_k = h_max·2^(−k) of a ladder so that each distinct
    /// matrix cM + A is factorised once and reused (two factorisations cached). A step is
    /// accepted when est ≤ tol; the ideal next step is h·0.9·(tol/est)^(1/(p+1)). On
    /// acceptance the step climbs one rung when that ideal is at least twice the step and 3
    /// steps were accepted on the rung (two rungs after one step when it is 4× or more; BDF2
    /// one rung after two steps); on rejection it drops as many rungs as the ideal asks (at
    /// least one, at most five) and retries from the same state. The first step is the
    /// largest rung not above `first`. The last step may pass the last output time.
    pub fn run_adaptive<E: From<Error>>(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        adaptive: &Adaptive,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> std::result::Result<(), E>,
        mut progress: impl FnMut(u64, f64),
    ) -> std::result::Result<RunStats, E> {
        let tol = adaptive.tolerance;
        if !(tol.is_finite() && tol > 0.0) {
            return Err(Error::model(
                "time.tolerance",
                format!("must be a positive number, got {tol}"),
            )
            .into());
        }
        let Some(&t_last) = outputs.last() else {
            return Ok(RunStats::default());
        };
        let top = adaptive.max.unwrap_or((t_last - t0) / 10.0);
        if !(top.is_finite() && top > 0.0) {
            return Err(Error::model(
                "time.dt_max",
                format!("must be a positive number, got {top}"),
            )
            .into());
        }
        let first = self.begin_adaptive(theta, t0, tol, adaptive.first, t_last)?;
        let mut ladder = Ladder::new(top, first);
        self.stats.tolerance = tol;
        self.stats.min_step = f64::INFINITY;
        let mut past = Past {
            accepted: 0,
            t: t0,
            t_prev: t0,
            t_prev2: t0,
            h_prev: 0.0,
        };
        let mut next_output = 0;
        while next_output < outputs.len() {
            let attempts = past.accepted + self.stats.rejected;
            if attempts as f64 >= crate::limits::MAX_STEPS {
                return Err(Error::model(
                    "time.tolerance",
                    format!(
                        "{attempts} adaptive steps reached t = {:e} s of {t_last} s; at most {:e} are allowed (raise time.tolerance or time.dt_max)",
                        past.t,
                        crate::limits::MAX_STEPS
                    ),
                ).into());
            }
            if ladder.k > MAX_RUNG {
                return Err(Error::Solver {
                    message: format!(
                        "adaptive step fell below {:e} s at t = {:e} s without meeting time.tolerance = {tol:e} K",
                        ladder.rung(MAX_RUNG),
                        past.t
                    ),
                }.into());
            }
            let h = ladder.rung(ladder.k);
            let (est, p) = self.attempt(&past, h)?;
            let ideal = if est > 0.0 {
                SAFETY * (tol / est).powf(1.0 / (p as f64 + 1.0))
            } else {
                f64::INFINITY
            };
            let accepted = est <= tol;
            if !accepted {
                // rejected (or non-finite): drop rungs and retry from the same state
                self.stats.rejected += 1;
                ladder.descend(ideal);
                continue;
            }
            self.accept(&mut past, h);
            ladder.on_rung += 1;
            next_output =
                self.dense_outputs(theta, &past, h, outputs, next_output, &mut on_output)?;
            progress(past.accepted, past.t);
            ladder.climb(ideal, self.scheme);
        }
        self.stats.accepted = past.accepted;
        Ok(RunStats {
            steps: past.accepted,
        })
    }

    /// Sets up an adaptive run from `theta` at `t0` (s): the buffers, the unknowns, f and θ'
    /// there. Returns the first step, s: `first`, or `tol` (K) over the largest initial rate,
    /// or a ten-thousandth of the span to `t_last` (s) if nothing moves.
    fn begin_adaptive(
        &mut self,
        theta: &[f64],
        t0: f64,
        tol: f64,
        first: Option<f64>,
        t_last: f64,
    ) -> Result<f64> {
        let n = self.sys.len();
        self.cg_error = CG_SHARE * tol;
        for v in [
            &mut self.u_prev2,
            &mut self.next,
            &mut self.d_now,
            &mut self.d_prev,
            &mut self.d_next,
            &mut self.pred,
            &mut self.hist,
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
        let par = self.options.parallel;
        self.take_state(theta, t0);
        Self::derivative(&self.sys, &self.u, &self.f_now, &mut self.d_now, par);
        match first {
            Some(h) if h.is_finite() && h > 0.0 => Ok(h),
            Some(h) => Err(Error::model(
                "time.dt",
                format!("must be a positive number, got {h}"),
            )),
            None => {
                let rate = self.d_now.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
                Ok(if rate > 0.0 {
                    tol / rate
                } else {
                    (t_last - t0) * 1e-4
                })
            }
        }
    }

    /// Accepts the attempted step of length `h` (s): shifts the history (θ, θ', f and the
    /// times) and counts it.
    fn accept(&mut self, past: &mut Past, h: f64) {
        std::mem::swap(&mut self.u_prev2, &mut self.u_prev);
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.next);
        std::mem::swap(&mut self.d_prev, &mut self.d_now);
        std::mem::swap(&mut self.d_now, &mut self.d_next);
        std::mem::swap(&mut self.f_now, &mut self.f_next);
        (past.t_prev2, past.t_prev) = (past.t_prev, past.t);
        past.t += h;
        past.h_prev = h;
        past.accepted += 1;
        if past.accepted == 1 {
            self.stats.first_step = h;
        }
        self.stats.min_step = self.stats.min_step.min(h);
        self.stats.max_step = self.stats.max_step.max(h);
    }
}
