//! The referee: one match of two runs on one maze, step by step (RULES.md).
//!
//! The caller drives it: [`Game::begin_step`] opens a step (incrementing the shared
//! counter `t`) and gives the sensor reading; [`Game::apply`] takes the bot's answer and
//! returns what happened. Nothing here knows about processes or time.

use serde::{Deserialize, Serialize};

use super::geometry::{Heading, Position};
use super::maze::Maze;
use super::maze::slide;
use super::score::Score;

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
                self.heading = match self.heading.rotated(rotation) {
                    Some(h) => h,
                    None => {
                        warnings.push(self.warning(
                            WarningKind::InvalidRotation,
                            format!("invalid rotation {rotation}: no rotation performed"),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::maze::Maze;

    /// A 4x4 maze whose inner walls are all open (goal room: x, y in {1, 2}).
    fn open_maze(n: u32) -> Maze {
        let mut m = Maze::closed(n).unwrap();
        for x in 0..n {
            for y in 0..n {
                m.set_open(Position::new(x, y), Heading::Up, true);
                m.set_open(Position::new(x, y), Heading::Right, true);
            }
        }
        m
    }

    fn play(game: &mut Game, action: Action) -> StepReport {
        game.begin_step().expect("a step should be open");
        game.apply(action)
    }

    #[test]
    fn reset_before_goal_is_rejected_and_costs_a_step() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        let r = play(&mut g, Action::RESET);
        assert_eq!(r.event, StepEvent::ResetRejected);
        assert_eq!(g.t(), 1);
        assert_eq!(g.run(), 0);
        assert_eq!(g.position(), Position::new(0, 0));
        assert_eq!(r.warnings[0].kind, WarningKind::ResetRejected);
        assert_eq!(g.run0_steps(), None);
    }

    #[test]
    fn reset_step_counts_in_run0_time() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        play(&mut g, Action::turn_move(0, 1)); // (0,1)
        play(&mut g, Action::turn_move(90, 1)); // (1,1): goal room
        assert!(g.hit_goal());
        let r = play(&mut g, Action::RESET); // t = 3
        assert_eq!(r.event, StepEvent::ResetAccepted);
        assert_eq!(g.run0_steps(), Some(3));
        assert_eq!(
            (g.position(), g.heading()),
            (Position::new(0, 0), Heading::Up)
        );
        // Run 1: 2 steps to the goal room.
        let s = g.begin_step().unwrap();
        assert_eq!((s.run, s.step), (1, 4));
        g.apply(Action::turn_move(0, 1));
        let r = play(&mut g, Action::turn_move(90, 1));
        assert_eq!(r.event, StepEvent::GoalReached);
        assert_eq!(g.end(), Some(GameEnd::Finished));
        assert_eq!(g.run1_steps(), Some(2));
        // Score = 2 + 3/30 = 2.100
        assert_eq!(g.score().unwrap().to_string(), "2.100");
        assert_eq!(g.begin_step(), None);
    }

    #[test]
    fn a_reset_in_run1_is_rejected() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        play(&mut g, Action::turn_move(90, 1)); // (1,0)
        play(&mut g, Action::turn_move(-90, 1)); // (1,1)
        play(&mut g, Action::RESET);
        let r = play(&mut g, Action::RESET);
        assert_eq!(r.event, StepEvent::ResetRejected);
        assert_eq!(g.run(), 1);
        assert_eq!(g.t(), 4);
    }

    #[test]
    fn passing_through_the_goal_does_not_count() {
        // RULES.md: entering counts at the end of a step's movement.
        let mut m = open_maze(4);
        // Make column 1 a corridor: from (1,0) up to (1,3) passes (1,1) and (1,2).
        m.set_open(Position::new(0, 0), Heading::Up, true);
        let mut g = Game::new(m, GameConfig::default());
        play(&mut g, Action::turn_move(90, 1)); // (1,0), facing right
        play(&mut g, Action::turn_move(-90, 3)); // to (1,3) through the goal room
        assert_eq!(g.position(), Position::new(1, 3));
        assert!(!g.hit_goal());
        assert_eq!(play(&mut g, Action::RESET).event, StepEvent::ResetRejected);
    }

    #[test]
    fn a_move_into_a_wall_leaves_the_robot_in_place() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        let r = play(&mut g, Action::turn_move(-90, 1)); // facing left at (0,0)
        assert_eq!(r.position, Position::new(0, 0));
        assert_eq!(r.heading, Heading::Left);
        assert!(r.blocked);
        assert_eq!(g.t(), 1);
        // A move that is cut short stops at the wall.
        let r = play(&mut g, Action::turn_move(90, 3)); // up 3 from (0,0): (0,3)
        assert_eq!((r.position, r.blocked), (Position::new(0, 3), false));
        let r = play(&mut g, Action::turn_move(0, -3)); // back down 3: (0,0)
        assert_eq!((r.position, r.blocked), (Position::new(0, 0), false));
        let r = play(&mut g, Action::turn_move(0, -1));
        assert_eq!((r.position, r.blocked), (Position::new(0, 0), true));
    }

    #[test]
    fn the_budget_is_1000_steps_shared_by_both_runs() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        play(&mut g, Action::turn_move(90, 1));
        play(&mut g, Action::turn_move(-90, 1));
        play(&mut g, Action::RESET);
        let mut steps = 3;
        while g.begin_step().is_some() {
            g.apply(Action::turn_move(0, 0));
            steps += 1;
        }
        assert_eq!(steps, 1000);
        assert_eq!(g.t(), 1000);
        assert_eq!(g.end(), Some(GameEnd::StepLimit));
        assert_eq!(g.score(), None);
        assert_eq!(g.run0_steps(), Some(3));
        assert_eq!(g.run1_steps(), None);
    }

    #[test]
    fn invalid_rotation_means_no_rotation_with_a_warning() {
        let mut g = Game::new(open_maze(4), GameConfig::default());
        for rot in [45, 180, 270, -270, i64::MAX] {
            let r = play(&mut g, Action::turn_move(rot, 0));
            assert_eq!(r.heading, Heading::Up);
            assert_eq!(r.warnings.len(), 1);
            assert_eq!(r.warnings[0].kind, WarningKind::InvalidRotation);
        }
        assert_eq!(g.t(), 5);
        assert_eq!(g.warnings().len(), 5);
    }

    #[test]
    fn movement_is_clamped_to_three_with_a_warning() {
        let mut g = Game::new(open_maze(8), GameConfig::default());
        let r = play(&mut g, Action::turn_move(0, 7));
        assert_eq!(r.position, Position::new(0, 3));
        assert_eq!(r.warnings[0].kind, WarningKind::MovementClamped);
        let r = play(&mut g, Action::turn_move(0, i64::MIN));
        assert_eq!(r.position, Position::new(0, 0));
        assert_eq!(r.warnings[0].kind, WarningKind::MovementClamped);
        let r = play(&mut g, Action::turn_move(0, 3));
        assert!(r.warnings.is_empty());
    }

    #[test]
    fn on_a_2x2_maze_the_start_counts_only_after_a_step() {
        let m = Maze::new(2, vec![3, 6, 9, 12]).unwrap();
        let mut g = Game::new(m, GameConfig::default());
        assert!(!g.hit_goal());
        assert_eq!(play(&mut g, Action::RESET).event, StepEvent::ResetRejected);
        play(&mut g, Action::turn_move(0, 0));
        assert!(g.hit_goal());
        play(&mut g, Action::RESET);
        let r = play(&mut g, Action::turn_move(0, 0));
        assert_eq!(r.event, StepEvent::GoalReached);
        assert_eq!(
            g.score().unwrap(),
            Score {
                run0_steps: 3,
                run1_steps: 1
            }
        );
    }

    mod property {
        use super::*;
        use proptest::prelude::*;

        /// A random valid maze: closed, then each inner wall opened with probability 1/2.
        fn random_maze(n: u32, bits: &[bool]) -> Maze {
            let mut m = Maze::closed(n).unwrap();
            let mut it = bits.iter().cycle();
            for x in 0..n {
                for y in 0..n {
                    for side in [Heading::Up, Heading::Right] {
                        if *it.next().unwrap() {
                            m.set_open(Position::new(x, y), side, true);
                        }
                    }
                }
            }
            m
        }

        fn action() -> impl Strategy<Value = Action> {
            prop_oneof![
                6 => (prop_oneof![Just(-90i64), Just(0), Just(90), any::<i64>()], -5i64..=5)
                    .prop_map(|(r, m)| Action::turn_move(r, m)),
                1 => Just(Action::RESET),
            ]
        }

        proptest! {
            #[test]
            fn random_play_follows_the_rules(
                half in 1u32..=4,
                bits in proptest::collection::vec(any::<bool>(), 1..64),
                actions in proptest::collection::vec(action(), 0..1200),
            ) {
                let n = half * 2;
                let maze = random_maze(n, &bits);
                let mut g = Game::new(maze.clone(), GameConfig::default());
                // An independent model of the rules, kept by hand.
                let (mut pos, mut heading) = (Position::new(0, 0), Heading::Up);
                let (mut run, mut t, mut seen_goal, mut run0) = (0u8, 0u32, false, None);
                for action in actions {
                    let Some(sense) = g.begin_step() else {
                        prop_assert!(t == 1000 || g.end() == Some(GameEnd::Finished));
                        break;
                    };
                    t += 1;
                    prop_assert_eq!(sense.step, t);
                    prop_assert_eq!(sense.run, run);
                    let expect_sensors = heading.sensor_headings().map(|h| maze.dist_to_wall(pos, h));
                    prop_assert_eq!(sense.sensors, expect_sensors);
                    let r = g.apply(action);
                    match action {
                        Action::Reset { .. } => {
                            if run == 0 && seen_goal {
                                prop_assert_eq!(r.event, StepEvent::ResetAccepted);
                                run = 1;
                                run0 = Some(t);
                                pos = Position::new(0, 0);
                                heading = Heading::Up;
                            } else {
                                prop_assert_eq!(r.event, StepEvent::ResetRejected);
                            }
                        }
                        Action::Move { rotation, movement } => {
                            heading = match rotation {
                                90 => heading.clockwise(),
                                -90 => heading.counter_clockwise(),
                                _ => heading,
                            };
                            let dir = if movement < 0 { heading.reverse() } else { heading };
                            let want = movement.clamp(-3, 3).unsigned_abs();
                            // Walk cell by cell; every crossed side must be open.
                            let mut moved = 0;
                            while moved < want && maze.is_open(pos, dir) {
                                pos = pos.step(dir, n).expect("closed perimeter keeps us on the grid");
                                moved += 1;
                            }
                            prop_assert!(pos.x < n && pos.y < n);
                            prop_assert_eq!(r.position, pos);
                            prop_assert_eq!(r.heading, heading);
                            prop_assert_eq!(r.blocked, moved < want);
                            if maze.is_goal(pos) {
                                if run == 0 {
                                    seen_goal = true;
                                } else {
                                    prop_assert_eq!(r.event, StepEvent::GoalReached);
                                    let score = g.score().unwrap();
                                    let run0 = run0.unwrap();
                                    prop_assert_eq!(score.run0_steps, run0);
                                    prop_assert_eq!(score.run1_steps, t - run0);
                                    let exact = (t - run0) as f64 + run0 as f64 / 30.0;
                                    prop_assert!((score.value() - exact).abs() <= 0.0005);
                                    break;
                                }
                            }
                        }
                    }
                    prop_assert_eq!(g.t(), t);
                    prop_assert!(t <= 1000);
                }
            }
        }
    }
}
