//! Forward Euler in enthalpy form, for models with phase change (PCS2022,
//! doi:10.1007/s42102-022-00092-3, eqs. 3 and 24, theory §6).
//!
//! Each body node carries its enthalpy per unit volume H_i and θ_i = T(H_i). The step is
//! `V_i (H_i' − H_i)/Δt = Σ_j λ̄_ij K_ij (θ_j − θ_i) + V_i s_i`, with K the model's pair
//! conductance for unit conductivity and λ̄_ij the bond rule's mean of the two nodes' λ(H)
//! (harmonic by default, PCS2022, eq. 5). λ̄ is symmetric, so energy Σ
//! V_i H_i is conserved by the bond sum. Buffers are allocated once; the bond sum is a parallel
//! gather.

use crate::error::{Error, Result};
use crate::material::Enthalpy;
use crate::model::Model;
use crate::operator::Conductance;
use crate::solve::exchange::Exchange;
use crate::solve::integrator::Integrator;
use crate::solve::stepper::{check_finite, first_non_finite, march, RunStats, Stepper};
use rayon::prelude::*;
use std::ops::Range;

/// Enthalpy-form explicit integrator state with preallocated buffers.
pub struct Enthalpic<'a> {
    model: &'a Model,
    /// Enthalpy relation of every material.
    relation: &'a [Enthalpy],
    /// Enthalpy per unit volume of the body nodes, J/m³.
    h: Vec<f64>,
    /// Conductivity of every node as the state is now, W/(m·K).
    lambda: Vec<f64>,
    /// Enthalpy rate of the body nodes, W/m³.
    rate: Vec<f64>,
    /// Unit capacities, so that the boundary's loads come out in W/m³.
    unit: Vec<f64>,
    /// K with the conductivities of the last output, W/K (for the heat flux).
    scaled: Conductance,
    /// Whether `h` and `lambda` have been set from a temperature field.
    ready: bool,
    /// The body rows this stepper computes (all of them, or one rank's).
    rows: Range<usize>,
    /// The other ranks of a distributed run.
    exchange: Option<&'a dyn Exchange>,
}

impl<'a> Enthalpic<'a> {
    /// Allocates the buffers for a model with phase change integrated by `integrator`.
    pub fn new(model: &'a Model, integrator: Integrator) -> Result<Self> {
        let Some(relation) = model.enthalpy.as_deref() else {
            return Err(Error::model(
                "material",
                "no material changes phase: use the linear explicit integrator",
            ));
        };
        if integrator != Integrator::Euler {
            return Err(Error::model(
                "time.integrator",
                format!(
                    "phase change runs with forward Euler (the axisymmetric phase-change paper, eq. 24), not {}",
                    integrator.name()
                ),
            ));
        }
        if !model.growth.is_empty() {
            return Err(Error::model(
                "crack",
                "growing cracks are not supported together with phase change",
            ));
        }
        let nb = model.cloud.n_body;
        Ok(Enthalpic {
            model,
            relation,
            h: vec![0.0; nb],
            lambda: vec![0.0; model.cloud.len()],
            rate: vec![0.0; nb],
            unit: vec![1.0; nb],
            scaled: model.conductance.clone(),
            ready: false,
            rows: 0..nb,
            exchange: None,
        })
    }

    /// Makes this stepper one rank of a distributed run: it computes the rows of `exchange`
    /// and, before every boundary application, receives the enthalpies of its ghosts (their
    /// temperatures and conductivities follow from them); at outputs every rank holds every
    /// node's state. The bits are a serial run's (each row keeps its order).
    pub fn distribute(&mut self, exchange: &'a dyn Exchange) {
        self.rows = exchange.rows();
        self.exchange = Some(exchange);
    }

    /// Receives the enthalpies of the ghosts and sets their temperatures and conductivities
    /// from them (driven ghosts are set by the boundary, as their owners set them).
    fn fill_ghosts(&mut self, theta: &mut [f64]) {
        let Some(ex) = self.exchange else {
            return;
        };
        ex.halo(&mut self.h);
        let (m, relation) = (self.model, self.relation);
        for (_, nodes) in &ex.plan().halo.recv {
            for &j in nodes {
                let j = j as usize;
                if !m.boundary.driven[j] {
                    let e = &relation[m.cloud.material[j] as usize];
                    theta[j] = e.temperature(self.h[j]);
                    self.lambda[j] = e.conductivity(self.h[j]);
                }
            }
        }
    }

