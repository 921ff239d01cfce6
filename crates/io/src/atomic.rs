//! Atomic file writes ([`write_atomic`]) under the lock ([`writing`]) that the interrupt
//! handler ([`crate::staging::interrupt`]) takes, so that no output file is cut in half.

use crate::error::{Error, Result};
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
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}
