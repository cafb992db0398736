//! minimal_bot: the Rust starter kit's simple bot.
//!
//! Run 0: head for the goal room along the plan with the fewest steps, treating unknown
//! edges as open, re-planned after every reading; only proven-open edges are crossed, so
//! the robot always knows where it is. Reset as soon as a move ends in the goal room.
//! Run 1: the fewest-step plan over proven-open edges.
//!
//! Debug drawing (for the replay viewer): a line of text, the cells of the plan, and the
//! walls it knows whenever it found a new one. It changes nothing in the moves.

use mazebot::map::{Map, Mode, Pose};
use mazebot::protocol::{self, Answer, Bot, DebugDraw, Start};

struct Minimal {
    map: Map,
    pose: Pose,
    hit_goal: bool,
    /// The debug drawing of the last answer, sent by `debug`.
    drawing: Option<DebugDraw>,
    /// How many walls the drawings have shown (walls are sent only when they change).
    walls_drawn: usize,
}

impl Minimal {
    /// The debug drawing for a step: `text`, and the cells the plan goes through.
    fn draw(&mut self, text: String, cells: Vec<(usize, usize)>) {
        let mut d = DebugDraw::new();
        d.text(text).path(cells);
        let walls = self.map.known_walls();
        if walls.len() != self.walls_drawn {
            self.walls_drawn = walls.len();
            d.walls(walls);
        }
        self.drawing = Some(d);
    }
}

impl Bot for Minimal {
    fn start(&mut self, start: &Start) {
        self.map = Map::new(start.maze_dim as usize);
        self.pose = Pose::START;
        self.walls_drawn = 0;
    }

    fn next_move(&mut self, sensors: [u32; 3], run: u8, _step: u32) -> Answer {
        self.map.sense(self.pose, sensors);
        let map = &self.map;
        let plan = if run == 0 {
            if self.hit_goal {
                self.pose = Pose::START;
                self.draw("goal room reached: reset".to_string(), Vec::new());
                return Answer::Reset;
            }
            map.plan(self.pose, |x, y| map.is_goal(x, y), Mode::Optimistic, true)
        } else {
            map.plan(self.pose, |x, y| map.is_goal(x, y), Mode::Known, false)
        };
        let (rotation, movement) = plan
            .as_ref()
            .and_then(|p| p.actions.first().copied())
            .unwrap_or((90, 0));
        let cells = plan.as_ref().map_or_else(Vec::new, |p| p.cells(self.pose));
        let kind = if run == 0 { "optimistic" } else { "proven" };
        let steps = plan.as_ref().map_or(0, |p| p.steps);
        // Every move crosses proven-open edges only, so it lands where planned.
        if let Some((next, _)) = map.apply(self.pose, rotation, movement, Mode::Known) {
            self.pose = next;
        }
        if map.is_goal(self.pose.x, self.pose.y) {
            self.hit_goal = true;
        }
        self.draw(format!("run {run}: {kind} plan, {steps} steps"), cells);
        Answer::Move { rotation, movement }
    }

    fn debug(&mut self) -> Option<DebugDraw> {
        self.drawing.take()
    }
}

fn main() {
    protocol::run(Minimal {
        map: Map::new(2),
        pose: Pose::START,
        hit_goal: false,
        drawing: None,
        walls_drawn: 0,
    });
}
