//! Reference solutions exported by other codes (ANSYS, Abaqus, FEniCS, …) as CSV tables:
//! reading and checking them. Interpolation onto the PD nodes is in `peritherm_post::report`.
//!
//! Format: a header naming the columns `time`, the coordinates (`x`; `x,y`; `x,y,z` for the
//! case's dimension) and `temperature`, in any order (other columns are ignored), then one
//! row per point and output time. Units as the case (s, m, °C). Lines starting with `#` are
//! comments.

use crate::error::{Error, Result};
use peritherm_core::math::Point;
use std::path::{Path, PathBuf};

/// The points and temperatures of a reference at one time.
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// Time, s.
    pub time: f64,
    /// Points, m.
    pub pos: Vec<Point>,
    /// Temperatures, °C.
    pub theta: Vec<f64>,
}

/// A reference table read from a CSV file, snapshots in increasing time.
#[derive(Debug, Clone)]
pub struct ReferenceTable {
    /// The file it was read from.
    pub path: PathBuf,
    /// Spatial dimension of its points.
    pub dim: usize,
    /// One snapshot per distinct time.
    pub snapshots: Vec<Snapshot>,
}

/// Two times are the same output when they differ by at most this fraction (of max(|t|, 1e-12 s)).
const TIME_TOLERANCE: f64 = 1e-9;

/// An error's key and message, before the file is added.
type KeyMessage = (String, String);

/// Where the columns a reference needs are in its rows.
struct Columns {
    /// Dimension of the points.
    dim: usize,
    /// The names wanted: time, the coordinates, temperature.
    wanted: Vec<&'static str>,
    /// The column of each wanted name.
    column: Vec<usize>,
}

impl Columns {
    /// The columns of `header` for a case of dimension `dim`; an error for a coordinate
    /// beyond `dim` or a missing column.
    fn find(header: &str, dim: usize) -> std::result::Result<Columns, KeyMessage> {
        let names: Vec<String> = header
            .split(',')
            .map(|c| c.trim().to_ascii_lowercase())
            .collect();
        let axes = ["x", "y", "z"];
        for extra in &axes[dim..] {
            if names.iter().any(|n| n == extra) {
                return Err((
                    "header".into(),
                    format!("has a `{extra}` column but the case is {dim}D; export {dim}D points (columns time,{},temperature)", axes[..dim].join(",")),
                ));
            }
        }
        let mut wanted = vec!["time"];
        wanted.extend(&axes[..dim]);
        wanted.push("temperature");
        let mut column = Vec::with_capacity(wanted.len());
        for w in &wanted {
            match names.iter().position(|n| n == w) {
                Some(c) => column.push(c),
                None => {
                    return Err((
                        "header".into(),
                        format!(
                            "missing column `{w}` (a {dim}D reference needs {}; found {})",
                            wanted.join(","),
                            names.join(",")
                        ),
                    ))
                }
            }
        }
        Ok(Columns {
            dim,
            wanted,
            column,
        })
    }

    /// (time s, point m, temperature °C) of the data line `line` (index `k` in the file).
    fn row(&self, k: usize, line: &str) -> std::result::Result<(f64, Point, f64), KeyMessage> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let mut v = [0.0; 5];
        for (slot, (&c, w)) in v.iter_mut().zip(self.column.iter().zip(&self.wanted)) {
            let cell = cells.get(c).copied().unwrap_or("");
            *slot = match cell.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    return Err((
                        format!("line {}", k + 1),
                        format!("column `{w}`: `{cell}` is not a finite number"),
                    ))
                }
            };
        }
        let mut p = Point::origin();
        for a in 0..self.dim {
            p[a] = v[1 + a];
        }
        Ok((v[0], p, v[1 + self.dim]))
    }
}

/// The rows grouped into snapshots of the same time, in increasing time.
fn snapshots(mut rows: Vec<(f64, Point, f64)>) -> Vec<Snapshot> {
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut snapshots: Vec<Snapshot> = Vec::new();
    for (t, p, theta) in rows {
        match snapshots.last_mut() {
            Some(s) if same_time(s.time, t) => {
                s.pos.push(p);
                s.theta.push(theta);
            }
            _ => snapshots.push(Snapshot {
                time: t,
                pos: vec![p],
                theta: vec![theta],
            }),
        }
    }
    snapshots
}

