//! Where a run came from, so that its directory stands on its own: every run writes the text
//! of its case as `case.toml` beside its fields, and its `run.json` records the case file's
//! absolute path and a stamp (size and hash) of every file the case read (mesh, reference
//! table). `compare`, `plot` and `report` load the case from that copy, from any working
//! directory, and refuse with a clear line when an input file changed since the run.

use crate::atomic::write_atomic;
use crate::case::Case;
use crate::error::{Error, Result};
use crate::output::{CaseOrigin, FileStamp, RunSummary};
use std::path::{Path, PathBuf};

/// File name of the case copy in a run's directory.
pub const CASE_COPY: &str = "case.toml";

/// FNV-1a, 64 bits: enough to notice that a mesh file changed (not a cryptographic hash).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    })
}

fn stamp(path: &Path) -> Result<FileStamp> {
    let bytes = std::fs::read(path).map_err(|error| Error::Io {
        path: path.to_path_buf(),
        error,
    })?;
    Ok(FileStamp {
        path: absolute(path).display().to_string(),
        bytes: bytes.len() as u64,
        fnv1a: format!("{:016x}", fnv1a(&bytes)),
    })
}

/// The origin of `case` (reads its input files once more to stamp them).
pub fn origin(case: &Case) -> Result<CaseOrigin> {
    Ok(CaseOrigin {
        path: absolute(&case.path).display().to_string(),
        inputs: case
            .inputs
            .iter()
            .map(|p| stamp(p))
            .collect::<Result<_>>()?,
    })
}

/// Writes the case copy of `case` into the run directory `dir`; returns its origin for run.json.
pub fn write_copy(dir: &Path, case: &Case) -> Result<CaseOrigin> {
    write_atomic(&dir.join(CASE_COPY), case.source.as_bytes())?;
    origin(case)
}

/// The case of the run in `dir` (summary `run`): its copy parsed as if it sat at the
/// recorded path, after checking that every input file is still the one the run read. Runs
/// written before the copy existed load the case path as the run recorded it.
pub fn case_of_run(dir: &Path, run: &RunSummary) -> Result<Case> {
    let Some(origin) = run.origin.as_ref() else {
        return Case::load(Path::new(&run.case));
    };
    let copy = dir.join(CASE_COPY);
    let text = std::fs::read_to_string(&copy).map_err(|error| Error::Io {
        path: copy.clone(),
        error,
    })?;
    for input in &origin.inputs {
        let now = stamp(Path::new(&input.path));
        if now.as_ref().ok() != Some(input) {
            return Err(Error::Io {
                path: PathBuf::from(&input.path),
                error: std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "changed or missing since the run in {} read it; run the case again",
                        dir.display()
                    ),
                ),
            });
        }
    }
    Case::parse(&text, Path::new(&origin.path))
}

#[cfg(test)]
mod tests {
    use super::fnv1a;

    /// Reference values of the FNV-1a 64-bit hash (Fowler, Noll & Vo's test vectors).
    #[test]
    fn fnv1a_vectors() {
        assert_eq!(fnv1a(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x85944171f73967e8);
    }
}
