#!/usr/bin/env python3
"""simple_bot: a small, deterministic reference bot for mazearena.

Strategy
--------
* Wall map. Every edge between two cells is unknown, open or wall (the outer
  perimeter starts as wall). Each sensor reading d in a direction reveals the
  edges along that ray: d open edges, then a wall.
* Run 0 (exploration). Flood fill from the goal room over every edge not known
  to be a wall (unknown counts as open), so each cell gets an optimistic
  distance to the goal. Each step the bot heads to a neighbour one closer,
  preferring straight ahead, then left, right, back, and moves up to 3 cells
  while the cells keep getting closer and the edges are known open (so the
  robot never hits a wall and always knows where it is). It re-plans every
  step. When a step has ended in the goal room it answers reset.
* Run 1 (timed run). A breadth-first search over (cell, heading) using only
  edges known to be open (unknown = wall): one step is one rotation (-90, 0,
  90) followed by a straight move of -3..3 cells, exactly the game's move. The
  bot follows the shortest such plan (re-planned each step; it never changes
  because the map is fixed by then).

It explores only until it first reaches the goal, so its run-1 path can be
longer than the optimum; it is a baseline, not a contender.

Debug drawing: each answer carries a ``mazebot.Debug`` for the replay viewer
(the flood-fill distances as a grid, the way down them to the goal as a path,
a line of text, and the walls it knows whenever it learnt a new one). It
changes nothing in the moves.
"""

import os
import sys
from collections import deque

sys.dont_write_bytecode = True  # leave no __pycache__ in the bot's folder
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mazebot  # noqa: E402

UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3
DELTA = ((0, 1), (1, 0), (0, -1), (-1, 0))
UNKNOWN, OPEN, WALL = None, True, False


