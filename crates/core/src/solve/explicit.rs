//! Explicit time integration: forward Euler (Wang, Oterkus & Oterkus; the axisymmetric phase-change
//! paper, doi:10.1007/s42102-022-00092-3) and classical RK4 (Bobaru & Duangpanya 2010, 2012).
//!
//! The rate of a free body node is `Σ_j K_ij (θ_j − θ_i)/(V_i ρc_i)` plus loads; driven nodes
//! (Dirichlet, flux relations) and fictitious nodes are set by the boundary at every stage.
//! Buffers are allocated once; the bond sum is a parallel gather.

use crate::error::Result;
use crate::model::Model;
use crate::operator::{row_sum, Conductance, ROW_CHUNK};
use crate::stencil::Stencils;
use rayon::prelude::*;
use std::borrow::Cow;

// the integrator and the stepping interface under their old paths
pub use crate::solve::integrator::{choose_dt, count_steps, steps_between, Integrator};
pub use crate::solve::stepper::{check_finite, RunStats};
use crate::solve::stepper::{march, Stepper};

fn rates(model: &Model, k: &Conductance, theta: &[f64], t: f64, out: &mut [f64]) {
    rates_with(model, k, None, theta, t, out);
}

/// [`rates`] through the stencils of K when there are some (the same bits).
fn rates_with(
    model: &Model,
    k: &Conductance,
    stencils: Option<&Stencils>,
    theta: &[f64],
    t: f64,
    out: &mut [f64],
) {
    let inv = &model.inv_heat_capacity;
    let driven = &model.boundary.driven;
    if let Some(st) = stencils {
        st.for_rows(theta, out, |i, s, o| {
            *o = if driven[i] { 0.0 } else { s * inv[i] };
        });
    } else {
        out.par_chunks_mut(ROW_CHUNK)
            .enumerate()
            .for_each(|(c, o)| {
                let first = c * ROW_CHUNK;
                let rows = first..first + o.len();
                let off = &k.offsets[first..=rows.end];
                for ((((o, w), &d), &inv), &ti) in o
                    .iter_mut()
                    .zip(off.windows(2))
                    .zip(&driven[rows.clone()])
                    .zip(&inv[rows.clone()])
                    .zip(&theta[rows])
                {
                    *o = if d {
                        0.0
                    } else {
                        row_sum(&k.cols[w[0]..w[1]], &k.vals[w[0]..w[1]], theta, ti) * inv
                    };
                }
            });
    }
    if model.boundary.has_loads() {
        model
            .boundary
            .add_loads(&model.cloud, &model.capacity, theta, t, out);
        for (o, &d) in out.iter_mut().zip(driven) {
            if d {
                *o = 0.0;
            }
        }
    }
}

/// One fused forward-Euler update of the body nodes, gather form: `next_i = θ_i + h·Σ_j K_ij
/// (θ_j − θ_i)/(V_i ρc_i)` for free nodes, `θ_i` for driven ones (the boundary sets them
/// after). The same bits as [`rates`] followed by `θ_i += h·rate_i`, in one pass; through the
/// stencils of K when there are some.
fn euler_fused(
    model: &Model,
    k: &Conductance,
    stencils: Option<&Stencils>,
    theta: &[f64],
    h: f64,
    next: &mut [f64],
) {
    let inv = &model.inv_heat_capacity;
    let driven = &model.boundary.driven;
    if let Some(st) = stencils {
        st.for_rows(theta, next, |i, s, o| {
            let ti = theta[i];
            *o = if driven[i] { ti } else { ti + h * (s * inv[i]) };
        });
        return;
    }
    next.par_chunks_mut(ROW_CHUNK)
        .enumerate()
        .for_each(|(c, o)| {
            let first = c * ROW_CHUNK;
            let rows = first..first + o.len();
            let off = &k.offsets[first..=rows.end];
            for ((((o, w), &d), &inv), &ti) in o
                .iter_mut()
                .zip(off.windows(2))
                .zip(&driven[rows.clone()])
                .zip(&inv[rows.clone()])
                .zip(&theta[rows])
            {
                *o = if d {
                    ti
                } else {
                    let s = row_sum(&k.cols[w[0]..w[1]], &k.vals[w[0]..w[1]], theta, ti);
                    ti + h * (s * inv)
                };
            }
        });
}

