#!/usr/bin/env node
'use strict';
/**
 * seed001_value_table.js: the strategy of seed report 001
 * (/work/shared/seeds/001_1c892acee0785893.txt): section 3.2 "System Workflow"
 * (update_map, find_goal_position, if_reach_goal, execute) and section 3.3
 * "Algorithms" (the value table of Udacity's "AI for robotics", find_best_spot_in_step_n,
 * find_path_to_goal, find_move_from_path with walking back along the record).
 * Section 3.4 reports 33.067 / 41.367 / 58.567 on test mazes 01 / 02 / 03.
 *
 * The report leaves much open. Its author's own code is public: a robot.py whose
 * update_value is the report's excerpt word for word, with a map.py, in three
 * versions. The behaviour below follows the version the report describes (best spot
 * within 3, 2, 1 cells; walking back along a record of steps; a lap of the goal
 * square), with the goal-square search of the earlier version. So built, the bot
 * reproduces the report exactly: runs of 362 + 21, 551 + 23 and 947 + 27 steps, i.e.
 * 33.067, 41.367 and 58.567. (The report's text says the path is built with
 * best_spot_in_step_1; that variant scores 27.867 / 46.567 / 51.867 instead, and
 * the later version's goal search 32.667 / 41.533 / 54.733, so neither was used.)
 *
 * What the bot does:
 * - Map (3.2.1): a (2n+1) x (2n+1) matrix with a 1 where a sensor saw a wall (at the
 *   end of each of the three rays, every step of run 0). Unknown counts as open.
 * - find_goal_position (3.2.2), run only when a new wall was seen: the 2x2 squares
 *   whose top-left cell (x, y) has n//3 <= x, y < 2*(n//3), x outer loop, y inner;
 *   the first with no wall known inside is the goal. The first guess is off-centre
 *   (top-left (4, 4) in a 12 maze) and moves as walls show up.
 * - Value table (3.3.1): 0 on the four goal cells, else the number of cells to them
 *   through edges with no known wall, 99 where that is 99 or more (the report's
 *   repeated sweeps; computed breadth-first, same table).
 * - Best spot within k cells (3.3.2): in each direction u, r, d, l, walk up to k
 *   cells while each cell's value is one less than the previous; the walk's end with
 *   the smallest value wins, ties to the later direction. As in the author's code,
 *   a walk that stops at a cell that does not descend reports that cell as its spot.
 * - find_path_to_goal (3.3.3): from (0, 0), repeated best spots within 3 cells until
 *   a goal cell, listing every cell passed.
 * - find_move_from_path (3.3.4): if the robot is not on the path, walk back: pop the
 *   last direction of the record (with up to two more equal ones) and retrace it in
 *   one move, turning toward the way back if it is to the side, backing up if it is
 *   behind; walking back is not recorded. On the path: the best spot within 3, then
 *   2, then 1 cells that is on the path; turn toward it and move that many cells,
 *   or back up without turning when it is behind. Failing that, one cell toward the
 *   next cell of the path.
 * - if_reach_goal (3.2.3): in the goal square, a clockwise lap of it (top-left cell:
 *   right, top-right: down, bottom-right: left, bottom-left: up), four moves, then
 *   reset. A new wall that moves the goal square cancels the lap.
 * - execute (3.2.4): the planner moves its robot cell by cell, stopping at walls it
 *   knows, and records the direction of every cell-step.
 * - Run 1: no mapping; the same path following on the final map.
 * - No randomness (the author's random walk has probability 0); the seed is unused.
 *
 * Guards added so that other mazes never crash the bot (none fires on the three test
 * mazes, whose results are the report's to the step):
 * - a refused reset (the square was not the goal room) restores the robot's state
 *   and rules that square out; the author's code would have gone out of step;
 * - no candidate square left, no descent in the value table from the start (e.g. a
 *   walled-in goal, or a start 99 or more cells away), an empty record or any
 *   exception: answer (0, 0), which is always safe, so the bot plays on to the
 *   step limit;
 * - a rotation of -1 (the author's "behind" marker) is sent as 0, as the original
 *   tester read it; moves off the grid count as blocked in the planner.
 * Like the author's code, the bot backs up over cells it has not always travelled,
 * so on other mazes it can bump an unseen wall and lose track of its position.
 */

const path = require('path');
const mazebot = require(path.join(__dirname, 'mazebot.js'));

