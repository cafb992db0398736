//! The task's numeric maze format (RULES.md "Maze file").
//!
//! Line 1 holds the side `n`; then `n` lines of `n` comma-separated values, one line per
//! column `x`, value `y` being the cell at height `y`. Numbers are plain decimal digits
//! (leading zeros allowed, no sign, no spaces); LF line endings; the final newline is
//! optional; a blank line anywhere is an error.

use super::{MazeError, decode, structure_error};
use crate::engine::geometry::Position;
use crate::engine::maze::Maze;

/// Parses the numeric format.
///
/// # Errors
/// A [`MazeError`] naming the line and column of the first problem.
pub fn parse(bytes: &[u8]) -> Result<Maze, MazeError> {
    let text = decode(bytes)?;
    if text.is_empty() {
        return Err(MazeError::syntax(1, 1, "the file is empty"));
    }
    let body = text.strip_suffix('\n').unwrap_or(text);
    let lines: Vec<&str> = body.split('\n').collect();
    for (i, line) in lines.iter().enumerate() {
        if let Some(col) = line.find('\r') {
            return Err(MazeError::syntax(
                i + 1,
                line[..col].chars().count() + 1,
                "carriage return found: the numeric format takes LF line endings, not CRLF",
            ));
        }
    }

    let dim = parse_dimension(lines[0])?;
    // Column positions of every value, so structural errors can name a column too.
    let mut cells = Vec::with_capacity((dim as usize).saturating_mul(dim as usize).min(1 << 20));
    for x in 0..dim as usize {
        let line_no = x + 2;
        let Some(line) = lines.get(x + 1) else {
            return Err(MazeError::syntax(
                line_no,
                1,
                format!(
                    "expected {dim} rows of cells after the dimension, found {x} (the file ends here)"
                ),
            ));
        };
        parse_row(line, line_no, dim, &mut cells)?;
    }
    if let Some(extra) = lines.get(dim as usize + 1) {
        let line_no = dim as usize + 2;
        let reason = if extra.trim().is_empty() {
            "blank line after the last row (only one final newline is allowed)".to_string()
        } else {
            format!("expected {dim} rows of cells after the dimension, found more")
        };
        return Err(MazeError::syntax(line_no, 1, reason));
    }

    Maze::new(dim, cells).map_err(|e| structure_error(e, |p: Position| p.x as usize + 2))
}

fn parse_dimension(line: &str) -> Result<u32, MazeError> {
    if line.is_empty() {
        return Err(MazeError::syntax(
            1,
            1,
            "the first line must hold the maze side n, but it is blank",
        ));
    }
    if let Some((col, ch)) = line.chars().enumerate().find(|(_, c)| !c.is_ascii_digit()) {
        return Err(MazeError::syntax(
            1,
            col + 1,
            format!("the first line must be the maze side n (digits only), found {ch:?}"),
        ));
    }
    let dim: u32 = line
        .parse()
        .map_err(|_| MazeError::syntax(1, 1, format!("the maze side {line} is too large")))?;
    if dim < 2 || !dim.is_multiple_of(2) {
        return Err(MazeError::syntax(
            1,
            1,
            format!("the maze side must be an even number >= 2, got {dim}"),
        ));
    }
    Ok(dim)
}

fn parse_row(line: &str, line_no: usize, dim: u32, cells: &mut Vec<u32>) -> Result<(), MazeError> {
    if line.is_empty() {
        return Err(MazeError::syntax(
            line_no,
            1,
            format!("blank line where a row of {dim} values was expected"),
        ));
    }
    let mut count = 0usize;
    let mut column = 1usize;
    for field in line.split(',') {
        count += 1;
        if count > dim as usize {
            return Err(MazeError::syntax(
                line_no,
                column,
                format!("expected {dim} comma-separated values, found more"),
            ));
        }
        if field.is_empty() {
            return Err(MazeError::syntax(
                line_no,
                column,
                "empty value (two commas in a row, or a comma at the end of the line)",
            ));
        }
        if let Some((off, ch)) = field.chars().enumerate().find(|(_, c)| !c.is_ascii_digit()) {
            return Err(MazeError::syntax(
                line_no,
                column + off,
                format!("{ch:?} is not a digit: values are plain decimal numbers 0..15"),
            ));
        }
        let trimmed = field.trim_start_matches('0');
        let value = if trimmed.is_empty() {
            0
        } else if trimmed.len() > 2 {
            u32::MAX
        } else {
            trimmed.parse::<u32>().unwrap_or(u32::MAX)
        };
        if value > 15 {
            return Err(MazeError::syntax(
                line_no,
                column,
                format!("value {field} is out of range: cell values are 0..15"),
            ));
        }
        cells.push(value);
        column += field.chars().count() + 1;
    }
    if count < dim as usize {
        return Err(MazeError::syntax(
            line_no,
            line.chars().count() + 1,
            format!("expected {dim} comma-separated values, found {count}"),
        ));
    }
    Ok(())
}

