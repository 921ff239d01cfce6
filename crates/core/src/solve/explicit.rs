//! Explicit time integration: forward Euler (Wang, Oterkus & Oterkus; PCS2022,
//! doi:10.1007/s42102-022-00092-3) and classical RK4 (Bobaru & Duangpanya 2010, 2012).
//!
//! The rate of a free body node is `Σ_j K_ij (θ_j − θ_i)/(V_i ρc_i)` plus loads; driven nodes
//! (Dirichlet, flux relations) and fictitious nodes are set by the boundary at every stage.
//! Buffers are allocated once; the bond sum is a parallel gather.

use crate::error::Result;
use crate::gather::{ColumnIndex, Columns, Precision, Rows, StepStorage, Values};
use crate::model::Model;
use crate::operator::{Conductance, ROW_CHUNK};
use crate::packed::PackedColumns;
use crate::solve::exchange::Exchange;
use crate::stencil::Stencils;
use rayon::prelude::*;
use std::borrow::Cow;
use std::ops::Range;

// the integrator and the stepping interface under their old paths
pub use crate::solve::integrator::{choose_dt, ExplicitScheme, Integrator};
use crate::solve::stepper::first_non_finite;
pub use crate::solve::stepper::{check_finite, RunStats};
use crate::solve::stepper::{march, Stepper};
pub use crate::solve::steps::{count_steps, steps_between};

/// The rate of every body row of `rows` into `out` (every body node; the other rows are left
/// as they are, or set by the loads), K/s: 0 at driven nodes, the bond sum over the heat
/// capacity plus the loads at free ones.
fn rates(model: &Model, k: Rows, theta: &[f64], t: f64, rows: Range<usize>, out: &mut [f64]) {
    let inv = &model.inv_heat_capacity;
    let driven = &model.boundary.driven;
    let mine = &mut out[rows.clone()];
    k.gather(theta, rows.clone(), driven, mine, |i, s, _, o| {
        *o = if driven[i] { 0.0 } else { s * inv[i] };
    });
    if model.boundary.has_loads() {
        model
            .boundary
            .add_loads(&model.cloud, &model.capacity, theta, t, out);
        for (o, &d) in out[rows.clone()].iter_mut().zip(&driven[rows]) {
            if d {
                *o = 0.0;
            }
        }
    }
}

/// One fused forward-Euler update of the body rows `rows`, gather form: `next_i = θ_i +
/// h·Σ_j K_ij (θ_j − θ_i)/(V_i ρc_i)` for free nodes, `θ_i` for driven ones (the boundary sets
/// them after), into `next` (the rows `rows`). The same bits as [`rates`] followed by
/// `θ_i += h·rate_i`, in one pass.
fn euler_fused(
    model: &Model,
    k: Rows,
    theta: &[f64],
    h: f64,
    rows: Range<usize>,
    next: &mut [f64],
) {
    let inv = &model.inv_heat_capacity;
    let driven = &model.boundary.driven;
    k.gather(theta, rows, driven, next, |i, s, ti, o| {
        *o = if driven[i] { ti } else { ti + h * (s * inv[i]) };
    });
}

/// Explicit integrator state with preallocated buffers.
pub struct Explicit<'a> {
    model: &'a Model,
    /// K as the step reads it.
    bonds: StepBonds<'a>,
    /// Index of the next growing-crack cut in `model.growth`.
    next_cut: usize,
    /// The explicit scheme stepped.
    scheme: ExplicitScheme,
    /// The rates of the scheme's stages (RK4: k1 … k4; Euler: the first only), K/s.
    rates: [Vec<f64>; 4],
    /// The temperatures at an RK4 stage, °C.
    stage: Vec<f64>,
    /// The body rows this stepper computes: all, or a rank's in a distributed run.
    rows: Range<usize>,
    /// The other ranks of a distributed run.
    exchange: Option<&'a dyn Exchange>,
}

/// K as the explicit step reads it: the model's K (or a copy that growing cracks cut), and the
/// storage the case asks for beside it.
struct StepBonds<'a> {
    /// K as it is now: the model's, or an owned copy that growing cracks cut in place.
    conductance: Cow<'a, Conductance>,
    /// K as shared stencils for the Euler step (lattice clouds without growing cracks, K in f64).
    stencils: Option<Stencils>,
    /// The columns of the rows stepped, packed (`kernel.columns = "packed"`, no stencils).
    packed: Option<Box<PackedColumns>>,
    /// K's values rounded to f32 (`kernel.precision = "f32"`), W/K.
    rounded: Option<Vec<f32>>,
    /// The column index and precision asked for.
    storage: StepStorage,
}