impl ReferenceTable {
    /// Reads a reference CSV for a case of dimension `dim`.
    pub fn read(path: &Path, dim: usize) -> Result<ReferenceTable> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Case {
            file: path.to_path_buf(),
            key: "-".into(),
            message: format!("cannot read the reference: {e}"),
        })?;
        ReferenceTable::parse(&text, path, dim)
    }

    /// Parses reference CSV text; `path` is used in messages.
    pub fn parse(text: &str, path: &Path, dim: usize) -> Result<ReferenceTable> {
        let err = |(key, message): KeyMessage| Error::Case {
            file: path.to_path_buf(),
            key,
            message,
        };
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let Some((_, header)) = lines.next() else {
            return Err(err(("header".into(), "the file is empty".into())));
        };
        let columns = Columns::find(header, dim).map_err(err)?;
        let rows = lines
            .map(|(k, line)| columns.row(k, line))
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(err)?;
        if rows.is_empty() {
            return Err(err(("-".into(), "no data rows after the header".into())));
        }
        Ok(ReferenceTable {
            path: path.to_path_buf(),
            dim,
            snapshots: snapshots(rows),
        })
    }

    /// The snapshot at time `t`, s, or None.
    pub fn at(&self, t: f64) -> Option<&Snapshot> {
        self.snapshots.iter().find(|s| same_time(s.time, t))
    }

    /// The times of the snapshots, s.
    pub fn times(&self) -> Vec<f64> {
        self.snapshots.iter().map(|s| s.time).collect()
    }

    /// Checks that every time of `outputs` (s) has a snapshot; the message lists what is there.
    pub fn check_times(&self, outputs: &[f64]) -> std::result::Result<(), String> {
        match outputs.iter().find(|&&t| self.at(t).is_none()) {
            None => Ok(()),
            Some(t) => Err(format!(
                "{} has no rows at t = {t} s (it has t = {}); export every output time of the case",
                self.path.display(),
                self.times()
                    .iter()
                    .map(|t| t.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }
}

fn same_time(a: f64, b: f64) -> bool {
    (a - b).abs() <= TIME_TOLERANCE * a.abs().max(b.abs()).max(1e-12)
}

/// The axis-aligned box of `points` grown by their mean spacing (box measure / count)^(1/dim),
/// as (min, max), m: the region a reference covers.
pub fn covered_box(points: &[Point], dim: usize) -> (Point, Point) {
    let mut lo = Point::new(f64::MAX, f64::MAX, f64::MAX);
    let mut hi = Point::new(f64::MIN, f64::MIN, f64::MIN);
    for p in points {
        for a in 0..dim {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let measure: f64 = (0..dim).map(|a| (hi[a] - lo[a]).max(0.0)).product();
    let h = (measure / points.len().max(1) as f64).powf(1.0 / dim as f64);
    for a in 0..dim {
        lo[a] -= h;
        hi[a] += h;
    }
    for a in dim..3 {
        lo[a] = 0.0;
        hi[a] = 0.0;
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, dim: usize) -> Result<ReferenceTable> {
        ReferenceTable::parse(text, Path::new("ref.csv"), dim)
    }

    /// Rows group into snapshots by time, columns in any order, extra columns ignored.
    #[test]
    fn reads_snapshots() {
        let t = parse(
            "# exported\ntemperature,x,y,time,node\n1,0,0,0.5,1\n2,1,0,0.5,2\n3,0,1,0.1,3\n",
            2,
        )
        .unwrap();
        assert_eq!(t.times(), vec![0.1, 0.5]);
        assert_eq!(t.at(0.5).unwrap().theta, vec![1.0, 2.0]);
        assert_eq!(t.at(0.1).unwrap().pos, vec![Point::new(0.0, 1.0, 0.0)]);
        assert!(t.check_times(&[0.1, 0.5]).is_ok());
        let e = t.check_times(&[0.1, 0.2]).unwrap_err();
        assert!(
            e.contains("no rows at t = 0.2") && e.contains("0.1, 0.5"),
            "{e}"
        );
    }

    /// Missing columns, a 3D file for a 2D case and bad numbers are named in the message.
    #[test]
    fn bad_files_are_named() {
        let e = parse("time,x,temperature\n0,0,1\n", 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ref.csv: header: missing column `y`"), "{e}");
        let e = parse("time,x,y,z,temperature\n0,0,0,0,1\n", 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("`z` column but the case is 2D"), "{e}");
        let e = parse("time,x,y,temperature\n0,0,0,1\n0,0,zero,1\n", 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3: column `y`: `zero`"), "{e}");
        let e = parse("time,x,temperature\n", 1).unwrap_err().to_string();
        assert!(e.contains("no data rows"), "{e}");
    }
}
