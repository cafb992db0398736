//! The champion's strategy: plays for the score, run-1 steps + run-0 steps / 30.
//!
//! The robot keeps a wall map from the sensor rays and plans in the referee's own unit,
//! the step (one rotation, then up to 3 cells straight). Unknown edges are seen three
//! ways: open (the optimistic plan, the best the maze could still allow), closed (the
//! proven plan, sure to work), and open at a price (the likely plan, where each unknown
//! edge costs a fraction of a step because it may be a wall). Plans that may guess
//! assume two rules of micromouse mazes ([`Map::with_maze_rules`]): the goal room has one
//! entrance, and every post but the centre one touches a wall.
//!
//! - Run 0, before the goal room: follow the optimistic fewest-step plan from where the
//!   robot stands, re-planned after every reading; ties go to plans through known ground.
//!   Moves only cross proven-open edges, so the robot always knows its cell.
//! - Run 0, after the goal room: the proven plan from the start takes K steps; the likely
//!   plan is expected to take L. If L < K, the nearest place from which the sensors will
//!   see an unknown edge of the likely plan costs c steps, i.e. c / 30 points: go and
//!   look while c / 30 < `gain_weight` * (K - L); otherwise reset. Reset at once when the
//!   proven plan is as short as the optimistic one (nothing left to gain).
//! - Run 1: the proven fewest-step plan.
//!
//! Deterministic: no randomness unless [`Params::tie_jitter`] is set (for studies).
//!
//! Debug drawing ([`Bot::debug`], for the replay viewer): a line on what it is doing,
//! the plan it follows as a path, its optimistic step counts to the goal room as a grid
//! (from the reset on, the proven ones run 1 follows), the cells it wants to look at in
//! orange, and
//! the walls it knows whenever it found a new one. Built only when asked for, after the
//! move is chosen: the moves are the same with or without it.

use crate::map::{Map, Mode, Plan, Pose, STEP_MILLI};
use crate::protocol::{Answer, Bot, DebugDraw, Start};

/// The champion's weights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// Before the goal: cost of an unknown edge, in thousandths of a step (a tie-break).
    pub unknown_milli: u64,
    /// After the goal: the expected cost of an unknown edge in the likely plan, in steps.
    pub likely_weight: f64,
    /// How much of the expected saving K - L a look is worth.
    pub gain_weight: f64,
    /// Before the goal: break ties between equally short plans at random instead, with
    /// this seed. Step counts never change (the jitter stays below 1/40 step per step).
    pub tie_jitter: Option<u64>,
}

impl Default for Params {
    /// The tuned weights (on generated mazes and a fifth of the contest mazes).
    fn default() -> Params {
        Params {
            unknown_milli: 1,
            likely_weight: 0.5,
            gain_weight: 1.0,
            tie_jitter: None,
        }
    }
}

/// Steps kept in hand at the end of run 0 beyond the proven run-1 plan.
const SAFETY_STEPS: u32 = 20;

/// Largest tie-break jitter per step, in thousandths of a step: 40 steps of it stay
/// below one step, longer than any optimistic plan in a 16x16 maze.
const JITTER_MILLI: u64 = 25;

/// What a step was about, for the debug drawing.
#[derive(Debug, Clone, PartialEq)]
enum Intent {
    /// Run 0: the optimistic plan toward the goal room.
    ToGoal,
    /// Run 0: the best run is proven; touch the goal room, then reset.
    Touch,
    /// Run 0, after the goal room: go where the sensors see an unknown edge of the
    /// likely plan.
    Look {
        known: u32,
        expected: f64,
        unknown_edges: Vec<(usize, usize, usize)>,
    },
    /// Run 0: reset with a proven run of this many steps.
    Reset(u32),
    /// Run 1: the proven plan.
    Run,
    /// No plan reaches the goal room: turn in place.
    Stuck,
}

/// The last step's decision, kept for [`Bot::debug`].
#[derive(Debug, Clone)]
struct Trace {
    run: u8,
    step: u32,
    /// Where the plan starts.
    from: Pose,
    intent: Intent,
    plan: Option<Plan>,
}

/// What the debug drawings sent so far showed (the viewer keeps each field until the
/// next one), so that big fields are sent only when they change.
#[derive(Debug, Clone, Default)]
struct Drawn {
    /// How many walls.
    walls: Option<usize>,
    /// The grid, and what it was computed from: the map's unknown edge count (the map
    /// only changes by learning an edge) and whether it was the proven one.
    grid: Option<Vec<Option<u32>>>,
    grid_from: Option<(usize, bool)>,
    /// The coloured cells.
    colors: Vec<(usize, usize)>,
}