const DIRS = ['u', 'r', 'd', 'l']; // the report's `adjs` order
// Heading -> the directions of the [left, front, right] sensors.
const DIR_SENSORS = { u: ['l', 'u', 'r'], r: ['u', 'r', 'd'], d: ['r', 'd', 'l'], l: ['d', 'l', 'u'] };
const DIR_MOVE = { u: [0, 1], r: [1, 0], d: [0, -1], l: [-1, 0] };
const DIR_REVERSE = { u: 'd', r: 'l', d: 'u', l: 'r' };
const COST = 1;
const MAX_STEP = 3;
const VALUE_INIT = 99; // the value table's initial value (the report's code)

const same = (a, b) => a[0] === b[0] && a[1] === b[1];
const contains = (list, p) => list.some((q) => same(q, p));

/**
 * The report's Map (section 3.2.1): a (2n+1) x (2n+1) matrix, 0 everywhere, 1 where a
 * wall has been seen. Cell (x, y) sits at column 2x+1, row 2n-1-2y (row 0 is the top);
 * the slots between cells hold the walls. Unknown counts as open.
 */
class WallMap {
  constructor(n) {
    this.n = n;
    this.dim = 2 * n + 1;
    this.cells = new Uint8Array(this.dim * this.dim);
  }

  at(col, row) {
    return this.cells[row * this.dim + col];
  }

  /** Map column and row of maze cell (x, y). */
  pos(x, y) {
    return [2 * x + 1, this.dim - 2 * y - 2];
  }

  /** A sensor saw `distance` open cells from `loc` toward `dir`: the wall slot after them. */
  update(loc, dir, distance) {
    const [c, r] = this.pos(loc[0], loc[1]);
    const [dx, dy] = DIR_MOVE[dir];
    const col = c + dx * (2 * distance + 1);
    const row = r - dy * (2 * distance + 1);
    if (col < 0 || row < 0 || col >= this.dim || row >= this.dim) return false;
    if (this.cells[row * this.dim + col] === 1) return false;
    this.cells[row * this.dim + col] = 1;
    return true;
  }

  /** No known wall between the cell and its neighbour toward `dir` (and still on the grid). */
  isValidMove(loc, dir) {
    const [dx, dy] = DIR_MOVE[dir];
    const nx = loc[0] + dx, ny = loc[1] + dy;
    if (nx < 0 || ny < 0 || nx >= this.n || ny >= this.n) return false; // (guard, see header)
    const [c, r] = this.pos(loc[0], loc[1]);
    return this.at(c + dx, r - dy) === 0;
  }

  /** No known wall between two adjacent cells. */
  isConnect(a, b) {
    const [c1, r1] = this.pos(a[0], a[1]);
    const [c2, r2] = this.pos(b[0], b[1]);
    return this.at((c1 + c2) / 2, (r1 + r2) / 2) === 0;
  }

  /** The 2x2 square whose top-left cell is (x, y) has no known wall inside. */
  isGoal(x, y) {
    const [c, r] = this.pos(x, y);
    for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) if (this.at(c + j, r + i) === 1) return false;
    return true;
  }
}

class ValueTableBot {
  start(info) {
    const n = (this.mazeDim = info.maze_dim);
    this.map = new WallMap(n);
    this.heading = 'u';
    this.location = [0, 0];
    this.goal = [[n - 1, n - 1]];
    this.goalChanged = false;
    this.finishing = false;
    this.finishCount = 4;
    this.values = Array.from({ length: n }, () => new Array(n).fill(VALUE_INIT));
    this.record = []; // the direction of every cell-step taken (walking back excluded)
    this.phase = 1; // the report's run numbering: 1 = exploration, 2 = timed run
    this.reverse = false;
    this.refused = []; // (guard) goal squares whose reset the server refused
    this.beforeReset = null;
  }

  inside(p) {
    return p[0] >= 0 && p[1] >= 0 && p[0] < this.mazeDim && p[1] < this.mazeDim;
  }

  value(p) {
    return this.values[p[0]][p[1]];
  }

  step(p, dir) {
    return [p[0] + DIR_MOVE[dir][0], p[1] + DIR_MOVE[dir][1]];
  }

  /** Rotation that faces `dir`, or -1 when it is behind the robot. */
  toRotation(dir) {
    const i = DIR_SENSORS[this.heading].indexOf(dir);
    return i < 0 ? -1 : [-90, 0, 90][i];
  }

