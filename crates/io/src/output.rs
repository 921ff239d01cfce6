//! Output files: fields as CSV, the run summary as JSON, each written atomically.
//!
//! Contract: for the k-th output time (k from 1), `field_<k>.csv` with the columns
//! `x,y,z,temperature,region,spacing,horizon,volume,damage,qx,qy,qz`, one row per body
//! node, and the same fields as a VTK unstructured grid `field_<k>.vtu` (a distributed run:
//! `field_<k>.pvtu` over one piece per rank, `field_<k>/piece_<r>.vtu`), all listed with their
//! times in `fields.pvd`; and `run.json`.
//! A case with a `[history]` also writes `history.csv` ([`crate::history`]); every run
//! (also one that fails or is interrupted) writes `case.toml`, the text of its case
//! ([`crate::provenance`]).

use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use peritherm_core::cloud::Cloud;
use peritherm_core::math::{Point, Vector};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A time (s) or coordinate (m) as tables, legends and file names show it: plainly (`0.5`,
/// `0.00005`), or in exponent form below 1e-6 (`2e-13`, where the plain form is a row of
/// zeros).
pub fn number_label(t: f64) -> String {
    if t != 0.0 && t.abs() < 1e-6 {
        format!("{t:e}")
    } else {
        format!("{t}")
    }
}

/// Path of the k-th field file (k from 1).
pub fn field_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("field_{k}.csv"))
}

/// Path of the k-th VTK file (k from 1).
pub fn vtu_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("field_{k}.vtu"))
}

/// One output time's body fields: temperature and what is derived from it.
pub struct Fields<'a> {
    /// Temperature of every node (body first), °C.
    pub theta: &'a [f64],
    /// Damage φ per body node (theory §5).
    pub damage: &'a [f64],
    /// Peridynamic heat flux per body node (theory §8), W/m².
    pub flux: &'a [Vector],
    /// The case's classical reference at each body node, °C, if it has one.
    pub reference: Option<&'a [f64]>,
}

/// CSV text of the body nodes, written to `s`: position, temperature, region, spacing,
/// horizon, volume, damage and heat flux, and the classical reference when the case has one.
pub fn field_csv(s: &mut dyn Write, cloud: &Cloud, f: &Fields) -> std::io::Result<()> {
    s.write_all("x,y,z,temperature,region,spacing,horizon,volume,damage,qx,qy,qz".as_bytes())?;
    s.write_all(if f.reference.is_some() {
        b",reference\n"
    } else {
        b"\n"
    })?;
    for i in 0..cloud.n_body {
        let (p, q) = (cloud.pos[i], f.flux[i]);
        write!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{}",
            p.x,
            p.y,
            p.z,
            f.theta[i],
            cloud.region[i],
            cloud.spacing[i],
            cloud.horizon[i],
            cloud.volume[i],
            f.damage[i],
            q.x,
            q.y,
            q.z
        )?;
        match f.reference {
            Some(r) => writeln!(s, ",{}", r[i])?,
            None => s.write_all(b"\n")?,
        }
    }
    Ok(())
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Input bytes per block of [`base64`] (a multiple of 3, so the blocks join seamlessly).
const B64_BLOCK: usize = 3 * 16_384;

/// Writes the standard base64 encoding of `bytes` (with padding), a block at a time.
fn base64(bytes: &[u8], out: &mut dyn Write) -> std::io::Result<()> {
    let mut text = Vec::with_capacity(B64_BLOCK / 3 * 4);
    for block in bytes.chunks(B64_BLOCK) {
        text.clear();
        for c in block.chunks(3) {
            let n = (c[0] as u32) << 16
                | (*c.get(1).unwrap_or(&0) as u32) << 8
                | *c.get(2).unwrap_or(&0) as u32;
            for k in 0..4 {
                text.push(match k <= c.len() {
                    true => B64[(n >> (18 - 6 * k) & 63) as usize],
                    false => b'=',
                });
            }
        }
        out.write_all(&text)?;
    }
    Ok(())
}