/// The champion bot.
#[derive(Debug, Clone)]
pub struct Champion {
    params: Params,
    map: Map,
    /// `map` with the maze rules assumed, for plans that may guess.
    belief: Map,
    pose: Pose,
    max_steps: u32,
    /// The run-0 step at which the robot first entered the goal room.
    goal_entered_at: Option<u32>,
    /// Whether to log the goal and the reset on stderr.
    log: bool,
    /// Whether to send debug drawings.
    draw: bool,
    /// The last step's decision, for the debug drawing.
    trace: Option<Trace>,
    /// What the debug drawings showed so far.
    drawn: Drawn,
}

impl Champion {
    /// A champion with these weights.
    pub fn new(params: Params) -> Champion {
        Champion {
            params,
            map: Map::new(2),
            belief: Map::new(2),
            pose: Pose::START,
            max_steps: 1000,
            goal_entered_at: None,
            log: true,
            draw: true,
            trace: None,
            drawn: Drawn::default(),
        }
    }

    /// The same champion, without log lines on stderr.
    pub fn quiet(mut self) -> Champion {
        self.log = false;
        self
    }

    /// The same champion, without debug drawings ([`Bot::debug`] gives `None`).
    pub fn without_debug(mut self) -> Champion {
        self.draw = false;
        self
    }

    /// The proven fewest-step plan from the start to the goal room.
    pub fn proven_plan(&self) -> Option<Plan> {
        let map = &self.map;
        map.plan(Pose::START, |x, y| map.is_goal(x, y), Mode::Known, false)
    }

    fn goal_plan(&self, from: Pose, mode: Mode, unknown_milli: u64, safe: bool) -> Option<Plan> {
        let map = match mode {
            Mode::Known => &self.map,
            Mode::Optimistic => &self.belief,
        };
        map.plan_weighted(from, |p| map.is_goal(p.x, p.y), mode, safe, unknown_milli)
    }

    /// The optimistic plan from where the robot stands.
    fn toward_goal(&self, step: u32) -> Option<Plan> {
        let map = &self.belief;
        let w = self.params.unknown_milli;
        match self.params.tie_jitter {
            None => self.goal_plan(self.pose, Mode::Optimistic, w, true),
            Some(seed) => {
                let salt = mix(seed ^ (u64::from(step) << 32));
                map.plan_costed(
                    self.pose,
                    |p| map.is_goal(p.x, p.y),
                    Mode::Optimistic,
                    true,
                    |p, (rotation, movement), unknown| {
                        let key = ((p.x * map.n + p.y) * 4 + p.heading) as u64;
                        let action = ((rotation + 90) * 7 + movement + 3) as u64;
                        let jitter = mix(salt ^ (key << 16) ^ action) % JITTER_MILLI;
                        STEP_MILLI + u64::from(unknown) * w + jitter
                    },
                )
            }
        }
    }

    /// The next step of run 0, or `None` to reset now; with the plan it follows and why.
    fn explore_step(&self, step: u32) -> Option<(i32, i32, Intent, Option<Plan>)> {
        let first = |plan: Option<Plan>, intent: Intent| {
            let (rotation, movement) = plan.as_ref()?.actions.first().copied()?;
            Some((rotation, movement, intent, plan))
        };
        let Some(best) = self.goal_plan(Pose::START, Mode::Optimistic, 1, false) else {
            // The goal room cannot be reached: turn in place until the end.
            return Some((90, 0, Intent::Stuck, None));
        };
        let known = self.goal_plan(Pose::START, Mode::Known, 1, false);
        let optimal_known = known.as_ref().is_some_and(|k| k.steps <= best.steps);
        if self.goal_entered_at.is_none() {
            return if optimal_known {
                // The best run is proven: go and touch the goal room, then reset.
                first(
                    self.goal_plan(self.pose, Mode::Known, 1, false),
                    Intent::Touch,
                )
            } else {
                first(self.toward_goal(step), Intent::ToGoal)
            };
        }
        let known = known?;
        if optimal_known || step + known.steps + SAFETY_STEPS >= self.max_steps {
            return None;
        }
        let likely_weight = self.params.likely_weight;
        let likely_milli = (likely_weight * STEP_MILLI as f64) as u64;
        let likely = self.goal_plan(Pose::START, Mode::Optimistic, likely_milli, false)?;
        let expected = f64::from(likely.steps) + likely_weight * f64::from(likely.unknown);
        let gain = f64::from(known.steps) - expected;
        if gain <= 0.0 {
            return None;
        }
        let look = self.look(&likely)?;
        let cost = f64::from(look.steps) / 30.0;
        if cost < self.params.gain_weight * gain {
            let intent = Intent::Look {
                known: known.steps,
                expected,
                unknown_edges: likely.unknown_edges,
            };
            first(Some(look), intent)
        } else {
            None
        }
    }

