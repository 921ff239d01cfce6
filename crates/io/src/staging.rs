//! Transactional output directories: a run writes into a fresh hidden directory beside
//! `--out` and swaps it into place when it ends, so `--out` never mixes files of two runs.
//!
//! - A run that completes replaces `--out` whole (stale `field_*` of a longer earlier run go).
//! - A run that fails during its time loop (non-finite state, a write error) still replaces
//!   it: its complete fields and a `run.json` whose `status` is `failed`, with the message.
//! - A run interrupted by SIGINT or SIGTERM ([`interrupt`]) does the same with `status`
//!   `interrupted` and the simulated time reached; no `.partial` file remains.
//! - A case refused before its time loop leaves `--out` as it was.
//!
//! An existing `--out` is only replaced when it holds nothing but peritherm output.

use crate::atomic::writing;
use crate::error::{Error, Result};
use crate::output::Unfinished;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Staged directories of the runs under way, outermost first.
static ACTIVE: Mutex<Vec<(PathBuf, PathBuf, String)>> = Mutex::new(Vec::new());
/// Simulated time the innermost run has reached, s (as f64 bits).
static REACHED: AtomicU64 = AtomicU64::new(0);
/// Distinguishes the staged directories of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

fn active() -> MutexGuard<'static, Vec<(PathBuf, PathBuf, String)>> {
    ACTIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Records the simulated time a run has reached, s (reported if it is interrupted).
pub fn reached(t: f64) {
    REACHED.store(t.to_bits(), Ordering::Relaxed);
}

/// Names an output directory may hold and still be replaced: a run's own files.
fn is_ours(name: &str) -> bool {
    name == "run.json"
        || name == crate::provenance::CASE_COPY
        || name == crate::history::FILE
        || name == "fem"
        || name == "fields.pvd"
        || name.starts_with('.')
        || ["field_", "map_", "damage_", "flux_"]
            .iter()
            .any(|p| name.starts_with(p))
}

/// Runs `write` into a staged copy of `out` for the run of `case` and swaps it in when it
/// succeeds; a failure after something was written leaves a run.json saying so, a refusal
/// before anything was written leaves `out` as it was. `write` may fail with the error of
/// any layer above this one (`E`), which holds this layer's.
pub fn write_into<T, E>(
    out: &Path,
    case: &str,
    write: impl FnOnce(&Path) -> std::result::Result<T, E>,
) -> std::result::Result<T, E>
where
    E: From<Error> + std::fmt::Display,
{
    let staged = Staged::begin(out, case)?;
    match write(staged.dir()) {
        Ok(value) => {
            staged.commit()?;
            Ok(value)
        }
        Err(e) => {
            let wrote = std::fs::read_dir(staged.dir()).is_ok_and(|mut d| d.next().is_some());
            if wrote {
                staged.fail(case, &e.to_string())?;
            }
            Err(e)
        }
    }
}

/// An output directory being written: files go into [`Staged::dir`] until [`Staged::commit`].
#[derive(Debug)]
pub struct Staged {
    out: PathBuf,
    tmp: PathBuf,
    done: bool,
}

