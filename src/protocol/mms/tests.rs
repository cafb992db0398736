//! Tests of the module's operations.

use super::*;
use crate::engine::game::{Game, GameConfig};
use crate::engine::mazefile;
use crate::engine::{Action, Sense};

fn write(s: &str) -> Next {
    Next::Write(s.into())
}

fn sense(run: u8, step: u32, sensors: [u32; 3]) -> Sense {
    Sense { run, step, sensors }
}

#[test]
fn queries_are_answered_from_the_sensed_walls_without_a_step() {
    let mut m = Mouse::new(12);
    assert_eq!(m.begin(&sense(0, 1, [0, 5, 0])).unwrap(), Next::Read);
    assert_eq!(m.line("mazeWidth").unwrap(), write("12"));
    assert_eq!(m.line("mazeHeight").unwrap(), write("12"));
    assert_eq!(m.line("wallFront").unwrap(), write("false"));
    assert_eq!(m.line("wallLeft").unwrap(), write("true"));
    assert_eq!(m.line("wallRight").unwrap(), write("true"));
    // The start's back is the outer wall.
    assert_eq!(m.line("wallBack").unwrap(), write("true"));
    // With a distance in half cells: 5 open cells ahead.
    assert_eq!(m.line("wallFront 11").unwrap(), write("true"));
    assert_eq!(m.line("wallFront 10").unwrap(), write("false"));
    assert_eq!(m.line("wallFront 9").unwrap(), write("false"));
    // Spaces and an empty line, as mms splits them.
    assert_eq!(m.line("  wallLeft  ").unwrap(), write("true"));
    assert_eq!(m.line("").unwrap(), Next::Read);
    // Turns answer at once and cost no step; the queries follow the mouse.
    assert_eq!(m.line("turnRight").unwrap(), write("ack"));
    assert_eq!(m.line("wallLeft").unwrap(), write("false"));
    assert_eq!(m.line("wallFront").unwrap(), write("true"));
    assert_eq!(m.line("turnLeft90").unwrap(), write("ack"));
    assert_eq!(m.line("wallFront").unwrap(), write("false"));
}

#[test]
fn display_and_unknown_commands_get_no_answer() {
    let mut m = Mouse::new(16);
    m.begin(&sense(0, 1, [0, 1, 0])).unwrap();
    for line in [
        "setColor 0 0 G",
        "setText 1 2 hello there",
        "clearAllColor",
        "setWall 0 0 n",
        "clearWall 0 0 n",
        "clearColor 0 0",
        "clearText 0 0",
        "clearAllText",
    ] {
        assert_eq!(m.line(line).unwrap(), Next::Read, "{line}");
    }
    let drawing: serde_json::Value = serde_json::from_str(&m.take_drawing().unwrap()).unwrap();
    // Each was undone by the next: the cleared state is drawn.
    assert_eq!(
        drawing,
        serde_json::json!({"colors": [], "cells": [], "walls": []})
    );
    assert_eq!(m.take_drawing(), None, "nothing changed since");
    m.line("setColor 1 2 r").unwrap();
    m.line("setText 3 4 a long text here").unwrap();
    m.line("setWall 0 0 e").unwrap();
    let drawing: serde_json::Value = serde_json::from_str(&m.take_drawing().unwrap()).unwrap();
    assert_eq!(
        drawing,
        serde_json::json!({"colors": [[1, 2, "#ff0000"]], "cells": [[3, 4, "a long tex"]],
                           "walls": [[0, 0, "right"]]})
    );
    // Arguments mms does not take: no answer, and a warning.
    for line in ["setColor 99 0 r", "setColor 0 0 q", "setWall 0 0 up"] {
        assert_eq!(m.line(line).unwrap(), Next::Read, "{line}");
    }
    assert_eq!(m.warnings().1, 3);
    assert_eq!(m.take_drawing(), None);
    for line in [
        "dance",
        "turnLeft 1",
        "mazeWidth 3",
        "getStat nothing",
        "wallFront x",
    ] {
        assert_eq!(m.line(line).unwrap(), Next::Read, "{line}");
    }
    let (kept, count) = m.warnings();
    assert_eq!(count, 3 + 5, "the three bad display lines, and these five");
    assert!(kept[3].contains("\"dance\""), "{kept:?}");
    assert_eq!(m.line("getStat total-turns").unwrap(), write("0"));
    assert_eq!(m.line("getStat best-run-distance").unwrap(), write("-1"));
}

