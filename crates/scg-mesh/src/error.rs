//! Errors of mesh and field input: each names the file and the entry at fault.

use std::path::PathBuf;

/// A mesh or field that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A file was read but its content is wrong.
    #[error("{file}: {entry}: {message}")]
    Invalid {
        /// The file.
        file: PathBuf,
        /// The entry at fault (a dictionary key, a list index, a cell or face number).
        entry: String,
        /// What is wrong.
        message: String,
    },
}

impl MeshError {
    /// An [`MeshError::Invalid`] error.
    pub fn invalid(
        file: impl Into<PathBuf>,
        entry: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        MeshError::Invalid {
            file: file.into(),
            entry: entry.into(),
            message: message.into(),
        }
    }
}
