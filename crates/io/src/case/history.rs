//! `[history]`: temperature histories at points.

use super::Ctx;
use crate::error::Result;
use crate::history::{HistoryPlot, HistorySpec};
use peritherm_core::limits::{MAX_HISTORY_POINTS, MAX_HISTORY_ROWS};
use peritherm_core::solve::Integrator;
use serde::Deserialize;

/// `[history]` as written: points sampled at a regular interval up to the last output.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HistorySection {
    /// Points whose nearest body node is recorded, m (one coordinate per dimension each).
    pub points: Vec<Vec<f64>>,
    /// Sampling interval, s.
    pub interval: f64,
    /// The report's plot: `temperature` (default) or `normalised` (also T / T_max).
    #[serde(default)]
    pub plot: HistoryPlot,
}

impl HistorySection {
    /// Validates `[history]`: a transient integrator, at least one point inside the case's
    /// dimension, a positive interval giving at most [`MAX_HISTORY_ROWS`] rows.
    pub(super) fn validate(
        self,
        cx: Ctx,
        dim: usize,
        outputs: &[f64],
        integrator: Integrator,
    ) -> Result<HistorySpec> {
        if integrator == Integrator::Steady {
            return Err(cx.err(
                "history",
                "a steady solve has no history; use a transient integrator",
            ));
        }
        if self.points.is_empty() || self.points.len() > MAX_HISTORY_POINTS {
            return Err(cx.err(
                "history.points",
                format!(
                    "give 1 to {MAX_HISTORY_POINTS} points, got {}",
                    self.points.len()
                ),
            ));
        }
        let mut points = Vec::new();
        for (k, p) in self.points.iter().enumerate() {
            points.push(cx.point(dim, p, &format!("history.points[{k}]"))?);
        }
        let interval = cx.positive("history.interval", self.interval)?;
        let last = outputs.last().copied().unwrap_or(interval);
        let max = MAX_HISTORY_ROWS / points.len() as f64;
        let times = crate::history::sample_times(interval, last, max)
            .map_err(|m| cx.err("history.interval", m))?;
        Ok(HistorySpec {
            points,
            times,
            plot: self.plot,
        })
    }
}