#[test]
fn display_floods_are_kept_within_their_budget() {
    let mut m = Mouse::new(16);
    m.begin(&sense(0, 1, [0, 1, 0])).unwrap();
    for i in 0..100_000 {
        let line = format!("setColor {} {} r", i % 16, i / 16 % 16);
        assert_eq!(m.line(&line).unwrap(), Next::Read);
        m.line(&format!("setText {} {} {i}", i % 16, i / 16 % 16))
            .unwrap();
    }
    // The state of a 16x16 maze, whatever the flood: well within a step's 16 KiB.
    let drawing = m.take_drawing().unwrap();
    assert!(
        drawing.len() < crate::protocol::MAX_DEBUG_STEP_BYTES,
        "{}",
        drawing.len()
    );
}

#[test]
fn moves_become_steps_of_at_most_three_cells_and_crash_at_walls() {
    let mut m = Mouse::new(16);
    m.begin(&sense(0, 1, [0, 5, 0])).unwrap();
    // moveForward 5 on 5 open cells: 3 then 2, then ack.
    assert_eq!(
        m.line("moveForward 5").unwrap(),
        Next::Act(Action::turn_move(0, 3))
    );
    assert_eq!(
        m.begin(&sense(0, 2, [0, 2, 0])).unwrap(),
        Next::Act(Action::turn_move(0, 2))
    );
    assert_eq!(m.begin(&sense(0, 3, [1, 0, 0])).unwrap(), write("ack"));
    // A wall right ahead: crash, no step.
    assert_eq!(m.line("moveForward").unwrap(), write("crash"));
    assert_eq!(m.line("moveForward 0").unwrap(), write("crash"));
    // A turn is folded into the next move.
    assert_eq!(m.line("turnLeft").unwrap(), write("ack"));
    assert_eq!(
        m.line("moveForward 4").unwrap(),
        Next::Act(Action::turn_move(-90, 1))
    );
    // It went as far as it could: crash after the step.
    assert_eq!(m.begin(&sense(0, 4, [0, 0, 0])).unwrap(), write("crash"));
    // A half turn costs a step of its own.
    assert_eq!(m.line("turnLeft").unwrap(), write("ack"));
    assert_eq!(m.line("turnLeft").unwrap(), write("ack"));
    assert_eq!(
        m.line("moveForward").unwrap(),
        Next::Act(Action::turn_move(90, 0))
    );
    // The robot faces north now; the mouse faces east, the robot's right.
    assert_eq!(
        m.begin(&sense(0, 5, [0, 0, 1])).unwrap(),
        Next::Act(Action::turn_move(90, 1))
    );
    assert_eq!(m.begin(&sense(0, 6, [0, 4, 0])).unwrap(), write("ack"));
}

#[test]
fn what_the_task_cannot_play_is_a_clear_failure() {
    let mut m = Mouse::new(16);
    m.begin(&sense(0, 1, [0, 3, 0])).unwrap();
    let e = m.line("moveForwardHalf").unwrap_err();
    assert!(e.0.contains("whole cells"), "{e}");
    assert_eq!(m.line("turnRight45").unwrap(), write("ack"));
    let e = m.line("moveForward").unwrap_err();
    assert!(e.0.contains("diagonal"), "{e}");
    assert_eq!(m.line("turnRight45").unwrap(), write("ack"));
    assert_eq!(
        m.line("wallLeft").unwrap(),
        write("false"),
        "two 45s are a quarter"
    );
    let e = m.line("ackReset").unwrap_err();
    assert!(e.0.contains("before the mouse reached the goal"), "{e}");
}

