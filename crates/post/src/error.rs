//! Typed errors of the post-processing layer: a plot that cannot be drawn, and the errors of
//! the layers below it passed through unchanged ([`IoError`] of the files, [`CoreError`] of
//! the numerics); the CLI turns each into one line.

use std::path::PathBuf;

pub use peritherm_io::error::{CoreError, Error as IoError};

/// Everything that can go wrong comparing, reporting and plotting (and, through the layers
/// below, reading a run or a case).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A plot whose data cannot be drawn (empty, non-finite, zero-size range) or whose
    /// files cannot be written.
    #[error("{path}: {message}")]
    Plot {
        /// The plot's file stem (`<stem>.png`, `<stem>.svg`).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An error of the IO layer (`peritherm-io`: a case, mesh or file), with its own message;
    /// never [`IoError::Core`], which converts to [`Error::Core`].
    #[error(transparent)]
    Io(IoError),
    /// An error of the numerics (`peritherm-core`), with its own message.
    #[error(transparent)]
    Core(#[from] CoreError),
}

/// Result alias of the post-processing layer (and of the drivers above it).
pub type Result<T> = std::result::Result<T, Error>;

impl From<IoError> for Error {
    /// The IO layer's error; a numerics error it carries becomes [`Error::Core`], so that each
    /// error has one form.
    fn from(e: IoError) -> Self {
        match e {
            IoError::Core(e) => Error::Core(e),
            e => Error::Io(e),
        }
    }
}

impl Error {
    /// Shorthand for a [`CoreError::Model`] (a key or component and what is wrong with it).
    pub fn model(key: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Core(CoreError::model(key, message))
    }

    /// The numerics' error this is, if it is one.
    pub fn core(&self) -> Option<&CoreError> {
        match self {
            Error::Core(e) | Error::Io(IoError::Core(e)) => Some(e),
            _ => None,
        }
    }

    /// The IO layer's error this is, if it is one (a case, mesh or file).
    pub fn io(&self) -> Option<&IoError> {
        match self {
            Error::Io(e) => Some(e),
            _ => None,
        }
    }
}
