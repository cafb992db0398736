//! The maze model: a square grid of cells, each with four sides that are open or walled.
//!
//! Openings use the task's 4-bit encoding (RULES.md "Maze file"): a bit is set where a
//! side is OPEN. A [`Maze`] can only be built through [`Maze::new`], which checks what
//! every playable maze must satisfy (even side >= 2, values 0..15, consistent walls,
//! closed perimeter); [`Maze::strict_problems`] adds the task's own conditions.

use std::collections::VecDeque;

use super::geometry::{Heading, Position};

/// The smallest side a maze may have (RULES.md edge cases: n even and >= 2).
pub const MIN_DIM: u32 = 2;

/// The task's own bounds on the side, checked by strict validation.
pub const STRICT_DIM: std::ops::RangeInclusive<u32> = 12..=16;

/// A valid maze: square, even side, consistent walls, closed perimeter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Maze {
    dim: u32,
    /// Opening bits per cell, indexed `x * dim + y` (the order of the numeric file).
    open: Vec<u8>,
}

/// Why a grid of openings is not a playable maze. Cells are named; the file formats
/// add the line where each cell is written.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StructureError {
    /// The side is odd or too small.
    #[error("the maze side must be an even number >= {MIN_DIM}, got {dim}")]
    BadDimension {
        /// The side found.
        dim: u32,
    },
    /// The number of cells does not match the side.
    #[error("expected {expected} cells for the given side, got {got}")]
    CellCount {
        /// dim * dim.
        expected: usize,
        /// Cells given.
        got: usize,
    },
    /// A cell value is not in 0..=15.
    #[error("cell {cell} has value {value}; values must be 0..15")]
    BadValue {
        /// The cell.
        cell: Position,
        /// The value found.
        value: u32,
    },
    /// Two neighbouring cells disagree about the wall between them.
    #[error(
        "inconsistent wall between cell {a} and cell {b}: {a} is {a_state} on its {a_side} side but {b} is {b_state} on its {b_side} side"
    )]
    InconsistentWall {
        /// The lower-left of the two cells.
        a: Position,
        /// Its neighbour to the right or above.
        b: Position,
        /// The side of `a` facing `b`.
        a_side: Heading,
        /// The side of `b` facing `a`.
        b_side: Heading,
        /// "open" or "closed".
        a_state: &'static str,
        /// "open" or "closed".
        b_state: &'static str,
    },
    /// A cell on the border is open towards the outside.
    #[error(
        "the outer perimeter is open at cell {cell} on its {side} side (a robot could walk off the grid)"
    )]
    OpenPerimeter {
        /// The border cell.
        cell: Position,
        /// The side that is open.
        side: Heading,
    },
}

impl StructureError {
    /// The first cell the error is about (used by the file formats to name a line).
    pub fn cell(&self) -> Option<Position> {
        match self {
            StructureError::BadValue { cell, .. } | StructureError::OpenPerimeter { cell, .. } => {
                Some(*cell)
            }
            StructureError::InconsistentWall { a, .. } => Some(*a),
            _ => None,
        }
    }
}

impl Maze {
    /// Builds a maze from its side and the opening bits of every cell in file order
    /// (`x * dim + y`), checking the structural rules of RULES.md.
    ///
    /// # Errors
    /// The first [`StructureError`] found, checked in the order: side, cell count,
    /// values, wall consistency (column by column), perimeter.
    pub fn new(dim: u32, cells: Vec<u32>) -> Result<Maze, StructureError> {
        if dim < MIN_DIM || !dim.is_multiple_of(2) {
            return Err(StructureError::BadDimension { dim });
        }
        let expected = dim as usize * dim as usize;
        if cells.len() != expected {
            return Err(StructureError::CellCount {
                expected,
                got: cells.len(),
            });
        }
        let mut open = Vec::with_capacity(expected);
        for (i, &v) in cells.iter().enumerate() {
            if v > 15 {
                let cell = Position::new(i as u32 / dim, i as u32 % dim);
                return Err(StructureError::BadValue { cell, value: v });
            }
            open.push(v as u8);
        }
        let maze = Maze { dim, open };
        maze.check_structure()?;
        Ok(maze)
    }

    /// A maze of side `dim` with every wall in place (for generators and editors).
    ///
    /// # Errors
    /// [`StructureError::BadDimension`] for an odd or too small side.
    pub fn closed(dim: u32) -> Result<Maze, StructureError> {
        if dim < MIN_DIM || !dim.is_multiple_of(2) {
            return Err(StructureError::BadDimension { dim });
        }
        Ok(Maze {
            dim,
            open: vec![0; dim as usize * dim as usize],
        })
    }