/// A VTK XML `DataArray` in inline binary form: base64 of the byte count (UInt64), then
/// base64 of the little-endian values, encoded separately as VTK's own writer does.
fn vtk_array(
    out: &mut dyn Write,
    (kind, name, comps): (&str, &str, usize),
    bytes: &[u8],
) -> std::io::Result<()> {
    write!(
        out,
        "<DataArray type=\"{kind}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"binary\">"
    )?;
    base64(&(bytes.len() as u64).to_le_bytes(), out)?;
    base64(bytes, out)?;
    out.write_all(b"</DataArray>\n")
}

fn f64_bytes(v: impl Iterator<Item = f64>) -> Vec<u8> {
    v.flat_map(f64::to_le_bytes).collect()
}

/// A VTK unstructured grid (`.vtu`) of the body nodes as vertices, with temperature, heat
/// flux, damage, the classical reference (if any), horizon, spacing, volume and region, for
/// ParaView, written to `out`.
pub fn field_vtu(out: &mut dyn Write, cloud: &Cloud, f: &Fields) -> std::io::Result<()> {
    field_vtu_rows(out, cloud, f, 0..cloud.n_body)
}

/// The point arrays of a field's VTK files, in their order: (VTK type, name, components).
fn point_arrays(reference: bool) -> Vec<(&'static str, &'static str, usize)> {
    let mut a = vec![
        ("Float64", "temperature", 1),
        ("Float64", "flux", 3),
        ("Float64", "damage", 1),
    ];
    if reference {
        a.push(("Float64", "reference", 1));
    }
    a.extend([
        ("Float64", "horizon", 1),
        ("Float64", "spacing", 1),
        ("Float64", "volume", 1),
        ("Int32", "region", 1),
    ]);
    a
}

/// The bytes of point array `name` ([`point_arrays`]) over the body nodes `rows`.
fn point_bytes(cloud: &Cloud, f: &Fields, name: &str, rows: Range<usize>) -> Vec<u8> {
    let scalar = |v: &[f64]| f64_bytes(v[rows.clone()].iter().copied());
    match name {
        "temperature" => scalar(f.theta),
        "flux" => f64_bytes(f.flux[rows].iter().flat_map(|q| [q.x, q.y, q.z])),
        "damage" => scalar(f.damage),
        "reference" => f.reference.map(scalar).unwrap_or_default(),
        "horizon" => scalar(&cloud.horizon),
        "spacing" => scalar(&cloud.spacing),
        "volume" => scalar(&cloud.volume),
        _ => cloud.region[rows]
            .iter()
            .flat_map(|r| (*r as i32).to_le_bytes())
            .collect(),
    }
}

/// [`field_vtu`] of the body nodes `rows` alone: one piece of a parallel file
/// ([`field_pvtu`]).
pub fn field_vtu_rows(
    s: &mut dyn Write,
    cloud: &Cloud,
    f: &Fields,
    rows: Range<usize>,
) -> std::io::Result<()> {
    let n = rows.len();
    s.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n")?;
    writeln!(s, "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">")?;
    s.write_all(b"<PointData Scalars=\"temperature\" Vectors=\"flux\">\n")?;
    for (kind, name, comps) in point_arrays(f.reference.is_some()) {
        let bytes = point_bytes(cloud, f, name, rows.clone());
        vtk_array(s, (kind, name, comps), &bytes)?;
    }
    s.write_all(b"</PointData>\n<Points>\n")?;
    let pos = cloud.pos[rows].iter().flat_map(|p| [p.x, p.y, p.z]);
    vtk_array(s, ("Float64", "Points", 3), &f64_bytes(pos))?;
    s.write_all(b"</Points>\n<Cells>\n")?;
    let ids: Vec<u8> = (0..n as i64).flat_map(i64::to_le_bytes).collect();
    vtk_array(s, ("Int64", "connectivity", 1), &ids)?;
    let offsets: Vec<u8> = (1..=n as i64).flat_map(i64::to_le_bytes).collect();
    vtk_array(s, ("Int64", "offsets", 1), &offsets)?;
    vtk_array(s, ("UInt8", "types", 1), &vec![1u8; n])?; // VTK_VERTEX
    s.write_all(b"</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
}

/// Path of the k-th parallel VTK file (k from 1): `field_<k>.pvtu`, whose pieces are
/// [`piece_path`].
pub fn pvtu_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("field_{k}.pvtu"))
}

