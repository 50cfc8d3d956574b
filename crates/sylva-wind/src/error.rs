//! Error types of the wind crate: bad parameters (naming the field) and bad files (naming
//! the byte offset or header field).

use thiserror::Error;

/// A parameter outside its valid range.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("wind parameter `{field}` = {value} is invalid: expected {expected}")]
pub struct ParamError {
    /// Dotted name of the field, as in the parameter file.
    pub field: &'static str,
    /// The value found.
    pub value: f64,
    /// The valid range, in words.
    pub expected: &'static str,
}

impl ParamError {
    pub(crate) fn new(field: &'static str, value: f64, expected: &'static str) -> Self {
        ParamError { field, value, expected }
    }
}

/// Any failure of the wind crate that a caller cannot rule out beforehand.
#[derive(Debug, Error)]
pub enum WindError {
    /// A parameter or grid setting is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The parameter combination is not supported (e.g. pair-mean coherence with the
    /// separable method on several heights).
    #[error("unsupported configuration: {0}")]
    Unsupported(String),
    /// An I/O error while reading or writing `path`. Its message names the file and the
    /// system's reason; the I/O error is in `error`, not repeated as the
    /// [`source`](std::error::Error::source), so a printed chain says it once.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// A wind file is malformed at a byte offset.
    #[error("malformed wind file at byte {offset}: {reason}")]
    Format {
        /// Byte offset of the problem from the start of the file.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// A structure cannot be exported in the requested format.
    #[error("cannot export: {0}")]
    Export(String),
    /// A wind sample is not finite or beyond physical bounds (see
    /// [`crate::field::check_samples`]); the message names its frame and grid point.
    #[error("{0}")]
    Samples(String),
}

impl WindError {
    pub(crate) fn format(offset: u64, reason: impl Into<String>) -> Self {
        WindError::Format { offset, reason: reason.into() }
    }

    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        WindError::Io { path: path.display().to_string(), error: source }
    }
}
