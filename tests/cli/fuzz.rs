//! A mutation fuzzer over the bundled cases, a small plate and a small gmsh mesh (issue 15):
//! every mutated input goes through the validation path of `check` and `run`
//! ([`peritherm::prepare`], in-process) and must end `Ok` or with one clear error line that
//! names a file, never a panic, an abort or a run past the time limit.
//!
//! `PERITHERM_FUZZ_INPUTS` and `PERITHERM_FUZZ_START` (a generator state) explore further.

use crate::common::hostile::{mutate, Rng, PLATE};
use peritherm::case::Case;
use peritherm::prepare::{build, plan, Options};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Inputs per CI run: issue 15 asks for at least 2 000 within 60 s.
const INPUTS: usize = 2400;
/// One input's limit: a validation that takes longer counts as a hang. Honest inputs take
/// milliseconds here (the budget below keeps the models small). One known input is slow:
/// two node coordinates of the 64-element square swapped (a warped element) keep the
/// consistent-weights solve (`crates/core/src/weights`) busy for 9-13 s; 30 s leaves room for it on a
/// loaded machine. Inputs slower than a quarter of the limit are reported on stderr, their
/// mesh kept in the temporary directory as `peritherm_fuzz_slow_<k>.msh`.
const PER_INPUT: Duration = Duration::from_secs(30);
/// The memory a mutated case may plan to use: keeps every model the fuzzer builds small
/// (the plate is 2 MiB), and makes the budget refuse the large bundled cases quickly.
const MAX_MEMORY: f64 = 16.0 * 1024.0 * 1024.0;
/// The generator's default starting state (any nonzero value; fixed for reproducible CI).
const START: u64 = 0x5eed_cafe_f00d_d00d;

/// One base input: a case text and where it pretends to live (for relative paths), and
/// optionally a mesh text it reads (`MESH` in the case is replaced by the mesh's path).
struct Base {
    case: String,
    path: PathBuf,
    mesh: Option<String>,
}

fn corpus(tmp: &Path) -> Vec<Base> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut bases = Vec::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(root.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    for p in names {
        bases.push(Base {
            case: std::fs::read_to_string(&p).unwrap(),
            path: p,
            mesh: None,
        });
    }
    // the small inputs whose models are built: weighted up by repetition
    let square = std::fs::read_to_string(root.join("tests/data/square_quad.msh")).unwrap();
    let mesh_case = "dimension = 2\n[mesh]\nfile = \"MESH\"\n[[region]]\nname = \"plate\"\nhorizon = { factor = 3.0 }\n[material.steel]\nconductivity = 50.0\ndensity = 7850.0\nspecific_heat = 420.0\n[boundary.left]\ntype = \"temperature\"\nvalue = 100.0\n[boundary.right]\ntype = \"flux\"\nvalue = \"10*t\"\n[time]\nend = 2.0\n[[crack]]\ngroup = \"top\"\n";
    for _ in 0..bases.len() {
        bases.push(Base {
            case: PLATE.to_string(),
            path: tmp.join("plate.toml"),
            mesh: None,
        });
        bases.push(Base {
            case: mesh_case.replace("[[crack]]\ngroup = \"top\"\n", ""),
            path: tmp.join("mesh.toml"),
            mesh: Some(square.clone()),
        });
    }
    bases
}

/// What one input did.
enum Outcome {
    Ok,
    Refused(String),
    Panicked(String),
}

/// The validation path of `check` (and of `run` before its time loop).
fn validate(text: &str, path: &Path) -> Result<(), String> {
    let case = Case::parse(text, path).map_err(|e| e.to_string())?;
    let options = Options {
        max_memory: Some(MAX_MEMORY),
        cache: None,
    };
    let model = build(&case, &options).map_err(|e| e.to_string())?;
    plan(&case, &model).map(|_| ()).map_err(|e| e.to_string())
}

/// A clear error: one line, short enough to read, naming a file.
fn is_clear(msg: &str) -> bool {
    !msg.is_empty()
        && !msg.contains('\n')
        && msg.len() < 2000
        && [".toml", ".msh", ".csv"].iter().any(|e| msg.contains(e))
}

