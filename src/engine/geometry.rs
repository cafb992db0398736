//! Headings, positions and the arithmetic of turning and stepping on the grid.
//!
//! Coordinates follow RULES.md: cell (0,0) is the bottom-left corner, `x` grows to
//! the right (east) and `y` grows upwards (north).

use serde::{Deserialize, Serialize};

/// One of the four directions a robot can face, or a side of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Heading {
    /// North, +y.
    Up,
    /// East, +x.
    Right,
    /// South, -y.
    Down,
    /// West, -x.
    Left,
}

impl Heading {
    /// All four headings in clockwise order starting from `Up`.
    pub const ALL: [Heading; 4] = [Heading::Up, Heading::Right, Heading::Down, Heading::Left];

    /// The wall bit of this side in the task's numeric format (1 up, 2 right, 4 down, 8 left).
    pub const fn bit(self) -> u8 {
        match self {
            Heading::Up => 1,
            Heading::Right => 2,
            Heading::Down => 4,
            Heading::Left => 8,
        }
    }

    /// Index 0..4 in clockwise order from `Up`.
    pub const fn index(self) -> usize {
        match self {
            Heading::Up => 0,
            Heading::Right => 1,
            Heading::Down => 2,
            Heading::Left => 3,
        }
    }

    /// The heading with the given clockwise index (taken modulo 4).
    pub const fn from_index(i: usize) -> Heading {
        Heading::ALL[i % 4]
    }

    /// A quarter turn clockwise (rotation +90).
    pub const fn clockwise(self) -> Heading {
        Heading::from_index(self.index() + 1)
    }

    /// A quarter turn counter-clockwise (rotation -90).
    pub const fn counter_clockwise(self) -> Heading {
        Heading::from_index(self.index() + 3)
    }

    /// The heading after a rotation of -90, 0 or 90 degrees; `None` for any other value
    /// (RULES.md: an invalid rotation means no rotation, with a warning).
    pub const fn rotated(self, rotation: i64) -> Option<Heading> {
        match rotation {
            -90 => Some(self.counter_clockwise()),
            0 => Some(self),
            90 => Some(self.clockwise()),
            _ => None,
        }
    }

    /// The opposite heading.
    pub const fn reverse(self) -> Heading {
        Heading::from_index(self.index() + 2)
    }

    /// The unit step `(dx, dy)` of this heading.
    pub const fn delta(self) -> (i32, i32) {
        match self {
            Heading::Up => (0, 1),
            Heading::Right => (1, 0),
            Heading::Down => (0, -1),
            Heading::Left => (-1, 0),
        }
    }

    /// The headings the three sensors point to: `[left, front, right]`.
    pub const fn sensor_headings(self) -> [Heading; 3] {
        [self.counter_clockwise(), self, self.clockwise()]
    }
}

impl std::fmt::Display for Heading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Heading::Up => "up",
            Heading::Right => "right",
            Heading::Down => "down",
            Heading::Left => "left",
        })
    }
}

/// A cell of the grid, `(x, y)`, with (0,0) the bottom-left corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Position {
    /// Column, 0 at the left edge.
    pub x: u32,
    /// Row, 0 at the bottom edge.
    pub y: u32,
}

impl Position {
    /// The cell at `(x, y)`.
    pub const fn new(x: u32, y: u32) -> Position {
        Position { x, y }
    }

    /// The neighbouring cell in `heading`, or `None` if it would leave a grid of side `dim`.
    pub fn step(self, heading: Heading, dim: u32) -> Option<Position> {
        let (dx, dy) = heading.delta();
        let x = self.x as i64 + dx as i64;
        let y = self.y as i64 + dy as i64;
        if x < 0 || y < 0 || x >= dim as i64 || y >= dim as i64 {
            None
        } else {
            Some(Position::new(x as u32, y as u32))
        }
    }
}

impl std::fmt::Display for Position {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "({}, {})", self.x, self.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_is_a_cycle() {
        for h in Heading::ALL {
            assert_eq!(h.clockwise().counter_clockwise(), h);
            assert_eq!(h.clockwise().clockwise(), h.reverse());
            assert_eq!(h.reverse().reverse(), h);
        }
        assert_eq!(Heading::Up.clockwise(), Heading::Right);
        assert_eq!(Heading::Up.counter_clockwise(), Heading::Left);
        assert_eq!(Heading::Up.rotated(90), Some(Heading::Right));
        assert_eq!(Heading::Up.rotated(-90), Some(Heading::Left));
        assert_eq!(Heading::Up.rotated(0), Some(Heading::Up));
        assert_eq!(Heading::Up.rotated(180), None);
    }

    #[test]
    fn sensors_of_up_are_left_up_right() {
        // RULES.md: sensors are [left, front, right] relative to the heading.
        assert_eq!(
            Heading::Up.sensor_headings(),
            [Heading::Left, Heading::Up, Heading::Right]
        );
        assert_eq!(
            Heading::Down.sensor_headings(),
            [Heading::Right, Heading::Down, Heading::Left]
        );
    }

    #[test]
    fn stepping_stays_on_the_grid() {
        let p = Position::new(0, 0);
        assert_eq!(p.step(Heading::Left, 4), None);
        assert_eq!(p.step(Heading::Down, 4), None);
        assert_eq!(p.step(Heading::Up, 4), Some(Position::new(0, 1)));
        assert_eq!(Position::new(3, 3).step(Heading::Right, 4), None);
    }
}
