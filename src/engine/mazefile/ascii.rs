//! The micromouse ASCII "mazefiles" format (posts `o`, walls `---` and `|`, `S`, `G`).
//!
//! A maze of `n x n` cells is drawn on `2n + 1` lines of `4n + 1` characters:
//!
//! ```text
//! o---o---o
//! | G     |
//! o   o---o
//! | S |   |
//! o---o---o
//! ```
//!
//! - Even lines (0-based) hold the posts `o` (or `+`) at columns `4j` and, between two
//!   posts, a 3-character segment: the wall is present if ANY of the three is `-`,
//!   absent if all are spaces.
//! - Odd lines hold the cells: a `|` at a post column is a wall, a space is an opening.
//!   The text inside a cell (columns `4j+1..4j+3`) may mark the start `S` or a goal
//!   cell `G`; any other text there is ignored.
//! - Line 1 is the north edge of the top row. CRLF line endings are accepted, short
//!   lines are padded with spaces, trailing spaces and trailing blank lines are ignored.
//! - The side `n` comes from the line count, `(lines - 1) / 2`, and must match the
//!   width: only square mazes with an even side are accepted.
//!
//! The game always starts in the bottom-left cell facing up, with the goal room in the
//! centre 2x2. So the drawing is turned (or mirrored) to bring the `S` cell (bottom-left
//! when no `S` is marked) to the bottom-left corner with its opening pointing up; a
//! rotation is preferred over a reflection when both fit. An `S` off the corners, a
//! start cell with no opening, or `G` marks that are not exactly the centre 2x2 are
//! rejected. Cells in error messages are named as drawn: `x` from the left, `y` from
//! the bottom, starting at 0.

use super::{MazeError, decode, structure_error};
use crate::engine::geometry::{Heading, Position};
use crate::engine::maze::{Maze, StructureError};

/// Parses the ASCII format.
///
/// # Errors
/// A [`MazeError`] naming the line (and column) of the first problem.
pub fn parse(bytes: &[u8]) -> Result<Maze, MazeError> {
    let drawing = Drawing::read(decode(bytes)?)?;
    let n = drawing.dim;
    drawing.check_perimeter()?;
    let start = drawing.start()?;
    drawing.check_goal()?;

    let symmetry = drawing.orient(start)?;
    let mut cells = vec![0u32; n as usize * n as usize];
    let mut drawn_of = vec![Position::new(0, 0); cells.len()];
    for x in 0..n {
        for y in 0..n {
            let drawn = Position::new(x, y);
            let cell = symmetry.cell(drawn, n);
            let i = (cell.x * n + cell.y) as usize;
            drawn_of[i] = drawn;
            for side in Heading::ALL {
                if drawing.is_open(drawn, side) {
                    cells[i] |= u32::from(symmetry.heading(side).bit());
                }
            }
        }
    }
    // Consistency holds by construction (each wall is drawn once) and the perimeter
    // was checked above, so this only fails on a bug; still, name a line if it does.
    Maze::new(n, cells).map_err(|e| {
        structure_error(e, |p: Position| {
            let drawn = drawn_of[(p.x * n + p.y) as usize];
            drawing.cell_line(drawn)
        })
    })
}

/// The drawing as a grid of characters, with the side it describes.
struct Drawing {
    /// Lines without their line ending, as characters (columns are counted in characters).
    lines: Vec<Vec<char>>,
    /// Cells per side.
    dim: u32,
}