  // --- update_goal: find_goal_position (section 3.2.2) ----------------------------
  updateGoal() {
    const n = this.mazeDim;
    const search = Math.floor(n / 3);
    for (let i = 0; i < search; i++) {
      for (let j = 0; j < search; j++) {
        const x = search + i, y = search + j;
        if (x < 0 || y < 1 || x + 1 >= n || y >= n) continue; // (guard: tiny mazes)
        if (this.refused.some((s) => s[0] === x && s[1] === y)) continue; // (guard)
        if (!this.map.isGoal(x, y)) continue;
        const square = [[x, y], [x + 1, y], [x + 1, y - 1], [x, y - 1]];
        if (x !== this.goal[0][0] || y !== this.goal[0][1]) {
          this.goalChanged = true;
          this.finishCount = 4;
          this.finishing = false;
        }
        return square;
      }
    }
    return null;
  }

  // --- update_map (section 3.2.1), then the value table ----------------------------
  updateMap(sensors) {
    let changed = false;
    const dirs = DIR_SENSORS[this.heading];
    for (let i = 0; i < 3; i++) if (this.map.update(this.location, dirs[i], sensors[i])) changed = true;
    if (changed) {
      const goal = this.updateGoal();
      if (goal === null) {
        this.noGoal = true; // (guard) every candidate square has a wall inside
      } else {
        this.noGoal = false;
        this.goal = goal;
        this.updateValue(this.goal);
      }
    }
    if (this.isReachGoal()) this.finishing = true;
  }

  isReachGoal() {
    if (!contains(this.goal, this.location)) return false;
    if (this.goalChanged) this.goalChanged = false;
    return true;
  }

  /**
   * update_value (section 3.3.1): goal cells 0, every other cell the number of
   * cells to the nearest goal cell through edges with no known wall, 99 where that
   * is 99 or more or there is no way. Breadth-first; the report's repeated sweeps
   * reach exactly this table.
   */
  updateValue(target) {
    const n = this.mazeDim;
    const values = Array.from({ length: n }, () => new Array(n).fill(VALUE_INIT));
    let frontier = target.filter((p) => this.inside(p));
    for (const p of frontier) values[p[0]][p[1]] = 0;
    for (let v = 1; v < VALUE_INIT && frontier.length; v++) {
      const next = [];
      for (const p of frontier) {
        for (const d of DIRS) {
          const q = this.step(p, d);
          if (!this.inside(q) || !this.map.isConnect(p, q) || values[q[0]][q[1]] <= v) continue;
          values[q[0]][q[1]] = v;
          next.push(q);
        }
      }
      frontier = next;
    }
    this.values = values;
  }

  // --- find_best_spot_in_step_n (section 3.3.2) ---------------------------------------
  /**
   * Walks up to `steps` cells toward `dir` while each cell's value is one less than
   * the previous one. Returns [cells walked, position]; when the walk ends at a cell
   * that does not descend, the position is that cell (one beyond the last cell
   * walked), as in the author's code.
   */
  longestStep(loc, dir, steps) {
    let util = this.value(loc);
    for (let count = 0; count < steps; count++) {
      const next = this.step(loc, dir);
      if (!this.inside(next) || !this.map.isConnect(loc, next)) return [count, loc];
      const util1 = this.value(next);
      if (util - COST < util1) return [count, next];
      util = util1;
      loc = next;
    }
    return [steps, loc];
  }

  /** The spot with the smallest value reachable in up to `steps` cells; ties: the later direction. */
  bestNeighbour(loc, steps) {
    let minCost = this.value(loc);
    let move = null;
    let best = loc;
    for (const d of DIRS) {
      const [k, pos] = this.longestStep(loc, d, steps);
      if (k > 0 && this.value(pos) <= minCost) {
        minCost = this.value(pos);
        move = [d, k];
        best = pos;
      }
    }
    return [move, best];
  }

  // --- find_path_to_goal (section 3.3.3) ------------------------------------------------
  /** Start to goal by repeated best spots; null when the table gives no way (guard). */
  findPath() {
    let p = [0, 0];
    const cells = [p];
    for (let guard = 0; !contains(this.goal, p); guard++) {
      const [move] = this.bestNeighbour(p, MAX_STEP);
      if (move === null || guard > this.mazeDim * this.mazeDim) return null;
      for (let i = 0; i < move[1]; i++) {
        p = this.step(p, move[0]);
        cells.push(p);
      }
    }
    return cells;
  }

  // --- find_move_from_path (section 3.3.4) ------------------------------------------------
  findNextMove(cells) {
    for (let i = 0; i < MAX_STEP; i++) {
      const [move, pos] = this.bestNeighbour(this.location, MAX_STEP - i);
      if (move !== null && contains(cells, pos)) {
        const rotation = this.toRotation(move[0]);
        if (rotation === -1) return [rotation, -move[1]];
        return [rotation, move[1]];
      }
    }
    const idx = cells.findIndex((c) => same(c, this.location));
    if (idx < 0 || idx + 1 >= cells.length) return null; // (guard)
    return this.command(this.location, cells[idx + 1]);
  }

