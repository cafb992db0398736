//! The referee: one match of two runs on one maze, step by step (RULES.md).
//!
//! The caller drives it: [`Game::begin_step`] opens a step (incrementing the shared
//! counter `t`) and gives the sensor reading; [`Game::apply`] takes the bot's answer and
//! returns what happened. Nothing here knows about processes or time.

use serde::{Deserialize, Serialize};

use super::geometry::{Heading, Position};
use super::maze::Maze;
use super::score::Score;
use super::solver::slide;

/// The shared step budget of the task (RULES.md "Runs, time, score").
pub const MAX_STEPS: u32 = 1000;

/// The largest movement, in cells, of one step.
pub const MAX_MOVEMENT: i64 = 3;

/// Settings of one game.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GameConfig {
    /// The budget of steps shared by both runs.
    pub max_steps: u32,
}

impl Default for GameConfig {
    fn default() -> Self {
        GameConfig {
            max_steps: MAX_STEPS,
        }
    }
}

/// A bot's answer for one step, as the referee understands it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Action {
    /// Rotate, then move. Values outside the rules are kept as sent (saturated to
    /// 64 bits) and handled leniently by [`Game::apply`].
    Move {
        /// -90, 0 or 90; anything else means no rotation, with a warning.
        rotation: i64,
        /// Cells to move, clamped to [-3, 3] with a warning.
        movement: i64,
    },
    /// Ask to end run 0.
    Reset {
        /// Always `true`.
        reset: bool,
    },
}

impl Action {
    /// The reset answer.
    pub const RESET: Action = Action::Reset { reset: true };

    /// A rotation-then-movement answer.
    pub const fn turn_move(rotation: i64, movement: i64) -> Action {
        Action::Move { rotation, movement }
    }
}

/// The sensor reading `[left, front, right]`: open cells to the nearest wall.
pub type Sensors = [u32; 3];

/// What the referee gives the bot at the start of a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Sense {
    /// 0 (exploration) or 1 (timed run).
    pub run: u8,
    /// The shared counter `t`, 1-based.
    pub step: u32,
    /// `[left, front, right]`.
    pub sensors: Sensors,
}

/// Why a game is over.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GameEnd {
    /// Run 1 reached the goal room.
    Finished,
    /// The shared budget ran out.
    StepLimit,
}

/// A lenient-rule event kept with the match (RULES.md: "a warning is recorded").
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Warning {
    /// The step `t` it happened at.
    pub step: u32,
    /// The run it happened in.
    pub run: u8,
    /// `invalid_rotation`, `movement_clamped` or `reset_rejected`.
    pub kind: WarningKind,
    /// A sentence for people.
    pub message: String,
}

/// The kinds of [`Warning`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    /// Rotation other than -90/0/90: no rotation performed.
    InvalidRotation,
    /// Movement outside [-3, 3]: clamped.
    MovementClamped,
    /// A reset before the goal was entered in run 0, or in run 1: step consumed.
    ResetRejected,
}

/// What one step did, for the trace.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepEvent {
    /// A normal rotation and movement.
    Move,
    /// Run 0 ended; the robot is back at the start.
    ResetAccepted,
    /// The reset was not allowed; nothing moved.
    ResetRejected,
    /// Run 1 ended in the goal room: the match is finished.
    GoalReached,
}

/// The result of [`Game::apply`]: one step of the trace.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepReport {
    /// The run the step belonged to.
    pub run: u8,
    /// The counter `t` of the step.
    pub step: u32,
    /// The reading the bot was given.
    pub sensors: Sensors,
    /// The answer.
    pub action: Action,
    /// What happened.
    pub event: StepEvent,
    /// Position after the step.
    pub position: Position,
    /// Heading after the step.
    pub heading: Heading,
    /// Whether a wall stopped the movement short.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub blocked: bool,
    /// Warnings raised by this step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<Warning>,
}

/// The state of one match on one maze.
#[derive(Debug, Clone)]
pub struct Game {
    maze: Maze,
    config: GameConfig,
    t: u32,
    run: u8,
    position: Position,
    heading: Heading,
    /// Whether the robot has ended a step's movement in the goal room during run 0.
    hit_goal: bool,
    open_step: Option<Sensors>,
    run0_steps: Option<u32>,
    run1_steps: Option<u32>,
    end: Option<GameEnd>,
    warnings: Vec<Warning>,
}

impl Game {
    /// A new game at the start of run 0: cell (0,0), facing up, `t` = 0.
    pub fn new(maze: Maze, config: GameConfig) -> Game {
        Game {
            maze,
            config,
            t: 0,
            run: 0,
            position: Position::new(0, 0),
            heading: Heading::Up,
            hit_goal: false,
            open_step: None,
            run0_steps: None,
            run1_steps: None,
            end: None,
            warnings: Vec::new(),
        }
    }

    /// The maze being played.
    pub fn maze(&self) -> &Maze {
        &self.maze
    }

    /// The settings.
    pub fn config(&self) -> GameConfig {
        self.config
    }