impl Drawing {
    fn read(text: &str) -> Result<Drawing, MazeError> {
        let mut lines: Vec<Vec<char>> = text
            .split('\n')
            .map(|l| l.strip_suffix('\r').unwrap_or(l).chars().collect())
            .collect();
        while lines
            .last()
            .is_some_and(|l| l.iter().all(|c| c.is_whitespace()))
        {
            lines.pop();
        }
        if lines.is_empty() {
            return Err(MazeError::syntax(1, 1, "the file is empty"));
        }
        if lines[0].iter().all(|c| c.is_whitespace()) {
            return Err(MazeError::syntax(
                1,
                1,
                "blank first line: the drawing must start on line 1 with its north wall",
            ));
        }
        for (i, line) in lines.iter().enumerate() {
            if let Some(col) = line.iter().position(|&c| c == '\r') {
                return Err(MazeError::syntax(
                    i + 1,
                    col + 1,
                    "carriage return in the middle of a line",
                ));
            }
        }
        let count = lines.len();
        if count.is_multiple_of(2) {
            return Err(MazeError::syntax(
                count,
                1,
                format!(
                    "the drawing has {count} lines but a maze of n rows takes 2n + 1 \
                     (a line of posts above and below every row of cells): the last line of posts is missing"
                ),
            ));
        }
        let dim = (count - 1) / 2;
        if dim == 0 {
            return Err(MazeError::syntax(
                1,
                1,
                "a single line of posts is not a maze: there is no row of cells",
            ));
        }
        let width = 4 * dim + 1;
        let trimmed = |l: &Vec<char>| l.len() - l.iter().rev().take_while(|&&c| c == ' ').count();
        if let Some(i) = lines.iter().position(|l| trimmed(l) > width) {
            return Err(MazeError::syntax(
                i + 1,
                width + 1,
                format!(
                    "text beyond column {width}: {count} lines make {dim} rows of cells, \
                     {width} characters wide; the maze is wider than tall (only square mazes are supported)"
                ),
            ));
        }
        let widest = lines.iter().map(trimmed).max().unwrap_or(0);
        if widest < width {
            return Err(MazeError::syntax(
                1,
                widest + 1,
                format!(
                    "the widest line has {widest} characters but {count} lines make {dim} rows of cells, \
                     {width} characters wide; the maze is taller than wide (only square mazes are supported)"
                ),
            ));
        }
        if !dim.is_multiple_of(2) {
            return Err(MazeError::syntax(
                1,
                1,
                format!("the maze is {dim}x{dim} cells; the side must be even"),
            ));
        }
        let drawing = Drawing {
            lines,
            dim: dim as u32,
        };
        drawing.check_characters()?;
        Ok(drawing)
    }

    /// The character at a 0-based line and column, a space past the end of a short line.
    fn at(&self, line: usize, col: usize) -> char {
        self.lines
            .get(line)
            .and_then(|l| l.get(col))
            .copied()
            .unwrap_or(' ')
    }