impl Staged {
    /// Starts writing `out` for the run of `case`: refuses an `out` that is a file or holds
    /// files that are not peritherm output, and creates a fresh hidden directory beside it.
    pub fn begin(out: &Path, case: &str) -> Result<Staged> {
        let io = |path: &Path, error| Error::Io {
            path: path.to_path_buf(),
            error,
        };
        if out.exists() {
            let entries = std::fs::read_dir(out).map_err(|e| io(out, e))?;
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if !is_ours(&name) {
                    return Err(io(
                        out,
                        std::io::Error::other(format!(
                            "--out: the directory holds `{name}`, which is not peritherm output; a run replaces its --out whole, so choose an empty or new directory"
                        )),
                    ));
                }
            }
        }
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|e| io(&parent, e))?;
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = parent.join(format!(".{name}.staged-{}-{n}", std::process::id()));
        if tmp.exists() {
            std::fs::remove_dir_all(&tmp).map_err(|e| io(&tmp, e))?;
        }
        std::fs::create_dir(&tmp).map_err(|e| io(&tmp, e))?;
        active().push((out.to_path_buf(), tmp.clone(), case.to_string()));
        reached(0.0);
        Ok(Staged {
            out: out.to_path_buf(),
            tmp,
            done: false,
        })
    }

    /// Where the run writes until it commits.
    pub fn dir(&self) -> &Path {
        &self.tmp
    }

    /// Swaps the written directory into place of `out`.
    pub fn commit(mut self) -> Result<()> {
        let _guard = writing();
        self.done = true;
        active().retain(|a| a.1 != self.tmp);
        swap(&self.tmp, &self.out)
    }

    /// Ends a run that failed during its time loop: its complete fields and a `run.json` of
    /// status `failed` with `message` replace `out`.
    pub fn fail(self, case: &str, message: &str) -> Result<()> {
        {
            let _guard = writing();
            write_unfinished(&self.tmp, "failed", case, message)?;
        }
        self.commit()
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.done {
            active().retain(|a| a.1 != self.tmp);
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Renames `tmp` to `out`, an existing `out` first moved aside and then removed.
fn swap(tmp: &Path, out: &Path) -> Result<()> {
    let io = |path: &Path, error| Error::Io {
        path: path.to_path_buf(),
        error,
    };
    if out.exists() {
        let old = tmp.with_extension("old");
        std::fs::rename(out, &old).map_err(|e| io(out, e))?;
        std::fs::rename(tmp, out).map_err(|e| io(out, e))?;
        std::fs::remove_dir_all(&old).map_err(|e| io(&old, e))
    } else {
        std::fs::rename(tmp, out).map_err(|e| io(out, e))
    }
}

/// Removes `.partial` files in `dir` and writes its `run.json` of an unfinished run.
fn write_unfinished(dir: &Path, status: &str, case: &str, message: &str) -> Result<()> {
    let mut fields = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".partial") {
                let _ = std::fs::remove_file(e.path());
            } else if name.starts_with("field_") && name.ends_with(".csv") {
                fields.push(name);
            }
        }
    }
    let index = |n: &String| {
        n.trim_start_matches("field_")
            .trim_end_matches(".csv")
            .parse::<usize>()
            .unwrap_or(0)
    };
    fields.sort_by_key(index);
    let record = Unfinished {
        status: status.into(),
        case: case.into(),
        time: f64::from_bits(REACHED.load(Ordering::Relaxed)),
        message: message.into(),
        fields,
    };
    let json = serde_json::to_string_pretty(&record).expect("plain data serialises");
    std::fs::write(dir.join("run.json"), json).map_err(|error| Error::Io {
        path: dir.join("run.json"),
        error,
    })
}

/// The signal handler's work (SIGINT or SIGTERM): waits for a write in flight, removes the
/// nested runs' directories, turns the outermost run's directory into an interrupted run
/// (`run.json` with the time reached, no `.partial` file) swapped into its `--out`, and
/// exits with status 130.
pub fn interrupt() -> ! {
    let guard = writing();
    let runs = active().clone();
    if let Some((out, tmp, case)) = runs.first() {
        for (_, nested, _) in &runs[1..] {
            let _ = std::fs::remove_dir_all(nested);
        }
        let message = "interrupted by SIGINT or SIGTERM";
        if write_unfinished(tmp, "interrupted", case, message).is_ok() {
            let _ = swap(tmp, out);
        }
        eprintln!(
            "error: {}: interrupted at t = {:e} s; {} holds the fields written and a run.json saying so",
            case,
            f64::from_bits(REACHED.load(Ordering::Relaxed)),
            out.display()
        );
    }
    std::mem::forget(guard);
    std::process::exit(130)
}