class SimpleBot:
    def start(self, maze_dim, seed, max_steps):
        n = self.n = maze_dim
        # edges[x][y][d]: UNKNOWN / OPEN / WALL for the side d of cell (x, y).
        self.edges = [[[UNKNOWN] * 4 for _ in range(n)] for _ in range(n)]
        for i in range(n):
            self._set(i, 0, DOWN, WALL)
            self._set(i, n - 1, UP, WALL)
            self._set(0, i, LEFT, WALL)
            self._set(n - 1, i, RIGHT, WALL)
        g = (n // 2 - 1, n // 2)
        self.goal = {(x, y) for x in g for y in g}
        self._home()
        self.run = 0
        self.entered_goal = False  # a step's movement has ended in the goal room (run 0)
        self.dist = None  # the last flood fill (run 0), for the debug drawing
        self.walls_sent = -1  # how many walls the last debug drawing listed
        self.grid_sent = False  # whether the drawing holds the distances of run 0

    def _home(self):
        self.x, self.y, self.heading = 0, 0, UP

    # --- map -------------------------------------------------------------
    def _inside(self, x, y):
        return 0 <= x < self.n and 0 <= y < self.n

    def _set(self, x, y, d, state):
        self.edges[x][y][d] = state
        dx, dy = DELTA[d]
        if self._inside(x + dx, y + dy):
            self.edges[x + dx][y + dy][(d + 2) % 4] = state

    def _sense(self, sensors):
        for rel, dist in zip((-1, 0, 1), sensors):
            d = (self.heading + rel) % 4
            x, y = self.x, self.y
            for _ in range(dist):
                self._set(x, y, d, OPEN)
                x, y = x + DELTA[d][0], y + DELTA[d][1]
            self._set(x, y, d, WALL)

    # --- run 0: flood fill, unknown = open ----------------------------------
    def _flood(self):
        dist = {c: 0 for c in self.goal}
        queue = deque(sorted(self.goal))
        while queue:
            x, y = queue.popleft()
            for d in range(4):
                if self.edges[x][y][d] is WALL:
                    continue
                nxt = (x + DELTA[d][0], y + DELTA[d][1])
                if nxt not in dist:
                    dist[nxt] = dist[(x, y)] + 1
                    queue.append(nxt)
        return dist

    def _explore_move(self):
        dist = self.dist = self._flood()
        if (self.x, self.y) not in dist:
            return 90, 0  # the goal room cannot be reached: turn in place until the end
        here = dist[(self.x, self.y)]
        for rel in (0, -1, 1, 2):  # straight, left, right, back
            d = (self.heading + rel) % 4
            nxt = (self.x + DELTA[d][0], self.y + DELTA[d][1])
            if self.edges[self.x][self.y][d] is not WALL and dist.get(nxt) == here - 1:
                break
        else:  # in the goal room without having entered it (only for n = 2)
            d = next(d for d in range(4) if self.edges[self.x][self.y][d] is OPEN)
            rel = (d - self.heading) % 4
        if rel == 2 and self.edges[self.x][self.y][d] is not OPEN:
            return 90, 0  # the edge behind is unsensed: turn to look at it
        rotation = {0: 0, 1: 90, 2: 0, 3: -90}[rel % 4]
        sign = -1 if rel == 2 else 1
        cells, x, y = 0, self.x, self.y
        while cells < 3 and self.edges[x][y][d] is OPEN:
            nx, ny = x + DELTA[d][0], y + DELTA[d][1]
            if cells > 0 and dist.get((nx, ny)) != dist[(x, y)] - 1:
                break
            x, y, cells = nx, ny, cells + 1
            if (x, y) in self.goal:
                break
        return rotation, sign * cells

    # --- run 1: BFS over (cell, heading), unknown = wall ---------------------
    def _plan_move(self):
        start = (self.x, self.y, self.heading)
        parent = {start: None}
        queue = deque([start])
        while queue:
            state = queue.popleft()
            x0, y0, h0 = state
            for rotation in (0, -90, 90):
                h = (h0 + rotation // 90) % 4
                for movement in (3, 2, 1, -1, -2, -3, 0):
                    d = h if movement >= 0 else (h + 2) % 4
                    x, y, ok = x0, y0, True
                    for _ in range(abs(movement)):
                        if self.edges[x][y][d] is not OPEN:
                            ok = False
                            break
                        x, y = x + DELTA[d][0], y + DELTA[d][1]
                    nxt = (x, y, h)
                    if not ok or nxt in parent:
                        continue
                    parent[nxt] = (state, (rotation, movement))
                    if (x, y) in self.goal:
                        # Walk back to the first action of the plan.
                        while parent[nxt][0] != start:
                            nxt = parent[nxt][0]
                        return parent[nxt][1]
                    queue.append(nxt)
        return None

    # --- the bot interface --------------------------------------------------
    def next_move(self, sensors, run, step):
        if run != self.run:  # the reset was accepted: back at the start
            self.run = run
            self._home()
        self._sense(sensors)
        if run == 0 and self.entered_goal:
            # clear the run-0 drawing: run 1 follows the known map only
            self.grid_sent = False
            return mazebot.reset(debug=self._debug("goal room entered: reset").grid([]).path([]))
        move = self._plan_move() if run == 1 else None
        if move is None:
            move = self._explore_move()
        text = "run 1: shortest known path" if run == 1 else "run 0: flood fill, unknown = open"
        debug = self._debug(text, self.dist if run == 0 else None)
        self._apply(*move)
        if run == 0 and (self.x, self.y) in self.goal:
            self.entered_goal = True
        return mazebot.move(move[0], move[1], debug=debug)

    # --- debug drawing (the replay viewer's layer; no effect on the moves) ----
    def _debug(self, text, dist=None):
        debug = mazebot.Debug().text(text)
        walls = [(x, y, d) for x in range(self.n) for y in range(self.n) for d in (UP, RIGHT)
                 if self.edges[x][y][d] is WALL
                 and self._inside(x + DELTA[d][0], y + DELTA[d][1])]
        changed = len(walls) != self.walls_sent
        if changed:  # fields are sticky: send the walls when they change
            self.walls_sent = len(walls)
            debug.walls(walls)
        if dist is not None:
            # the distances follow the known walls: sent again only when they change, so a
            # match's drawing stays well inside the server's 64 KiB
            if changed or not self.grid_sent:
                self.grid_sent = True
                debug.grid([[dist.get((x, y)) for y in range(self.n)] for x in range(self.n)])
            # the way down the distances from the robot's cell to the goal room
            path, (x, y) = [], (self.x, self.y)
            while (x, y) in dist:
                path.append((x, y))
                if dist[(x, y)] == 0:
                    break
                x, y = next(((x + DELTA[d][0], y + DELTA[d][1]) for d in range(4)
                             if self.edges[x][y][d] is not WALL
                             and dist.get((x + DELTA[d][0], y + DELTA[d][1])) == dist[(x, y)] - 1),
                            (None, None))
            debug.path(path)
        return debug

    def _apply(self, rotation, movement):
        """Dead reckoning; exact because moves only cross edges known to be open."""
        self.heading = (self.heading + rotation // 90) % 4
        d = self.heading if movement >= 0 else (self.heading + 2) % 4
        self.x += DELTA[d][0] * abs(movement)
        self.y += DELTA[d][1] * abs(movement)

    def end(self, message):
        print("simple_bot: %s" % (message,))


if __name__ == "__main__":
    mazebot.run(SimpleBot())
