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

mod display;

use crate::engine::{Action, Sense};

/// The most unknown-command warnings a match keeps (their count goes on).
pub const MAX_WARNINGS: usize = 20;

/// The longest cell text kept for the drawing (mms shows about ten characters).
pub const MAX_CELL_TEXT_CHARS: usize = 10;

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

    /// Whether run 0 has reached the goal and the task waits for the mouse's reset.
    pub fn waits_for_run_1(&self) -> bool {
        self.run == 0 && self.in_goal_this_run
    }

    /// The warnings kept, and how many unknown commands there were in all.
    pub fn warnings(&self) -> (&[String], u64) {
        (&self.warnings, self.unknown_count)
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
mod tests;
