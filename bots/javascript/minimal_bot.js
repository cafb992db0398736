#!/usr/bin/env node
'use strict';
/**
 * minimal_bot.js: a small, deterministic reference bot for mazearena.
 *
 * Strategy
 * - Wall map. Every edge between two cells is unknown, open or wall (the outer
 *   perimeter starts as wall). A sensor reading d in a direction reveals the
 *   edges along that ray: d open edges, then a wall.
 * - Run 0 (exploration). Flood fill from the goal room over every edge not known
 *   to be a wall (unknown counts as open): each cell gets an optimistic distance
 *   to the goal. The robot heads to a neighbour one closer (straight ahead first,
 *   then left, right, back) and moves up to 3 cells while the cells keep getting
 *   closer and the edges are known open, so it never hits a wall and always knows
 *   where it is. It re-plans every step and answers reset once a step has ended
 *   in the goal room.
 * - Run 1 (timed run). Breadth-first search over (cell, heading) using only
 *   edges known to be open: one search step is one game step (a rotation of
 *   -90/0/90, then a straight move of -3..3 cells).
 * - If the goal cannot be reached (a walled-in goal room), the robot turns on
 *   the spot until the step limit: a safe move that never crashes.
 *
 * It explores only until it first reaches the goal, so its run-1 path can be
 * longer than the optimum: a baseline, not a contender.
 *
 * Debug drawing: each answer carries a mazebot.Debug for the replay viewer (the
 * flood-fill distances as a grid, the way down them to the goal as a path, a line
 * of text, and the walls it knows whenever it learnt a new one). It changes nothing
 * in the moves.
 */

const path = require('path');
const mazebot = require(path.join(__dirname, 'mazebot.js'));

const UP = 0, RIGHT = 1, DOWN = 2, LEFT = 3;
const DX = [0, 1, 0, -1];
const DY = [1, 0, -1, 0];
const UNKNOWN = 0, OPEN = 1, WALL = 2;

class MinimalBot {
  start(info) {
    const n = (this.n = info.maze_dim);
    // edges[(x * n + y) * 4 + d]: UNKNOWN / OPEN / WALL for side d of cell (x, y).
    this.edges = new Uint8Array(n * n * 4);
    for (let i = 0; i < n; i++) {
      this.setEdge(i, 0, DOWN, WALL);
      this.setEdge(i, n - 1, UP, WALL);
      this.setEdge(0, i, LEFT, WALL);
      this.setEdge(n - 1, i, RIGHT, WALL);
    }
    this.goal = [];
    for (const x of [n / 2 - 1, n / 2]) for (const y of [n / 2 - 1, n / 2]) this.goal.push([x, y]);
    this.home();
    this.run = 0;
    this.enteredGoal = false;
    this.dist = null; // the last flood fill (run 0), for the debug drawing
    this.wallsSent = -1; // how many walls the last debug drawing listed
  }

  home() {
    this.x = 0;
    this.y = 0;
    this.heading = UP;
  }

  // --- map -------------------------------------------------------------------
  inside(x, y) {
    return x >= 0 && y >= 0 && x < this.n && y < this.n;
  }

  edge(x, y, d) {
    return this.edges[(x * this.n + y) * 4 + d];
  }

  setEdge(x, y, d, state) {
    this.edges[(x * this.n + y) * 4 + d] = state;
    const nx = x + DX[d], ny = y + DY[d];
    if (this.inside(nx, ny)) this.edges[(nx * this.n + ny) * 4 + ((d + 2) % 4)] = state;
  }

  isGoal(x, y) {
    const h = this.n / 2;
    return (x === h - 1 || x === h) && (y === h - 1 || y === h);
  }

  sense(sensors) {
    [-1, 0, 1].forEach((rel, i) => {
      const d = (this.heading + rel + 4) % 4;
      let x = this.x, y = this.y;
      for (let k = 0; k < sensors[i]; k++) {
        this.setEdge(x, y, d, OPEN);
        x += DX[d];
        y += DY[d];
      }
      if (this.inside(x, y)) this.setEdge(x, y, d, WALL);
    });
  }

  // --- run 0: flood fill from the goal, unknown = open -------------------------
  flood() {
    const n = this.n;
    const dist = new Int32Array(n * n).fill(-1);
    const queue = [];
    for (const [x, y] of this.goal) {
      dist[x * n + y] = 0;
      queue.push([x, y]);
    }
    for (let head = 0; head < queue.length; head++) {
      const [x, y] = queue[head];
      for (let d = 0; d < 4; d++) {
        if (this.edge(x, y, d) === WALL) continue;
        const nx = x + DX[d], ny = y + DY[d];
        if (!this.inside(nx, ny) || dist[nx * n + ny] >= 0) continue;
        dist[nx * n + ny] = dist[x * n + y] + 1;
        queue.push([nx, ny]);
      }
    }
    return dist;
  }

