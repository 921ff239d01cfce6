//! The repository tracks sources, not what building, running or testing them writes: `git
//! ls-files` from the workspace root lists no Python bytecode, nothing of cargo's `target/`,
//! no run output and no plot under `plots/`.
//!
//! A copy that is not a git checkout (a source tarball), or a machine without `git`, skips
//! the check with a note: there is nothing tracked to inspect.

use std::path::Path;
use std::process::Command;

/// Why a tracked path is generated output, or `None` when it may be tracked.
fn generated(path: &str) -> Option<&'static str> {
    if path.split('/').any(|part| part == "__pycache__") {
        Some("a __pycache__ directory (Python bytecode)")
    } else if path.ends_with(".pyc") {
        Some("Python bytecode (.pyc)")
    } else if path.starts_with("target/") {
        Some("cargo's build directory target/")
    } else if path.starts_with("out/") {
        // where the scripts and the documented commands write runs, reports and their
        // plots (`--out out/...`); .gitignore lists it
        Some("run output under out/")
    } else if path.starts_with("plots/") && path != "plots/README.md" {
        // plots/ is not in the tree: it held only a README announcing plots to come, removed
        // as stale in commit 279fe74, and `peritherm plot` and the reports write into the
        // run's output directory. A README may return; any other file there is a drawn plot
        Some("a plot under plots/ (plots are written into the run's output directory)")
    } else {
        None
    }
}

/// The tracked paths of the checkout at `root`, or why they cannot be listed.
fn tracked_files(root: &Path) -> Result<Vec<String>, String> {
    let inside = Command::new("git")
        .args(["rev-parse", "--is-inside-work-tree"])
        .current_dir(root)
        .output()
        .map_err(|e| format!("git cannot be run ({e})"))?;
    if !inside.status.success() {
        return Err(format!(
            "{} is not a git checkout ({})",
            root.display(),
            String::from_utf8_lossy(&inside.stderr).trim()
        ));
    }
    let listed = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .expect("git ran a moment ago");
    assert!(
        listed.status.success(),
        "git ls-files failed in a checkout: {}",
        String::from_utf8_lossy(&listed.stderr)
    );
    Ok(String::from_utf8_lossy(&listed.stdout)
        .split('\0')
        .filter(|p| !p.is_empty())
        .map(str::to_owned)
        .collect())
}

#[test]
fn git_tracks_no_generated_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = match tracked_files(root) {
        Ok(files) => files,
        Err(why) => {
            println!("skipped: {why}; the tracked-files check needs a git checkout");
            return;
        }
    };
    assert!(
        files.iter().any(|f| f == "Cargo.toml"),
        "git ls-files in {} does not list Cargo.toml: not the workspace's checkout?",
        root.display()
    );
    let offending: Vec<String> = files
        .iter()
        .filter_map(|f| generated(f).map(|why| format!("{f}: {why}")))
        .collect();
    assert!(
        offending.is_empty(),
        "git tracks generated files (`git rm --cached` them; .gitignore should cover them):\n{}",
        offending.join("\n")
    );
}

#[test]
fn the_rules_tell_generated_files_from_sources() {
    for path in [
        "scripts/__pycache__/study.cpython-311.pyc",
        "python/peritherm/__pycache__/x.py",
        "scripts/study.pyc",
        "target/release/peritherm",
        "out/bench/bar/run.json",
        "plots/field.png",
    ] {
        assert!(
            generated(path).is_some(),
            "{path} should count as generated"
        );
    }
    for path in [
        "scripts/study.py",
        "docs/images/crack_plate_map.png",
        "crates/core/src/cloud/fictitious.rs",
        "validation/bench_step.json",
        "tests/data/make_fixtures.py",
        "docs/target/notes.md",
        "plots/README.md",
        "python/src/lib.rs",
    ] {
        assert!(generated(path).is_none(), "{path} should count as a source");
    }
}
