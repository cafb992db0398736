//! A wall map built from the sensor rays, and a planner in the referee's own units.
//!
//! Every edge between two cells is unknown, open or a wall. A sensor reading `d` in a
//! direction proves `d` open edges along that ray and a wall after them. The planner
//! searches over (cell, heading) with the moves the referee allows in one step: one
//! rotation (-90, 0, 90), then 0 to 3 cells forward or backward in a straight line. So a
//! plan's length is exactly the number of steps it takes.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Directions, clockwise: up (+y), right (+x), down, left.
pub const UP: usize = 0;
/// Right (+x).
pub const RIGHT: usize = 1;
/// Down (-y).
pub const DOWN: usize = 2;
/// Left (-x).
pub const LEFT: usize = 3;

/// One step, in the thousandths of a step that plan costs are counted in.
pub const STEP_MILLI: u64 = 1000;

const DX: [i32; 4] = [0, 1, 0, -1];
const DY: [i32; 4] = [1, 0, -1, 0];

/// What is known of one edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// Not seen yet.
    Unknown,
    /// Proven open.
    Open,
    /// Proven wall.
    Wall,
}

/// Where the robot is and where it faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pose {
    /// Column, 0 at the left.
    pub x: usize,
    /// Row, 0 at the bottom.
    pub y: usize,
    /// UP, RIGHT, DOWN or LEFT.
    pub heading: usize,
}

impl Pose {
    /// The start of every run: (0,0) facing up.
    pub const START: Pose = Pose {
        x: 0,
        y: 0,
        heading: UP,
    };
}

/// The map of a maze of side `n`.
#[derive(Debug, Clone)]
pub struct Map {
    /// Side.
    pub n: usize,

    edges: Vec<[Edge; 4]>,
}

/// How the planner treats unknown edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Only proven-open edges: a plan that is sure to work.
    Known,
    /// Unknown edges count as open: the best the maze could still allow.
    Optimistic,
}

/// A plan: the answers to give, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    /// Number of steps.
    pub steps: u32,
    /// Unknown edges it crosses.
    pub unknown: u32,
    /// (rotation, movement) per step.
    pub actions: Vec<(i32, i32)>,
    /// The pose after each step.
    pub poses: Vec<Pose>,
    /// Every unknown edge it crosses, as (x, y, direction) from the first cell.
    pub unknown_edges: Vec<(usize, usize, usize)>,
}

impl Plan {
    /// Every cell the plan goes through from `from`, in order, `from`'s cell first: for a
    /// debug drawing's `path`.
    pub fn cells(&self, from: Pose) -> Vec<(usize, usize)> {
        let mut cells = vec![(from.x, from.y)];
        let (mut x, mut y) = (from.x, from.y);
        for next in &self.poses {
            while (x, y) != (next.x, next.y) {
                if x != next.x {
                    x = if next.x > x { x + 1 } else { x - 1 };
                } else {
                    y = if next.y > y { y + 1 } else { y - 1 };
                }
                cells.push((x, y));
            }
        }
        cells
    }
}

impl Map {
    /// An empty map: only the perimeter is known (walls).
    pub fn new(n: usize) -> Map {
        let mut map = Map {
            n,

            edges: vec![[Edge::Unknown; 4]; n * n],
        };
        for x in 0..n {
            for y in 0..n {
                for d in 0..4 {
                    if map.neighbor(x, y, d).is_none() {
                        map.edges[x * n + y][d] = Edge::Wall;
                    }
                }
            }
        }
        map
    }

    /// The cell next to (x, y) in direction `d`, if on the grid.
    pub fn neighbor(&self, x: usize, y: usize, d: usize) -> Option<(usize, usize)> {
        let nx = x as i32 + DX[d];
        let ny = y as i32 + DY[d];
        if nx < 0 || ny < 0 || nx >= self.n as i32 || ny >= self.n as i32 {
            None
        } else {
            Some((nx as usize, ny as usize))
        }
    }

