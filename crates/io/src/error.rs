//! The one error type of every stage.
//!
//! Every failure a user can cause is reported as one line that names the file and, where known,
//! the place in it (`scenes/office.ron:12:5`, `materials["white"].reflectance`, `vertex 17`). Stages
//! map [`Error::Usage`] to exit code 2 and everything else to exit code 1, and never panic on
//! bad input.

use std::fmt;
use std::path::{Path, PathBuf};

#[derive(Debug)]
pub enum Error {
    /// The command line itself is wrong (exit code 2).
    Usage(String),
    /// A problem with the content of a file, with the place in it when known.
    Input {
        path: PathBuf,
        place: Option<String>,
        message: String,
    },
    /// An operating-system error reading or writing a file.
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn input(path: impl AsRef<Path>, message: impl Into<String>) -> Error {
        Error::Input {
            path: path.as_ref().to_path_buf(),
            place: None,
            message: message.into(),
        }
    }
    pub fn at(
        path: impl AsRef<Path>,
        place: impl Into<String>,
        message: impl Into<String>,
    ) -> Error {
        Error::Input {
            path: path.as_ref().to_path_buf(),
            place: Some(place.into()),
            message: message.into(),
        }
    }
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }
    /// The process exit code the stages use for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Usage(_) => 2,
            _ => 1,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Messages are kept to one line: embedded newlines (from library errors) become "; ".
        let one_line = |s: &str| s.trim().replace('\n', "; ");
        match self {
            Error::Usage(m) => write!(f, "{}", one_line(m)),
            Error::Input {
                path,
                place: Some(p),
                message,
            } => write!(f, "{}: {}: {}", path.display(), p, one_line(message)),
            Error::Input {
                path,
                place: None,
                message,
            } => write!(f, "{}: {}", path.display(), one_line(message)),
            Error::Io { path, source } => {
                let what = match source.kind() {
                    std::io::ErrorKind::NotFound => "file not found".to_string(),
                    _ => source.to_string(),
                };
                write!(f, "{}: {}", path.display(), one_line(&what))
            }
        }
    }
}

impl std::error::Error for Error {}