    /// The step counter `t` (the number of steps begun).
    pub fn t(&self) -> u32 {
        self.t
    }

    /// The current run, 0 or 1.
    pub fn run(&self) -> u8 {
        self.run
    }

    /// The robot's cell.
    pub fn position(&self) -> Position {
        self.position
    }

    /// The robot's heading.
    pub fn heading(&self) -> Heading {
        self.heading
    }

    /// Whether the robot has been in the goal room during run 0.
    pub fn hit_goal(&self) -> bool {
        self.hit_goal
    }

    /// How the game ended, once it has.
    pub fn end(&self) -> Option<GameEnd> {
        self.end
    }

    /// Run-0 steps, once a reset has been accepted.
    pub fn run0_steps(&self) -> Option<u32> {
        self.run0_steps
    }

    /// Run-1 steps, once the game is finished.
    pub fn run1_steps(&self) -> Option<u32> {
        self.run1_steps
    }

    /// The score, once the game is finished.
    pub fn score(&self) -> Option<Score> {
        Some(Score {
            run0_steps: self.run0_steps?,
            run1_steps: self.run1_steps?,
        })
    }

    /// Every warning so far.
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The sensor reading at the robot's current cell and heading.
    pub fn sensors(&self) -> Sensors {
        self.heading
            .sensor_headings()
            .map(|h| self.maze.dist_to_wall(self.position, h))
    }

    /// Opens the next step: increments `t` and returns the reading to send, or `None`
    /// when the game is over (the budget is spent, or run 1 finished).
    ///
    /// # Panics
    /// If the previous step was opened but not [applied](Game::apply) (a caller bug).
    pub fn begin_step(&mut self) -> Option<Sense> {
        assert!(
            self.open_step.is_none(),
            "begin_step called twice without apply"
        );
        if self.end.is_some() {
            return None;
        }
        // RULES.md: t is incremented at the start of every step; when it would exceed
        // the budget the match ends ("step limit").
        if self.t >= self.config.max_steps {
            self.end = Some(GameEnd::StepLimit);
            return None;
        }
        self.t += 1;
        let sensors = self.sensors();
        self.open_step = Some(sensors);
        Some(Sense {
            run: self.run,
            step: self.t,
            sensors,
        })
    }

    /// Plays the bot's answer for the open step.
    ///
    /// # Panics
    /// If no step is open (call [`Game::begin_step`] first; a caller bug).
    pub fn apply(&mut self, action: Action) -> StepReport {
        let sensors = self
            .open_step
            .take()
            .expect("apply called without an open step");
        let (run, step) = (self.run, self.t);
        let mut warnings = Vec::new();
        let mut blocked = false;
        let event = match action {
            Action::Reset { .. } => {
                if self.run == 0 && self.hit_goal {
                    // An accepted reset ends run 0; run-0 time includes this step.
                    self.run0_steps = Some(self.t);
                    self.run = 1;
                    self.position = Position::new(0, 0);
                    self.heading = Heading::Up;
                    StepEvent::ResetAccepted
                } else {
                    let why = if self.run == 0 {
                        "reset rejected: the robot has not been in the goal room yet"
                    } else {
                        "reset rejected: a reset is only allowed in run 0"
                    };
                    warnings.push(self.warning(WarningKind::ResetRejected, why.to_string()));
                    StepEvent::ResetRejected
                }
            }
            Action::Move { rotation, movement } => {
                self.heading = match rotation {
                    -90 => self.heading.counter_clockwise(),
                    0 => self.heading,
                    90 => self.heading.clockwise(),
                    other => {
                        warnings.push(self.warning(
                            WarningKind::InvalidRotation,
                            format!("invalid rotation {other}: no rotation performed"),
                        ));
                        self.heading
                    }
                };
                let clamped = movement.clamp(-MAX_MOVEMENT, MAX_MOVEMENT);
                if clamped != movement {
                    warnings.push(self.warning(
                        WarningKind::MovementClamped,
                        format!("movement {movement} limited to {clamped}"),
                    ));
                }
                let (end, stopped) = slide(&self.maze, self.position, self.heading, clamped);
                self.position = end;
                blocked = stopped;
                if self.maze.is_goal(self.position) {
                    self.hit_goal = true;
                    if self.run == 1 {
                        let run0 = self.run0_steps.unwrap_or(0);
                        self.run1_steps = Some(self.t - run0);
                        self.end = Some(GameEnd::Finished);
                    }
                }
                if self.end == Some(GameEnd::Finished) {
                    StepEvent::GoalReached
                } else {
                    StepEvent::Move
                }
            }
        };
        self.warnings.extend(warnings.iter().cloned());
        StepReport {
            run,
            step,
            sensors,
            action,
            event,
            position: self.position,
            heading: self.heading,
            blocked,
            warnings,
        }
    }

    fn warning(&self, kind: WarningKind, message: String) -> Warning {
        Warning {
            step: self.t,
            run: self.run,
            kind,
            message,
        }
    }
}