#[test]
fn mutated_cases_and_meshes_end_ok_or_with_one_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let bases = corpus(tmp.path());
    let inputs: usize = std::env::var("PERITHERM_FUZZ_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(INPUTS);
    let start = std::env::var("PERITHERM_FUZZ_START")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(START);
    let dir = tmp.path().to_path_buf();
    let (tx, rx) = mpsc::channel();
    // the input under validation, shown if it hangs
    let current = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let shared = current.clone();
    let started = Instant::now();
    // panics of the worker are counted as failures: keep their messages off the output
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().name() != Some("fuzz-worker") {
            default_hook(info);
        }
    }));
    // one worker: a hang is seen by the clock of this thread, which cannot be blocked
    let worker = std::thread::Builder::new().name("fuzz-worker".into());
    let _ = worker.spawn(move || {
        let mut rng = Rng::new(start);
        for k in 0..inputs {
            let base = &bases[rng.below(bases.len())];
            let (mut case, mut mesh) = (base.case.clone(), base.mesh.clone());
            for _ in 0..1 + rng.below(3) {
                match &mesh {
                    Some(m) if rng.below(2) == 0 => mesh = Some(mutate(m, &mut rng)),
                    _ => case = mutate(&case, &mut rng),
                }
            }
            if let Some(m) = &mesh {
                let file = dir.join(format!("fuzz_{k}.msh"));
                std::fs::write(&file, m).unwrap();
                case = case.replace("MESH", &file.display().to_string());
            }
            let path = base.path.clone();
            *shared.lock().unwrap() = format!("{}:\n{case}", path.display());
            let text = case.clone();
            let clock = Instant::now();
            let outcome = match std::panic::catch_unwind(move || validate(&text, &path)) {
                Ok(Ok(())) => Outcome::Ok,
                Ok(Err(m)) => Outcome::Refused(m),
                Err(p) => Outcome::Panicked(
                    p.downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| p.downcast_ref::<String>().cloned())
                        .unwrap_or_default(),
                ),
            };
            if clock.elapsed() > PER_INPUT / 4 {
                let kept = std::env::temp_dir().join(format!("peritherm_fuzz_slow_{k}.msh"));
                let _ = std::fs::copy(dir.join(format!("fuzz_{k}.msh")), kept);
                eprintln!(
                    "fuzz: input {k} ({}) took {:.1} s",
                    base.path.display(),
                    clock.elapsed().as_secs_f64()
                );
                if std::env::var_os("PERITHERM_FUZZ_SHOW").is_some() {
                    eprintln!("{case}");
                }
            }
            let _ = std::fs::remove_file(dir.join(format!("fuzz_{k}.msh")));
            if tx.send((k, case, outcome)).is_err() {
                return;
            }
        }
    });
    let (mut ok, mut refused, mut failures) = (0, 0, Vec::new());
    for _ in 0..inputs {
        let done = ok + refused + failures.len();
        let (k, case, outcome) = match rx.recv_timeout(PER_INPUT) {
            Ok(r) => r,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                // keep a mutated mesh for the record (the temporary directory goes)
                let kept = std::env::temp_dir().join("peritherm_fuzz_hang.msh");
                let _ = std::fs::copy(tmp.path().join(format!("fuzz_{done}.msh")), &kept);
                panic!(
                    "input {done} ran past {PER_INPUT:?} (a hang; a mutated mesh is kept as {}): {}",
                    kept.display(),
                    current.lock().map(|c| c.clone()).unwrap_or_default()
                )
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                panic!("the fuzz worker stopped at input {done} (a panic outside the validation)")
            }
        };
        match outcome {
            Outcome::Ok => ok += 1,
            Outcome::Refused(m) if is_clear(&m) => refused += 1,
            Outcome::Refused(m) => failures.push(format!("input {k}: unclear error `{m}`\n{case}")),
            Outcome::Panicked(m) => failures.push(format!("input {k}: panicked: {m}\n{case}")),
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    eprintln!(
        "fuzz: {inputs} inputs in {seconds:.1} s: {ok} ok, {refused} refused, {} failed",
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {inputs} inputs failed; the first:\n{}",
        failures.len(),
        failures[..failures.len().min(3)].join("\n----\n")
    );
    // the mutations must leave some inputs valid (measured: about 10%), or the fuzzer
    // tests only the parser
    assert!(ok > inputs / 50, "only {ok} of {inputs} inputs were valid");
}
