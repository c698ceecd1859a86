//! The error of this crate: one line naming the file, the line where known, and the problem.

use std::fmt;

/// A malformed or unsupported photometric file. `Display` gives `file:line: message` (or
/// `file: message` when no line applies), one line, as the stages print it.
#[derive(Debug, Clone, PartialEq)]
pub struct PhotometryError {
    /// The file as the caller named it.
    pub file: String,
    /// 1-based line number of the offending value, when one applies.
    pub line: Option<usize>,
    /// What is wrong, in one line.
    pub message: String,
}

impl PhotometryError {
    pub fn new(file: &str, line: Option<usize>, message: impl Into<String>) -> Self {
        PhotometryError {
            file: file.to_string(),
            line,
            message: message.into().replace(['\n', '\r'], " "),
        }
    }
}

impl fmt::Display for PhotometryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.file, line, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for PhotometryError {}

/// Renders a token for an error message, truncated so a message stays one short line.
pub(crate) fn show(token: &str) -> String {
    let mut s: String = token.chars().take(24).collect();
    if token.chars().count() > 24 {
        s.push('…');
    }
    s.escape_debug().to_string()
}
