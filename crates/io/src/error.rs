//! Typed errors of the IO layer: a case file or mesh that cannot be used, a file that cannot
//! be read or written, and the numerics' errors ([`CoreError`]) passed through unchanged; the
//! CLI turns each into one line.

use std::path::PathBuf;

pub use peritherm_core::Error as CoreError;

/// Everything that can go wrong reading a case or mesh, or reading and writing a run's files.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A case file that cannot be read, parsed or validated.
    #[error("{file}: {key}: {message}")]
    Case {
        /// The case file.
        file: PathBuf,
        /// The offending key, dotted (e.g. `time.dt`).
        key: String,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A mesh file that cannot be read or does not describe a usable body.
    #[error("{path}: {message}")]
    Mesh {
        /// The mesh file.
        path: PathBuf,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Output could not be written (or a run's files read back).
    #[error("{path}: {error}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error (shown in the message, so not chained as a source).
        error: std::io::Error,
    },
    /// An error of the numerics (`peritherm-core`), with its own message.
    #[error(transparent)]
    Core(#[from] CoreError),
}

/// Result alias of the IO layer.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for a [`CoreError::Model`] (a key or component and what is wrong with it).
    pub fn model(key: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Core(CoreError::model(key, message))
    }

    /// The numerics' error this is, if it is one.
    pub fn core(&self) -> Option<&CoreError> {
        match self {
            Error::Core(e) => Some(e),
            _ => None,
        }
    }
}
