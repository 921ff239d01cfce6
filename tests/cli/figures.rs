//! Figures checked, not pasted: the tables of README.md and docs/ are rendered from the
//! committed figure files of `validation/`, and a figure that moves fails its check.

use crate::common::case::CaseToml;
use crate::common::cli::{command, peritherm, write_case};
use peritherm_post::figures::{block_names, fill_block, Check, Figures, DIR};
use std::path::{Path, PathBuf};

/// The repository root (figure files and docs are found from it).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown file of docs/.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md")];
    for entry in std::fs::read_dir(root().join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            docs.push(path);
        }
    }
    docs.sort();
    docs
}

/// Every `<!-- figures:NAME -->` block of the docs shows `validation/NAME.json` rendered, and
/// every figure file is shown somewhere. With `PERITHERM_BLESS=1` (scripts/update-docs.sh) the
/// blocks are rewritten from the files instead of compared.
#[test]
fn docs_show_the_committed_figures() {
    let bless = std::env::var_os("PERITHERM_BLESS").is_some();
    let mut shown = Vec::new();
    let mut stale = Vec::new();
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        let mut new = text.clone();
        for name in block_names(&text) {
            let file = root().join(DIR).join(format!("{name}.json"));
            let figures = Figures::read(&file).unwrap_or_else(|e| panic!("{}: {e}", doc.display()));
            new = fill_block(&new, &name, &figures.markdown()).unwrap();
            shown.push(name);
        }
        if new != text {
            match bless {
                true => std::fs::write(&doc, new).unwrap(),
                false => stale.push(doc.display().to_string()),
            }
        }
    }
    assert!(
        stale.is_empty(),
        "tables differ from validation/*.json (run scripts/update-docs.sh): {stale:?}"
    );
    for entry in std::fs::read_dir(root().join(DIR)).unwrap() {
        let stem = entry
            .unwrap()
            .path()
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        assert!(
            shown.contains(&stem),
            "validation/{stem}.json is shown by no docs block"
        );
    }
}

/// `peritherm ARGS --out OUT` for a figure check.
fn rerun(args: &[String], out: &Path) -> Result<(), String> {
    let o = command().args(args).arg("--out").arg(out).output().unwrap();
    o.status
        .success()
        .then_some(())
        .ok_or_else(|| String::from_utf8_lossy(&o.stderr).into_owned())
}

/// The checker can fail: the figures of a small run hold when it runs again, and the same
/// figures with one measure moved by 1e-9 relative, or one field file's hash changed, do not.
#[test]
fn a_moved_figure_fails_its_check() {
    let dir = tempfile::tempdir().unwrap();
    let case = CaseToml::new(1)
        .domain("[0.0]", "[1.0]")
        .domain_key("area = 1.0")
        .region("bar", "cells = [50]", 3.0)
        .material("m", 1.0, 1.0, 1.0)
        .section("[boundary.x_min]\ntype = \"temperature\"\nvalue = 0.0\n[boundary.x_max]\ntype = \"temperature\"\nvalue = 0.0")
        .section("[reference.solution]\nkind = \"bar_fixed_ends\"\nx0 = 0.0\nlength = 1.0\ndiffusivity = 1.0\nleft = 0.0\nright = 0.0\ninitial = 1.0")
        .initial_value(1.0)
        .end(0.02)
        .time_key("outputs = [0.005, 0.02]");
    let case = write_case(dir.path(), "bar.toml", &case.text());
    let out = dir.path().join("run");
    let json = dir.path().join("accuracy.json");
    // the keys set on the command line are part of the run: a rerun must set them too
    let set = [
        "--set",
        "time.end=0.01",
        "--set",
        "time.outputs=[0.005, 0.01]",
    ];
    let args = [
        "run",
        case.as_str(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    assert!(peritherm(&[&args[..], &set].concat()).status.success());
    let table = peritherm(&[
        "table",
        out.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(
        table.status.success(),
        "{}",
        String::from_utf8_lossy(&table.stderr)
    );
    let figures = Figures::read(&json).unwrap();
    let measures = figures
        .checks
        .iter()
        .filter(|c| matches!(c, Check::Measure { .. }));
    let files = figures
        .checks
        .iter()
        .filter(|c| matches!(c, Check::File { .. }));
    assert_eq!(
        (measures.count(), files.count()),
        (6, 2),
        "3 measures and a field at 2 times"
    );
    let scratch = dir.path().join("rerun");
    assert_eq!(figures.verify(&scratch, rerun), Vec::<String>::new());

    let mut moved = figures.clone();
    for check in &mut moved.checks {
        match check {
            Check::Measure { value, pointer, .. } if pointer.ends_with("0/max_abs_diff") => {
                *value *= 1.0 + 1e-9
            }
            Check::File { fnv1a, file, .. } if file == "field_2.csv" => *fnv1a = "0".repeat(16),
            _ => {}
        }
    }
    let failures = moved.verify(&dir.path().join("rerun2"), rerun);
    assert_eq!(failures.len(), 2, "{failures:?}");
}
