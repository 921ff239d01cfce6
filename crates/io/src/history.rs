//! Temperature histories: the body nodes nearest a case's `[history]` points, sampled at
//! regular times between the outputs (the steps land on them as on output times), with the
//! analytical reference at the same node and time. Written as `history.csv` beside the
//! fields, summarised in run.json, drawn by the report against time.
//!
//! Contract of `history.csv`: a header `time,point,x,y,z,temperature,reference`, then one row
//! per sample time and point, the times increasing: t = 0, the multiples of the interval up
//! to the last output, and the output times; `reference` is empty when the case has no
//! analytical reference (tables and the FEM are fields at the output times only).

use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use peritherm_analytic::Reference;
use peritherm_core::cloud::Cloud;
use peritherm_core::math::Point;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// File name of the history in a run directory.
pub const FILE: &str = "history.csv";

/// What the report draws from a history.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HistoryPlot {
    /// Temperature against time, °C.
    #[default]
    Temperature,
    /// Temperature against time, and each curve divided by its own largest |θ| (T / T_max).
    Normalised,
}

/// A validated `[history]`: where and when to sample.
#[derive(Debug, Clone, PartialEq)]
pub struct HistorySpec {
    /// The points whose nearest body node is recorded, m.
    pub points: Vec<Point>,
    /// Sample times, s, increasing, each in (0, last output].
    pub times: Vec<f64>,
    /// The report's plot of the history.
    pub plot: HistoryPlot,
}

/// One recorded point of a run, summarised in run.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HistoryPoint {
    /// The recorded node's position (x, y, z), m.
    pub node: [f64; 3],
    /// Largest PD temperature over the samples, °C.
    pub peak: f64,
    /// Time of that peak, s.
    pub peak_time: f64,
    /// Largest reference temperature over the samples, °C (None: no analytical reference).
    pub reference_peak: Option<f64>,
    /// max |θ_pd − θ_ref| over the samples, °C.
    pub max_abs_diff: Option<f64>,
    /// max |θ_pd/max|θ_pd| − θ_ref/max|θ_ref|| over the samples (the normalised curves).
    pub max_abs_diff_normalised: Option<f64>,
}

/// The history block of run.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HistorySummary {
    /// The CSV file, relative to the run directory.
    pub file: String,
    /// Samples per point (t = 0 included).
    pub samples: usize,
    /// One entry per `[history]` point.
    pub points: Vec<HistoryPoint>,
}

/// Collects the samples of a run.
pub struct Recorder<'a> {
    nodes: Vec<usize>,
    reference: Option<&'a Reference>,
    /// Per sample: (t, PD θ per point, reference θ per point).
    rows: Vec<(f64, Vec<f64>, Option<Vec<f64>>)>,
    pos: Vec<Point>,
}

impl<'a> Recorder<'a> {
    /// A recorder of the body nodes of `cloud` nearest the spec's points, with the analytical
    /// `reference` evaluated beside them (None: no reference column).
    pub fn new(spec: &HistorySpec, cloud: &Cloud, reference: Option<&'a Reference>) -> Self {
        let nodes: Vec<usize> = spec
            .points
            .iter()
            .map(|target| {
                (0..cloud.n_body)
                    .min_by(|&a, &b| {
                        let da = (cloud.pos[a] - target).norm();
                        let db = (cloud.pos[b] - target).norm();
                        da.total_cmp(&db)
                    })
                    .unwrap_or(0)
            })
            .collect();
        let pos = nodes.iter().map(|&i| cloud.pos[i]).collect();
        Recorder {
            nodes,
            reference,
            rows: Vec::new(),
            pos,
        }
    }

    /// Records the temperatures `theta` (every node, body first) at time `t`, s.
    pub fn record(&mut self, t: f64, theta: &[f64]) {
        let pd = self.nodes.iter().map(|&i| theta[i]).collect();
        let reference = self
            .reference
            .map(|r| self.pos.iter().map(|p| r.eval(p.x, p.y, p.z, t)).collect());
        self.rows.push((t, pd, reference));
    }

    /// Writes `history.csv` into `dir` and returns the summary for run.json.
    pub fn write(&self, dir: &Path) -> Result<HistorySummary> {
        let mut s = String::from("time,point,x,y,z,temperature,reference\n");
        for (t, pd, reference) in &self.rows {
            for (k, p) in self.pos.iter().enumerate() {
                let r = reference
                    .as_ref()
                    .map(|r| r[k].to_string())
                    .unwrap_or_default();
                let _ = writeln!(s, "{t},{k},{},{},{},{},{r}", p.x, p.y, p.z, pd[k]);
            }
        }
        write_atomic(&dir.join(FILE), s.as_bytes())?;
        let points = (0..self.pos.len()).map(|k| self.summary(k)).collect();
        Ok(HistorySummary {
            file: FILE.into(),
            samples: self.rows.len(),
            points,
        })
    }