    /// Every rank takes every node's state (θ, H and λ) from their owners (a distributed run).
    fn gather(&mut self, theta: &mut [f64]) {
        let Some(ex) = self.exchange else {
            return;
        };
        ex.all_gather(theta);
        let nb = self.h.len();
        let mut all = vec![0.0; theta.len()];
        all[..nb].copy_from_slice(&self.h);
        ex.all_gather(&mut all);
        self.h.copy_from_slice(&all[..nb]);
        let (relation, material) = (self.relation, &self.model.cloud.material);
        for (i, (l, &th)) in self.lambda.iter_mut().zip(theta.iter()).enumerate() {
            let e = &relation[material[i] as usize];
            *l = match i < nb {
                true => e.conductivity(self.h[i]),
                false => e.conductivity(e.enthalpy(th)),
            };
        }
    }

    fn of(&self, i: usize) -> &Enthalpy {
        &self.relation[self.model.cloud.material[i] as usize]
    }

    /// Enthalpy per unit volume of the body nodes, J/m³.
    pub fn enthalpy(&self) -> &[f64] {
        &self.h
    }

    /// Total enthalpy of the body, Σ V_i H_i, J (relative to H = 0).
    pub fn energy(&self) -> f64 {
        self.h
            .iter()
            .zip(&self.model.cloud.volume)
            .map(|(h, v)| h * v)
            .sum()
    }

    /// Melted fraction of every body node (0 frozen … 1 melted).
    pub fn melted_fraction(&self) -> Vec<f64> {
        (0..self.h.len())
            .map(|i| self.of(i).melted_fraction(self.h[i]))
            .collect()
    }

    /// Applies the boundary at `t` with the current conductivities and brings H of driven
    /// nodes and λ of driven and fictitious nodes in line with their new temperatures.
    fn constrain(&mut self, theta: &mut [f64], t: f64) {
        let m = self.model;
        m.boundary
            .apply_with(&m.cloud, theta, t, Some(&self.lambda));
        let relation = self.relation;
        let material = &m.cloud.material;
        for (i, (&th, l)) in theta.iter().zip(self.lambda.iter_mut()).enumerate() {
            let e = &relation[material[i] as usize];
            if i >= m.cloud.n_body {
                *l = e.conductivity(e.enthalpy(th));
            } else if m.boundary.driven[i] {
                self.h[i] = e.enthalpy(th);
                *l = e.conductivity(self.h[i]);
            }
        }
    }

    /// Sets H and λ from the temperature field `theta` (all nodes) at time `t`.
    fn start(&mut self, theta: &mut [f64], t: f64) {
        let (relation, material) = (self.relation, &self.model.cloud.material);
        for (i, (h, l)) in self.h.iter_mut().zip(self.lambda.iter_mut()).enumerate() {
            let e = &relation[material[i] as usize];
            *h = e.enthalpy(theta[i]);
            *l = e.conductivity(*h);
        }
        self.constrain(theta, t);
        self.ready = true;
    }

