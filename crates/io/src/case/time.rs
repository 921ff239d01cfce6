//! `[initial]`, `[source]` and `[time]`.

use super::{Ctx, ValueSpec};
use crate::error::Result;
use peritherm_core::expr::Expr;
use peritherm_core::material::{any_phase_change, Material};
use peritherm_core::model::Initial;
use peritherm_core::solve::Integrator;
use serde::Deserialize;

/// `[initial]`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// θ0: number or expression of x, y, z (default 0), °C.
    #[serde(default)]
    pub value: Option<ValueSpec>,
}

/// `[source]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSpec {
    /// s(x, y, z, t), W/m³.
    pub value: ValueSpec,
}

/// `[time]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time, s.
    pub end: f64,
    /// Time step, s (default: 0.95 of the stable bound).
    #[serde(default)]
    pub dt: Option<f64>,
    /// euler, rk4 or an implicit scheme (default rk4; euler with phase change, PCS2022).
    #[serde(default)]
    pub integrator: Option<Integrator>,
    /// Output times, s (default: the end time).
    #[serde(default)]
    pub outputs: Vec<f64>,
    /// Adaptive Δt of the implicit schemes: local error allowed per step, max over the
    /// unknowns, K (default: none, fixed Δt).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Largest adaptive step, s (default: a tenth of the last output time).
    #[serde(default)]
    pub dt_max: Option<f64>,
}

/// The initial field: `[initial]`, or per region when a `[[region]]` gives `initial`
/// (`per_region`), then with a uniform `[initial]` for the others.
pub(super) fn initial(cx: Ctx, spec: &InitialSpec, per_region: &[Option<f64>]) -> Result<Initial> {
    let base = match &spec.value {
        Some(v) => cx.expr(v, "initial.value")?,
        None => Expr::constant(0.0),
    };
    if !base.is_time_independent() {
        return Err(cx.err("initial.value", "must not depend on t"));
    }
    if per_region.iter().all(Option::is_none) {
        return Ok(Initial::Field(base));
    }
    if !base.is_uniform() {
        return Err(cx.err(
            "region.initial",
            "cannot be combined with an [initial] expression of x, y, z",
        ));
    }
    let b0 = base.eval(0.0, 0.0, 0.0, 0.0);
    Ok(Initial::PerRegion(
        per_region.iter().map(|v| v.unwrap_or(b0)).collect(),
    ))
}

impl TimeSpec {
    /// The end time and the output times (default: the end), s: positive, increasing, up to
    /// the end; a positive `dt`.
    pub(super) fn outputs(&self, cx: Ctx) -> Result<(f64, Vec<f64>)> {
        let end = cx.positive("time.end", self.end)?;
        if let Some(dt) = self.dt {
            cx.positive("time.dt", dt)?;
        }
        let mut outputs = self.outputs.clone();
        if outputs.is_empty() {
            outputs.push(end);
        }
        for (k, &t) in outputs.iter().enumerate() {
            if !(t > 0.0 && t <= end * (1.0 + 1e-12)) {
                return Err(cx.err(
                    format!("time.outputs[{k}]"),
                    format!("{t} is not in (0, time.end = {end}]"),
                ));
            }
            if k > 0 && t <= outputs[k - 1] {
                return Err(cx.err(format!("time.outputs[{k}]"), "output times must increase"));
            }
        }
        Ok((end, outputs))
    }

    /// The integrator (default: euler with phase change, else rk4) and its adaptive-step keys:
    /// `tolerance` for a linear implicit scheme, `dt_max` with `tolerance`, `dt` up to `dt_max`.
    pub(super) fn integrator(&self, cx: Ctx, materials: &[Material]) -> Result<Integrator> {
        let phase_change = any_phase_change(materials);
        let integrator = self.integrator.unwrap_or(if phase_change {
            Integrator::Euler
        } else {
            Integrator::Rk4
        });
        if let Some(tol) = self.tolerance {
            cx.positive("time.tolerance", tol)?;
            if !matches!(
                integrator,
                Integrator::BackwardEuler | Integrator::CrankNicolson | Integrator::Bdf2
            ) {
                return Err(cx.err(
                    "time.tolerance",
                    format!(
                        "adaptive steps are an option of backward_euler, crank_nicolson and bdf2, not of {}",
                        integrator.name()
                    ),
                ));
            }
            if phase_change {
                return Err(cx.err(
                    "time.tolerance",
                    "adaptive steps need a linear material; phase change is integrated by euler",
                ));
            }
        }
        if let Some(h) = self.dt_max {
            cx.positive("time.dt_max", h)?;
            if self.tolerance.is_none() {
                return Err(cx.err(
                    "time.dt_max",
                    "bounds adaptive steps only: give time.tolerance too",
                ));
            }
            if let Some(dt) = self.dt.filter(|&dt| dt > h) {
                return Err(cx.err(
                    "time.dt",
                    format!("the first adaptive step {dt} exceeds time.dt_max = {h}"),
                ));
            }
        }
        Ok(integrator)
    }
}