    /// What is known of the edge on side `d` of (x, y).
    pub fn edge(&self, x: usize, y: usize, d: usize) -> Edge {
        self.edges[x * self.n + y][d]
    }

    /// Records an edge (both sides).
    pub fn set(&mut self, x: usize, y: usize, d: usize, e: Edge) {
        self.edges[x * self.n + y][d] = e;
        if let Some((nx, ny)) = self.neighbor(x, y, d) {
            self.edges[nx * self.n + ny][(d + 2) % 4] = e;
        }
    }

    /// Records what the sensors saw from `pose`: `[left, front, right]` open cells.
    pub fn sense(&mut self, pose: Pose, sensors: [u32; 3]) {
        for (i, &dist) in sensors.iter().enumerate() {
            let d = (pose.heading + 3 + i) % 4;
            let (mut x, mut y) = (pose.x, pose.y);
            for _ in 0..dist {
                self.set(x, y, d, Edge::Open);
                match self.neighbor(x, y, d) {
                    Some((nx, ny)) => (x, y) = (nx, ny),
                    None => break,
                }
            }
            self.set(x, y, d, Edge::Wall);
        }
    }

    /// Whether (x, y) is in the goal room (the centre 2x2).
    pub fn is_goal(&self, x: usize, y: usize) -> bool {
        let (a, b) = (self.n / 2 - 1, self.n / 2);
        (x == a || x == b) && (y == a || y == b)
    }

    /// The poses from which the sensors would see edge `d` of (x, y): along the line
    /// through the edge, across proven-open edges, facing it or sideways to it.
    pub fn viewpoints(&self, x: usize, y: usize, d: usize) -> Vec<Pose> {
        let mut out = Vec::new();
        let sides = [
            (x, y, d),
            match self.neighbor(x, y, d) {
                Some((nx, ny)) => (nx, ny, (d + 2) % 4),
                None => (x, y, d),
            },
        ];
        for (sx, sy, look) in sides {
            let (mut cx, mut cy) = (sx, sy);
            loop {
                for heading in [look, (look + 1) % 4, (look + 3) % 4] {
                    out.push(Pose {
                        x: cx,
                        y: cy,
                        heading,
                    });
                }
                let back = (look + 2) % 4;
                if self.edge(cx, cy, back) != Edge::Open {
                    break;
                }
                match self.neighbor(cx, cy, back) {
                    Some((nx, ny)) => (cx, cy) = (nx, ny),
                    None => break,
                }
            }
        }
        out
    }

    /// The walls known inside the maze (the perimeter left out), each once, as
    /// `(x, y, UP)` or `(x, y, RIGHT)`: for a debug drawing's `walls`.
    pub fn known_walls(&self) -> Vec<(usize, usize, usize)> {
        let n = self.n;
        let mut out = Vec::new();
        for x in 0..n {
            for y in 0..n {
                for d in [UP, RIGHT] {
                    let inside = if d == UP { y + 1 < n } else { x + 1 < n };
                    if inside && self.edges[x * n + y][d] == Edge::Wall {
                        out.push((x, y, d));
                    }
                }
            }
        }
        out
    }

