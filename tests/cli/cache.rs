//! The cache of consistent weights (`--cache`, `$PERITHERM_CACHE`): a rerun that changes
//! nothing the weights depend on loads them, a Δt sweep pays the set-up once, an edit of the
//! mesh, a horizon or a kernel key computes them again, a damaged cache file is never trusted,
//! and the fields are the same bytes with and without the cache.

use crate::common::cli::command;
use crate::common::runs::same_field_files;
use std::path::{Path, PathBuf};

/// A corrected gmsh case (2 020 default triangles, δ = 3Δ, consistent weights by default)
/// on the mesh `mesh`.
fn case_text(mesh: &Path) -> String {
    format!(
        r#"title = "weights cache"
dimension = 2
[mesh]
file = "{}"
[[region]]
name = "body"
horizon = {{ factor = 3 }}
[kernel]
p = 2
profile = "constant"
[material.unit]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[boundary.held]
type = "temperature"
value = 0.0
[initial]
value = 100.0
[time]
end = 1e-5
"#,
        mesh.display()
    )
}

/// A directory with the case and its own copy of the mesh, and an empty cache in it.
struct Setting {
    dir: tempfile::TempDir,
}

impl Setting {
    fn new() -> Setting {
        let dir = tempfile::tempdir().unwrap();
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mesh = dir.path().join("rect.msh");
        std::fs::copy(root.join("meshes/conv_rect_tri_L1.msh"), &mesh).unwrap();
        std::fs::write(dir.path().join("case.toml"), case_text(&mesh)).unwrap();
        Setting { dir }
    }

    fn cache(&self) -> PathBuf {
        self.dir.path().join("cache")
    }

