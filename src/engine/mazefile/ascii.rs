//! The micromouse ASCII "mazefiles" format (posts `o`, walls `---` and `|`, `S`, `G`).

use super::MazeError;
use crate::engine::maze::Maze;

/// Parses the ASCII format.
///
/// # Errors
/// A [`MazeError`] naming the line and column of the first problem.
pub fn parse(bytes: &[u8]) -> Result<Maze, MazeError> {
    let _ = super::decode(bytes)?;
    Err(MazeError::syntax(1, 1, "the ASCII format is not supported yet"))
}