    /// For every cell (index `x * n + y`), the fewest steps from it, at its best heading,
    /// until a movement ends in a cell where `target` holds, crossing only edges allowed
    /// in `mode` (0 in a target cell; `None` where no plan exists). The distances a
    /// flood fill gives, in the referee's steps: for a debug drawing's `grid`.
    pub fn steps_to(&self, target: impl Fn(usize, usize) -> bool, mode: Mode) -> Vec<Option<u32>> {
        let n = self.n;
        // reach[c * 4 + d]: how many cells (up to 3) a straight move from cell c in
        // direction d may cross in `mode`.
        let mut reach = vec![0u8; n * n * 4];
        let allowed = |e: Edge| e == Edge::Open || (e == Edge::Unknown && mode == Mode::Optimistic);
        // Each direction from its far side, so the next cell's reach is known first.
        for d in 0..4 {
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = match d {
                        UP => (i, n - 1 - j),
                        RIGHT => (n - 1 - j, i),
                        DOWN => (i, j),
                        _ => (j, i),
                    };
                    let c = x * n + y;
                    if allowed(self.edges[c][d]) {
                        if let Some((nx, ny)) = self.neighbor(x, y, d) {
                            reach[c * 4 + d] = 1 + reach[(nx * n + ny) * 4 + d].min(2);
                        }
                    }
                }
            }
        }
        // The index step of one cell in each direction (cell index x * n + y).
        let offset = [1isize, n as isize, -1, -(n as isize)];
        let mut dist = vec![u32::MAX; n * n * 4];
        let mut queue = Vec::with_capacity(n * n * 4);
        for x in 0..n {
            for y in 0..n {
                if target(x, y) {
                    for h in 0..4 {
                        dist[(x * n + y) * 4 + h] = 0;
                        queue.push((x * n + y) * 4 + h);
                    }
                }
            }
        }
        // Backwards, breadth first: the poses that reach (cell, h) in one step are those
        // that turn to h (from h, h-90 or h+90) and then move straight 0..3 cells forward
        // or backward to arrive here, i.e. that stand up to `reach` cells away behind or
        // ahead of the cell.
        let mut head = 0;
        while head < queue.len() {
            let state = queue[head];
            head += 1;
            let (cell, h) = (state / 4, state % 4);
            let d = dist[state] + 1;
            let befores = [h, (h + 3) % 4, (h + 1) % 4];
            for back in [(h + 2) % 4, h] {
                for k in 0..=reach[cell * 4 + back] as isize {
                    if k == 0 && back == h {
                        continue; // movement 0 is counted once
                    }
                    let from = (cell as isize + k * offset[back]) as usize;
                    for &before in &befores {
                        let p = from * 4 + before;
                        if dist[p] == u32::MAX {
                            dist[p] = d;
                            queue.push(p);
                        }
                    }
                }
            }
        }
        (0..n * n)
            .map(|c| {
                let best = dist[c * 4..c * 4 + 4]
                    .iter()
                    .copied()
                    .min()
                    .unwrap_or(u32::MAX);
                (best != u32::MAX).then_some(best)
            })
            .collect()
    }

    /// Unknown edges in the whole map.
    pub fn unknown_count(&self) -> usize {
        self.edges
            .iter()
            .flatten()
            .filter(|e| **e == Edge::Unknown)
            .count()
            / 2
    }

    /// Where `(rotation, movement)` takes the robot from `pose`, if every edge crossed is
    /// allowed in `mode`; with the number of unknown edges crossed.
    pub fn apply(
        &self,
        pose: Pose,
        rotation: i32,
        movement: i32,
        mode: Mode,
    ) -> Option<(Pose, u32)> {
        let (heading, dir) = turn_and_direction(pose.heading, rotation, movement);
        let (mut x, mut y) = (pose.x, pose.y);
        let mut unknown = 0;
        for _ in 0..movement.unsigned_abs() {
            match self.edge(x, y, dir) {
                Edge::Wall => return None,
                Edge::Unknown if mode == Mode::Known => return None,
                Edge::Unknown => unknown += 1,
                Edge::Open => {}
            }
            (x, y) = self.neighbor(x, y, dir)?;
        }
        Some((Pose { x, y, heading }, unknown))
    }

    /// The fewest steps from `from` until a movement ends in a cell where `target` holds
    /// (ties: fewest unknown edges). With `safe_first`, the first step may only cross
    /// proven-open edges, so it can be taken without losing track of the robot.
    pub fn plan(
        &self,
        from: Pose,
        target: impl Fn(usize, usize) -> bool,
        mode: Mode,
        safe_first: bool,
    ) -> Option<Plan> {
        self.plan_weighted(from, |p| target(p.x, p.y), mode, safe_first, 1)
    }

    /// Like [`Map::plan`], but the target is a pose (cell and heading), and each unknown
    /// edge crossed costs `unknown_milli` thousandths of a step: with a weight above 0,
    /// plans through known ground are preferred to slightly shorter ones through unknown
    /// ground (they are likelier to be real).
    pub fn plan_weighted(
        &self,
        from: Pose,
        target: impl Fn(Pose) -> bool,
        mode: Mode,
        safe_first: bool,
        unknown_milli: u64,
    ) -> Option<Plan> {
        self.plan_costed(from, target, mode, safe_first, |_, _, unknown| {
            STEP_MILLI + u64::from(unknown) * unknown_milli
        })
    }

    /// The cheapest plan from `from` until a movement ends in a pose where `target`
    /// holds, where `step_cost(pose, (rotation, movement), unknown)` prices each step in
    /// thousandths of a step ([`STEP_MILLI`] for a plain step): the general form of
    /// [`Map::plan_weighted`], e.g. to break ties in a chosen order.
    pub fn plan_costed(
        &self,
        from: Pose,
        target: impl Fn(Pose) -> bool,
        mode: Mode,
        safe_first: bool,
        step_cost: impl Fn(Pose, (i32, i32), u32) -> u64,
    ) -> Option<Plan> {
        let n = self.n;
        let index = |p: Pose| (p.x * n + p.y) * 4 + p.heading;
        let mut best = vec![u64::MAX; n * n * 4];
        let mut prev: Vec<Option<(Pose, (i32, i32))>> = vec![None; n * n * 4];
        let mut heap = BinaryHeap::new();
        best[index(from)] = 0;
        heap.push(Reverse((0u64, from.x, from.y, from.heading, true)));
        while let Some(Reverse((cost, x, y, heading, first))) = heap.pop() {
            let pose = Pose { x, y, heading };
            if cost > best[index(pose)] {
                continue;
            }
            if !first && target(pose) {
                return Some(self.unwind(from, pose, &prev));
            }
            let step_mode = if first && safe_first {
                Mode::Known
            } else {
                mode
            };
            for rotation in [0, 90, -90] {
                for movement in [3i32, 2, 1, 0, -1, -2, -3] {
                    let Some((next, unknown)) = self.apply(pose, rotation, movement, step_mode)
                    else {
                        continue;
                    };
                    let c = cost + step_cost(pose, (rotation, movement), unknown);
                    // The target counts only at the end of a step, so the start pose is
                    // never a goal by itself: allow re-entering it.
                    if c < best[index(next)] || (next == from && first) {
                        if c < best[index(next)] {
                            best[index(next)] = c;
                        }
                        prev[index(next)] = Some((pose, (rotation, movement)));
                        heap.push(Reverse((c, next.x, next.y, next.heading, false)));
                    }
                }
            }
        }
        None
    }

    /// The map with two rules of micromouse mazes assumed, for plans that may guess:
    /// - the goal room has a single entrance: once an opening into the room is proven,
    ///   every unknown edge of the room's outline is taken as a wall;
    /// - every post but the centre one touches a wall: where three edges at a post are
    ///   proven open, the fourth is taken as a wall.
    ///
    /// Both hold in the three classic mazes; of the 521 contest mazes, 470 have one goal
    /// entrance and 456 no free-standing post. Keep the real map for anything that must
    /// be sure.
    pub fn with_maze_rules(&self) -> Map {
        let mut belief = self.clone();
        let n = self.n;
        let (a, b) = (n / 2 - 1, n / 2);
        let mut outline = Vec::new();
        for (x, y) in [(a, a), (a, b), (b, a), (b, b)] {
            for d in 0..4 {
                if let Some((nx, ny)) = self.neighbor(x, y, d) {
                    if !self.is_goal(nx, ny) {
                        outline.push((x, y, d));
                    }
                }
            }
        }
        if outline
            .iter()
            .any(|&(x, y, d)| self.edge(x, y, d) == Edge::Open)
        {
            for (x, y, d) in outline {
                if self.edge(x, y, d) == Edge::Unknown {
                    belief.set(x, y, d, Edge::Wall);
                }
            }
        }
        // The post at (px, py) is the corner shared by cells (px-1..=px, py-1..=py).
        for px in 1..n {
            for py in 1..n {
                if (px, py) == (n / 2, n / 2) {
                    continue;
                }
                let around = [
                    (px - 1, py, RIGHT),
                    (px - 1, py - 1, RIGHT),
                    (px - 1, py - 1, UP),
                    (px, py - 1, UP),
                ];
                let open = around
                    .iter()
                    .filter(|&&(x, y, d)| belief.edge(x, y, d) == Edge::Open)
                    .count();
                let mut unknown = around
                    .iter()
                    .filter(|&&(x, y, d)| belief.edge(x, y, d) == Edge::Unknown);
                if let (3, Some(&(x, y, d)), None) = (open, unknown.next(), unknown.next()) {
                    belief.set(x, y, d, Edge::Wall);
                }
            }
        }
        belief
    }

    fn unwind(&self, from: Pose, end: Pose, prev: &[Option<(Pose, (i32, i32))>]) -> Plan {
        let n = self.n;
        let index = |p: Pose| (p.x * n + p.y) * 4 + p.heading;
        let mut actions = Vec::new();
        let mut poses = Vec::new();
        let mut at = end;
        while let Some((p, action)) = prev[index(at)] {
            actions.push(action);
            poses.push(at);
            at = p;
            if at == from || actions.len() > n * n * 4 {
                break;
            }
        }
        actions.reverse();
        poses.reverse();
        let mut unknown_edges = Vec::new();
        let mut pose = from;
        for (&(rotation, movement), &next) in actions.iter().zip(&poses) {
            let (_, dir) = turn_and_direction(pose.heading, rotation, movement);
            let (mut x, mut y) = (pose.x, pose.y);
            for _ in 0..movement.unsigned_abs() {
                if self.edge(x, y, dir) == Edge::Unknown {
                    unknown_edges.push((x, y, dir));
                }
                if let Some(c) = self.neighbor(x, y, dir) {
                    (x, y) = c;
                }
            }
            pose = next;
        }
        Plan {
            steps: actions.len() as u32,
            unknown: unknown_edges.len() as u32,
            actions,
            poses,
            unknown_edges,
        }
    }
}