#[test]
fn an_unsensed_back_costs_a_step_to_look() {
    let mut m = Mouse::new(16);
    m.begin(&sense(0, 1, [0, 3, 0])).unwrap();
    assert_eq!(
        m.line("moveForward").unwrap(),
        Next::Act(Action::turn_move(0, 1))
    );
    // At (0,1): the back is where it came from (open), known.
    assert_eq!(m.begin(&sense(0, 2, [2, 2, 0])).unwrap(), write("ack"));
    assert_eq!(m.line("wallBack").unwrap(), write("false"));
    // Turn left twice: the mouse faces south (known: open); its back is north,
    // sensed as the front. Its left is east: sensed (a wall).
    m.line("turnLeft").unwrap();
    m.line("turnLeft").unwrap();
    assert_eq!(m.line("wallFront").unwrap(), write("false"));
    assert_eq!(m.line("wallBack").unwrap(), write("false"));
    assert_eq!(m.line("wallLeft").unwrap(), write("true"));
    // Behind the mouse (north): 2 open cells, then a wall.
    assert_eq!(m.line("wallBack 5").unwrap(), write("true"));
    assert_eq!(m.line("wallBack 4").unwrap(), write("false"));

    // In the middle of the maze, facing north, nothing known behind: a look.
    let mut m = Mouse::new(16);
    (m.x, m.y) = (5, 5);
    m.begin(&sense(0, 9, [1, 1, 1])).unwrap();
    assert_eq!(
        m.line("wallBack").unwrap(),
        Next::Act(Action::turn_move(90, 0))
    );
    // Now facing east: the old back is sensed on the right, and answered.
    assert_eq!(m.begin(&sense(0, 10, [1, 1, 2])).unwrap(), write("false"));
    // The mouse still faces north: its move turns the robot back first.
    assert_eq!(
        m.line("moveForward").unwrap(),
        Next::Act(Action::turn_move(-90, 1))
    );
}

use crate::engine::{Heading, Maze, Position};

/// What a mouse program talks to: the translator with the referee, or a model of
/// mms's own rules on the true maze.
trait Api {
    /// Sends `line`; the answer, if the command has one.
    fn ask(&mut self, line: &str) -> Option<String>;
    /// The cells the mouse has been in, in order (each cell once per visit).
    fn path(&self) -> Vec<(i32, i32)>;
    /// Whether the game is over.
    fn over(&self) -> bool;
}

/// The translator playing the real referee.
struct Refereed {
    game: Game,
    mouse: Mouse,
    path: Vec<(i32, i32)>,
    over: bool,
}

impl Refereed {
    fn new(maze: Maze) -> Refereed {
        let mut game = Game::new(maze.clone(), GameConfig::default());
        let mut mouse = Mouse::new(maze.dim());
        let s = game.begin_step().unwrap();
        assert_eq!(mouse.begin(&s).unwrap(), Next::Read);
        Refereed {
            game,
            mouse,
            path: vec![(0, 0)],
            over: false,
        }
    }
}

impl Api for Refereed {
    fn ask(&mut self, line: &str) -> Option<String> {
        let mut next = self.mouse.line(line).unwrap();
        loop {
            match next {
                Next::Write(a) => return Some(a),
                Next::Read => return None,
                Next::Act(a) => {
                    let before = self.game.position();
                    self.game.apply(a);
                    let after = self.game.position();
                    // The translator knows where the robot is and which way it faces.
                    assert_eq!(
                        (after.x as i32, after.y as i32),
                        (self.mouse.x, self.mouse.y)
                    );
                    assert_eq!(self.game.heading().index() as u8, self.mouse.heading);
                    // The cells passed, one by one (moves go in a line).
                    let (mut x, mut y) = (before.x as i32, before.y as i32);
                    while (x, y) != (after.x as i32, after.y as i32) {
                        x += (after.x as i32 - x).signum();
                        y += (after.y as i32 - y).signum();
                        self.path.push((x, y));
                    }
                    match self.game.begin_step() {
                        Some(s) => next = self.mouse.begin(&s).unwrap(),
                        None => {
                            self.over = true;
                            return None;
                        }
                    }
                }
            }
        }
    }
    fn path(&self) -> Vec<(i32, i32)> {
        self.path.clone()
    }
    fn over(&self) -> bool {
        self.over
    }
}

/// mms's rules (docs/PROTOCOL-mms.md, "mms's rules"), on the true maze: answers from
/// the walls, moves cell by cell to the first wall, turns in place.
struct Model {
    maze: Maze,
    at: Position,
    heading: Heading,
    path: Vec<(i32, i32)>,
}