    /// A plan to the nearest pose from which the sensors will see an unknown edge of
    /// `plan`: along the edge's line across proven-open edges, facing it or sideways.
    fn look(&self, plan: &Plan) -> Option<Plan> {
        let map = &self.map;
        let n = map.n;
        let index = |p: Pose| (p.x * n + p.y) * 4 + p.heading;
        let mut targets = vec![false; n * n * 4];
        for &(x, y, d) in &plan.unknown_edges {
            for p in map.viewpoints(x, y, d) {
                targets[index(p)] = true;
            }
        }
        map.plan_weighted(
            self.pose,
            |p| targets[index(p)],
            Mode::Optimistic,
            true,
            self.params.unknown_milli,
        )
    }
}

impl Bot for Champion {
    fn start(&mut self, start: &Start) {
        self.map = Map::new(start.maze_dim as usize);
        self.belief = self.map.clone();
        self.pose = Pose::START;
        self.max_steps = start.max_steps;
        self.goal_entered_at = None;
        self.trace = None;
        self.drawn = Drawn::default();
    }

    fn next_move(&mut self, sensors: [u32; 3], run: u8, step: u32) -> Answer {
        self.map.sense(self.pose, sensors);
        self.belief = self.map.with_maze_rules();
        let from = self.pose;
        let (action, intent, plan) = if run == 0 {
            match self.explore_step(step) {
                Some((rotation, movement, intent, plan)) => {
                    (Some((rotation, movement)), intent, plan)
                }
                None if self.goal_entered_at.is_some() => {
                    let proven = self.proven_plan();
                    let known = proven.as_ref().map_or(0, |p| p.steps);
                    if self.log {
                        eprintln!(
                            "champion: reset at step {step} with a proven run of {known} steps"
                        );
                    }
                    self.pose = Pose::START;
                    self.trace = Some(Trace {
                        run,
                        step,
                        from: Pose::START,
                        intent: Intent::Reset(known),
                        plan: proven,
                    });
                    return Answer::Reset;
                }
                None => (None, Intent::Stuck, None),
            }
        } else {
            let plan = self.goal_plan(self.pose, Mode::Known, 1, false);
            let action = plan.as_ref().and_then(|p| p.actions.first().copied());
            (action, Intent::Run, plan)
        };
        self.trace = Some(Trace {
            run,
            step,
            from,
            intent: if action.is_some() {
                intent
            } else {
                Intent::Stuck
            },
            plan: plan.filter(|_| action.is_some()),
        });
        // No plan: the goal room cannot be reached; turn in place until the end.
        let (rotation, movement) = action.unwrap_or((90, 0));
        if let Some((next, _)) = self.map.apply(self.pose, rotation, movement, Mode::Known) {
            self.pose = next;
        }
        if run == 0 && self.goal_entered_at.is_none() && self.map.is_goal(self.pose.x, self.pose.y)
        {
            self.goal_entered_at = Some(step);
            if self.log {
                eprintln!("champion: goal room entered at step {step}");
            }
        }
        Answer::Move { rotation, movement }
    }

