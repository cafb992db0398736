//! The mms mouse protocol (docs/PROTOCOL-mms.md): a mouse written for the mms simulator
//! writes one command a line and reads the answers; this translator turns that
//! conversation into the task's steps, exactly and deterministically.
//!
//! Pure: lines and sensor readings in, answers and actions out. The translator knows
//! where the robot is and which way it faces from the actions it gave and the sensors of
//! each step (a move goes as far as the sensed open cells allow), and keeps the walls the
//! robot has sensed. The mouse has its own idea of its heading: it turns at once (turns
//! cost no step), and the robot's rotation is folded into its next move. Every rule below
//! is one of the doc's.

use crate::engine::{Action, Sense};

/// The most unknown-command warnings a match keeps (their count goes on).
pub const MAX_WARNINGS: usize = 20;

/// The longest cell text kept for the drawing (mms shows about ten characters).
pub const MAX_CELL_TEXT_CHARS: usize = 10;

/// mms's colour letters and the colours the replay draws them with.
const COLORS: [(char, &str); 15] = [
    ('k', "#000000"),
    ('b', "#0000ff"),
    ('a', "#808080"),
    ('c', "#00ffff"),
    ('g', "#00ff00"),
    ('o', "#ffa500"),
    ('r', "#ff0000"),
    ('w', "#ffffff"),
    ('y', "#ffff00"),
    ('B', "#00008b"),
    ('C', "#008b8b"),
    ('A', "#a9a9a9"),
    ('G', "#006400"),
    ('R', "#8b0000"),
    ('Y', "#9b870c"),
];

/// What the mouse has drawn (mms's display): kept as state, so a flood of commands costs
/// nothing but the state's size, which the maze bounds.
#[derive(Debug, Clone, Default)]
struct Display {
    colors: std::collections::BTreeMap<(i32, i32), &'static str>,
    texts: std::collections::BTreeMap<(i32, i32), String>,
    walls: std::collections::BTreeSet<(i32, i32, Dir)>,
    /// Which of the three changed since the last step's drawing.
    changed: [bool; 3],
}

/// What the runner does next.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Next {
    /// Play this action as the step's answer.
    Act(Action),
    /// Write this line (without its "\n") to the mouse, then read its next line.
    Write(String),
    /// Read the mouse's next line.
    Read,
}

/// A mouse's fault: the match ends as a protocol error with this reason.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct MmsError(pub String);

/// A direction: 0 north (+y), 1 east (+x), 2 south, 3 west.
type Dir = u8;

/// The four sides' knowledge of one cell: bit `d` of `known` says side `d` is known,
/// bit `d` of `wall` that it is a wall.
#[derive(Debug, Clone, Copy, Default)]
struct Sides {
    known: u8,
    wall: u8,
}

/// A command that takes more than one step, carried over to the next.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Pending {
    None,
    /// `moveForward`: cells still to go; whether the last step stopped at a wall.
    Move {
        remaining: u32,
        crashed: bool,
    },
    /// A wall query waiting for the look it asked.
    Query(String),
    /// `ackReset`, played: answer `ack`.
    Reset,
}

/// The counts `getStat` answers.
#[derive(Debug, Clone, Copy, Default)]
struct Stats {
    total_distance: i64,
    total_turns: i64,
    run_distance: i64,
    run_turns: i64,
    best_distance: Option<i64>,
    best_turns: Option<i64>,
}

/// The referee's side of one mms mouse in one match.
#[derive(Debug, Clone)]
pub struct Mouse {
    dim: i32,
    /// The robot in the game: its cell and heading.
    x: i32,
    y: i32,
    heading: Dir,
    /// The mouse's heading in eighths of a turn (0 north, 2 east, ...).
    mouse8: u8,
    sides: Vec<Sides>,
    /// The current step's run and sensors (`None` before the first step).
    run: u8,
    sensors: Option<[u32; 3]>,
    /// Whether the robot has ended a step in the goal room in this run.
    in_goal_this_run: bool,
    /// Run 0 has reached the goal and the robot came back to the start: the task's reset
    /// is played before the mouse's next move.
    reset_due: bool,
    /// `wasReset` has answered `true`.
    told_reset: bool,
    pending: Pending,
    stats: Stats,
    warnings: Vec<String>,
    unknown_count: u64,
    display: Display,
}

