//! Validation figures kept as data: a table that a command measured, written into a committed
//! JSON file (`validation/<name>.json`) together with the commit and machine it came from and
//! the checks a rerun must pass. The Markdown tables of the docs are rendered from these files
//! (between `<!-- figures:NAME -->` and `<!-- /figures:NAME -->`), never typed by hand.

use peritherm_io::output::RunSummary;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Folder of the figure files, relative to the repository root.
pub const DIR: &str = "validation";

/// Relative tolerance of a measure of a run whose fields are reproduced bit for bit (explicit
/// integrators): the figure must not move at all; 1e-12 only absorbs the last digit of JSON's
/// shortest round-trip printing.
pub const REL_TOL_EXACT: f64 = 1e-12;

/// Relative tolerance of a measure of an implicit, adaptive or steady run: the sparse
/// factorisations (faer) split their work by the thread count, so a rerun on another machine
/// or thread count may move the fields in their last bits, and an adaptive run's accepted
/// steps with them; a figure that is a small difference (1e-6 K against a field of 100 K)
/// may then move by far more than the fields' round-off.
pub const REL_TOL_SOLVER: f64 = 1e-4;

/// A table of measured figures and how to check them again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figures {
    /// Name of the table: the docs show it in the block `<!-- figures:NAME -->`.
    pub name: String,
    /// The command (from the repository root) that measured the figures and wrote this file.
    pub command: String,
    /// Where and when the figures were measured.
    pub provenance: Provenance,
    /// Column headings.
    pub columns: Vec<String>,
    /// Rows of formatted cells, one per column.
    pub rows: Vec<Vec<String>>,
    /// What a rerun of the commands must reproduce.
    #[serde(default)]
    pub checks: Vec<Check>,
}

/// Where and when figures were measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    /// `git rev-parse --short=12 HEAD`, with `+changes` when the work tree differed from it.
    pub commit: String,
    /// UTC date of the measurement, YYYY-MM-DD.
    pub date: String,
    /// Processor model (from /proc/cpuinfo) or `unknown`.
    pub machine: String,
    /// Threads the runs used.
    pub threads: usize,
    /// One-minute load average when the file was written (other work on the machine slows
    /// the wall times, never the measures).
    pub load: f64,
}

/// One figure a rerun must reproduce.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Check {
    /// A number in a JSON file that `peritherm ARGS --out DIR` writes, within `rel_tol`.
    Measure {
        /// Arguments of `peritherm` (without `--out`).
        args: Vec<String>,
        /// File in the output directory, e.g. `run.json`.
        file: String,
        /// JSON pointer to the number, e.g. `/reference/0/max_abs_diff`.
        pointer: String,
        /// The committed value.
        value: f64,
        /// Largest accepted |new − value| / |value|.
        rel_tol: f64,
    },
    /// A file that `peritherm ARGS --out DIR` writes, byte for byte.
    File {
        /// Arguments of `peritherm` (without `--out`).
        args: Vec<String>,
        /// File in the output directory, e.g. `field_1.csv`.
        file: String,
        /// FNV-1a 64-bit hash of its bytes, hexadecimal.
        fnv1a: String,
    },
}

impl Check {
    /// Arguments of the `peritherm` command whose output this check reads.
    pub fn args(&self) -> &[String] {
        match self {
            Check::Measure { args, .. } | Check::File { args, .. } => args,
        }
    }

    /// Checks the output directory of a rerun; the error says what moved.
    pub fn verify(&self, out: &Path) -> Result<(), String> {
        match self {
            Check::Measure {
                file,
                pointer,
                value,
                rel_tol,
                ..
            } => {
                let new = read_measure(&out.join(file), pointer)?;
                within(new, *value, *rel_tol)
                    .then_some(())
                    .ok_or_else(|| format!("{file} {pointer}: {new:e}, committed {value:e} (relative tolerance {rel_tol:e})"))
            }
            Check::File { file, fnv1a, .. } => {
                let bytes = std::fs::read(out.join(file)).map_err(|e| format!("{file}: {e}"))?;
                let new = fnv1a_hex(&bytes);
                (new == *fnv1a)
                    .then_some(())
                    .ok_or_else(|| format!("{file}: hash {new}, committed {fnv1a}"))
            }
        }
    }
}

/// True when `new` is finite and within `rel_tol` of the finite `value` (NaN never is).
pub fn within(new: f64, value: f64, rel_tol: f64) -> bool {
    new.is_finite() && value.is_finite() && (new - value).abs() <= rel_tol * value.abs()
}