impl StepBonds<'_> {
    /// The storage the step reads: the stencils while K is the model's, else K's rows with
    /// the column index and the precision asked for.
    fn rows(&self) -> Rows<'_> {
        if let (Cow::Borrowed(_), Some(st)) = (&self.conductance, &self.stencils) {
            return Rows::Stencils(st);
        }
        let columns = match &self.packed {
            Some(p) => Columns::Packed(p),
            None => Columns::Csr(&self.conductance),
        };
        let values = match &self.rounded {
            Some(v) => Values::F32(v),
            None => Values::F64(&self.conductance.vals),
        };
        Rows::Bonds(columns, values)
    }

    /// Packs the columns of `rows` as the storage asks (none where stencils hold K); depends
    /// on the rows stepped and on the stencils.
    fn pack_columns(&mut self, rows: Range<usize>) {
        let asked = self.storage.columns == ColumnIndex::Packed && self.stencils.is_none();
        self.packed = match asked {
            true => PackedColumns::build(&self.conductance, rows).map(Box::new),
            false => None,
        };
    }

    /// Rounds K's values to f32 where the storage asks for it; depends on the precision only.
    fn round_values(&mut self) {
        let f32 = self.storage.precision == Precision::F32;
        self.rounded = f32.then(|| self.conductance.vals.iter().map(|&v| v as f32).collect());
    }
}

/// The stencils of K for `scheme` on `model`: built for Euler without growing cracks, when
/// the cloud repeats rows (lattices); None otherwise.
fn stencils_for(model: &Model, scheme: ExplicitScheme, precision: Precision) -> Option<Stencils> {
    match scheme {
        ExplicitScheme::Euler if model.growth.is_empty() && precision == Precision::F64 => {
            Stencils::build(&model.conductance)
        }
        _ => None,
    }
}