/// Path of piece `r` (rank r's rows) of the k-th parallel VTK file: `field_<k>/piece_<r>.vtu`.
pub fn piece_path(dir: &Path, k: usize, r: usize) -> PathBuf {
    dir.join(format!("field_{k}"))
        .join(format!("piece_{r}.vtu"))
}

/// A parallel VTK unstructured grid (`.pvtu`) over `pieces` (paths relative to it, written by
/// [`field_vtu_rows`]), with the point arrays of a field with or without a reference.
pub fn field_pvtu(pieces: &[String], reference: bool) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PUnstructuredGrid GhostLevel=\"0\">\n<PPointData Scalars=\"temperature\" Vectors=\"flux\">\n");
    for (kind, name, comps) in point_arrays(reference) {
        let _ = writeln!(
            s,
            "<PDataArray type=\"{kind}\" Name=\"{name}\" NumberOfComponents=\"{comps}\"/>"
        );
    }
    s.push_str("</PPointData>\n<PPoints>\n<PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n</PPoints>\n");
    for p in pieces {
        let _ = writeln!(s, "<Piece Source=\"{p}\"/>");
    }
    s.push_str("</PUnstructuredGrid>\n</VTKFile>\n");
    s
}

/// Path of the time series of a run's VTK files: `fields.pvd`.
pub fn pvd_path(dir: &Path) -> PathBuf {
    dir.join("fields.pvd")
}

/// A ParaView time series (`.pvd`) of `(time in s, file relative to it)`, in order.
pub fn series_pvd(entries: &[(f64, String)]) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n");
    for (t, file) in entries {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{t:e}\" part=\"0\" file=\"{file}\"/>"
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

/// Node positions, temperatures and spacings read back from a `field_<k>.csv`.
pub struct FieldRows {
    /// Positions, m.
    pub pos: Vec<Point>,
    /// Temperatures, °C.
    pub theta: Vec<f64>,
    /// Spacings Δ, m.
    pub spacing: Vec<f64>,
    /// Region index of each node (0 if the file has no such column).
    pub region: Vec<u32>,
    /// Damage φ of each node (0 if the file has no such column).
    pub damage: Vec<f64>,
    /// Peridynamic heat flux of each node, W/m² (0 if the file has no such columns).
    pub flux: Vec<Vector>,
    /// The classical reference at each node, °C, when the file has a `reference` column.
    pub reference: Option<Vec<f64>>,
}

/// Reads a `field_<k>.csv` (columns x, y, z, temperature, region, spacing first; damage and
/// qx, qy, qz when present).
pub fn read_field(path: &Path) -> Result<FieldRows> {
    let bad = |m: String| Error::Io {
        path: path.to_path_buf(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidData, m),
    };
    let text = std::fs::read_to_string(path).map_err(|error| Error::Io {
        path: path.to_path_buf(),
        error,
    })?;
    // every line of a complete file ends with a newline: a file cut mid-number does not
    if !text.ends_with('\n') {
        return Err(bad(
            "does not end with a newline: the file is cut short".into()
        ));
    }
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("");
    if !header.starts_with("x,y,z,temperature,region,spacing") {
        return Err(bad(
            "not a peritherm field file (header x,y,z,temperature,region,spacing,...)".into(),
        ));
    }
    let mut rows = FieldRows {
        pos: Vec::new(),
        theta: Vec::new(),
        spacing: Vec::new(),
        region: Vec::new(),
        damage: Vec::new(),
        flux: Vec::new(),
        reference: None,
    };
    let reference_column = header.split(',').position(|c| c == "reference");
    let mut reference = Vec::new();
    for (k, line) in lines.enumerate() {
        let v: Vec<f64> = line
            .split(',')
            .take(reference_column.map_or(12, |c| c + 1).max(12))
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| bad(format!("line {}: {e}", k + 2)))?;
        if v.len() < 6 {
            return Err(bad(format!("line {}: fewer than 6 columns", k + 2)));
        }
        if let Some(c) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(format!(
                "line {}: column {} is {}, not a finite number",
                k + 2,
                c + 1,
                v[c]
            )));
        }
        rows.pos.push(Point::new(v[0], v[1], v[2]));
        rows.theta.push(v[3]);
        rows.spacing.push(v[5]);
        rows.region.push(v[4] as u32);
        let extra = |k: usize| v.get(k).copied().unwrap_or(0.0);
        rows.damage.push(extra(8));
        rows.flux.push(Vector::new(extra(9), extra(10), extra(11)));
        if let Some(c) = reference_column {
            let r = v
                .get(c)
                .ok_or_else(|| bad(format!("line {}: no reference value", k + 2)))?;
            reference.push(*r);
        }
    }
    rows.reference = reference_column.map(|_| reference);
    if rows.pos.is_empty() {
        return Err(bad("has a header but no rows".into()));
    }
    Ok(rows)
}