/// The number at a JSON pointer of a file.
fn read_measure(path: &Path, pointer: &str) -> Result<f64, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{name}: {e}"))?;
    json.pointer(pointer)
        .and_then(serde_json::Value::as_f64)
        .ok_or_else(|| format!("{name}: no number at {pointer}"))
}

/// FNV-1a, 64 bits, hexadecimal: identifies a file's bytes (not a cryptographic hash).
pub fn fnv1a_hex(bytes: &[u8]) -> String {
    format!("{:016x}", peritherm_io::provenance::fnv1a(bytes))
}

impl Figures {
    /// Reads a figure file.
    pub fn read(path: &Path) -> Result<Figures, String> {
        let name = path.display();
        let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
        serde_json::from_str(&text).map_err(|e| format!("{name}: {e}"))
    }

    /// The file's text (pretty JSON, ending in a newline).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain data serialises") + "\n"
    }

    /// The table as Markdown.
    pub fn table(&self) -> String {
        let mut s = format!("| {} |\n", self.columns.join(" | "));
        s += &format!("|{}\n", "---|".repeat(self.columns.len()));
        for row in &self.rows {
            s += &format!("| {} |\n", row.join(" | "));
        }
        s
    }

    /// The table as Markdown, with a line saying where it came from.
    pub fn markdown(&self) -> String {
        let p = &self.provenance;
        let mut s = self.table();
        s += &format!(
            "\n*Written by `{}` at commit {} on {} ({} threads, load {:.1}), {}, into `{DIR}/{}.json`.*\n",
            self.command, p.commit, p.machine, p.threads, p.load, p.date, self.name
        );
        s
    }

    /// Reruns every check: `run(args, dir)` runs `peritherm ARGS --out DIR` once per distinct
    /// argument list (in `scratch/<k>`); returns what moved, one line each (empty: all hold).
    pub fn verify(
        &self,
        scratch: &Path,
        mut run: impl FnMut(&[String], &Path) -> Result<(), String>,
    ) -> Vec<String> {
        let mut groups: BTreeMap<&[String], Vec<&Check>> = BTreeMap::new();
        for check in &self.checks {
            groups.entry(check.args()).or_default().push(check);
        }
        let mut failures = Vec::new();
        for (k, (args, checks)) in groups.into_iter().enumerate() {
            let out = scratch.join(format!("{}_{k}", self.name));
            let label = format!("{}: peritherm {}", self.name, args.join(" "));
            if let Err(e) = run(args, &out) {
                failures.push(format!("{label}: {e}"));
                continue;
            }
            let moved = checks.iter().filter_map(|c| c.verify(&out).err());
            failures.extend(moved.map(|m| format!("{label}: {m}")));
        }
        failures
    }
}

/// A figure file from a Markdown table (`| a | b |` lines: the header, the separator, the
/// rows; other lines are left out), for tables that a command prints, with no checks (speed
/// figures depend on the machine).
pub fn from_markdown(name: &str, command: &str, provenance: Provenance, table: &str) -> Figures {
    let cells = |line: &str| -> Vec<String> {
        let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
        inner.split('|').map(|c| c.trim().to_string()).collect()
    };
    let lines: Vec<&str> = table
        .lines()
        .filter(|l| l.trim_start().starts_with('|'))
        .collect();
    let columns = lines.first().map(|l| cells(l)).unwrap_or_default();
    Figures {
        name: name.into(),
        command: command.into(),
        provenance,
        columns,
        rows: lines.iter().skip(2).map(|l| cells(l)).collect(),
        checks: Vec::new(),
    }
}

/// Replaces the block `<!-- figures:NAME -->` … `<!-- /figures:NAME -->` of a Markdown text by
/// `body`; None when the text has no such block.
pub fn fill_block(doc: &str, name: &str, body: &str) -> Option<String> {
    let open = format!("<!-- figures:{name} -->\n");
    let close = format!("<!-- /figures:{name} -->");
    let start = doc.find(&open)? + open.len();
    let end = start + doc[start..].find(&close)?;
    Some(format!("{}{body}{}", &doc[..start], &doc[end..]))
}

/// Names of the figure blocks a Markdown text shows, in order.
pub fn block_names(doc: &str) -> Vec<String> {
    doc.match_indices("<!-- figures:")
        .filter_map(|(i, m)| {
            let rest = &doc[i + m.len()..];
            rest.find(" -->").map(|end| rest[..end].to_string())
        })
        .collect()
}

