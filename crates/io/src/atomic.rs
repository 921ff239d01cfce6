//! Atomic file writes ([`write_atomic`]) under the lock ([`writing`]) that the interrupt
//! handler ([`crate::staging::interrupt`]) takes, so that no output file is cut in half.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;
use std::sync::{Mutex, MutexGuard};

/// Held while a file is written and while a directory is swapped in; the interrupt handler
/// takes it and never lets go, so no write is cut in half and none starts after it.
static WRITING: Mutex<()> = Mutex::new(());

/// The lock of `WRITING`, poisoned or not.
pub fn writing() -> MutexGuard<'static, ()> {
    WRITING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Writes `bytes` to a temporary file beside `path`, then renames it into place.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` streams into a buffered writer (no copy of the whole file
/// in memory); a failed write leaves no file at `path` and no temporary beside it.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial"));
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        error: source,
    };
    // an interrupt waits for this write to end ([`crate::staging::interrupt`])
    let _guard = writing();
    let written = std::fs::File::create(&tmp).and_then(|file| {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        write(&mut w)?;
        w.into_inner().map(drop).map_err(|e| e.into_error())
    });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    std::fs::rename(&tmp, path).map_err(io)
}