/// Comparison with a classical solution at one output time (theory §9).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Comparison {
    /// Output time, s.
    pub time: f64,
    /// max |θ_c − θ_pd| over the body nodes, °C.
    pub max_abs_diff: f64,
    /// Bobaru & Duangpanya 2010, eq. 45: mean of ((θ_c − θ_pd)/θ_c)² over nodes with θ_c ≠ 0.
    pub mean_sq_rel_diff: f64,
    /// Bobaru & Duangpanya 2012, eq. 13 along the probe line (all nodes when no line is set).
    pub l2_rel_line: f64,
    /// PCS2022 (doi:10.1007/s42102-022-00092-3), eq. 27: rms difference
    /// / max |θ_c|.
    pub epsilon: f64,
    /// Relative L2 error over all body nodes compared, weighted by node volume:
    /// √(Σ V_i (θ_pd − θ_c)² / Σ V_i θ_c²), dimensionless (0 where θ_c ≡ 0).
    #[serde(default)]
    pub l2_rel_volume: f64,
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

/// A file's identity when a run read it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileStamp {
    /// Absolute path.
    pub path: String,
    /// Size, bytes.
    pub bytes: u64,
    /// FNV-1a 64-bit hash of the contents, hexadecimal.
    pub fnv1a: String,
}

/// The case of a run: where its file was and the files it read.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CaseOrigin {
    /// Absolute path of the case file (the copy's relative paths resolve against its folder).
    pub path: String,
    /// The other files the case read, stamped.
    pub inputs: Vec<FileStamp>,
}

/// `run.json` of a run that did not complete.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Unfinished {
    /// `interrupted` or `failed`.
    pub status: String,
    /// Case file.
    pub case: String,
    /// Simulated time reached, s.
    pub time: f64,
    /// Why it stopped.
    pub message: String,
    /// The complete field files it wrote, in output order.
    pub fields: Vec<String>,
}