/// The accuracy table of finished runs against their references (the columns of
/// [`RunSummary::table_header`]), with a check per measure and, for explicit runs, per field
/// file. `runs` pairs each run.json with its output directory.
pub fn accuracy(
    name: &str,
    command: &str,
    provenance: Provenance,
    runs: &[(&Path, &RunSummary)],
) -> Figures {
    let columns = RunSummary::TABLE_COLUMNS;
    of_runs(name, command, &columns, provenance, runs, |dir, run| {
        (run.table_cells(), run_checks(dir, run))
    })
}

/// A figure table of finished runs under the headings `columns`: `each(dir, run)` gives the
/// rows and checks of one run (its run.json with its output directory).
fn of_runs(
    name: &str,
    command: &str,
    columns: &[&str],
    provenance: Provenance,
    runs: &[(&Path, &RunSummary)],
    mut each: impl FnMut(&Path, &RunSummary) -> (Vec<Vec<String>>, Vec<Check>),
) -> Figures {
    let mut rows = Vec::new();
    let mut checks = Vec::new();
    for (dir, run) in runs {
        let (r, c) = each(dir, run);
        rows.extend(r);
        checks.extend(c);
    }
    Figures {
        name: name.into(),
        command: command.into(),
        provenance,
        columns: columns.iter().map(|c| c.to_string()).collect(),
        rows,
        checks,
    }
}

/// The checks of one run: its measures at every output time and, when its integrator is
/// explicit (bit-reproducible), the bytes of its field files.
fn run_checks(dir: &Path, run: &RunSummary) -> Vec<Check> {
    let args = run_args(run);
    let exact = is_exact(run);
    let rel_tol = if exact { REL_TOL_EXACT } else { REL_TOL_SOLVER };
    let mut checks = Vec::new();
    for (i, c) in run.reference.iter().enumerate() {
        let measures = [
            ("max_abs_diff", c.max_abs_diff),
            ("mean_sq_rel_diff", c.mean_sq_rel_diff),
            ("l2_rel_line", c.l2_rel_line),
        ];
        for (key, value) in measures.into_iter().filter(|(_, v)| *v != 0.0) {
            checks.push(Check::Measure {
                args: args.clone(),
                file: "run.json".into(),
                pointer: format!("/reference/{i}/{key}"),
                value,
                rel_tol,
            });
        }
    }
    if exact {
        checks.extend(field_checks(dir, run).into_iter().map(|(_, c)| c));
    }
    checks
}

/// `peritherm` arguments that repeat a run: `run CASE` and the keys it set.
fn run_args(run: &RunSummary) -> Vec<String> {
    let mut args = vec!["run".to_string(), run.case.clone()];
    for s in &run.settings {
        args.extend(["--set".to_string(), s.clone()]);
    }
    args
}

/// True for the integrators whose fields a rerun reproduces bit for bit (explicit steps;
/// implicit solves may take the direct or the iterative path).
fn is_exact(run: &RunSummary) -> bool {
    matches!(run.integrator.as_str(), "euler" | "rk4")
}

/// A check of each CSV field file of a run, byte for byte, with its hash.
fn field_checks(dir: &Path, run: &RunSummary) -> Vec<(String, Check)> {
    let mut checks = Vec::new();
    for file in &run.fields {
        let csv = file.replace(".vtu", ".csv");
        if let Ok(bytes) = std::fs::read(dir.join(&csv)) {
            let fnv1a = fnv1a_hex(&bytes);
            let check = Check::File {
                args: run_args(run),
                file: csv,
                fnv1a: fnv1a.clone(),
            };
            checks.push((fnv1a, check));
        }
    }
    checks
}

/// Relative tolerance of a run's thermal energy on a rerun: exact for explicit runs; for
/// implicit ones, 1e-9 covers the ~1e-10 K that the choice of linear solver moves.
const ENERGY_REL_TOL: f64 = 1e-9;

/// Energies below this, J, are round-off of a total that cancels (see [`fields`]).
const ENERGY_FLOOR: f64 = 1e-9;

/// The fields table: per run and output time, the case, the keys set, the integrator, the size,
/// the thermal energy and the hash of the field file, with a check of the energy and, for
/// explicit runs, of the field file byte for byte. `runs` pairs each run.json with its output
/// directory.
pub fn fields(
    name: &str,
    command: &str,
    provenance: Provenance,
    runs: &[(&Path, &RunSummary)],
) -> Figures {
    let columns = [
        "case",
        "set",
        "integrator",
        "nodes",
        "steps",
        "t (s)",
        "energy (J)",
        "field (FNV-1a)",
    ];
    of_runs(name, command, &columns, provenance, runs, field_rows)
}

