//! The committed figures hold: every check of every figure file in `validation/` (the
//! accuracy table's measures and field files, the studies' figures) is run again and compared
//! within its stated tolerance (`peritherm_post::figures`). Ignored by default: it reruns the
//! bundled cases at full length (more than an hour on 2 cores); `scripts/check-figures.sh`
//! runs it, for every file or for the names it is given (`PERITHERM_FIGURES=a,b`).

use peritherm_post::figures::{Figures, DIR};
use std::path::{Path, PathBuf};

/// `peritherm ARGS --out OUT`, from the repository root (the figure files name cases by their
/// path from there).
fn rerun(args: &[String], out: &Path) -> Result<(), String> {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_peritherm"))
        .env("PERITHERM_CACHE", "off")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .map_err(|e| e.to_string())?;
    o.status
        .success()
        .then_some(())
        .ok_or_else(|| String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
#[ignore = "reruns every bundled case at full length (more than an hour): scripts/check-figures.sh"]
fn committed_figures_hold() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(DIR);
    let scratch = tempfile::tempdir().unwrap();
    let only = std::env::var("PERITHERM_FIGURES").ok();
    let named = |p: &Path| {
        let stem = p.file_stem().unwrap_or_default().to_string_lossy();
        only.as_deref()
            .is_none_or(|names| names.split(',').any(|n| n == stem))
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| named(p))
        .collect();
    assert!(!files.is_empty(), "no figure file named {only:?} in {DIR}/");
    files.sort();
    let mut failures = Vec::new();
    for file in files {
        let figures = Figures::read(&file).unwrap();
        let moved = figures.verify(scratch.path(), rerun);
        eprintln!(
            "{}: {} checks, {} moved",
            file.display(),
            figures.checks.len(),
            moved.len()
        );
        failures.extend(moved);
    }
    assert!(
        failures.is_empty(),
        "figures moved:\n{}",
        failures.join("\n")
    );
}