  exploreMove() {
    const n = this.n;
    const dist = (this.dist = this.flood());
    const here = dist[this.x * n + this.y];
    if (here < 0) return { rotation: 90, movement: 0, note: 'goal unreachable' };
    let rel = -1, d = -1;
    for (const r of [0, -1, 1, 2]) {
      const dd = (this.heading + r + 4) % 4;
      const nx = this.x + DX[dd], ny = this.y + DY[dd];
      if (this.edge(this.x, this.y, dd) !== WALL && this.inside(nx, ny) && dist[nx * n + ny] === here - 1) {
        rel = r;
        d = dd;
        break;
      }
    }
    if (d < 0) {
      // In the goal room without having entered it (only for n = 2): step out.
      for (const r of [0, -1, 1]) {
        const dd = (this.heading + r + 4) % 4;
        if (this.edge(this.x, this.y, dd) === OPEN) return { rotation: r * 90, movement: 1 };
      }
      return { rotation: 90, movement: 0 };
    }
    if (rel === 2 && this.edge(this.x, this.y, d) !== OPEN) return { rotation: 90, movement: 0 }; // look behind
    const rotation = rel === 2 ? 0 : rel * 90;
    const sign = rel === 2 ? -1 : 1;
    let cells = 0, x = this.x, y = this.y;
    while (cells < 3 && this.edge(x, y, d) === OPEN) {
      const nx = x + DX[d], ny = y + DY[d];
      if (cells > 0 && dist[nx * n + ny] !== dist[x * n + y] - 1) break;
      x = nx;
      y = ny;
      cells++;
      if (this.isGoal(x, y)) break;
    }
    return { rotation, movement: sign * cells };
  }

  // --- run 1: BFS over (cell, heading), unknown = wall -------------------------
  planMove() {
    const n = this.n;
    const key = (x, y, h) => (x * n + y) * 4 + h;
    const start = key(this.x, this.y, this.heading);
    const parent = new Int32Array(n * n * 4).fill(-2);
    const action = new Array(n * n * 4);
    parent[start] = -1;
    const queue = [start];
    for (let head = 0; head < queue.length; head++) {
      const s = queue[head];
      const h0 = s % 4, cell = (s - h0) / 4, x0 = Math.floor(cell / n), y0 = cell % n;
      for (const rotation of [0, -90, 90]) {
        const h = (h0 + rotation / 90 + 4) % 4;
        for (const movement of [3, 2, 1, -1, -2, -3, 0]) {
          const d = movement >= 0 ? h : (h + 2) % 4;
          let x = x0, y = y0, ok = true;
          for (let k = 0; k < Math.abs(movement); k++) {
            if (this.edge(x, y, d) !== OPEN) {
              ok = false;
              break;
            }
            x += DX[d];
            y += DY[d];
          }
          const next = key(x, y, h);
          if (!ok || parent[next] !== -2) continue;
          parent[next] = s;
          action[next] = { rotation, movement };
          if (this.isGoal(x, y)) {
            let t = next;
            while (parent[t] !== start) t = parent[t];
            return action[t];
          }
          queue.push(next);
        }
      }
    }
    return null;
  }

  // --- the bot interface -------------------------------------------------------
  nextMove(sensors, run) {
    if (run !== this.run) {
      this.run = run; // the reset was accepted: back at the start
      this.home();
    }
    this.sense(sensors);
    if (run === 0 && this.enteredGoal) {
      // clear the run-0 drawing: run 1 follows the known map only
      return mazebot.reset(this.debug('goal room entered: reset').grid([]).path([]));
    }
    let move = run === 1 ? this.planMove() : null;
    if (move === null) move = this.exploreMove();
    const text = run === 1 ? 'run 1: shortest known path' : 'run 0: flood fill, unknown = open';
    move.debug = this.debug(text, run === 0 ? this.dist : null);
    this.apply(move.rotation, move.movement);
    if (run === 0 && this.isGoal(this.x, this.y)) this.enteredGoal = true;
    return move;
  }

  // --- debug drawing (the replay viewer's layer; no effect on the moves) ---------
  debug(text, dist = null) {
    const n = this.n;
    const dbg = new mazebot.Debug().text(text);
    const walls = [];
    for (let x = 0; x < n; x++) {
      for (let y = 0; y < n; y++) {
        if (y + 1 < n && this.edge(x, y, UP) === WALL) walls.push([x, y, UP]);
        if (x + 1 < n && this.edge(x, y, RIGHT) === WALL) walls.push([x, y, RIGHT]);
      }
    }
    if (walls.length !== this.wallsSent) {
      // fields are sticky: send the walls only when they change
      this.wallsSent = walls.length;
      dbg.walls(walls);
    }
    if (dist !== null) {
      const at = (x, y) => (this.inside(x, y) ? dist[x * n + y] : -1);
      dbg.grid(Array.from({ length: n }, (_, x) => Array.from({ length: n }, (_, y) => (at(x, y) >= 0 ? at(x, y) : null))));
      // the way down the distances from the robot's cell to the goal room
      const path = [];
      let x = this.x, y = this.y;
      while (at(x, y) >= 0) {
        path.push([x, y]);
        if (at(x, y) === 0) break;
        const d = [0, 1, 2, 3].find((k) => this.edge(x, y, k) !== WALL && at(x + DX[k], y + DY[k]) === at(x, y) - 1);
        if (d === undefined) break;
        x += DX[d];
        y += DY[d];
      }
      dbg.path(path);
    }
    return dbg;
  }

  /** Dead reckoning; exact because moves only cross edges known to be open. */
  apply(rotation, movement) {
    this.heading = (this.heading + rotation / 90 + 4) % 4;
    const d = movement >= 0 ? this.heading : (this.heading + 2) % 4;
    this.x += DX[d] * Math.abs(movement);
    this.y += DY[d] * Math.abs(movement);
  }

  end(msg) {
    console.log('minimal_bot:', JSON.stringify(msg));
  }
}

if (require.main === module) mazebot.run(new MinimalBot());

module.exports = { MinimalBot };