/// The heading after `rotation` (-90, 0 or 90; anything else: no turn) and the
/// direction `movement` then travels in (backwards when negative).
pub fn turn_and_direction(heading: usize, rotation: i32, movement: i32) -> (usize, usize) {
    let heading = match rotation {
        90 => (heading + 1) % 4,
        -90 => (heading + 3) % 4,
        _ => heading,
    };
    let dir = if movement >= 0 {
        heading
    } else {
        (heading + 2) % 4
    };
    (heading, dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensing_records_rays_and_walls() {
        let mut m = Map::new(4);
        m.sense(Pose::START, [0, 3, 1]);
        assert_eq!(m.edge(0, 0, UP), Edge::Open);
        assert_eq!(m.edge(0, 2, UP), Edge::Open);
        assert_eq!(m.edge(0, 3, UP), Edge::Wall);
        assert_eq!(m.edge(0, 0, RIGHT), Edge::Open);
        assert_eq!(m.edge(1, 0, RIGHT), Edge::Wall);
        assert_eq!(m.edge(1, 0, LEFT), Edge::Open);
    }

    #[test]
    fn plans_count_steps_like_the_referee() {
        // An open 4x4 map: from (0,0) up, one step reaches (1,1)? No: two steps
        // (a move and a turn-and-move), as one step is one straight line.
        let mut m = Map::new(4);
        for x in 0..4 {
            for y in 0..4 {
                for d in 0..4 {
                    if m.neighbor(x, y, d).is_some() {
                        m.set(x, y, d, Edge::Open);
                    }
                }
            }
        }
        let p = m
            .plan(Pose::START, |x, y| m.is_goal(x, y), Mode::Known, false)
            .unwrap();
        assert_eq!(p.steps, 2);
        let unknown = Map::new(4);
        assert!(unknown
            .plan(
                Pose::START,
                |x, y| unknown.is_goal(x, y),
                Mode::Known,
                false
            )
            .is_none());
        let o = unknown
            .plan(
                Pose::START,
                |x, y| unknown.is_goal(x, y),
                Mode::Optimistic,
                false,
            )
            .unwrap();
        assert_eq!((o.steps, o.unknown), (2, 2));
    }

    #[test]
    fn steps_to_agrees_with_the_planner() {
        // A pseudo-random 8x8 map with open, unknown and wall edges.
        let mut m = Map::new(8);
        let mut z = 12345u64;
        for x in 0..8 {
            for y in 0..8 {
                for d in [UP, RIGHT] {
                    if m.neighbor(x, y, d).is_some() {
                        z = z
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        let e = match (z >> 33) % 5 {
                            0 => Edge::Wall,
                            1 => Edge::Unknown,
                            _ => Edge::Open,
                        };
                        m.set(x, y, d, e);
                    }
                }
            }
        }
        for mode in [Mode::Known, Mode::Optimistic] {
            let steps = m.steps_to(|x, y| m.is_goal(x, y), mode);
            for x in 0..8 {
                for y in 0..8 {
                    let want = if m.is_goal(x, y) {
                        Some(0)
                    } else {
                        (0..4)
                            .filter_map(|heading| {
                                m.plan(Pose { x, y, heading }, |a, b| m.is_goal(a, b), mode, false)
                                    .map(|p| p.steps)
                            })
                            .min()
                    };
                    assert_eq!(steps[x * 8 + y], want, "({x}, {y}) {mode:?}");
                }
            }
        }
        assert_eq!(m.known_walls().len(), {
            let mut count = 0;
            for x in 0..8 {
                for y in 0..8 {
                    count += (0..4)
                        .filter(|&d| m.neighbor(x, y, d).is_some() && m.edge(x, y, d) == Edge::Wall)
                        .count();
                }
            }
            count / 2
        });
    }

    #[test]
    fn one_goal_entrance_closes_the_rest_of_the_outline() {
        let mut m = Map::new(4);
        // Goal room: (1,1), (1,2), (2,1), (2,2). Nothing known: nothing assumed.
        assert_eq!(m.with_maze_rules().edge(1, 1, LEFT), Edge::Unknown);
        m.set(1, 1, DOWN, Edge::Open);
        let b = m.with_maze_rules();
        assert_eq!(b.edge(1, 1, DOWN), Edge::Open);
        assert_eq!(b.edge(1, 1, LEFT), Edge::Wall);
        assert_eq!(b.edge(2, 2, UP), Edge::Wall);
        // Edges inside the room stay unknown; the real map is untouched.
        assert_eq!(b.edge(1, 1, UP), Edge::Unknown);
        assert_eq!(m.edge(1, 1, LEFT), Edge::Unknown);
    }

    #[test]
    fn a_post_with_three_open_edges_has_a_wall_on_the_fourth() {
        let mut m = Map::new(4);
        // The post at (1, 1): edges (0,1)-(1,1), (0,0)-(1,0), (0,0)-(0,1), (1,0)-(1,1).
        m.set(0, 1, RIGHT, Edge::Open);
        m.set(0, 0, RIGHT, Edge::Open);
        assert_eq!(m.with_maze_rules().edge(0, 0, UP), Edge::Unknown);
        m.set(0, 0, UP, Edge::Open);
        assert_eq!(m.with_maze_rules().edge(1, 0, UP), Edge::Wall);
        // The centre post may stand free: the goal room has no inner walls.
        let mut m = Map::new(4);
        m.set(1, 2, RIGHT, Edge::Open);
        m.set(1, 1, RIGHT, Edge::Open);
        m.set(1, 1, UP, Edge::Open);
        assert_eq!(m.with_maze_rules().edge(2, 1, UP), Edge::Unknown);
    }
}
