//! minimal_bot: the Rust starter kit's simple bot.
//!
//! Run 0: head for the goal room along the plan with the fewest steps, treating unknown
//! edges as open, re-planned after every reading; only proven-open edges are crossed, so
//! the robot always knows where it is. Reset as soon as a move ends in the goal room.
//! Run 1: the fewest-step plan over proven-open edges.

use mazebot::map::{Map, Mode, Pose};
use mazebot::protocol::{self, Answer, Bot, Start};

struct Minimal {
    map: Map,
    pose: Pose,
    hit_goal: bool,
}

impl Bot for Minimal {
    fn start(&mut self, start: &Start) {
        self.map = Map::new(start.maze_dim as usize);
        self.pose = Pose::START;
    }

    fn next_move(&mut self, sensors: [u32; 3], run: u8, _step: u32) -> Answer {
        self.map.sense(self.pose, sensors);
        let map = &self.map;
        let plan = if run == 0 {
            if self.hit_goal {
                self.pose = Pose::START;
                return Answer::Reset;
            }
            map.plan(self.pose, |x, y| map.is_goal(x, y), Mode::Optimistic, true)
        } else {
            map.plan(self.pose, |x, y| map.is_goal(x, y), Mode::Known, false)
        };
        let (rotation, movement) = plan
            .and_then(|p| p.actions.first().copied())
            .unwrap_or((90, 0));
        // Every move crosses proven-open edges only, so it lands where planned.
        if let Some((next, _)) = map.apply(self.pose, rotation, movement, Mode::Known) {
            self.pose = next;
        }
        if map.is_goal(self.pose.x, self.pose.y) {
            self.hit_goal = true;
        }
        Answer::Move { rotation, movement }
    }
}

fn main() {
    protocol::run(Minimal {
        map: Map::new(2),
        pose: Pose::START,
        hit_goal: false,
    });
}