fn step_of(d: Dir) -> (i32, i32) {
    match d & 3 {
        0 => (0, 1),
        1 => (1, 0),
        2 => (0, -1),
        _ => (-1, 0),
    }
}

impl Mouse {
    /// A mouse on an `dim` x `dim` maze, at (0,0) facing north.
    pub fn new(dim: u32) -> Mouse {
        let dim = dim as i32;
        let mut m = Mouse {
            dim,
            x: 0,
            y: 0,
            heading: 0,
            mouse8: 0,
            sides: vec![Sides::default(); (dim * dim).max(1) as usize],
            run: 0,
            sensors: None,
            in_goal_this_run: false,
            reset_due: false,
            told_reset: false,
            pending: Pending::None,
            stats: Stats::default(),
            warnings: Vec::new(),
            unknown_count: 0,
            display: Display::default(),
        };
        // The outer wall is known.
        for i in 0..dim {
            m.set(i, 0, 2, true);
            m.set(i, dim - 1, 0, true);
            m.set(0, i, 3, true);
            m.set(dim - 1, i, 1, true);
        }
        m
    }

    fn inside(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.dim && y < self.dim
    }

    /// Records side `d` of cell (x, y) (and the same edge seen from the neighbour).
    fn set(&mut self, x: i32, y: i32, d: Dir, wall: bool) {
        let d = d & 3;
        for (cx, cy, cd) in [(x, y, d), (x + step_of(d).0, y + step_of(d).1, (d + 2) & 3)] {
            if self.inside(cx, cy) {
                let s = &mut self.sides[(cy * self.dim + cx) as usize];
                s.known |= 1 << cd;
                if wall {
                    s.wall |= 1 << cd;
                } else {
                    s.wall &= !(1 << cd);
                }
            }
        }
    }

    /// Side `d` of (x, y): `Some(true)` a wall, `Some(false)` open, `None` unknown.
    fn side(&self, x: i32, y: i32, d: Dir) -> Option<bool> {
        if !self.inside(x, y) {
            return Some(true);
        }
        let s = self.sides[(y * self.dim + x) as usize];
        let bit = 1 << (d & 3);
        (s.known & bit != 0).then_some(s.wall & bit != 0)
    }

    fn is_goal(&self, x: i32, y: i32) -> bool {
        let lo = self.dim / 2 - 1;
        (lo..=lo + 1).contains(&x) && (lo..=lo + 1).contains(&y)
    }

    /// Records what the sensors of `sense` say from the robot's cell and heading.
    fn sense_walls(&mut self, sensors: [u32; 3]) {
        for (i, open) in sensors.iter().enumerate() {
            let d = (self.heading + 3 + i as u8) & 3; // left, front, right
            let (dx, dy) = step_of(d);
            let (mut cx, mut cy) = (self.x, self.y);
            for _ in 0..*open {
                self.set(cx, cy, d, false);
                cx += dx;
                cy += dy;
            }
            self.set(cx, cy, d, true);
        }
    }

    /// A new step begins with `sense`: what to do first (go on with a command that takes
    /// several steps, or read the mouse's next line).
    ///
    /// # Errors
    /// A mouse fault while going on.
    pub fn begin(&mut self, sense: &Sense) -> Result<Next, MmsError> {
        if sense.run != self.run {
            // The task's reset was accepted: a new run from the start, facing north.
            self.run = sense.run;
            self.in_goal_this_run = false;
        }
        self.sensors = Some(sense.sensors);
        self.sense_walls(sense.sensors);
        match std::mem::replace(&mut self.pending, Pending::None) {
            Pending::None => Ok(Next::Read),
            Pending::Reset => Ok(Next::Write("ack".into())),
            Pending::Query(line) => self.line(&line),
            Pending::Move { remaining, crashed } => {
                if crashed {
                    Ok(Next::Write("crash".into()))
                } else if remaining == 0 {
                    Ok(Next::Write("ack".into()))
                } else {
                    self.advance(remaining)
                }
            }
        }
    }

