//! Maze files: the task's numeric format and the micromouse ASCII "mazefiles" format.
//!
//! Both parsers take the file's bytes and return a [`Maze`] or a [`MazeError`] that says
//! where (line and column, 1-based) and why. [`parse`] picks the format from the first
//! character: a digit means numeric, `o` means ASCII.

pub mod ascii;
pub mod numeric;

use super::geometry::Position;
use super::maze::{Maze, StructureError};

/// The largest maze file accepted (RULES.md edge cases: a file over 1 MiB is rejected).
pub const MAX_FILE_BYTES: usize = 1024 * 1024;

/// A maze file that cannot be played, with the place and the reason.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MazeError {
    /// The text itself is malformed at a given place.
    #[error("line {line}, column {column}: {reason}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// What is wrong there.
        reason: String,
    },
    /// The text is well formed but the walls break a rule of RULES.md.
    #[error("line {line}: {error}")]
    Structure {
        /// The line where the (first) cell concerned is written.
        line: usize,
        /// The rule that is broken, naming the cell(s).
        error: StructureError,
    },
    /// The file is larger than [`MAX_FILE_BYTES`]; the place where it passes the limit
    /// is named.
    #[error(
        "line {line}, column {column}: the file goes past the 1 MiB limit here (maze files are at most {MAX_FILE_BYTES} bytes)"
    )]
    TooLarge {
        /// 1-based line where the limit is passed.
        line: usize,
        /// 1-based column (in bytes) where the limit is passed.
        column: usize,
    },
}

impl MazeError {
    pub(crate) fn syntax(line: usize, column: usize, reason: impl Into<String>) -> MazeError {
        MazeError::Syntax {
            line,
            column,
            reason: reason.into(),
        }
    }

    /// The 1-based line the error points at.
    pub fn line(&self) -> usize {
        match self {
            MazeError::Syntax { line, .. }
            | MazeError::Structure { line, .. }
            | MazeError::TooLarge { line, .. } => *line,
        }
    }
}

/// The two file formats a maze can come in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// The task's format: `n`, then `n` lines of `n` comma-separated 4-bit values.
    Numeric,
    /// The micromouse community format with posts `o`, walls `---` and `|`.
    Ascii,
}

/// Guesses the format from the first non-blank character.
pub fn detect(bytes: &[u8]) -> Format {
    match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'o') | Some(b'+') => Format::Ascii,
        _ => Format::Numeric,
    }
}

/// Parses a maze file of either format (see [`detect`]).
///
/// # Errors
/// A [`MazeError`] naming the line (and column) and the reason.
pub fn parse(bytes: &[u8]) -> Result<Maze, MazeError> {
    match detect(bytes) {
        Format::Numeric => numeric::parse(bytes),
        Format::Ascii => ascii::parse(bytes),
    }
}

/// Checks the size and decodes UTF-8, naming the line and column of a bad byte.
pub(crate) fn decode(bytes: &[u8]) -> Result<&str, MazeError> {
    if bytes.len() > MAX_FILE_BYTES {
        let head = &bytes[..MAX_FILE_BYTES];
        let line = head.iter().filter(|&&b| b == b'\n').count() + 1;
        let column =
            MAX_FILE_BYTES - head.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1) + 1;
        return Err(MazeError::TooLarge { line, column });
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = good.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let column = String::from_utf8_lossy(&good[line_start..]).chars().count() + 1;
        MazeError::syntax(line, column, "the file is not valid UTF-8 text")
    })
}

/// Maps a structural error to the line where its cell is written.
pub(crate) fn structure_error(
    error: StructureError,
    line_of: impl Fn(Position) -> usize,
) -> MazeError {
    let line = error.cell().map_or(1, line_of);
    MazeError::Structure { line, error }
}