/// Explicit integrator state with preallocated buffers.
pub struct Explicit<'a> {
    model: &'a Model,
    /// K as it is now: the model's, or an owned copy that growing cracks cut in place.
    conductance: Cow<'a, Conductance>,
    /// Index of the next growing-crack cut in `model.growth`.
    next_cut: usize,
    integrator: Integrator,
    k: [Vec<f64>; 4],
    stage: Vec<f64>,
    /// K as shared stencils for the Euler step (lattice clouds without growing cracks).
    stencils: Option<Stencils>,
}

impl<'a> Explicit<'a> {
    /// Allocates the buffers for a model.
    pub fn new(model: &'a Model, integrator: Integrator) -> Self {
        let nb = model.cloud.n_body;
        let stages = match integrator {
            Integrator::Rk4 => 4,
            _ => 1,
        };
        let k = std::array::from_fn(|s| {
            if s < stages {
                vec![0.0; nb]
            } else {
                Vec::new()
            }
        });
        let conductance = if model.growth.is_empty() {
            Cow::Borrowed(&model.conductance)
        } else {
            Cow::Owned(model.conductance.clone())
        };
        Explicit {
            model,
            conductance,
            next_cut: 0,
            integrator,
            k,
            stage: vec![0.0; model.cloud.len()],
            stencils: match integrator {
                Integrator::Euler if model.growth.is_empty() => Stencils::build(&model.conductance),
                _ => None,
            },
        }
    }

    /// Turns the stencils of K ([`crate::stencil`]) on or off for the Euler step and tells
    /// whether they are in use: they exist for Euler without growing cracks on clouds that
    /// repeat rows (lattices). Off forces the plain CSR rows; both give the same bits.
    pub fn set_stencils(&mut self, on: bool) -> bool {
        self.stencils = match (on, self.stencils.take()) {
            (false, _) => None,
            (true, Some(s)) => Some(s),
            (true, None)
                if self.integrator == Integrator::Euler && self.model.growth.is_empty() =>
            {
                Stencils::build(&self.model.conductance)
            }
            (true, None) => None,
        };
        self.stencils.is_some()
    }

    /// Bytes held by the stencils of K (0 without them), B.
    pub fn stencil_bytes(&self) -> usize {
        self.stencils.as_ref().map_or(0, Stencils::bytes)
    }

    /// K as it is now (growing cracks cut it as their tips pass), W/K.
    pub fn conductance(&self) -> &Conductance {
        &self.conductance
    }

    /// Cuts, in place, the pairs whose growing-crack cut time has come by `t`.
    pub fn cut_until(&mut self, t: f64) {
        let cuts = &self.model.growth;
        while self.next_cut < cuts.len() && cuts[self.next_cut].time <= t {
            let c = cuts[self.next_cut];
            let k = self.conductance.to_mut();
            for (row, e) in c.entries.into_iter().flatten() {
                k.diag[row] -= k.vals[e] * (1.0 - c.mu);
                k.vals[e] *= c.mu;
            }
            self.next_cut += 1;
        }
    }