    fn debug(&mut self) -> Option<DebugDraw> {
        if !self.draw {
            return None;
        }
        let trace = self.trace.as_ref()?;
        let n = self.map.n;
        let mut d = DebugDraw::new();
        let steps = trace.plan.as_ref().map_or(0, |p| p.steps);
        let text = match &trace.intent {
            Intent::ToGoal => format!(
                "run 0, step {}: optimistic plan to the goal room, {steps} steps ({} unknown edges)",
                trace.step,
                trace.plan.as_ref().map_or(0, |p| p.unknown)
            ),
            Intent::Touch => format!(
                "run 0, step {}: best run proven; to the goal room ({steps} steps), then reset",
                trace.step
            ),
            Intent::Look {
                known, expected, ..
            } => format!(
                "run 0, step {}: proven run {known} steps, likely {expected:.1}: going to look ({steps} step{} away)",
                trace.step,
                if steps == 1 { "" } else { "s" }
            ),
            Intent::Reset(known) => format!(
                "run 0, step {}: reset; run 1 will take {known} steps",
                trace.step
            ),
            Intent::Run => format!("run 1, step {}: proven plan, {steps} steps left", trace.step),
            Intent::Stuck => format!("step {}: no way to the goal room; turning", trace.step),
        };
        d.text(text);
        d.path(
            trace
                .plan
                .as_ref()
                .map_or_else(Vec::new, |p| p.cells(trace.from)),
        );
        // Cells on both sides of the unknown edges a look is for, in orange. Every field
        // is sent only when it changes: the viewer keeps showing the last one.
        let mut colors = Vec::new();
        if let Intent::Look { unknown_edges, .. } = &trace.intent {
            for &(x, y, dir) in unknown_edges {
                colors.push((x, y));
                colors.extend(self.map.neighbor(x, y, dir));
            }
            colors.sort_unstable();
            colors.dedup();
        }
        if colors != self.drawn.colors {
            d.no_colors();
            for &(x, y) in &colors {
                d.color(x, y, "#f80");
            }
            self.drawn.colors = colors;
        }
        let walls = self.map.known_walls();
        if self.drawn.walls != Some(walls.len()) {
            self.drawn.walls = Some(walls.len());
            d.walls(walls);
        }
        // Run 0: the optimistic step counts to the goal room (maze rules assumed); from
        // the reset on, the proven ones that run 1 follows. Recomputed only when the map
        // has changed (the belief map is made from it).
        let proven = trace.run == 1 || matches!(trace.intent, Intent::Reset(_));
        let from = (self.map.unknown_count(), proven);
        if self.drawn.grid_from != Some(from) {
            self.drawn.grid_from = Some(from);
            let map = if proven { &self.map } else { &self.belief };
            let mode = if proven {
                Mode::Known
            } else {
                Mode::Optimistic
            };
            let grid = map.steps_to(|x, y| map.is_goal(x, y), mode);
            if self.drawn.grid.as_ref() != Some(&grid) {
                d.grid((0..n).map(|x| grid[x * n..(x + 1) * n].iter().copied()));
                self.drawn.grid = Some(grid);
            }
        }
        Some(d)
    }
}

/// SplitMix64's output function: a well-mixed hash of `z`.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{Edge, RIGHT, UP};

    fn champion(n: u32) -> Champion {
        let mut c = Champion::new(Params::default()).quiet();
        c.start(&Start {
            maze_dim: n,
            max_steps: 1000,
            seed: 0,
            move_timeout_ms: 1000,
        });
        c
    }

    #[test]
    fn first_moves_cross_only_proven_edges() {
        let mut c = champion(4);
        // Walls left and right, two open cells ahead: only up is proven.
        match c.next_move([0, 2, 0], 0, 1) {
            Answer::Move { rotation, movement } => {
                assert_eq!(rotation, 0);
                assert!((1..=2).contains(&movement), "{movement}");
            }
            Answer::Reset => panic!("reset before the goal room"),
        }
    }

    #[test]
    fn resets_once_the_proven_run_is_the_best_possible() {
        let mut c = champion(4);
        for x in 0..4 {
            for y in 0..4 {
                for d in 0..4 {
                    if c.map.neighbor(x, y, d).is_some() {
                        c.map.set(x, y, d, Edge::Wall);
                    }
                }
            }
        }
        // Fully known: one way, up one cell, then right into the goal room at (1, 1).
        c.map.set(0, 0, UP, Edge::Open);
        c.map.set(0, 1, RIGHT, Edge::Open);
        c.pose = Pose {
            x: 1,
            y: 1,
            heading: RIGHT,
        };
        c.goal_entered_at = Some(2);
        assert_eq!(c.next_move([0, 0, 0], 0, 3), Answer::Reset);
        // Run 1 follows the proven plan.
        let up = Answer::Move {
            rotation: 0,
            movement: 1,
        };
        assert_eq!(c.next_move([0, 1, 0], 1, 4), up);
        let right = Answer::Move {
            rotation: 90,
            movement: 1,
        };
        assert_eq!(c.next_move([0, 0, 1], 1, 5), right);
    }
}