impl Api for Model {
    fn ask(&mut self, line: &str) -> Option<String> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let rel = |r: usize| Heading::from_index(self.heading.index() + r);
        Some(match words.as_slice() {
            ["mazeWidth"] | ["mazeHeight"] => self.maze.dim().to_string(),
            ["wallFront"] => (!self.maze.is_open(self.at, rel(0))).to_string(),
            ["wallRight"] => (!self.maze.is_open(self.at, rel(1))).to_string(),
            ["wallBack"] => (!self.maze.is_open(self.at, rel(2))).to_string(),
            ["wallLeft"] => (!self.maze.is_open(self.at, rel(3))).to_string(),
            ["turnLeft"] => {
                self.heading = rel(3);
                "ack".into()
            }
            ["turnRight"] => {
                self.heading = rel(1);
                "ack".into()
            }
            ["moveForward", rest @ ..] => {
                let n: u32 = rest.first().map_or(1, |t| t.parse().unwrap());
                for _ in 0..n {
                    if !self.maze.is_open(self.at, self.heading) {
                        return Some("crash".into());
                    }
                    self.at = self.at.step(self.heading, self.maze.dim()).unwrap();
                    self.path.push((self.at.x as i32, self.at.y as i32));
                }
                "ack".into()
            }
            _ => return None,
        })
    }
    fn path(&self) -> Vec<(i32, i32)> {
        self.path.clone()
    }
    fn over(&self) -> bool {
        false
    }
}

/// The official templates' mouse: follow the left wall until the goal room, moving
/// `stride` cells at once where the wall allows it.
fn left_wall_follower(api: &mut dyn Api, goal: impl Fn(i32, i32) -> bool, stride: u32) {
    let mut at = (0i32, 0i32);
    let mut dir = 0u8;
    for _ in 0..400 {
        if goal(at.0, at.1) || api.over() {
            return;
        }
        if api.ask("wallLeft").as_deref() == Some("false") {
            api.ask("turnLeft");
            dir = (dir + 3) & 3;
        }
        while api.ask("wallFront").as_deref() == Some("true") {
            api.ask("turnRight");
            dir = (dir + 1) & 3;
        }
        let answer = if stride > 1 {
            api.ask(&format!("moveForward {stride}"))
        } else {
            api.ask("moveForward")
        };
        let moved = match answer.as_deref() {
            Some("ack") => stride,
            _ => 1, // a crash after at least one cell (the front was open)
        };
        let (dx, dy) = [(0, 1), (1, 0), (0, -1), (-1, 0)][dir as usize];
        at = (at.0 + dx * moved as i32, at.1 + dy * moved as i32);
        if stride > 1 {
            // A long move's crash ends where the wall is: ask the model's way back.
            return;
        }
    }
}

fn classic(n: u32) -> Maze {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../shared/mazes/classic/test_maze_0{n}.txt")),
    )
    .unwrap();
    mazefile::parse(text.as_bytes()).unwrap()
}

#[test]
fn a_left_wall_follower_takes_the_path_it_takes_under_mms_rules() {
    for n in 1..=3 {
        let maze = classic(n);
        let goal = {
            let m = maze.clone();
            move |x: i32, y: i32| {
                m.is_goal(Position {
                    x: x as u32,
                    y: y as u32,
                })
            }
        };
        let mut refereed = Refereed::new(maze.clone());
        left_wall_follower(&mut refereed, &goal, 1);
        let mut model = Model {
            maze: maze.clone(),
            at: Position { x: 0, y: 0 },
            heading: Heading::Up,
            path: vec![(0, 0)],
        };
        left_wall_follower(&mut model, &goal, 1);
        let (a, b) = (refereed.path(), model.path());
        assert!(b.len() > 5, "maze {n}: the mouse went somewhere: {b:?}");
        // The same cells in the same order (a left-wall follower may circle an island
        // goal room for ever: then both circle it alike, 400 moves long).
        if refereed.over || goal(refereed.mouse.x, refereed.mouse.y) {
            assert_eq!(a, b[..a.len()], "maze {n}");
        } else {
            assert_eq!(a, b, "maze {n}");
        }
    }
}