    /// Advances `theta` (all nodes) from t to t + h, constraints included; growing cracks
    /// cut the bonds their tips have passed by t first.
    ///
    /// # Panics
    /// If built with an implicit integrator (those run through [`crate::solve::implicit`];
    /// `run_case` dispatches them there).
    pub fn step(&mut self, theta: &mut [f64], t: f64, h: f64) {
        self.cut_until(t);
        let m = self.model;
        let k = &*self.conductance;
        let nb = m.cloud.n_body;
        match self.integrator {
            Integrator::BackwardEuler
            | Integrator::CrankNicolson
            | Integrator::Bdf2
            | Integrator::Steady => {
                panic!("implicit integrators run through solve::implicit, not Explicit")
            }
            Integrator::Euler if m.boundary.has_loads() => {
                // built from the model's K: not used once something owns a copy of K to change it
                let st = match self.conductance {
                    Cow::Borrowed(_) => self.stencils.as_ref(),
                    Cow::Owned(_) => None,
                };
                rates_with(m, k, st, theta, t, &mut self.k[0]);
                theta[..nb]
                    .par_chunks_mut(ROW_CHUNK)
                    .zip(self.k[0].par_chunks(ROW_CHUNK))
                    .for_each(|(y, r)| {
                        for (y, r) in y.iter_mut().zip(r) {
                            *y += h * r;
                        }
                    });
            }
            Integrator::Euler => {
                // the new body temperatures into k[0], then back into θ (the caller's slice)
                // built from the model's K: not used once something owns a copy of K to change it
                let st = match self.conductance {
                    Cow::Borrowed(_) => self.stencils.as_ref(),
                    Cow::Owned(_) => None,
                };
                euler_fused(m, k, st, theta, h, &mut self.k[0]);
                theta[..nb]
                    .par_chunks_mut(ROW_CHUNK)
                    .zip(self.k[0].par_chunks(ROW_CHUNK))
                    .for_each(|(y, n)| y.copy_from_slice(n));
            }
            Integrator::Rk4 => {
                let [k1, k2, k3, k4] = &mut self.k;
                let stage = &mut self.stage;
                rates(m, k, theta, t, k1);
                stage.copy_from_slice(theta);
                axpy(&mut stage[..nb], &theta[..nb], 0.5 * h, k1);
                m.boundary.apply(&m.cloud, stage, t + 0.5 * h);
                rates(m, k, stage, t + 0.5 * h, k2);
                axpy(&mut stage[..nb], &theta[..nb], 0.5 * h, k2);
                m.boundary.apply(&m.cloud, stage, t + 0.5 * h);
                rates(m, k, stage, t + 0.5 * h, k3);
                axpy(&mut stage[..nb], &theta[..nb], h, k3);
                m.boundary.apply(&m.cloud, stage, t + h);
                rates(m, k, stage, t + h, k4);
                let h6 = h / 6.0;
                theta[..nb]
                    .par_iter_mut()
                    .with_min_len(4096)
                    .enumerate()
                    .for_each(|(i, y)| *y += h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]));
            }
        }
        m.boundary.apply(&m.cloud, theta, t + h);
    }

    /// Integrates from `t0` through each output time, calling `on_output(k, t, θ, K)` there and
    /// `progress(steps)` now and then. Steps never exceed `dt` and land on the output times.
    pub fn run(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        dt: f64,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance) -> Result<()>,
        progress: impl FnMut(u64),
    ) -> Result<RunStats> {
        march(
            self,
            theta,
            t0,
            dt,
            outputs,
            |me, k, t, theta| on_output(k, t, theta, &me.conductance),
            progress,
        )
    }
}

impl Stepper for Explicit<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn begin(&mut self, _theta: &mut [f64], t: f64) {
        self.cut_until(t);
    }
    fn advance(&mut self, theta: &mut [f64], t: f64, _t1: f64, h: f64) -> Result<()> {
        self.step(theta, t, h);
        Ok(())
    }
    fn settle(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        check_finite(theta, self.model.cloud.n_body, t)?;
        self.cut_until(t);
        Ok(())
    }
    fn conductance_now(&mut self) -> &Conductance {
        &self.conductance
    }
}

fn axpy(out: &mut [f64], y: &[f64], a: f64, k: &[f64]) {
    out.par_chunks_mut(ROW_CHUNK)
        .zip(y.par_chunks(ROW_CHUNK))
        .zip(k.par_chunks(ROW_CHUNK))
        .for_each(|((o, y), k)| {
            for ((o, y), k) in o.iter_mut().zip(y).zip(k) {
                *o = y + a * k;
            }
        });
}