    /// The mouse wrote `line` (without its line break).
    ///
    /// # Errors
    /// A command the task cannot play (a diagonal, a half-cell move, a reset before the
    /// goal).
    pub fn line(&mut self, line: &str) -> Result<Next, MmsError> {
        let tokens: Vec<&str> = line.split(' ').filter(|t| !t.is_empty()).collect();
        let Some((&command, args)) = tokens.split_first() else {
            return Ok(self.unknown(line));
        };
        let number = |args: &[&str]| -> Option<Option<i64>> {
            match args {
                [] => Some(None),
                [n] => n.parse::<i64>().ok().map(Some),
                _ => None,
            }
        };
        match command {
            "mazeWidth" | "mazeHeight" if args.is_empty() => Ok(Next::Write(self.dim.to_string())),
            "wallFront" | "wallBack" | "wallLeft" | "wallRight" => {
                let Some(n) = number(args) else {
                    return Ok(self.unknown(line));
                };
                let rel = match command {
                    "wallFront" => 0,
                    "wallRight" => 1,
                    "wallBack" => 2,
                    _ => 3,
                };
                self.wall_query(line, rel, n.unwrap_or(1))
            }
            "moveForward" => {
                let Some(n) = number(args) else {
                    return Ok(self.unknown(line));
                };
                self.on_grid("moveForward")?;
                let n = n.unwrap_or(1);
                if n < 1 {
                    return Ok(Next::Write("crash".into()));
                }
                self.advance(n.min(i64::from(u32::MAX)) as u32)
            }
            "moveForwardHalf" => Err(MmsError(
                "moveForwardHalf: the task's robot moves whole cells only".into(),
            )),
            "turnLeft" | "turnLeft90" | "turnRight" | "turnRight90" | "turnLeft45"
            | "turnRight45"
                if args.is_empty() =>
            {
                let eighths: i8 = match command {
                    "turnLeft" | "turnLeft90" => -2,
                    "turnRight" | "turnRight90" => 2,
                    "turnLeft45" => -1,
                    _ => 1,
                };
                self.mouse8 = (self.mouse8 as i8 + eighths).rem_euclid(8) as u8;
                self.stats.total_turns += 1;
                self.stats.run_turns += 1;
                Ok(Next::Write("ack".into()))
            }
            "wasReset" if args.is_empty() => {
                let now = self.run == 0 && self.in_goal_this_run && !self.told_reset;
                if now {
                    self.told_reset = true;
                }
                Ok(Next::Write(now.to_string()))
            }
            "ackReset" if args.is_empty() => self.ack_reset(),
            "getStat" => match args {
                [name] => match self.stat(name) {
                    Some(v) => Ok(Next::Write(v.to_string())),
                    None => Ok(self.unknown(line)),
                },
                _ => Ok(self.unknown(line)),
            },
            "setWall" | "clearWall" | "setColor" | "clearColor" | "clearAllColor" | "setText"
            | "clearText" | "clearAllText" => {
                if !self.draw(command, args) {
                    return Ok(self.unknown(line));
                }
                Ok(Next::Read)
            }
            _ => Ok(self.unknown(line)),
        }
    }

    /// An unknown command: no answer (as mms), a warning kept.
    fn unknown(&mut self, line: &str) -> Next {
        self.unknown_count += 1;
        if self.warnings.len() < MAX_WARNINGS {
            let mut text: String = line.chars().take(200).collect();
            if text.len() < line.len() {
                text.push('…');
            }
            self.warnings
                .push(format!("unknown mms command {text:?}: not answered"));
        }
        Next::Read
    }

    /// Applies a display command to the drawing; false when its arguments are not
    /// ones mms takes (a cell outside the maze, an unknown colour or side).
    fn draw(&mut self, command: &str, args: &[&str]) -> bool {
        let dim = self.dim;
        let cell = |args: &[&str]| -> Option<(i32, i32)> {
            let x: i32 = args.first()?.parse().ok()?;
            let y: i32 = args.get(1)?.parse().ok()?;
            (x >= 0 && y >= 0 && x < dim && y < dim).then_some((x, y))
        };
        let d = &mut self.display;
        match (command, args.len()) {
            ("setColor", 3) => {
                let (Some(c), Some(color)) = (cell(args), args[2].chars().next()) else {
                    return false;
                };
                let Some(hex) = COLORS.iter().find(|(k, _)| *k == color).map(|(_, h)| *h) else {
                    return false;
                };
                if args[2].chars().count() != 1 {
                    return false;
                }
                d.colors.insert(c, hex);
                d.changed[0] = true;
            }
            ("clearColor", 2) => {
                let Some(c) = cell(args) else { return false };
                d.changed[0] |= d.colors.remove(&c).is_some();
            }
            ("clearAllColor", 0) => {
                d.changed[0] |= !d.colors.is_empty();
                d.colors.clear();
            }
            ("setText", n) if n >= 2 => {
                let Some(c) = cell(args) else { return false };
                let text: String = args[2..]
                    .join(" ")
                    .chars()
                    .take(MAX_CELL_TEXT_CHARS)
                    .collect();
                d.texts.insert(c, text);
                d.changed[1] = true;
            }
            ("clearText", 2) => {
                let Some(c) = cell(args) else { return false };
                d.changed[1] |= d.texts.remove(&c).is_some();
            }
            ("clearAllText", 0) => {
                d.changed[1] |= !d.texts.is_empty();
                d.texts.clear();
            }
            ("setWall" | "clearWall", 3) => {
                let Some((x, y)) = cell(args) else {
                    return false;
                };
                let side = match args[2] {
                    "n" => 0,
                    "e" => 1,
                    "s" => 2,
                    "w" => 3,
                    _ => return false,
                };
                let changed = if command == "setWall" {
                    d.walls.insert((x, y, side))
                } else {
                    d.walls.remove(&(x, y, side))
                };
                d.changed[2] |= changed;
            }
            _ => return false,
        }
        true
    }