    /// `peritherm --cache <cache|off> run case.toml --out <name> [--set ...]`; its run.json.
    fn run(&self, name: &str, cached: bool, set: &[&str]) -> serde_json::Value {
        let out = self.dir.path().join(name);
        let cache = if cached { self.cache() } else { "off".into() };
        let mut cmd = command();
        cmd.arg("--cache")
            .arg(&cache)
            .arg("run")
            .arg(self.dir.path().join("case.toml"));
        cmd.arg("--out").arg(&out).arg("-q");
        for s in set {
            cmd.args(["--set", s]);
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(out.join("run.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    }

    /// The one cache file.
    fn entry(&self) -> PathBuf {
        let files: Vec<PathBuf> = std::fs::read_dir(self.cache())
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "weights"))
            .collect();
        assert_eq!(files.len(), 1, "{files:?}");
        files[0].clone()
    }
}

fn reused(summary: &serde_json::Value) -> bool {
    summary["consistency"]["reused"].as_bool().unwrap()
}

fn setup_seconds(summary: &serde_json::Value) -> f64 {
    summary["setup_seconds"].as_f64().unwrap()
}

fn fields(summary: &serde_json::Value) -> Vec<String> {
    let files = summary["fields"]
        .as_array()
        .expect("run.json lists its fields");
    files
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect()
}

/// A second run with another end time loads the weights: its set-up takes at most 10 % of the
/// first's (the issue's bound; loading reads 8 B per bond, solving costs thousands of bond
/// sweeps), and its fields are the bytes of a run without the cache.
#[test]
fn a_rerun_with_another_end_time_reuses_the_weights() {
    let s = Setting::new();
    let first = s.run("first", true, &[]);
    let again = s.run("again", true, &["time.end=2e-5"]);
    let plain = s.run("plain", false, &["time.end=2e-5"]);
    assert!(!reused(&first) && reused(&again) && !reused(&plain));
    let (a, b) = (setup_seconds(&first), setup_seconds(&again));
    assert!(b <= 0.1 * a, "set-up {b} s against {a} s");
    let dirs = (s.dir.path().join("plain"), s.dir.path().join("again"));
    same_field_files(
        &dirs.0,
        &dirs.1,
        &fields(&plain),
        "without and with the cache",
    );
}

/// A sweep over Δt solves the weights once and loads them for every other variant.
#[test]
fn a_time_step_sweep_pays_the_set_up_once() {
    let s = Setting::new();
    let out = s.dir.path().join("sweep");
    let o = command()
        .arg("--cache")
        .arg(s.cache())
        .args(["sweep", "--vary", "time.dt=1e-6,5e-7,2.5e-7", "--out"])
        .arg(&out)
        .arg(s.dir.path().join("case.toml"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut solved = 0;
    let mut variants = 0;
    for e in std::fs::read_dir(&out).unwrap() {
        let run = e.unwrap().path().join("run.json");
        if let Ok(text) = std::fs::read_to_string(run) {
            let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
            variants += 1;
            solved += usize::from(!reused(&summary));
        }
    }
    assert_eq!(
        (variants, solved),
        (3, 1),
        "variants, and those that solved the weights"
    );
}

/// Editing the mesh file in place, a horizon or a kernel key computes the weights again (and
/// the edited case's weights are then cached too: two entries).
#[test]
fn editing_the_mesh_a_horizon_or_a_kernel_key_recomputes() {
    let s = Setting::new();
    assert!(!reused(&s.run("first", true, &[])));
    let edits: [&[&str]; 3] = [
        &["region.0.horizon.factor=3.1"],
        &["kernel.profile=\"conical\""],
        &["kernel.p=1"],
    ];
    for set in edits {
        assert!(!reused(&s.run("edited", true, set)), "{set:?}");
        assert!(reused(&s.run("edited", true, set)), "{set:?} again");
    }
    // one interior node of the mesh moved by 1e-9 m: the same file name, other content
    let mesh = s.dir.path().join("rect.msh");
    let text = std::fs::read_to_string(&mesh).unwrap();
    let end = text.find("$EndNodes").unwrap();
    let line = text[..end].trim_end().rfind('\n').unwrap() + 1;
    let (x, rest) = text[line..end].split_once(' ').unwrap();
    let moved = format!("{:e}", x.parse::<f64>().unwrap() + 1e-9);
    let edited = format!("{}{moved} {rest}{}", &text[..line], &text[end..]);
    std::fs::write(&mesh, edited).unwrap();
    assert!(!reused(&s.run("moved", true, &[])), "an edited mesh");
    assert!(reused(&s.run("moved", true, &[])), "the edited mesh again");
}

/// A truncated cache file, and one with a flipped bit, are detected: the weights are computed
/// again (the same bytes of fields) and the entry is written anew.
#[test]
fn a_damaged_cache_file_is_recomputed_not_trusted() {
    let s = Setting::new();
    let first = s.run("first", true, &[]);
    let entry = s.entry();
    let bytes = std::fs::read(&entry).unwrap();
    let damaged = [bytes[..bytes.len() / 2].to_vec(), {
        let mut b = bytes.clone();
        let at = b.len() - 1000;
        b[at] ^= 0x01;
        b
    }];
    for (k, d) in damaged.iter().enumerate() {
        std::fs::write(&entry, d).unwrap();
        let name = format!("damaged{k}");
        let summary = s.run(&name, true, &[]);
        assert!(!reused(&summary), "damage {k} was trusted");
        let dirs = (s.dir.path().join("first"), s.dir.path().join(&name));
        same_field_files(
            &dirs.0,
            &dirs.1,
            &fields(&first),
            "intact and damaged cache",
        );
        assert_eq!(
            std::fs::read(s.entry()).unwrap(),
            bytes,
            "the entry is written anew"
        );
    }
}

/// `check` does not solve the weights (it estimates them and leaves the cache empty); after a
/// run has solved them, `check` loads them.
#[test]
fn check_estimates_the_weights_and_loads_what_a_run_kept() {
    let s = Setting::new();
    let check = || {
        let o = command()
            .arg("--cache")
            .arg(s.cache())
            .arg("check")
            .arg(s.dir.path().join("case.toml"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let first = check();
    assert!(
        first.contains("consistent weights not in the weights cache"),
        "{first}"
    );
    assert!(first.contains("estimated"), "{first}");
    let kept = std::fs::read_dir(s.cache()).map_or(0, |d| d.count());
    assert_eq!(kept, 0, "check kept nothing in the cache");
    assert!(!reused(&s.run("first", true, &[])), "the first run solves");
    let second = check();
    assert!(
        second.contains("consistent weights at 1868 nodes loaded from the weights cache"),
        "{second}"
    );
    assert!(reused(&s.run("after", true, &[])), "the run after check");
}
