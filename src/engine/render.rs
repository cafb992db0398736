//! A maze as an SVG picture: walls, posts, the start cell, the goal room and an
//! optional route through cell centres.
//!
//! Pure string building: the caller writes the text where it wants. The picture is
//! drawn north up, cell (0,0) at the bottom-left, with the column and row numbers along
//! the bottom and left edges. Every wall segment is one `<line class="wall">` element,
//! drawn once (the shared side of two cells is not doubled).

use std::fmt::Write as _;

use super::geometry::{Heading, Position};
use super::maze::Maze;

/// The side of a cell in pixels.
pub const CELL: u32 = 40;

/// The margin around the grid, with room for the axis numbers.
const MARGIN: u32 = 28;

/// The styles of a drawn maze (the text of its `<style>` element).
pub const SVG_STYLE: &str = "
.wall { stroke: #1d2330; stroke-width: 5; stroke-linecap: round; }
.post { fill: #1d2330; }
.axis { font: 11px sans-serif; fill: #6b7280; text-anchor: middle; dominant-baseline: central; }
.route { fill: none; stroke: #d9480f; stroke-width: 4; stroke-linejoin: round; stroke-linecap: round; opacity: 0.85; }
";

/// Draws `maze` as a standalone SVG document; `path`, when given, is drawn as a
/// polyline through the centres of its cells (for example a solver's
/// [`Solution::path`](super::solver::Solution::path)).
pub fn svg(maze: &Maze, path: Option<&[Position]>) -> String {
    let n = maze.dim();
    let size = n * CELL + 2 * MARGIN;
    let mut out = String::with_capacity(200 * (n * n) as usize + 2048);
    // `write!` into a String cannot fail; the results are ignored on purpose.
    let _ = write!(
        out,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{size}" height="{size}" viewBox="0 0 {size} {size}">
<title>maze {n}x{n}</title>
<style>{SVG_STYLE}</style>
<rect x="0" y="0" width="{size}" height="{size}" fill="#ffffff"/>
<rect x="{MARGIN}" y="{MARGIN}" width="{side}" height="{side}" fill="#f8f9fb"/>
"##,
        side = n * CELL,
    );

    // The goal room, then the start cell.
    let room = maze.goal_room();
    let (gx, gy) = corner(room[0].x, room[0].y + 2, n);
    let _ = writeln!(
        out,
        r##"<rect class="goal" x="{gx}" y="{gy}" width="{w}" height="{w}" fill="#ffe8a3"/>"##,
        w = 2 * CELL
    );
    let (sx, sy) = corner(0, 1, n);
    let _ = writeln!(
        out,
        r##"<rect class="start" x="{sx}" y="{sy}" width="{CELL}" height="{CELL}" fill="#d3f9d8"/>"##
    );
    let (cx, cy) = centre(Position::new(0, 0), n);
    let _ = writeln!(
        out,
        r##"<text x="{cx}" y="{cy}" font-family="sans-serif" font-size="20" font-weight="bold" fill="#2b8a3e" text-anchor="middle" dominant-baseline="central">S</text>"##
    );
    for g in room {
        let (gcx, gcy) = centre(g, n);
        let _ = writeln!(
            out,
            r##"<text x="{gcx}" y="{gcy}" font-family="sans-serif" font-size="16" font-weight="bold" fill="#c99a06" text-anchor="middle" dominant-baseline="central">G</text>"##
        );
    }

    // Axis numbers.
    for i in 0..n {
        let along = MARGIN + i * CELL + CELL / 2;
        let _ = writeln!(
            out,
            r#"<text class="axis" x="{along}" y="{y}">{i}</text>"#,
            y = MARGIN + n * CELL + MARGIN / 2
        );
        let (_, row) = centre(Position::new(0, i), n);
        let _ = writeln!(
            out,
            r#"<text class="axis" x="{x}" y="{row}">{i}</text>"#,
            x = MARGIN / 2
        );
    }

    if let Some(path) = path.filter(|p| !p.is_empty()) {
        let points: Vec<String> = path
            .iter()
            .filter(|p| p.x < n && p.y < n)
            .map(|&p| {
                let (x, y) = centre(p, n);
                format!("{x},{y}")
            })
            .collect();
        let _ = writeln!(
            out,
            r#"<polyline class="route" points="{}"/>"#,
            points.join(" ")
        );
    }

    for (x1, y1, x2, y2) in wall_segments(maze) {
        let _ = writeln!(
            out,
            r#"<line class="wall" x1="{x1}" y1="{y1}" x2="{x2}" y2="{y2}"/>"#
        );
    }

    for px in 0..=n {
        for py in 0..=n {
            let (x, y) = corner(px, py, n);
            let _ = writeln!(
                out,
                r#"<rect class="post" x="{}" y="{}" width="6" height="6"/>"#,
                x - 3,
                y - 3
            );
        }
    }
    out.push_str("</svg>\n");
    out
}

/// The pixel position of grid corner `(px, py)`: the bottom-left corner of cell
/// `(px, py)`, with `py = n` the top edge.
fn corner(px: u32, py: u32, n: u32) -> (u32, u32) {
    (MARGIN + px * CELL, MARGIN + (n - py.min(n)) * CELL)
}

/// The pixel centre of a cell.
fn centre(cell: Position, n: u32) -> (u32, u32) {
    let (x, y) = corner(cell.x, cell.y, n);
    (x + CELL / 2, y - CELL / 2)
}

/// Every closed wall once, as pixel end points: the top and right side of each cell,
/// plus the bottom of the bottom row and the left of the left column.
fn wall_segments(maze: &Maze) -> Vec<(u32, u32, u32, u32)> {
    let n = maze.dim();
    let mut segments = Vec::new();
    for x in 0..n {
        for y in 0..n {
            let cell = Position::new(x, y);
            let closed = |h: Heading| !maze.is_open(cell, h);
            let mut add = |a: (u32, u32), b: (u32, u32)| segments.push((a.0, a.1, b.0, b.1));
            if closed(Heading::Up) {
                add(corner(x, y + 1, n), corner(x + 1, y + 1, n));
            }
            if closed(Heading::Right) {
                add(corner(x + 1, y, n), corner(x + 1, y + 1, n));
            }
            if y == 0 && closed(Heading::Down) {
                add(corner(x, 0, n), corner(x + 1, 0, n));
            }
            if x == 0 && closed(Heading::Left) {
                add(corner(0, y, n), corner(0, y + 1, n));
            }
        }
    }
    segments
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::mazefile;
    use crate::engine::solver;

    /// shared/mazes/classic/test_maze_01.txt.
    const MAZE_01: &str = "12
1,5,7,5,5,5,7,5,7,5,5,6
3,5,14,3,7,5,15,4,9,5,7,12
11,6,10,10,9,7,13,6,3,5,13,4
10,9,13,12,3,13,5,12,9,5,7,6
9,5,6,3,15,5,5,7,7,4,10,10
3,5,15,14,10,3,6,10,11,6,10,10
9,7,12,11,12,9,14,9,14,11,13,14
3,13,5,12,2,3,13,6,9,14,3,14
11,4,1,7,15,13,7,13,6,9,14,10
11,5,6,10,9,7,13,5,15,7,14,8
11,5,12,10,2,9,5,6,10,8,9,6
9,5,5,13,13,5,5,12,9,5,5,12
";

    /// Closed walls counted from the numeric bits, each shared wall once.
    fn count_walls(m: &Maze) -> usize {
        let n = m.dim();
        let mut count = 0;
        for x in 0..n {
            for y in 0..n {
                let bits = m.bits(Position::new(x, y));
                count += usize::from(bits & 1 == 0) + usize::from(bits & 2 == 0);
                count +=
                    usize::from(y == 0 && bits & 4 == 0) + usize::from(x == 0 && bits & 8 == 0);
            }
        }
        count
    }

    #[test]
    fn draws_every_wall_once_and_the_route() {
        let maze = mazefile::parse(MAZE_01.as_bytes()).unwrap();
        let solution = solver::solve(&maze).unwrap();
        let text = svg(&maze, Some(&solution.path));
        assert!(text.starts_with("<svg ") && text.ends_with("</svg>\n"));
        assert_eq!(text.matches("<line ").count(), count_walls(&maze));
        assert_eq!(text.matches(r#"class="wall""#).count(), count_walls(&maze));
        assert_eq!(text.matches("<polyline ").count(), 1);
        // The route starts at the centre of (0,0): x = 28 + 20, y = 28 + 11 * 40 + 20.
        assert!(text.contains(r#"points="48,488 "#), "route start");
        assert_eq!(text.matches(r#"class="post""#).count(), 13 * 13);
        assert_eq!(text.matches('<').count(), text.matches('>').count());
    }

    #[test]
    fn no_route_means_no_polyline() {
        let closed = Maze::closed(4).unwrap();
        let text = svg(&closed, None);
        assert!(!text.contains("<polyline"));
        // 4x4 all closed: 5 horizontal and 5 vertical lines of 4 segments each.
        assert_eq!(text.matches("<line ").count(), 40);
        assert_eq!(svg(&closed, Some(&[])), text);
        let open = Maze::new(2, vec![3, 6, 9, 12]).unwrap();
        assert_eq!(svg(&open, None).matches("<line ").count(), 8);
    }
}