    /// The drawing's fields that changed since the last call, as the replay's debug
    /// object (docs/PROTOCOL.md, "Debug drawing": `colors`, `cells`, `walls`; each field
    /// whole, as the viewer keeps the latest of each); `None` when nothing changed.
    pub fn take_drawing(&mut self) -> Option<String> {
        let d = &mut self.display;
        if !d.changed.iter().any(|c| *c) {
            return None;
        }
        let mut object = serde_json::Map::new();
        if d.changed[0] {
            let colors: Vec<serde_json::Value> = d
                .colors
                .iter()
                .map(|((x, y), hex)| serde_json::json!([x, y, hex]))
                .collect();
            object.insert("colors".into(), colors.into());
        }
        if d.changed[1] {
            let cells: Vec<serde_json::Value> = d
                .texts
                .iter()
                .map(|((x, y), t)| serde_json::json!([x, y, t]))
                .collect();
            object.insert("cells".into(), cells.into());
        }
        if d.changed[2] {
            let walls: Vec<serde_json::Value> = d
                .walls
                .iter()
                .map(|(x, y, side)| {
                    let name = ["up", "right", "down", "left"][*side as usize];
                    serde_json::json!([x, y, name])
                })
                .collect();
            object.insert("walls".into(), walls.into());
        }
        d.changed = [false; 3];
        Some(serde_json::Value::Object(object).to_string())
    }

    /// Whether run 0 has reached the goal and the task waits for the mouse's reset.
    pub fn waits_for_run_1(&self) -> bool {
        self.run == 0 && self.in_goal_this_run
    }

    /// The warnings kept, and how many unknown commands there were in all.
    pub fn warnings(&self) -> (&[String], u64) {
        (&self.warnings, self.unknown_count)
    }

    fn on_grid(&self, what: &str) -> Result<(), MmsError> {
        if self.mouse8 % 2 == 1 {
            return Err(MmsError(format!(
                "{what} while the mouse faces a diagonal (after a 45-degree turn): the task's \
                 robot faces and moves along the grid only"
            )));
        }
        Ok(())
    }

    /// The mouse's heading as a direction.
    fn mouse_dir(&self) -> Dir {
        self.mouse8 / 2
    }

    /// `wallX N` relative to the mouse (`rel` quarter turns clockwise from its front).
    fn wall_query(&mut self, line: &str, rel: u8, n: i64) -> Result<Next, MmsError> {
        self.on_grid("a wall query")?;
        if n < 1 {
            return Ok(self.unknown(line));
        }
        let within = ((n - 1) / 2) as u32; // open cells that still count as "a wall"
        let d = (self.mouse_dir() + rel) & 3;
        let (dx, dy) = step_of(d);
        let (mut cx, mut cy) = (self.x, self.y);
        let mut open = 0u32;
        loop {
            match self.side(cx, cy, d) {
                Some(true) => return Ok(Next::Write((open <= within).to_string())),
                Some(false) => {
                    open += 1;
                    if open > within {
                        return Ok(Next::Write("false".into()));
                    }
                    cx += dx;
                    cy += dy;
                }
                None => break,
            }
        }
        // Not sensed yet: the robot turns a quarter to look (a step), and the query is
        // answered at the next step. Only the robot's back can be unknown here.
        self.pending = Pending::Query(line.to_string());
        self.heading = (self.heading + 1) & 3;
        Ok(Next::Act(Action::Move {
            rotation: 90,
            movement: 0,
        }))
    }