impl<'a> Explicit<'a> {
    /// Allocates the buffers for a model.
    pub fn new(model: &'a Model, scheme: ExplicitScheme) -> Self {
        let nb = model.cloud.n_body;
        let stages = match scheme {
            ExplicitScheme::Rk4 => 4,
            ExplicitScheme::Euler => 1,
        };
        let rates = std::array::from_fn(|s| {
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
        let mut bonds = StepBonds {
            conductance,
            stencils: stencils_for(model, scheme, model.step.precision),
            packed: None,
            rounded: None,
            storage: model.step,
        };
        bonds.pack_columns(0..nb);
        bonds.round_values();
        Explicit {
            model,
            bonds,
            next_cut: 0,
            scheme,
            rates,
            stage: vec![0.0; model.cloud.len()],
            rows: 0..nb,
            exchange: None,
        }
    }

    /// Makes this stepper one rank of a distributed run: it computes the rows of
    /// `exchange` and fills its ghosts from the other ranks before every boundary
    /// application; at outputs ([`Stepper::settle`]) every rank holds the whole field. The
    /// temperatures have the same bits as a serial run's (each row keeps its order).
    pub fn distribute(&mut self, exchange: &'a dyn Exchange) {
        self.rows = exchange.rows();
        self.exchange = Some(exchange);
        self.bonds.pack_columns(self.rows.clone());
    }

    /// Turns the stencils of K ([`crate::stencil`]) on or off for the Euler step and tells
    /// whether they are in use: they exist for Euler without growing cracks on clouds that
    /// repeat rows (lattices). Off forces the plain CSR rows; both give the same bits.
    pub fn set_stencils(&mut self, on: bool) -> bool {
        let b = &mut self.bonds;
        b.stencils = match (on, b.stencils.take()) {
            (false, _) => None,
            (true, Some(s)) => Some(s),
            (true, None) => stencils_for(self.model, self.scheme, b.storage.precision),
        };
        b.pack_columns(self.rows.clone());
        b.stencils.is_some()
    }

    /// Reads K with the column index and precision of `storage` instead of the model's (the
    /// stencils, where they exist, are kept for f64 and dropped for f32).
    pub fn set_storage(&mut self, storage: StepStorage) {
        self.bonds.storage = storage;
        if storage.precision == Precision::F32 {
            self.bonds.stencils = None;
        }
        self.bonds.pack_columns(self.rows.clone());
        self.bonds.round_values();
    }

    /// Bytes held by the stencils of K (0 without them), B.
    pub fn stencil_bytes(&self) -> usize {
        self.bonds.stencils.as_ref().map_or(0, Stencils::bytes)
    }

    /// Bytes held beside K by the packed columns and the rounded values (0 without them), B.
    pub fn storage_bytes(&self) -> usize {
        let b = &self.bonds;
        b.packed.as_ref().map_or(0, |p| p.bytes())
            + b.rounded.as_ref().map_or(0, |v| v.capacity() * 4)
    }

    /// K as it is now (growing cracks cut it as their tips pass), W/K.
    pub fn conductance(&self) -> &Conductance {
        &self.bonds.conductance
    }

    /// Cuts, in place, the pairs whose growing-crack cut time has come by `t`.
    pub fn cut_until(&mut self, t: f64) {
        let cuts = &self.model.growth;
        while self.next_cut < cuts.len() && cuts[self.next_cut].time <= t {
            let c = cuts[self.next_cut];
            let b = &mut self.bonds;
            let k = b.conductance.to_mut();
            for (row, e) in c.entries.into_iter().flatten() {
                k.diag[row] -= k.vals[e] * (1.0 - c.mu);
                k.vals[e] *= c.mu;
                if let Some(r) = &mut b.rounded {
                    r[e] = k.vals[e] as f32;
                }
            }
            self.next_cut += 1;
        }
    }

    /// Advances `theta` (all nodes) from t to t + h, constraints included; growing cracks
    /// cut the bonds their tips have passed by t first.
    pub fn step(&mut self, theta: &mut [f64], t: f64, h: f64) {
        self.cut_until(t);
        let m = self.model;
        let rows = self.rows.clone();
        // the stencils are built from the model's K: not used once a copy of K is cut
        let k = self.bonds.rows();
        let out = &mut self.rates[0];
        match self.scheme {
            ExplicitScheme::Euler if m.boundary.has_loads() => {
                rates(m, k, theta, t, rows.clone(), out);
                update(&mut theta[rows.clone()], &out[rows], |y, r| *y += h * r);
            }
            ExplicitScheme::Euler => {
                // the new body temperatures into the rate buffer, then back into θ
                euler_fused(m, k, theta, h, rows.clone(), &mut out[rows.clone()]);
                update(&mut theta[rows.clone()], &out[rows], |y, n| *y = n);
            }
            ExplicitScheme::Rk4 => self.rk4(theta, t, h),
        }
        constrain(m, self.exchange, theta, t + h);
    }

    /// One classical RK4 step of the rows of this stepper (the constraints set at each stage).
    fn rk4(&mut self, theta: &mut [f64], t: f64, h: f64) {
        let (m, k, ex) = (self.model, self.bonds.rows(), self.exchange);
        let r = self.rows.clone();
        let [k1, k2, k3, k4] = &mut self.rates;
        let stage = &mut self.stage;
        rates(m, k, theta, t, r.clone(), k1);
        stage.copy_from_slice(theta);
        axpy(stage, theta, 0.5 * h, k1, r.clone());
        constrain(m, ex, stage, t + 0.5 * h);
        rates(m, k, stage, t + 0.5 * h, r.clone(), k2);
        axpy(stage, theta, 0.5 * h, k2, r.clone());
        constrain(m, ex, stage, t + 0.5 * h);
        rates(m, k, stage, t + 0.5 * h, r.clone(), k3);
        axpy(stage, theta, h, k3, r.clone());
        constrain(m, ex, stage, t + h);
        rates(m, k, stage, t + h, r.clone(), k4);
        let h6 = h / 6.0;
        theta[r.clone()]
            .par_iter_mut()
            .with_min_len(4096)
            .zip(&k1[r.clone()])
            .zip(&k2[r.clone()])
            .zip(&k3[r.clone()])
            .zip(&k4[r])
            .for_each(|((((y, a), b), c), d)| *y += h6 * (a + 2.0 * (b + c) + d));
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
            |me, k, t, theta| on_output(k, t, theta, &me.bonds.conductance),
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
    fn check(&self, theta: &[f64], t: f64) -> Result<()> {
        first_non_finite(theta, self.rows.clone(), self.exchange, t)
    }
    fn settle(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        if let Some(ex) = self.exchange {
            // every rank takes the whole field: the output, energy and NaN check are serial's
            ex.all_gather(theta);
        }
        check_finite(theta, self.model.cloud.n_body, t)?;
        self.cut_until(t);
        Ok(())
    }
    fn conductance_now(&mut self) -> &Conductance {
        &self.bonds.conductance
    }
}

/// Fills the ghosts of `theta` (distributed runs), then sets its constrained and fictitious
/// nodes at `t` (s).
fn constrain(model: &Model, exchange: Option<&dyn Exchange>, theta: &mut [f64], t: f64) {
    if let Some(ex) = exchange {
        ex.halo(theta);
    }
    model.boundary.apply(&model.cloud, theta, t);
}

/// `f(y_i, x_i)` for every entry, in parallel tasks of [`ROW_CHUNK`].
fn update(y: &mut [f64], x: &[f64], f: impl Fn(&mut f64, f64) + Sync) {
    y.par_chunks_mut(ROW_CHUNK)
        .zip(x.par_chunks(ROW_CHUNK))
        .for_each(|(y, x)| {
            for (y, &x) in y.iter_mut().zip(x) {
                f(y, x);
            }
        });
}

/// `out_i = y_i + a·k_i` for the rows `rows`, in parallel tasks of [`ROW_CHUNK`].
fn axpy(out: &mut [f64], y: &[f64], a: f64, k: &[f64], rows: Range<usize>) {
    out[rows.clone()]
        .par_chunks_mut(ROW_CHUNK)
        .zip(y[rows.clone()].par_chunks(ROW_CHUNK))
        .zip(k[rows].par_chunks(ROW_CHUNK))
        .for_each(|((o, y), k)| {
            for ((o, y), k) in o.iter_mut().zip(y).zip(k) {
                *o = y + a * k;
            }
        });
}
