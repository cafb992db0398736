//! The fewest run-1 steps with full knowledge of the maze (RULES.md "Reference figures").
//!
//! Breadth-first search over (cell, heading): each step is one rotation (-90, 0, 90)
//! followed by a movement of -3..=3 cells that stops at walls, exactly as the referee
//! plays it; the search ends when a movement ends in a goal cell.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use super::game::Action;
use super::geometry::{Heading, Position};
use super::maze::Maze;
use super::maze::slide;

/// An optimal run 1.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Solution {
    /// The fewest steps from the start to the goal room.
    pub steps: u32,
    /// One optimal list of answers, in order.
    pub actions: Vec<Action>,
    /// The cells the robot stands on after each step (the start cell first).
    pub path: Vec<Position>,
}

/// Finds the fewest steps from (0,0) facing up to any goal cell, or `None` when the
/// goal room cannot be reached.
pub fn solve(maze: &Maze) -> Option<Solution> {
    let n = maze.dim();
    let states = (n * n * 4) as usize;
    let index = |p: Position, h: Heading| ((p.x * n + p.y) * 4) as usize + h.index();
    // Predecessor state and the action that led here.
    let mut prev: Vec<Option<(usize, Action)>> = vec![None; states];
    let mut seen = vec![false; states];
    let start = (Position::new(0, 0), Heading::Up);
    seen[index(start.0, start.1)] = true;
    let mut queue = VecDeque::from([start]);
    let mut found = None;
    'search: while let Some((cell, heading)) = queue.pop_front() {
        let from = index(cell, heading);
        for (rotation, h) in [0i64, 90, -90]
            .into_iter()
            .filter_map(|r| heading.rotated(r).map(|h| (r, h)))
        {
            for movement in [3i64, 2, 1, 0, -1, -2, -3] {
                let (end, _) = slide(maze, cell, h, movement);
                let to = index(end, h);
                if seen[to] {
                    continue;
                }
                seen[to] = true;
                prev[to] = Some((from, Action::turn_move(rotation, movement)));
                if maze.is_goal(end) {
                    found = Some(to);
                    break 'search;
                }
                queue.push_back((end, h));
            }
        }
    }
    let mut state = found?;
    let mut actions = Vec::new();
    let mut path = Vec::new();
    while let Some((p, action)) = prev[state] {
        actions.push(action);
        path.push(cell_of(state, n));
        state = p;
    }
    path.push(Position::new(0, 0));
    actions.reverse();
    path.reverse();
    Some(Solution {
        steps: actions.len() as u32,
        actions,
        path,
    })
}

fn cell_of(state: usize, n: u32) -> Position {
    let c = (state / 4) as u32;
    Position::new(c / n, c % n)
}