  /** One cell toward an adjacent target: turn and go, or back up when it is behind. */
  command(from, to) {
    const d = DIRS.find((dir) => same(this.step(from, dir), to));
    if (d === undefined) return null; // (guard)
    const rotation = this.toRotation(d);
    return rotation === -1 ? [0, -1] : [rotation, 1];
  }

  /** Walking back: pop up to 3 equal steps from the record and undo them in one move. */
  reverseMove() {
    this.reverse = true;
    const previous = this.record.pop();
    let count = 1;
    for (let i = 0; i < 2; i++) {
      if (this.record.length && this.record[this.record.length - 1] === previous) {
        this.record.pop();
        count += 1;
      }
    }
    const rotation = this.toRotation(DIR_REVERSE[previous]);
    return rotation === -1 ? [0, -count] : [rotation, count];
  }

  policyWalk() {
    this.reverse = false;
    const cells = this.findPath();
    if (cells === null) return null; // (guard)
    if (!contains(cells, this.location)) {
      if (!this.record.length) return null; // (guard)
      return this.reverseMove();
    }
    return this.findNextMove(cells);
  }

  /** if_reach_goal (section 3.2.3): a lap of the goal square, then reset. */
  finishMoves() {
    if (this.finishCount > 0) {
      const pos = this.goal.findIndex((c) => same(c, this.location));
      if (pos < 0) return null; // (guard)
      this.finishCount -= 1;
      return this.command(this.location, this.step(this.location, ['r', 'd', 'l', 'u'][pos]));
    }
    return [0, 0];
  }

  // --- execute (section 3.2.4) ---------------------------------------------------------
  execute(rotation, movement) {
    const back = movement < 0;
    if (rotation === 90 || rotation === -90) this.heading = DIR_SENSORS[this.heading][rotation / 90 + 1];
    let dir = back ? DIR_REVERSE[this.heading] : this.heading;
    for (let i = 0; i < Math.abs(movement); i++) {
      if (this.map.isValidMove(this.location, dir)) {
        if (!this.reverse) this.record.push(dir);
        this.location = this.step(this.location, dir);
      }
    }
  }

  // --- the bot interface -----------------------------------------------------------------
  nextMove(sensors, run) {
    if (run === 0 && this.phase === 2 && this.beforeReset) {
      // (guard) the server refused the reset: this square is not the goal room.
      Object.assign(this, this.beforeReset);
      this.refused.push(this.goal[0]);
      this.beforeReset = null;
      console.log(`seed001: reset refused, square ${JSON.stringify(this.goal)} is not the goal room`);
      this.finishing = false;
      this.finishCount = 4;
      const goal = this.updateGoal();
      this.noGoal = goal === null;
      if (goal !== null) {
        this.goal = goal;
        this.updateValue(goal);
      }
    }
    if (run === 1) this.beforeReset = null;
    let move;
    try {
      move = this.plan(sensors);
    } catch (e) {
      console.log('seed001: internal error, standing still:', e && e.stack);
      move = null;
    }
    if (move === mazebot.RESET) return move;
    if (move === null) move = [0, 0]; // a safe move: nothing happens
    let [rotation, movement] = move;
    if (rotation !== 90 && rotation !== -90) rotation = 0;
    this.execute(rotation, movement);
    return { rotation, movement };
  }

  plan(sensors) {
    this.reverse = false;
    if (this.phase === 1) {
      this.updateMap(sensors);
      if (this.noGoal) return null;
      if (this.finishing) {
        const move = this.finishMoves();
        if (move === null) {
          this.finishing = false; // (guard) not in the square after all
          return this.policyWalk();
        }
        if (move[0] === 0 && move[1] === 0) {
          this.beforeReset = {
            phase: 1, heading: this.heading, location: this.location, record: this.record.slice(),
          };
          this.phase = 2;
          this.heading = 'u';
          this.location = [0, 0];
          this.record = [];
          return mazebot.RESET;
        }
        return move;
      }
      return this.policyWalk();
    }
    return this.policyWalk();
  }

  end(msg) {
    console.log('seed001:', JSON.stringify(msg));
  }
}

if (require.main === module) mazebot.run(new ValueTableBot());

module.exports = { ValueTableBot };