/// Writes a maze in the numeric format, LF line endings and a final newline.
pub fn write(maze: &Maze) -> String {
    let n = maze.dim() as usize;
    let mut out = String::with_capacity(n * n * 3 + 8);
    out.push_str(&n.to_string());
    out.push('\n');
    for row in maze.cells().chunks(n) {
        let line: Vec<String> = row.iter().map(|v| v.to_string()).collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

impl Maze {
    /// The SHA-256 of the maze's canonical numeric text
    /// ([`numeric::write`](crate::engine::mazefile::numeric::write)), as lowercase hex:
    /// the same layout gives the same hash whichever file format it came from.
    pub fn hash(&self) -> String {
        use sha2::{Digest, Sha256};
        let digest = Sha256::digest(write(self).as_bytes());
        digest.iter().map(|b| format!("{b:02x}")).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO: &str = "2\n3,6\n9,12\n";

    fn err(text: &str) -> MazeError {
        parse(text.as_bytes()).unwrap_err()
    }

    #[test]
    fn round_trip() {
        let m = parse(TWO.as_bytes()).unwrap();
        assert_eq!(write(&m), TWO);
        assert!(
            parse(TWO.trim_end().as_bytes()).is_ok(),
            "final newline is optional"
        );
        assert!(
            parse(b"2\n03,006\n9,12").is_ok(),
            "leading zeros are allowed"
        );
    }

    #[test]
    fn errors_name_line_and_column() {
        assert_eq!(err("").line(), 1);
        assert_eq!(
            err("2\n3,6\n9,x2\n"),
            MazeError::syntax(
                3,
                3,
                "'x' is not a digit: values are plain decimal numbers 0..15"
            )
        );
        assert!(matches!(
            err("2\n3,6\n9,16\n"),
            MazeError::Syntax {
                line: 3,
                column: 3,
                ..
            }
        ));
        assert!(matches!(
            err("2\r\n3,6\n9,12\n"),
            MazeError::Syntax {
                line: 1,
                column: 2,
                ..
            }
        ));
        assert!(matches!(
            err("2\n3,6\n9,12\n\n"),
            MazeError::Syntax { line: 4, .. }
        ));
        assert!(matches!(
            err("2\n3,6,1\n9,12\n"),
            MazeError::Syntax {
                line: 2,
                column: 5,
                ..
            }
        ));
        assert!(matches!(
            err("2\n3\n9,12\n"),
            MazeError::Syntax { line: 2, .. }
        ));
        assert!(matches!(err("2\n3,6\n"), MazeError::Syntax { line: 3, .. }));
        assert!(matches!(err("3\n"), MazeError::Syntax { line: 1, .. }));
        assert!(matches!(
            err("-2\n"),
            MazeError::Syntax {
                line: 1,
                column: 1,
                ..
            }
        ));
        assert!(matches!(
            err("2\n3, 6\n9,12\n"),
            MazeError::Syntax {
                line: 2,
                column: 3,
                ..
            }
        ));
    }

    #[test]
    fn structural_errors_name_the_line_of_the_cell() {
        // (1,0) closed on its left while (0,0) is open right.
        let e = err("2\n3,6\n1,12\n");
        assert!(matches!(e, MazeError::Structure { line: 2, .. }), "{e}");
        // (1,1) open right on the perimeter.
        let e = err("2\n3,6\n9,14\n");
        assert!(matches!(e, MazeError::Structure { line: 3, .. }), "{e}");
    }

    #[test]
    fn oversized_and_non_utf8_files_are_rejected() {
        let big = vec![b'1'; super::super::MAX_FILE_BYTES + 1];
        assert!(matches!(parse(&big), Err(MazeError::TooLarge { .. })));
        assert!(matches!(
            parse(b"2\n3,\xff\n"),
            Err(MazeError::Syntax {
                line: 2,
                column: 3,
                ..
            })
        ));
    }
}