/// Summary written to run.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSummary {
    /// `complete` (an unfinished run's run.json is a [`Unfinished`]).
    #[serde(default = "complete")]
    pub status: String,
    /// Case title.
    pub title: String,
    /// Case file.
    pub case: String,
    /// Solver that wrote the run: `peridynamics` or `fem` (run.json files without it:
    /// peridynamics).
    #[serde(default = "peridynamics")]
    pub solver: String,
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
    /// Stable bound on the step, s (0 for the FEM solver, whose schemes are unconditionally
    /// stable).
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
    /// Consistent-weights correction: nodes corrected and left out, moment errors before and
    /// after, iterations, and the range of factors applied to the pair conductances.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub consistency: Option<peritherm_core::weights::Consistency>,
    /// How the explicit step read K, when the case asked for other than K's own u32 columns and
    /// f64 values (`kernel.columns`, `kernel.precision`), e.g. "packed columns, f32 K".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_storage: Option<String>,
    /// Comparison with the case's classical reference, per output time.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference: Vec<Comparison>,
    /// Implicit runs: solves, factorisations, accepted and rejected steps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub implicit: Option<peritherm_core::solve::implicit::ImplicitStats>,
    /// The `[history]` samples: their file and, per point, peaks and differences.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<crate::history::HistorySummary>,
    /// Keys set on the command line over the case file's (`run --set`, a sweep's variant), as
    /// `KEY=VALUE`: `peritherm run CASE --set KEY=VALUE ...` repeats the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub settings: Vec<String>,
    /// Where the case came from ([`crate::provenance`]); absent in runs written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<CaseOrigin>,
    /// A distributed run (`mpiexec -n N peritherm run`): what each rank held and exchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ranks: Option<Ranks>,
}

/// What the ranks of a distributed run held and exchanged (run.json `ranks`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Ranks {
    /// Number of ranks (the communicator's size).
    pub size: usize,
    /// `rows` (each rank steps its rows of K) or `replicated` (every rank steps the whole
    /// model; the enthalpy and implicit steppers are not distributed yet).
    pub mode: String,
    /// Body nodes (rows) of each rank.
    pub nodes: Vec<usize>,
    /// Ghost body nodes each rank receives per exchange.
    pub ghosts: Vec<usize>,
    /// Pairs of K in each rank's rows.
    pub pairs: Vec<usize>,
    /// Directed bonds of each rank's rows, and from fictitious nodes into them.
    #[serde(default)]
    pub bonds: Vec<usize>,
    /// `share` (each rank built the bonds of its rows alone) or `whole` (every rank built the
    /// whole model: consistent weights, cracks, phase change, implicit and adaptive steps).
    #[serde(default)]
    pub setup: String,
    /// Bytes all ranks receive per halo exchange (an Euler step has one, RK4 four), B.
    pub halo_bytes: usize,
    /// Longest time any rank spent in halo exchanges, s.
    pub exchange_seconds: f64,
}

fn peridynamics() -> String {
    "peridynamics".into()
}

fn complete() -> String {
    "complete".into()
}

impl RunSummary {
    /// The index of the output at time `t`, s: the first output time within 1e-9 of `t`
    /// (relative), as two runs of one case write them.
    pub fn output_index(&self, t: f64) -> Option<usize> {
        self.output_times
            .iter()
            .position(|x| (x - t).abs() <= 1e-9 * t.abs())
    }

    /// Reads `dir/run.json`.
    pub fn read(dir: &Path) -> Result<RunSummary> {
        let path = dir.join("run.json");
        let text = std::fs::read_to_string(&path).map_err(|error| Error::Io {
            path: path.clone(),
            error,
        })?;
        let bad = |m: String| Error::Io {
            path: path.clone(),
            error: std::io::Error::new(std::io::ErrorKind::InvalidData, m),
        };
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        let status = value
            .get("status")
            .and_then(|s| s.as_str())
            .map(str::to_string);
        if let Some(status) = status {
            if status != "complete" {
                let u: Unfinished =
                    serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
                return Err(bad(format!(
                    "the run of {} is {status} at t = {:e} s ({}); it has no results to read, run it again",
                    u.case, u.time, u.message
                )));
            }
        }
        let summary: RunSummary = serde_json::from_value(value).map_err(|e| bad(e.to_string()))?;
        summary.check(dir)?;
        Ok(summary)
    }