    /// Advances `theta` (all nodes) and the enthalpies from t to t + h, constraints included.
    /// The first call takes the enthalpies from `theta`.
    pub fn step(&mut self, theta: &mut [f64], t: f64, h: f64) {
        if !self.ready {
            self.start(theta, t);
        }
        let m = self.model;
        let k = &m.conductance;
        let rule = m.bond_rule;
        let (lambda, driven, volume) = (&self.lambda, &m.boundary.driven, &m.cloud.volume);
        let th: &[f64] = theta;
        let rows = self.rows.clone();
        self.rate[rows.clone()]
            .par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(r0, r)| {
                let i = rows.start + r0;
                *r = if driven[i] {
                    0.0
                } else {
                    let (ti, li) = (th[i], lambda[i]);
                    let row = k.offsets[i]..k.offsets[i + 1];
                    let mut s = 0.0;
                    for (&j, &kij) in k.cols[row.clone()].iter().zip(&k.vals[row]) {
                        let j = j as usize;
                        s += kij * rule.combine(li, lambda[j]) * (th[j] - ti);
                    }
                    s / volume[i]
                };
            });
        if m.boundary.has_loads() {
            m.boundary
                .add_loads(&m.cloud, &self.unit, theta, t, &mut self.rate);
        }
        let relation = self.relation;
        let material = &m.cloud.material;
        theta[rows.clone()]
            .par_iter_mut()
            .with_min_len(4096)
            .zip(self.h[rows.clone()].par_iter_mut())
            .zip(self.lambda[rows.clone()].par_iter_mut())
            .zip(&self.rate[rows.clone()])
            .enumerate()
            .for_each(|(r0, (((y, hi), li), r))| {
                let i = rows.start + r0;
                if !driven[i] {
                    let e = &relation[material[i] as usize];
                    *hi += h * r;
                    *y = e.temperature(*hi);
                    *li = e.conductivity(*hi);
                }
            });
        self.fill_ghosts(theta);
        self.constrain(theta, t + h);
    }

    /// K with the current conductivities, K_ij = λ̄_ij K_ij(λ = 1), W/K.
    pub fn scale_conductance(&mut self) {
        let k = &self.model.conductance;
        let rule = self.model.bond_rule;
        for i in 0..k.n_rows() {
            let mut d = 0.0;
            for e in k.offsets[i]..k.offsets[i + 1] {
                let j = k.cols[e] as usize;
                let v = k.vals[e] * rule.combine(self.lambda[i], self.lambda[j]);
                self.scaled.vals[e] = v;
                d += v;
            }
            self.scaled.diag[i] = d;
        }
    }

    /// K as last set by `scale_conductance`, W/K.
    pub fn scaled(&self) -> &Conductance {
        &self.scaled
    }

    /// Takes the enthalpies from `theta` at `t` now unless they were (as the first step would).
    pub fn prime(&mut self, theta: &mut [f64], t: f64) {
        if !self.ready {
            self.start(theta, t);
        }
    }

    /// Makes the next step take the enthalpies from the temperature field again.
    pub fn restart(&mut self) {
        self.ready = false;
    }

    /// Integrates from `t0` through each output time, calling `on_output(k, t, θ, K, E)` there
    /// (K with the conductivities of that moment, E = Σ V_i H_i in J) and `progress(steps)` now
    /// and then. Steps never exceed `dt` and land on the output times.
    pub fn run(
        &mut self,
        theta: &mut [f64],
        t0: f64,
        dt: f64,
        outputs: &[f64],
        mut on_output: impl FnMut(usize, f64, &[f64], &Conductance, f64) -> Result<()>,
        progress: impl FnMut(u64),
    ) -> Result<RunStats> {
        if !self.ready {
            self.start(theta, t0);
        }
        march(
            self,
            theta,
            t0,
            dt,
            outputs,
            |me, k, t, theta| {
                me.scale_conductance();
                let energy = me.energy();
                on_output(k, t, theta, &me.scaled, energy)
            },
            progress,
        )
    }
}

impl Stepper for Enthalpic<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn begin(&mut self, theta: &mut [f64], t: f64) {
        self.start(theta, t);
    }
    fn advance(&mut self, theta: &mut [f64], t: f64, _t1: f64, h: f64) -> Result<()> {
        self.step(theta, t, h);
        Ok(())
    }
    fn check(&self, theta: &[f64], t: f64) -> Result<()> {
        first_non_finite(theta, self.rows.clone(), self.exchange, t)
    }
    fn settle(&mut self, theta: &mut [f64], t: f64) -> Result<()> {
        self.gather(theta);
        check_finite(theta, self.model.cloud.n_body, t)
    }
    fn conductance_now(&mut self) -> &Conductance {
        self.scale_conductance();
        &self.scaled
    }
    fn energy_now(&self, theta: &[f64]) -> f64 {
        if self.ready {
            self.energy()
        } else {
            self.model.energy(theta)
        }
    }
}