    /// The summary of point `k`.
    fn summary(&self, k: usize) -> HistoryPoint {
        let p = self.pos[k];
        let pd: Vec<(f64, f64)> = self.rows.iter().map(|(t, v, _)| (*t, v[k])).collect();
        let (peak_time, peak) =
            pd.iter().copied().fold(
                (0.0, f64::NEG_INFINITY),
                |a, b| if b.1 > a.1 { b } else { a },
            );
        let reference: Option<Vec<f64>> = self
            .rows
            .iter()
            .map(|(_, _, r)| r.as_ref().map(|r| r[k]))
            .collect();
        let compared = reference.map(|r| {
            let v: Vec<f64> = pd.iter().map(|p| p.1).collect();
            let diff = max_abs_diff(&v, &r, 1.0, 1.0);
            let scale = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let (sp, sr) = (scale(&v), scale(&r));
            let normalised = (sp > 0.0 && sr > 0.0).then(|| max_abs_diff(&v, &r, sp, sr));
            (
                r.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                diff,
                normalised,
            )
        });
        HistoryPoint {
            node: [p.x, p.y, p.z],
            peak,
            peak_time,
            reference_peak: compared.map(|c| c.0),
            max_abs_diff: compared.map(|c| c.1),
            max_abs_diff_normalised: compared.and_then(|c| c.2),
        }
    }
}

/// max_i |a_i/sa − b_i/sb|.
fn max_abs_diff(a: &[f64], b: &[f64], sa: f64, sb: f64) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0, |m, (x, y)| f64::max(m, (x / sa - y / sb).abs()))
}

/// One point's curves read back from `history.csv`: (node position, PD (t, θ), reference
/// (t, θ) when recorded).
pub type Curves = (Point, Vec<(f64, f64)>, Option<Vec<(f64, f64)>>);

/// Reads the curves of every point from `dir/history.csv`.
pub fn read(dir: &Path) -> Result<Vec<Curves>> {
    let path = dir.join(FILE);
    let text = std::fs::read_to_string(&path).map_err(|error| Error::Io {
        path: path.clone(),
        error,
    })?;
    let bad = |line: usize, m: &str| Error::Io {
        path: path.clone(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("line {line}: {m}")),
    };
    let mut curves: Vec<Curves> = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() != 7 {
            return Err(bad(n + 1, "expected 7 columns"));
        }
        let num = |c: &str| c.parse::<f64>().map_err(|_| bad(n + 1, "not a number"));
        let k: usize = cols[1].parse().map_err(|_| bad(n + 1, "bad point index"))?;
        let (t, theta) = (num(cols[0])?, num(cols[5])?);
        if k == curves.len() {
            let p = Point::new(num(cols[2])?, num(cols[3])?, num(cols[4])?);
            let reference = (!cols[6].is_empty()).then(Vec::new);
            curves.push((p, Vec::new(), reference));
        } else if k > curves.len() {
            return Err(bad(n + 1, "point index out of order"));
        }
        let c = &mut curves[k];
        c.1.push((t, theta));
        if let Some(r) = c.2.as_mut() {
            r.push((t, num(cols[6])?));
        }
    }
    Ok(curves)
}

/// The sample times k·`interval` ≤ `last` (k ≥ 1), s, or a message when there would be more
/// than `max` of them.
pub fn sample_times(interval: f64, last: f64, max: f64) -> std::result::Result<Vec<f64>, String> {
    let n = (last / interval * (1.0 + 1e-12)).floor();
    if !peritherm_core::limits::within(n, max) {
        return Err(format!(
            "{n:e} samples up to the last output {last} s; at most {max:e} are allowed"
        ));
    }
    Ok((1..=n as usize).map(|k| k as f64 * interval).collect())
}

/// `outputs` and `samples` merged into one increasing list of times, s (a sample within
/// 1e-9 of an output's magnitude is that output).
pub fn merge(outputs: &[f64], samples: &[f64]) -> Vec<f64> {
    let mut all: Vec<f64> = outputs.iter().chain(samples).copied().collect();
    all.sort_by(f64::total_cmp);
    all.dedup_by(|b, a| (*b - *a).abs() <= 1e-9 * a.abs().max(b.abs()));
    // keep the output times exactly
    for t in all.iter_mut() {
        if let Some(o) = outputs
            .iter()
            .find(|o| (*o - *t).abs() <= 1e-9 * o.abs().max(t.abs()))
        {
            *t = *o;
        }
    }
    all
}

/// Index of `t` in `outputs` (within 1e-9 relative), s.
pub fn output_index(outputs: &[f64], t: f64) -> Option<usize> {
    outputs
        .iter()
        .position(|o| (o - t).abs() <= 1e-9 * o.abs().max(t.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples merge with outputs without duplicates, outputs kept exactly.
    #[test]
    fn samples_merge_with_outputs() {
        let s = sample_times(0.1, 0.5, 1e6).unwrap();
        assert_eq!(s.len(), 5);
        let m = merge(&[0.25, 0.3], &s);
        assert_eq!(m.len(), 6, "{m:?}");
        assert!(m.contains(&0.25) && m.contains(&0.3));
        assert_eq!(output_index(&[0.25, 0.3], m[3]), Some(1));
        assert!(sample_times(1e-9, 1.0, 1e6).is_err());
    }
}