    /// Checks what a reader relies on: one field file per output time, one energy per
    /// output, finite measures.
    fn check(&self, dir: &Path) -> Result<()> {
        let bad = |m: String| Error::Io {
            path: dir.join("run.json"),
            error: std::io::Error::new(std::io::ErrorKind::InvalidData, m),
        };
        if self.fields.len() != self.output_times.len() {
            return Err(bad(format!(
                "lists {} field files for {} output times",
                self.fields.len(),
                self.output_times.len()
            )));
        }
        if self.output_times.iter().any(|t| !t.is_finite()) {
            return Err(bad("an output time is not finite".into()));
        }
        let measures = self.reference.iter().flat_map(|c| {
            [
                c.max_abs_diff,
                c.mean_sq_rel_diff,
                c.l2_rel_line,
                c.epsilon,
                c.l2_rel_volume,
            ]
        });
        if measures.into_iter().any(|v| !v.is_finite()) {
            return Err(bad(
                "a comparison with the reference is not finite (NaN or infinite)".into(),
            ));
        }
        Ok(())
    }

    /// Reads the k-th field (k from 0) of the run in `dir` and checks it is complete: one row
    /// per body node (`nodes` of run.json), every value finite.
    pub fn read_field(&self, dir: &Path, k: usize) -> Result<FieldRows> {
        let path = dir.join(&self.fields[k]);
        let rows = read_field(&path)?;
        if rows.pos.len() != self.nodes {
            return Err(Error::Io {
                path,
                error: std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "has {} rows but run.json says {} nodes: the file is incomplete or from another run",
                        rows.pos.len(),
                        self.nodes
                    ),
                ),
            });
        }
        Ok(rows)
    }

    /// Columns of the accuracy table ([`RunSummary::table_cells`]).
    pub const TABLE_COLUMNS: [&'static str; 10] = [
        "case",
        "t (s)",
        "nodes",
        "max abs diff (°C)",
        "eq 45",
        "eq 13",
        "probe PD / classical (°C)",
        "bonds",
        "steps",
        "wall (s)",
    ];

    /// Cells of the accuracy table, one row per output time, comparing this run with its
    /// reference.
    pub fn table_cells(&self) -> Vec<Vec<String>> {
        let name = Path::new(&self.case)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let row = |c: &Comparison| {
            let probe = c
                .probe
                .as_ref()
                .map(|p| format!("{:.3} / {:.3}", p.peridynamic, p.classical))
                .unwrap_or_else(|| "-".into());
            vec![
                name.clone(),
                number_label(c.time),
                self.nodes.to_string(),
                format!("{:.3e}", c.max_abs_diff),
                format!("{:.3e}", c.mean_sq_rel_diff),
                format!("{:.3e}", c.l2_rel_line),
                probe,
                self.bonds.to_string(),
                self.steps.to_string(),
                format!("{:.1}", self.wall_seconds),
            ]
        };
        self.reference.iter().map(row).collect()
    }

    /// Markdown rows (one per output time) comparing this run with its reference.
    pub fn table_rows(&self) -> Vec<String> {
        let cells = self.table_cells();
        cells
            .iter()
            .map(|r| format!("| {} |", r.join(" | ")))
            .collect()
    }

    /// Header of [`RunSummary::table_rows`].
    pub fn table_header() -> String {
        let columns = Self::TABLE_COLUMNS;
        format!(
            "| {} |\n|{}",
            columns.join(" | "),
            "---|".repeat(columns.len())
        )
    }

    /// Writes run.json atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let json = serde_json::to_string_pretty(self).expect("plain data serialises");
        write_atomic(&dir.join("run.json"), json.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::base64;

    /// RFC 4648 test vectors.
    #[test]
    fn base64_vectors() {
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foobar", "Zm9vYmFy"),
        ] {
            let mut s = Vec::new();
            base64(raw.as_bytes(), &mut s).unwrap();
            assert_eq!(s, enc.as_bytes());
        }
    }

    /// Encoded a block at a time, a long array is the concatenation of its 3-byte groups'
    /// encodings, across the blocks' seams and at its padded end.
    #[test]
    fn base64_blocks_join_seamlessly() {
        let raw: Vec<u8> = (0..2 * super::B64_BLOCK + 5)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        let mut whole = Vec::new();
        base64(&raw, &mut whole).unwrap();
        let mut groups = Vec::new();
        for c in raw.chunks(3) {
            base64(c, &mut groups).unwrap();
        }
        assert_eq!(whole, groups);
    }
}