/// The rows of one run in the fields table (one per output time) and its checks.
fn field_rows(dir: &Path, run: &RunSummary) -> (Vec<Vec<String>>, Vec<Check>) {
    let mut rows = Vec::new();
    let mut checks = Vec::new();
    let exact = is_exact(run);
    let files = field_checks(dir, run);
    for (k, (t, energy)) in run.output_times.iter().zip(&run.energy).enumerate() {
        let hash = files.get(k).map_or("-".into(), |(h, _)| h.clone());
        rows.push(vec![
            format!("`{}`", run.case),
            run.settings.join(" "),
            run.integrator.clone(),
            run.nodes.to_string(),
            run.steps.to_string(),
            format!("{t:e}"),
            format!("{energy:.9e}"),
            if exact { hash } else { format!("({hash})") },
        ]);
        // an energy that cancels to round-off (a body held at +θ and −θ) is no digest of
        // an implicit run's field: only explicit runs, whose files are compared, keep it
        if !exact && energy.abs() < ENERGY_FLOOR {
            continue;
        }
        checks.push(Check::Measure {
            args: run_args(run),
            file: "run.json".into(),
            pointer: format!("/energy/{k}"),
            value: *energy,
            rel_tol: if exact { REL_TOL_EXACT } else { ENERGY_REL_TOL },
        });
    }
    if exact {
        checks.extend(files.into_iter().map(|(_, c)| c));
    }
    (rows, checks)
}

impl Provenance {
    /// This machine now: its processor, the threads given, the load average and today's UTC
    /// date; `commit` comes from the caller (git is the command line's business).
    pub fn here(commit: String, threads: usize) -> Provenance {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let machine = cpuinfo
            .lines()
            .find_map(|l| l.strip_prefix("model name"))
            .and_then(|l| l.split_once(':'))
            .map(|(_, m)| m.trim().to_string())
            .unwrap_or_else(|| "unknown".into());
        let load = std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|l| l.split_whitespace().next()?.parse().ok())
            .unwrap_or(f64::NAN);
        Provenance {
            commit,
            date: utc_date(std::time::SystemTime::now()),
            machine,
            threads,
            load,
        }
    }
}

/// YYYY-MM-DD of a time, UTC (the civil-from-days conversion of the proleptic Gregorian calendar).
pub fn utc_date(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, UNIX_EPOCH};

    /// Known dates: the epoch, a leap day, the end of a century year, and today's kind of date.
    #[test]
    fn utc_dates() {
        let at = |s: u64| utc_date(UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01");
        assert_eq!(at(951_782_400), "2000-02-29");
        assert_eq!(at(978_220_800), "2000-12-31");
        assert_eq!(at(1_796_169_600), "2026-12-02");
    }

    /// A block is replaced between its markers only; a missing block is None.
    #[test]
    fn blocks_are_filled_between_their_markers() {
        let doc = "a\n<!-- figures:t -->\nold\n<!-- /figures:t -->\nb\n";
        let new = fill_block(doc, "t", "new\n").unwrap();
        assert_eq!(new, "a\n<!-- figures:t -->\nnew\n<!-- /figures:t -->\nb\n");
        assert_eq!(block_names(&new), vec!["t".to_string()]);
        assert!(fill_block(doc, "u", "x").is_none());
    }

    /// A printed Markdown table becomes the same table again.
    #[test]
    fn markdown_tables_round_trip() {
        let p = Provenance::here("x".into(), 1);
        let table = "| a | b |\n|---|---|\n| 1 | 2 |\n| 3 | 4 |\n";
        let f = from_markdown("t", "c", p, &format!("intro\n{table}\nafter"));
        assert_eq!(f.columns, ["a", "b"]);
        assert_eq!(f.rows, [["1", "2"], ["3", "4"]]);
        assert_eq!(f.table(), table);
    }

    /// NaN and infinities never pass; the tolerance is relative.
    #[test]
    fn tolerance_is_relative_and_refuses_nan() {
        assert!(within(1.0 + 1e-13, 1.0, 1e-12));
        assert!(!within(1.0 + 1e-11, 1.0, 1e-12));
        assert!(!within(f64::NAN, 1.0, 1.0));
        assert!(!within(1.0, f64::NAN, 1.0));
        assert!(!within(f64::INFINITY, f64::INFINITY, 1.0));
    }
}