    fn check_structure(&self) -> Result<(), StructureError> {
        let n = self.dim;
        for x in 0..n {
            for y in 0..n {
                let a = Position::new(x, y);
                for side in [Heading::Right, Heading::Up] {
                    if let Some(b) = a.step(side, n) {
                        let a_open = self.bits(a) & side.bit() != 0;
                        let b_open = self.bits(b) & side.reverse().bit() != 0;
                        if a_open != b_open {
                            let state = |o: bool| if o { "open" } else { "closed" };
                            return Err(StructureError::InconsistentWall {
                                a,
                                b,
                                a_side: side,
                                b_side: side.reverse(),
                                a_state: state(a_open),
                                b_state: state(b_open),
                            });
                        }
                    }
                }
            }
        }
        for x in 0..n {
            for y in 0..n {
                let cell = Position::new(x, y);
                for side in Heading::ALL {
                    if cell.step(side, n).is_none() && self.bits(cell) & side.bit() != 0 {
                        return Err(StructureError::OpenPerimeter { cell, side });
                    }
                }
            }
        }
        Ok(())
    }

    /// The side of the square grid.
    pub fn dim(&self) -> u32 {
        self.dim
    }

    /// The opening bits of a cell (1 up, 2 right, 4 down, 8 left).
    ///
    /// # Panics
    /// If `cell` is outside the grid (a caller bug).
    pub fn bits(&self, cell: Position) -> u8 {
        assert!(
            cell.x < self.dim && cell.y < self.dim,
            "cell {cell} is outside a maze of side {}",
            self.dim
        );
        self.open[(cell.x * self.dim + cell.y) as usize]
    }

    /// All opening bits in file order (`x * dim + y`).
    pub fn cells(&self) -> &[u8] {
        &self.open
    }

    /// Whether the robot may move from `cell` one cell towards `heading`.
    pub fn is_open(&self, cell: Position, heading: Heading) -> bool {
        self.bits(cell) & heading.bit() != 0
    }

    /// Opens or closes the wall on `side` of `cell`, and the matching side of its
    /// neighbour. Walls on the perimeter cannot be opened (the call is ignored).
    pub fn set_open(&mut self, cell: Position, side: Heading, open: bool) {
        let Some(other) = cell.step(side, self.dim) else {
            return;
        };
        let (i, j) = (
            (cell.x * self.dim + cell.y) as usize,
            (other.x * self.dim + other.y) as usize,
        );
        if open {
            self.open[i] |= side.bit();
            self.open[j] |= side.reverse().bit();
        } else {
            self.open[i] &= !side.bit();
            self.open[j] &= !side.reverse().bit();
        }
    }

    /// The number of open cells from `cell` to the nearest wall towards `heading`
    /// (the sensor reading, RULES.md "The robot").
    pub fn dist_to_wall(&self, mut cell: Position, heading: Heading) -> u32 {
        let mut n = 0;
        while self.is_open(cell, heading) {
            // A closed perimeter guarantees the step stays on the grid.
            match cell.step(heading, self.dim) {
                Some(next) => cell = next,
                None => break,
            }
            n += 1;
        }
        n
    }

    /// The four cells of the goal room: x and y both in {n/2 - 1, n/2}.
    pub fn goal_room(&self) -> [Position; 4] {
        let (a, b) = (self.dim / 2 - 1, self.dim / 2);
        [
            Position::new(a, a),
            Position::new(a, b),
            Position::new(b, a),
            Position::new(b, b),
        ]
    }

    /// Whether `cell` is one of the goal room's cells.
    pub fn is_goal(&self, cell: Position) -> bool {
        in_goal_room(self.dim, cell)
    }

    /// Cells reachable from `from` through open sides, in breadth-first order.
    pub fn reachable_from(&self, from: Position) -> Vec<bool> {
        let n = self.dim;
        let mut seen = vec![false; (n * n) as usize];
        let mut queue = VecDeque::from([from]);
        seen[(from.x * n + from.y) as usize] = true;
        while let Some(c) = queue.pop_front() {
            for h in Heading::ALL {
                if self.is_open(c, h)
                    && let Some(next) = c.step(h, n)
                {
                    let i = (next.x * n + next.y) as usize;
                    if !seen[i] {
                        seen[i] = true;
                        queue.push_back(next);
                    }
                }
            }
        }
        seen
    }

