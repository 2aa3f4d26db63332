//! Typed errors for every reader and writer, carrying the context a user needs to fix the input:
//! file, line, section and what was expected.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in an input a problem was found.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Location {
    /// File name as given by the user (`-` for standard input).
    pub file: String,
    /// 1-based line number, 0 when the problem concerns the file as a whole.
    pub line: usize,
    /// Section keyword (`$$STARTNODES`, `$Elements`, ...) when known.
    pub section: Option<String>,
}

impl Location {
    /// A location at `line` of `file`, inside `section` if any.
    pub fn new(file: &str, line: usize, section: Option<&str>) -> Self {
        Location {
            file: file.to_string(),
            line,
            section: section.map(str::to_string),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if self.line > 0 {
            write!(f, ":{}", self.line)?;
        }
        if let Some(s) = &self.section {
            write!(f, " (in {s})")?;
        }
        Ok(())
    }
}

/// Errors raised while reading, interpreting or writing model files.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened, read or written.
    // The OS error is part of the message rather than a `source`, so that a chain printed
    // with `{:#}` does not say it twice.
    #[error("{path}: {}", io_reason(cause))]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The operating-system error.
        cause: std::io::Error,
    },
    /// The content does not follow the format.
    #[error("{at}: {message}")]
    Format {
        /// Where the problem is.
        at: Location,
        /// What was expected and what was found.
        message: String,
    },
    /// The content is well formed but inconsistent (ids out of range, counts that disagree).
    #[error("{at}: {message}")]
    Invalid {
        /// Where the problem is.
        at: Location,
        /// What is inconsistent.
        message: String,
    },
    /// A model cannot be renumbered safely because a section's ids are not understood.
    #[error("cannot renumber: section {section} {reason}")]
    Unremappable {
        /// The section keyword.
        section: String,
        /// Why it cannot be remapped.
        reason: String,
    },
    /// A feature the input asks for that this program does not support.
    #[error("{at}: unsupported: {message}")]
    Unsupported {
        /// Where the request is.
        at: Location,
        /// What is not supported.
        message: String,
    },
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            cause: source,
        }
    }

    /// What went wrong without the file's name, for a caller whose own error names it: an I/O
    /// error's reason, or the whole message of any other.
    pub fn reason(&self) -> String {
        match self {
            Error::Io { cause, .. } => cause.to_string(),
            e => e.to_string(),
        }
    }

    /// A format error at `at`.
    pub fn format(at: Location, message: impl Into<String>) -> Self {
        Error::Format {
            at,
            message: message.into(),
        }
    }

    /// An invalid-content error at `at`.
    pub fn invalid(at: Location, message: impl Into<String>) -> Self {
        Error::Invalid {
            at,
            message: message.into(),
        }
    }
}

/// Result alias for this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The OS error in plain words, without the `(os error N)` suffix where a plain phrase exists.
fn io_reason(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    match e.kind() {
        K::NotFound => "no such file or folder".into(),
        K::PermissionDenied => "permission denied".into(),
        K::AlreadyExists => "already exists".into(),
        _ => e.to_string(),
    }
}
