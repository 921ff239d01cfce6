//! Output files: fields as CSV, the run summary as JSON, each written atomically.
//!
//! Contract: for the k-th output time (k from 1), `field_<k>.csv` with the columns
//! `x,y,z,temperature,region,spacing,horizon,volume`, one row per body node; and `run.json`.

use crate::cloud::Cloud;
use crate::error::{Error, Result};
use crate::math::Point;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Writes `bytes` to a temporary file beside `path`, then renames it into place.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial"));
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        error: source,
    };
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Path of the k-th field file (k from 1).
pub fn field_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("field_{k}.csv"))
}

/// CSV text of the body nodes' temperatures.
pub fn field_csv(cloud: &Cloud, theta: &[f64]) -> String {
    let mut s = String::with_capacity(cloud.n_body * 80);
    s.push_str("x,y,z,temperature,region,spacing,horizon,volume\n");
    for (i, (p, t)) in cloud.pos.iter().zip(theta).take(cloud.n_body).enumerate() {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            p.x, p.y, p.z, t, cloud.region[i], cloud.spacing[i], cloud.horizon[i], cloud.volume[i]
        );
    }
    s
}

/// Reads the positions and temperatures of a `field_<k>.csv`.
pub fn read_field(path: &Path) -> Result<(Vec<Point>, Vec<f64>)> {
    let bad = |m: String| Error::Io {
        path: path.to_path_buf(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidData, m),
    };
    let text = std::fs::read_to_string(path).map_err(|error| Error::Io {
        path: path.to_path_buf(),
        error,
    })?;
    let mut lines = text.lines();
    if !lines
        .next()
        .is_some_and(|h| h.starts_with("x,y,z,temperature"))
    {
        return Err(bad(
            "not a peritherm field file (header x,y,z,temperature,...)".into(),
        ));
    }
    let (mut pos, mut theta) = (Vec::new(), Vec::new());
    for (k, line) in lines.enumerate() {
        let v: Vec<f64> = line
            .split(',')
            .take(4)
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| bad(format!("line {}: {e}", k + 2)))?;
        if v.len() < 4 {
            return Err(bad(format!("line {}: fewer than 4 columns", k + 2)));
        }
        pos.push(Point::new(v[0], v[1], v[2]));
        theta.push(v[3]);
    }
    Ok((pos, theta))
}

/// Comparison with a classical solution at one output time (formulation §9).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Comparison {
    /// Output time, s.
    pub time: f64,
    /// max |θ_c − θ_pd| over the body nodes, °C.
    pub max_abs_diff: f64,
    /// Seed 000 eq 45: mean of ((θ_c − θ_pd)/θ_c)² over nodes with θ_c ≠ 0.
    pub mean_sq_rel_diff: f64,
    /// Seed 003 eq 13 along the probe line (all nodes when no line is set).
    pub l2_rel_line: f64,
    /// Seed 001 eq 27: rms difference / max |θ_c|.
    pub epsilon: f64,
    /// Nodes on the probe line.
    pub line_nodes: usize,
    /// The body node nearest to the reference's probe point, if one is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probe: Option<Probe>,
}

/// Temperatures at one node, PD and classical.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Probe {
    /// Node x, m.
    pub x: f64,
    /// Node y, m.
    pub y: f64,
    /// Peridynamic temperature, °C.
    pub peridynamic: f64,
    /// Classical temperature, °C.
    pub classical: f64,
}

/// Summary written to run.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSummary {
    /// Case title.
    pub title: String,
    /// Case file.
    pub case: String,
    /// Body nodes.
    pub nodes: usize,
    /// Fictitious nodes.
    pub fictitious_nodes: usize,
    /// Directed bonds (j in H_i, any node i).
    pub bonds: usize,
    /// Stored pair conductances (nonzeros of K over body rows).
    pub pairs: usize,
    /// Time steps taken.
    pub steps: u64,
    /// Time step, s.
    pub dt: f64,
    /// Stable bound on the step, s.
    pub dt_stable: f64,
    /// Integrator.
    pub integrator: String,
    /// Output times, s.
    pub output_times: Vec<f64>,
    /// Field file names, in output order.
    pub fields: Vec<String>,
    /// Total thermal energy Σ V ρc θ of the body at t = 0, J.
    pub initial_energy: f64,
    /// Total thermal energy at each output time, J.
    pub energy: Vec<f64>,
    /// Seconds to build the model.
    pub setup_seconds: f64,
    /// Seconds of time integration, output writing included, the reference comparison not.
    pub wall_seconds: f64,
    /// Seconds spent evaluating the classical reference.
    #[serde(default)]
    pub reference_seconds: f64,
    /// Rayon threads used.
    pub threads: usize,
    /// Linear-consistency correction: max relative first moment before and after, CG
    /// iterations, and the smallest factor applied to a pair conductance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub consistency: Option<[f64; 4]>,
    /// Comparison with the case's classical reference, per output time.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference: Vec<Comparison>,
}

impl RunSummary {
    /// Reads `dir/run.json`.
    pub fn read(dir: &Path) -> Result<RunSummary> {
        let path = dir.join("run.json");
        let text = std::fs::read_to_string(&path).map_err(|error| Error::Io {
            path: path.clone(),
            error,
        })?;
        serde_json::from_str(&text).map_err(|e| Error::Io {
            path,
            error: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
        })
    }

    /// Markdown rows (one per output time) comparing this run with its reference.
    pub fn table_rows(&self) -> Vec<String> {
        let name = Path::new(&self.case)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        self.reference
            .iter()
            .map(|c| {
                let probe = c
                    .probe
                    .as_ref()
                    .map(|p| format!("{:.3} / {:.3}", p.peridynamic, p.classical))
                    .unwrap_or_else(|| "-".into());
                format!(
                    "| {name} | {} | {} | {:.3e} | {:.3e} | {:.3e} | {probe} | {} | {} | {:.1} |",
                    c.time,
                    self.nodes,
                    c.max_abs_diff,
                    c.mean_sq_rel_diff,
                    c.l2_rel_line,
                    self.bonds,
                    self.steps,
                    self.wall_seconds
                )
            })
            .collect()
    }

    /// Header of [`RunSummary::table_rows`].
    pub fn table_header() -> &'static str {
        "| case | t (s) | nodes | max abs diff (°C) | eq 45 | eq 13 | probe PD / classical (°C) | bonds | steps | wall (s) |\n|---|---|---|---|---|---|---|---|---|---|"
    }

    /// Writes run.json atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let json = serde_json::to_string_pretty(self).expect("plain data serialises");
        write_atomic(&dir.join("run.json"), json.as_bytes())
    }
}