    /// The task's own conditions (RULES.md "Task mazes"), as a list of plain-language
    /// problems; empty when the maze is a valid task maze.
    pub fn strict_problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        if !STRICT_DIM.contains(&self.dim) {
            problems.push(format!(
                "the side is {}; task mazes have 12 <= n <= 16",
                self.dim
            ));
        }
        let start = Position::new(0, 0);
        if self.is_open(start, Heading::Right) {
            problems.push("the start cell (0, 0) must have a wall on its right".to_string());
        }
        if !self.is_open(start, Heading::Up) {
            problems.push("the start cell (0, 0) must be open on top".to_string());
        }
        let seen = self.reachable_from(start);
        if !self
            .goal_room()
            .iter()
            .any(|g| seen[(g.x * self.dim + g.y) as usize])
        {
            problems.push("no cell of the goal room can be reached from the start".to_string());
        }
        problems
    }
}

/// Whether `cell` is in the goal room (the centre 2 x 2) of a maze of side `dim`: the
/// room depends on the side alone.
pub fn in_goal_room(dim: u32, cell: Position) -> bool {
    let (a, b) = (dim / 2 - 1, dim / 2);
    (cell.x == a || cell.x == b) && (cell.y == a || cell.y == b)
}

/// Where a movement of `movement` cells (negative: backwards) from `cell` facing
/// `heading` ends, stopping at the first wall (RULES.md: "at a wall the robot stops
/// where it is"), and whether a wall cut it short.
pub fn slide(maze: &Maze, mut cell: Position, heading: Heading, movement: i64) -> (Position, bool) {
    let dir = if movement >= 0 {
        heading
    } else {
        heading.reverse()
    };
    for _ in 0..movement.unsigned_abs() {
        match cell.step(dir, maze.dim()) {
            Some(next) if maze.is_open(cell, dir) => cell = next,
            _ => return (cell, true),
        }
    }
    (cell, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2x2 maze with every inner wall open.
    fn open_2x2() -> Maze {
        // (0,0): up+right = 3; (0,1): down+right = 6; (1,0): up+left = 9; (1,1): down+left = 12
        Maze::new(2, vec![3, 6, 9, 12]).unwrap()
    }

    #[test]
    fn odd_or_tiny_sides_are_rejected() {
        assert_eq!(
            Maze::new(3, vec![0; 9]),
            Err(StructureError::BadDimension { dim: 3 })
        );
        assert_eq!(
            Maze::new(0, vec![]),
            Err(StructureError::BadDimension { dim: 0 })
        );
    }

    #[test]
    fn values_over_15_are_rejected() {
        let err = Maze::new(2, vec![3, 6, 9, 16]).unwrap_err();
        assert!(matches!(err, StructureError::BadValue { value: 16, .. }));
    }

    #[test]
    fn inconsistent_walls_name_both_cells() {
        // (0,0) says open right, (1,0) says closed left.
        let err = Maze::new(2, vec![3, 6, 1, 12]).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("(0, 0)") && text.contains("(1, 0)"), "{text}");
    }

    #[test]
    fn open_perimeter_is_rejected() {
        // (0,0) open down.
        let err = Maze::new(2, vec![7, 6, 9, 12]).unwrap_err();
        assert_eq!(
            err,
            StructureError::OpenPerimeter {
                cell: Position::new(0, 0),
                side: Heading::Down
            }
        );
    }

    #[test]
    fn goal_room_is_the_centre_square() {
        let m = Maze::closed(12).unwrap();
        assert!(m.is_goal(Position::new(5, 5)));
        assert!(m.is_goal(Position::new(6, 5)));
        assert!(m.is_goal(Position::new(5, 6)));
        assert!(m.is_goal(Position::new(6, 6)));
        assert!(!m.is_goal(Position::new(4, 5)));
        assert!(!m.is_goal(Position::new(7, 6)));
        // n = 2: every cell is a goal cell.
        assert!(open_2x2().is_goal(Position::new(0, 0)));
    }

    #[test]
    fn set_open_changes_both_sides() {
        let mut m = Maze::closed(4).unwrap();
        m.set_open(Position::new(1, 1), Heading::Up, true);
        assert!(m.is_open(Position::new(1, 2), Heading::Down));
        m.set_open(Position::new(0, 0), Heading::Left, true); // perimeter: ignored
        assert!(!m.is_open(Position::new(0, 0), Heading::Left));
        assert!(Maze::new(4, m.cells().iter().map(|&b| b as u32).collect()).is_ok());
    }

    #[test]
    fn distance_to_wall_counts_open_cells() {
        let m = open_2x2();
        assert_eq!(m.dist_to_wall(Position::new(0, 0), Heading::Up), 1);
        assert_eq!(m.dist_to_wall(Position::new(0, 0), Heading::Left), 0);
    }
}
