//! Figure files from the command line ([`peritherm_post::figures`]): `peritherm table --json`
//! and the provenance of a measurement (the git commit of the work tree, this machine).

use crate::atomic::write_atomic;
use crate::error::Result;
use crate::output::RunSummary;
use crate::sweep::Row;
use peritherm_post::figures::{accuracy, fields, Check, Figures, Provenance, REL_TOL_SOLVER};
use std::path::{Path, PathBuf};
use std::process::Command;

/// `git rev-parse --short=12 HEAD` of the current directory, with `+changes` when tracked
/// files outside `validation/` differ from it (the figure files themselves are what a
/// measurement rewrites); `unknown` outside a git work tree.
pub fn commit() -> String {
    let git = |args: &[&str]| {
        let out = Command::new("git").args(args).output().ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(head) => match git(&[
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            ":/",
            ":(top,exclude)validation",
        ]) {
            Some(changes) if changes.is_empty() => head,
            _ => format!("{head}+changes"),
        },
        None => "unknown".into(),
    }
}

/// This machine and work tree now ([`Provenance::here`] with [`commit`]).
pub fn provenance(threads: usize) -> Provenance {
    Provenance::here(commit(), threads)
}

/// Which table `peritherm table` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableKind {
    /// The runs against their classical references.
    Accuracy,
    /// The runs' fields: energy and the hash of each field file.
    Fields,
}

/// `peritherm table`: the accuracy table of finished runs as Markdown; with `json`, the
/// `kind` of table written as a figure file named after the file's stem, saying it was measured
/// by `command`.
pub fn table(
    runs: &[PathBuf],
    json: Option<&Path>,
    kind: TableKind,
    command: &str,
) -> Result<String> {
    let summaries = runs
        .iter()
        .map(|dir| RunSummary::read(dir))
        .collect::<peritherm_io::Result<Vec<_>>>()?;
    let pairs: Vec<(&Path, &RunSummary)> =
        runs.iter().map(PathBuf::as_path).zip(&summaries).collect();
    let threads = summaries.first().map_or(0, |s| s.threads);
    let name = json
        .and_then(Path::file_stem)
        .map_or("table".into(), |s| s.to_string_lossy().into_owned());
    let provenance = provenance(threads);
    let figures = match kind {
        TableKind::Accuracy => accuracy(&name, command, provenance, &pairs),
        TableKind::Fields => fields(&name, command, provenance, &pairs),
    };
    match json {
        Some(path) => {
            write_atomic(path, figures.to_json().as_bytes())?;
            Ok(figures.markdown().trim_end().to_string())
        }
        None => Ok(figures.table().trim_end().to_string()),
    }
}

/// The figures of a sweep: its table and, when `args` can repeat it (a sweep against its cases'
/// references or its first variant, not a run directory), a check of every measure of its
/// sweep.json. Variants may be implicit or adaptive, so every measure has the solver's
/// tolerance ([`REL_TOL_SOLVER`]).
pub fn sweep_figures(
    name: &str,
    command: &str,
    provenance: Provenance,
    args: Option<Vec<String>>,
    rows: &[Row],
) -> Figures {
    let (columns, cells) = crate::sweep::cells(rows);
    let mut checks = Vec::new();
    for (i, r) in rows.iter().enumerate().filter(|_| args.is_some()) {
        let measures = [
            ("max_abs", Some(r.max_abs)),
            ("mean_abs", r.mean_abs),
            ("eq13", r.eq13),
            ("epsilon", r.epsilon),
            ("l2_rel", r.l2_rel),
        ];
        for (key, value) in measures {
            let Some(value) = value.filter(|v| *v != 0.0) else {
                continue;
            };
            checks.push(Check::Measure {
                args: args.clone().unwrap_or_default(),
                file: "sweep.json".into(),
                pointer: format!("/{i}/{key}"),
                value,
                rel_tol: REL_TOL_SOLVER,
            });
        }
    }
    Figures {
        name: name.into(),
        command: command.into(),
        provenance,
        columns,
        rows: cells,
        checks,
    }
}