    /// Posts, wall segments and wall columns may only hold the characters of the format.
    fn check_characters(&self) -> Result<(), MazeError> {
        for (i, line) in self.lines.iter().enumerate() {
            for (col, &c) in line.iter().enumerate() {
                let (ok, what) = match (i.is_multiple_of(2), col.is_multiple_of(4)) {
                    (true, true) => (matches!(c, 'o' | '+' | ' '), "a post 'o'"),
                    (true, false) => (matches!(c, '-' | ' '), "a wall segment ('-' or spaces)"),
                    (false, true) => (matches!(c, '|' | ' '), "a wall '|' or a space"),
                    (false, false) => (true, ""),
                };
                if !ok {
                    return Err(MazeError::syntax(
                        i + 1,
                        col + 1,
                        format!("unexpected {c:?} where {what} belongs"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The 0-based line holding the cell's text.
    fn text_line(&self, cell: Position) -> usize {
        2 * (self.dim - 1 - cell.y) as usize + 1
    }

    /// The 1-based line where a cell is drawn.
    fn cell_line(&self, cell: Position) -> usize {
        self.text_line(cell) + 1
    }

    /// Whether the drawing shows no wall on `side` of `cell` (x from the left, y from
    /// the bottom, as drawn).
    fn is_open(&self, cell: Position, side: Heading) -> bool {
        let line = self.text_line(cell);
        let col = 4 * cell.x as usize;
        match side {
            Heading::Up | Heading::Down => {
                let l = if side == Heading::Up {
                    line - 1
                } else {
                    line + 1
                };
                (col + 1..col + 4).all(|c| self.at(l, c) != '-')
            }
            Heading::Left => self.at(line, col) != '|',
            Heading::Right => self.at(line, col + 4) != '|',
        }
    }

    /// The outer walls must all be drawn; names the first gap in reading order.
    fn check_perimeter(&self) -> Result<(), MazeError> {
        let n = self.dim;
        let open = |cell: Position, side: Heading, line: usize| {
            if self.is_open(cell, side) {
                Err(MazeError::Structure {
                    line,
                    error: StructureError::OpenPerimeter { cell, side },
                })
            } else {
                Ok(())
            }
        };
        for x in 0..n {
            open(Position::new(x, n - 1), Heading::Up, 1)?;
        }
        for y in (0..n).rev() {
            let line = self.cell_line(Position::new(0, y));
            open(Position::new(0, y), Heading::Left, line)?;
            open(Position::new(n - 1, y), Heading::Right, line)?;
        }
        for x in 0..n {
            open(Position::new(x, 0), Heading::Down, 2 * n as usize + 1)?;
        }
        Ok(())
    }

    /// Every cell whose text holds `mark`, with the 1-based line and column of the mark.
    fn marked(&self, mark: char) -> Vec<(Position, usize, usize)> {
        let n = self.dim;
        let mut found = Vec::new();
        for y in (0..n).rev() {
            for x in 0..n {
                let cell = Position::new(x, y);
                let line = self.text_line(cell);
                let col = 4 * x as usize;
                if let Some(c) = (col + 1..col + 4).find(|&c| self.at(line, c) == mark) {
                    found.push((cell, line + 1, c + 1));
                }
            }
        }
        found
    }

    /// The start cell as drawn: the one `S` (in a corner), or the bottom-left corner.
    fn start(&self) -> Result<(Position, usize, usize), MazeError> {
        let marks = self.marked('S');
        let last = self.dim - 1;
        match marks.as_slice() {
            [] => Ok((Position::new(0, 0), 2 * self.dim as usize, 2)),
            [one] => {
                let (cell, line, col) = *one;
                if (cell.x == 0 || cell.x == last) && (cell.y == 0 || cell.y == last) {
                    Ok(*one)
                } else {
                    Err(MazeError::syntax(
                        line,
                        col,
                        format!(
                            "the start S is in cell {cell}, not in a corner; the game starts in a corner \
                             cell (it is turned to the bottom-left)"
                        ),
                    ))
                }
            }
            [first, second, ..] => Err(MazeError::syntax(
                second.1,
                second.2,
                format!(
                    "a second start S in cell {} (the first is in cell {}, line {}); a maze has one start",
                    second.0, first.0, first.1
                ),
            )),
        }
    }

    /// Marked goal cells, if any, must be exactly the centre 2x2 room (which every
    /// rotation and reflection maps onto itself, so it is checked as drawn).
    fn check_goal(&self) -> Result<(), MazeError> {
        let marks = self.marked('G');
        let Some(&(_, line, col)) = marks.first() else {
            return Ok(());
        };
        let (a, b) = (self.dim / 2 - 1, self.dim / 2);
        let centre = |p: Position| (p.x == a || p.x == b) && (p.y == a || p.y == b);
        if marks.len() == 4 && marks.iter().all(|m| centre(m.0)) {
            return Ok(());
        }
        let (line, col) = marks
            .iter()
            .find(|m| !centre(m.0))
            .map_or((line, col), |m| (m.1, m.2));
        let names: Vec<String> = marks.iter().map(|m| m.0.to_string()).collect();
        let room: Vec<String> = [(a, a), (a, b), (b, a), (b, b)]
            .iter()
            .map(|&(x, y)| Position::new(x, y).to_string())
            .collect();
        Err(MazeError::syntax(
            line,
            col,
            format!(
                "goal cells marked at {} are not the centre 2x2 room {}",
                names.join(", "),
                room.join(", ")
            ),
        ))
    }

    /// The rotation or reflection that brings the start cell to the bottom-left corner
    /// with its opening pointing up (a rotation when both would do).
    fn orient(&self, start: (Position, usize, usize)) -> Result<Symmetry, MazeError> {
        let (cell, line, col) = start;
        let n = self.dim;
        let open: Vec<Heading> = Heading::ALL
            .into_iter()
            .filter(|&h| self.is_open(cell, h))
            .collect();
        let candidates = Symmetry::ALL
            .into_iter()
            .filter(|s| s.cell(cell, n) == Position::new(0, 0));
        for s in candidates {
            let mapped: Vec<Heading> = open.iter().map(|&h| s.heading(h)).collect();
            if mapped.contains(&Heading::Up) {
                return Ok(s);
            }
        }
        Err(MazeError::syntax(
            line,
            col,
            format!("the start cell {cell} has no opening: the robot could never leave it"),
        ))
    }
}

/// One of the 8 symmetries of the square: an optional left-right mirror, then
/// `turns` quarter turns clockwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Symmetry {
    mirror: bool,
    turns: u8,
}

impl Symmetry {
    /// The rotations first, so a rotation wins over a reflection when both fit.
    const ALL: [Symmetry; 8] = {
        let mut all = [Symmetry {
            mirror: false,
            turns: 0,
        }; 8];
        let mut i = 0;
        while i < 8 {
            all[i] = Symmetry {
                mirror: i >= 4,
                turns: (i % 4) as u8,
            };
            i += 1;
        }
        all
    };

    fn cell(self, p: Position, n: u32) -> Position {
        let (mut x, mut y) = (p.x, p.y);
        if self.mirror {
            x = n - 1 - x;
        }
        for _ in 0..self.turns {
            (x, y) = (y, n - 1 - x);
        }
        Position::new(x, y)
    }

    fn heading(self, h: Heading) -> Heading {
        let mut h = match (self.mirror, h) {
            (true, Heading::Left) => Heading::Right,
            (true, Heading::Right) => Heading::Left,
            _ => h,
        };
        for _ in 0..self.turns {
            h = h.clockwise();
        }
        h
    }
}

/// Draws a maze in the ASCII format, LF line endings, `S` on the start cell (0,0) and
/// `G` on the goal room; [`parse`] reads it back to the same maze.
pub fn write(maze: &Maze) -> String {
    draw(maze, Position::new(0, 0))
}

/// Draws `maze` as it is, marking `start` with `S` (and `SG` if it is a goal cell).
fn draw(maze: &Maze, start: Position) -> String {
    let n = maze.dim();
    let width = 4 * n as usize + 2;
    let mut out = String::with_capacity(width * (2 * n as usize + 1));
    let posts = |out: &mut String, y: u32, side: Heading| {
        for x in 0..n {
            out.push('o');
            let wall = !maze.is_open(Position::new(x, y), side);
            out.push_str(if wall { "---" } else { "   " });
        }
        out.push_str("o\n");
    };
    for y in (0..n).rev() {
        posts(&mut out, y, Heading::Up);
        for x in 0..n {
            let cell = Position::new(x, y);
            out.push(if maze.is_open(cell, Heading::Left) {
                ' '
            } else {
                '|'
            });
            out.push_str(match (cell == start, maze.is_goal(cell)) {
                (true, true) => " SG",
                (true, false) => " S ",
                (false, true) => " G ",
                (false, false) => "   ",
            });
        }
        let last = Position::new(n - 1, y);
        out.push(if maze.is_open(last, Heading::Right) {
            ' '
        } else {
            '|'
        });
        out.push('\n');
    }
    posts(&mut out, 0, Heading::Down);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: u32, y: u32) -> Position {
        Position::new(x, y)
    }

    /// 4x4: S bottom-left open up only, G in the centre, a few inner walls.
    const FOUR: &str = "\
o---o---o---o---o
|               |
o   o---o   o   o
|   | G   G |   |
o   o   o   o   o
|   | G   G     |
o   o---o---o   o
| S |           |
o---o---o---o---o
";

    #[test]
    fn imports_a_small_maze_with_the_numeric_bits() {
        let m = parse(FOUR.as_bytes()).unwrap();
        assert_eq!(m.dim(), 4);
        // Start: open up only.
        assert_eq!(m.bits(p(0, 0)), 1);
        // (0,1): up + down, wall on the right.
        assert_eq!(m.bits(p(0, 1)), 1 | 4);
        // (0,3): top-left corner, open down and right.
        assert_eq!(m.bits(p(0, 3)), 2 | 4);
        // (1,2): goal, wall above and on the left, open right and down.
        assert_eq!(m.bits(p(1, 2)), 2 | 4);
        // (2,1): goal, walls below; open up, left, right.
        assert_eq!(m.bits(p(2, 1)), 1 | 2 | 8);
        // (3,0): bottom-right corner, open up and left.
        assert_eq!(m.bits(p(3, 0)), 1 | 8);
        let problems = m.strict_problems();
        assert!(
            problems.len() == 1 && problems[0].contains("12 <= n"),
            "{problems:?}"
        );
    }

    #[test]
    fn crlf_short_lines_and_trailing_blank_lines_are_tolerated() {
        let m = parse(FOUR.as_bytes()).unwrap();
        let crlf = FOUR.replace('\n', "\r\n");
        assert_eq!(parse(crlf.as_bytes()).unwrap(), m);
        // Inner lines of posts cut after their last wall: the missing end is spaces.
        let short = FOUR
            .replace("o   o---o   o   o", "o   o---o")
            .replace("o   o   o   o   o", "o")
            .replace("o   o---o---o   o", "o   o---o---o   ");
        assert_eq!(parse(short.as_bytes()).unwrap(), m);
        // A cell line cut before its last wall column: the wall is missing there.
        let cut = FOUR.replace("|               |\n", "|\n");
        let e = parse(cut.as_bytes()).unwrap_err();
        assert!(matches!(e, MazeError::Structure { line: 2, .. }), "{e}");
        assert_eq!(parse(format!("{FOUR}\n  \n").as_bytes()).unwrap(), m);
        assert_eq!(parse(FOUR.trim_end().as_bytes()).unwrap(), m);
    }

    #[test]
    fn a_start_in_another_corner_is_turned_to_the_bottom_left() {
        let four = parse(FOUR.as_bytes()).unwrap();
        assert_eq!(write(&four), FOUR, "the writer draws FOUR exactly");
        // Draw FOUR under each of the 8 symmetries, S following the start cell: the
        // importer must bring every one of them back (FOUR's start opens up only, so
        // exactly one symmetry fits).
        let mut drawings = std::collections::HashSet::new();
        for s in Symmetry::ALL {
            let mut cells = vec![0u32; 16];
            for x in 0..4 {
                for y in 0..4 {
                    let q = s.cell(p(x, y), 4);
                    for h in Heading::ALL {
                        if four.is_open(p(x, y), h) {
                            cells[(q.x * 4 + q.y) as usize] |= u32::from(s.heading(h).bit());
                        }
                    }
                }
            }
            let moved = Maze::new(4, cells).unwrap();
            let text = draw(&moved, s.cell(p(0, 0), 4));
            assert_eq!(parse(text.as_bytes()).unwrap(), four, "{s:?}\n{text}");
            drawings.insert(text);
        }
        assert_eq!(drawings.len(), 8);
        // One by hand: turned a quarter clockwise, S at the top-left opening right.
        let turned = "\
o---o---o---o---o
| S             |
o---o---o---o   o
|   | G   G |   |
o   o   o   o   o
|   | G   G     |
o   o   o---o   o
|               |
o---o---o---o---o
";
        assert_eq!(parse(turned.as_bytes()).unwrap(), four);
    }

    #[test]
    fn writing_round_trips_even_the_smallest_maze() {
        let two = Maze::new(2, vec![3, 6, 9, 12]).unwrap();
        let text = write(&two);
        assert!(text.contains(" SG"), "{text}");
        assert_eq!(parse(text.as_bytes()).unwrap(), two);
    }

    #[test]
    fn a_start_open_both_ways_keeps_its_rotation() {
        let both = "\
o---o---o
| G   G |
o   o   o
| G  SG |
o---o---o
";
        // S at the bottom-right, open up and left: turned a quarter clockwise it sits
        // at the bottom-left open up and right.
        let m = parse(both.as_bytes()).unwrap();
        assert_eq!(m.bits(p(0, 0)), 1 | 2);
        assert_eq!(Symmetry::ALL[1].cell(p(1, 0), 2), p(0, 0));
    }

    #[test]
    fn bad_starts_are_rejected() {
        let middle = FOUR
            .replace("| S |", "|   |")
            .replace("|               |", "|     S         |");
        let e = parse(middle.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                MazeError::Syntax {
                    line: 2,
                    column: 7,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("not in a corner"), "{e}");

        let two = FOUR.replace("|               |", "| S             |");
        let e = parse(two.as_bytes()).unwrap_err();
        assert!(e.to_string().contains("second start"), "{e}");

        let shut = FOUR.replace("o   o---o---o   o", "o---o---o---o   o");
        let e = parse(shut.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                MazeError::Syntax {
                    line: 8,
                    column: 3,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("no opening"), "{e}");
    }

    #[test]
    fn goal_marks_off_the_centre_are_rejected() {
        let off = FOUR.replace("|               |", "|             G |");
        let e = parse(off.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                MazeError::Syntax {
                    line: 2,
                    column: 15,
                    ..
                }
            ),
            "{e}"
        );
        let text = e.to_string();
        assert!(
            text.contains("(3, 3)") && text.contains("not the centre 2x2 room"),
            "{text}"
        );
        // Unmarked goal: the centre is assumed.
        let none = FOUR.replace('G', " ");
        assert_eq!(
            parse(none.as_bytes()).unwrap(),
            parse(FOUR.as_bytes()).unwrap()
        );
    }

    #[test]
    fn non_square_and_odd_sides_are_rejected() {
        let wide = "o---o---o---o---o\n| S             |\no---o---o---o---o\n";
        let e = parse(wide.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                MazeError::Syntax {
                    line: 1,
                    column: 6,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("not square") || e.to_string().contains("only square"));
        let tall = "o---o\n|   |\no   o\n| S |\no---o\n";
        let e = parse(tall.as_bytes()).unwrap_err();
        assert!(e.to_string().contains("taller than wide"), "{e}");
        let odd = "o---o\n| S |\no---o\n";
        assert!(
            parse(odd.as_bytes())
                .unwrap_err()
                .to_string()
                .contains("must be even")
        );
        let even_lines = "o---o---o\n| G   G |\no   o   o\n| S   G |\n";
        assert!(matches!(
            parse(even_lines.as_bytes()),
            Err(MazeError::Syntax { line: 4, .. })
        ));
        assert!(matches!(
            parse(b""),
            Err(MazeError::Syntax {
                line: 1,
                column: 1,
                ..
            })
        ));
        assert!(matches!(
            parse(b"o\n"),
            Err(MazeError::Syntax { line: 1, .. })
        ));
        let late = format!("\n{FOUR}");
        let e = parse(late.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                MazeError::Syntax {
                    line: 1,
                    column: 1,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("blank first line"), "{e}");
    }

    #[test]
    fn an_open_perimeter_names_its_line() {
        let top = FOUR.replacen("o---o---o---o---o", "o---o---o   o---o", 1);
        let e = parse(top.as_bytes()).unwrap_err();
        assert!(matches!(e, MazeError::Structure { line: 1, .. }), "{e}");
        let side = FOUR.replace("|   | G   G     |", "|   | G   G      ");
        let e = parse(side.as_bytes()).unwrap_err();
        assert!(matches!(e, MazeError::Structure { line: 6, .. }), "{e}");
        assert!(e.to_string().contains("right side"), "{e}");
        let bottom = FOUR.replace(
            "| S |           |\no---o---o---o---o",
            "| S |           |\no---o   o---o---o",
        );
        let e = parse(bottom.as_bytes()).unwrap_err();
        assert!(matches!(e, MazeError::Structure { line: 9, .. }), "{e}");
    }

    #[test]
    fn stray_characters_and_bad_bytes_are_named() {
        let bad = FOUR.replacen("o---o---o---o---o", "o---o-x-o---o---o", 1);
        assert!(matches!(
            parse(bad.as_bytes()),
            Err(MazeError::Syntax {
                line: 1,
                column: 7,
                ..
            })
        ));
        let bad = FOUR.replace("| S |", "| S #");
        assert!(matches!(
            parse(bad.as_bytes()),
            Err(MazeError::Syntax {
                line: 8,
                column: 5,
                ..
            })
        ));
        assert!(matches!(
            parse(b"o---o\n\xff"),
            Err(MazeError::Syntax {
                line: 2,
                column: 1,
                ..
            })
        ));
        let mid_cr = FOUR.replacen("o---o", "o-\r-o", 1);
        assert!(matches!(
            parse(mid_cr.as_bytes()),
            Err(MazeError::Syntax {
                line: 1,
                column: 3,
                ..
            })
        ));
        // Any '-' in a segment is a wall; text inside cells is ignored.
        let loose = FOUR
            .replace("o   o---o   o   o", "o   o- -o   o   o")
            .replace("| S |", "|1S |");
        assert_eq!(
            parse(loose.as_bytes()).unwrap(),
            parse(FOUR.as_bytes()).unwrap()
        );
    }

    #[test]
    fn every_small_edit_parses_or_fails_cleanly() {
        let chars: Vec<char> = FOUR.chars().collect();
        for i in 0..=chars.len() {
            let cut: String = chars[..i].iter().collect();
            if let Err(e) = parse(cut.as_bytes()) {
                assert!(e.line() >= 1, "{e:?}");
            }
            for c in ['o', '-', '|', ' ', 'S', 'G', 'x', '\n', '\r', 'é'] {
                let mut edited = chars.clone();
                if i < edited.len() {
                    edited[i] = c;
                } else {
                    edited.push(c);
                }
                let text: String = edited.iter().collect();
                match parse(text.as_bytes()) {
                    Ok(m) => assert!(m.is_open(p(0, 0), Heading::Up), "{text}"),
                    Err(e) => assert!(e.line() >= 1, "{e:?}"),
                }
            }
        }
    }
}