    /// Goes on with a `moveForward` that has `remaining` cells to go: one step.
    fn advance(&mut self, remaining: u32) -> Result<Next, MmsError> {
        if self.reset_due {
            self.reset_due = false;
            self.play_reset();
            self.pending = Pending::Move {
                remaining,
                crashed: false,
            };
            return Ok(Next::Act(Action::RESET));
        }
        let sensors = self.sensors.unwrap_or([0, 0, 0]);
        let quarter = (self.mouse_dir() + 4 - self.heading) & 3;
        if quarter == 2 {
            // A half turn: a step of its own.
            self.heading = (self.heading + 1) & 3;
            self.pending = Pending::Move {
                remaining,
                crashed: false,
            };
            return Ok(Next::Act(Action::Move {
                rotation: 90,
                movement: 0,
            }));
        }
        let (rotation, open) = match quarter {
            1 => (90, sensors[2]),
            3 => (-90, sensors[0]),
            _ => (0, sensors[1]),
        };
        if open == 0 {
            // A wall right ahead: no movement (mms answers at once; the robot turns with
            // its next move).
            return Ok(Next::Write("crash".into()));
        }
        self.heading = self.mouse_dir();
        let (dx, dy) = step_of(self.heading);
        let mut moved = 0u32;
        let want = remaining.min(3);
        while moved < want && moved < open {
            self.x += dx;
            self.y += dy;
            moved += 1;
            // Entering the goal room ends the step there, as mms counts a run.
            if !self.in_goal_this_run && self.is_goal(self.x, self.y) {
                break;
            }
        }
        if self.is_goal(self.x, self.y) {
            self.in_goal_this_run = true;
        }
        self.stats.total_distance += i64::from(moved);
        self.stats.run_distance += i64::from(moved);
        let crashed = moved < want && moved == open;
        let left = remaining - moved;
        if self.run == 0 && self.in_goal_this_run && (self.x, self.y) == (0, 0) {
            self.reset_due = true;
        }
        self.pending = Pending::Move {
            remaining: if crashed { 0 } else { left },
            crashed,
        };
        Ok(Next::Act(Action::Move {
            rotation,
            movement: i64::from(moved),
        }))
    }

    /// The robot after the task's reset: the start, facing north; a new run's counts.
    fn play_reset(&mut self) {
        self.x = 0;
        self.y = 0;
        self.heading = 0;
        if self
            .stats
            .best_distance
            .is_none_or(|b| self.stats.run_distance < b)
        {
            self.stats.best_distance = Some(self.stats.run_distance);
            self.stats.best_turns = Some(self.stats.run_turns);
        }
        self.stats.run_distance = 0;
        self.stats.run_turns = 0;
    }

    fn ack_reset(&mut self) -> Result<Next, MmsError> {
        if self.run == 0 && self.in_goal_this_run {
            self.reset_due = false;
            self.play_reset();
            self.mouse8 = 0;
            self.pending = Pending::Reset;
            return Ok(Next::Act(Action::RESET));
        }
        if self.run == 1 && (self.x, self.y) == (0, 0) && self.stats.run_distance == 0 {
            // Already at the start of run 1 (the referee reset the robot): the mouse's
            // own reset only sets its heading back to north.
            self.mouse8 = 0;
            return Ok(Next::Write("ack".into()));
        }
        Err(MmsError(format!(
            "ackReset {}: the task's robot goes back to the start only once, after run 0 \
             has reached the goal",
            if self.run == 0 {
                "before the mouse reached the goal"
            } else {
                "in the timed run"
            }
        )))
    }

    fn stat(&self, name: &str) -> Option<i64> {
        let s = &self.stats;
        Some(match name {
            "total-distance" => s.total_distance,
            "total-turns" => s.total_turns,
            "best-run-distance" => s.best_distance.unwrap_or(-1),
            "best-run-turns" => s.best_turns.unwrap_or(-1),
            "current-run-distance" => s.run_distance,
            "current-run-turns" => s.run_turns,
            "total-effective-distance"
            | "best-run-effective-distance"
            | "current-run-effective-distance"
            | "score" => -1,
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::game::{Game, GameConfig};
    use crate::engine::mazefile;

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
}
