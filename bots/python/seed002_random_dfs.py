#!/usr/bin/env python3
"""seed002_random_dfs: the randomized explorer + flood fill of seed report 002.

Source: /work/shared/seeds/002_bb41d7a828be9332.txt (Shashwata Mandal, "Capstone
Report: Plot and Navigate a Virtual Maze", August 19, 2017): section "Algorithms
and Techniques" (randomized depth-first exploration preferring unvisited cells,
val_grid, flood fill over 1-3-cell moves from the start, path_grid backtrack,
the goal cell with the smallest weight), "Methodology / Implementation" (the
code excerpts: possible moves from the sensors, +90 turn in a dead end,
cellValue, count_cell, makeFloodFillWeights / updateFurthur, actionGrid, the
run-1 movement code), "Refinement" (one-cell moves in the goal room, avoiding
dead or explored cells and loops) and "Results / Model Evaluation and
Validation" (forced reset at 950 steps; 10 runs: 39.09 / 52.06 / 56.55).

What the bot does
-----------------
* Mapping (cellValue): only the robot's own cell is mapped, from its three
  sensors (open when the reading is > 0) and the side it came in through.
* Run 0 (exploration), one cell per move: the possible moves are left, forward
  and right where the sensor reads > 0; if there is none (a dead end) the robot
  turns +90 without moving. Otherwise it picks at random among the moves that
  lead to an unvisited cell; if there is none, at random among the others,
  avoiding cells it knows to be dead ends (three walls) unless nothing else is
  possible.
* Reset: once the whole maze has been visited (every cell) - the report's
  "once the entire maze is reconstructed" - or, the goal having been reached,
  when the step counter reaches 950 (the report's forced reset). The reset is
  only sent once the goal room has been entered.
* Run 1: flood fill from the start over the visited cells: a cell's weight is
  the fewest moves of 1-3 cells in a straight line (through visited cells and
  sides known to be open) from the start; the goal cell with the smallest
  weight is chosen and the path is backtracked through path_grid; the robot
  makes one move per straight segment (rotation -90/0/+90 then up to 3 cells).

Choices where the report is vague (what the author most likely did)
-------------------------------------------------------------------
* Exploration moves are one cell long. The report says moves of up to 3 cells
  were tried in the first run and that inside the goal room moves were cut to
  one cell, but its mapping (cellValue) only records the cells the robot stops
  in and the flood fill only uses those, so single-cell moves are what makes
  "the entire maze reconstructed" possible.
* "Priority towards unvisited cells" and "avoiding multiple visits to dead or
  explored cells": random choice among the moves to unvisited cells, else among
  visited cells that are not dead ends (3 known walls), else any possible move.
* The report's actionGrid only looks at one goal cell (a loop bug:
  range(1)); the text says the goal cell with the smallest weight is chosen,
  which is what this bot does.
* The forced reset: at step >= 950 as soon as the goal has been reached (the
  report's "forced to reset at 950 steps for the first round"). If the goal has
  not been reached by then the robot keeps exploring and resets as soon as it
  enters the goal room.
* Randomness: random.Random(seed) with the start message's seed, so a match
  is reproducible.
* If the goal can never be reached the robot keeps exploring with safe moves
  until the step limit.

Additions (not in the report)
-----------------------------
* Goal seeking: if the goal room has not been entered by step 800, the robot
  stops exploring at random and heads for it (fewest cells, sides never seen
  counted as open, one cell a step; a side never sensed is looked at first
  with a +90 turn). Without it 2-16% of the matches on the classic mazes never
  reach the goal (the report's 10 runs a maze all did); with it every seed
  tried (1000 a maze) finishes, and runs that find the goal by step 800 are
  unchanged.
* The outer walls are known from the start.
"""

import os
import random
import sys
from collections import deque

sys.dont_write_bytecode = True  # leave no __pycache__ in the bot's folder
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mazebot  # noqa: E402
import mazemap  # noqa: E402
from mazemap import UP, DOWN, LEFT, RIGHT, DELTA, OPEN, WALL  # noqa: E402

FORCED_RESET_STEP = 950
SEEK_GOAL_STEP = 800  # not in the report: see "Additions" in the header


class RandomDfsBot:
    def start(self, maze_dim, seed, max_steps):
        n = self.n = maze_dim
        self.rng = random.Random(seed if seed is not None else 0)
        # val_grid: the sides of every visited cell (UNKNOWN until visited);
        # the outer walls are known from the start.
        self.edges = mazemap.new_edges(n)
        self.visited = [[False] * n for _ in range(n)]
        self.unique = 0
        self.goal = mazemap.goal_room(n)
        self.found_goal = False
        self.run = 0
        self.route = None
        self._home()

    def _home(self):
        self.x, self.y, self.heading = 0, 0, UP

    # --- cellValue() / count_cell() ----------------------------------------------
    def _cell_value(self, sensors):
        mazemap.sense_cell(self.edges, self.x, self.y, self.heading, sensors)

    def _count_cell(self):
        if not self.visited[self.x][self.y]:
            self.visited[self.x][self.y] = True
            self.unique += 1

    def _is_dead_end(self, x, y):
        return self.visited[x][y] and (x, y) not in self.goal and \
            sum(1 for s in self.edges[x][y] if s is WALL) >= 3

    # --- run 0 -------------------------------------------------------------------
    def _explore(self, sensors):
        possible = [(rel, (self.heading + rel) % 4)
                    for rel, dist in zip((-1, 0, 1), sensors) if dist > 0]
        if not possible:  # dead end
            return 90, 0
        unvisited, plain = [], []
        for rel, d in possible:
            x, y = self.x + DELTA[d][0], self.y + DELTA[d][1]
            if not self.visited[x][y]:
                unvisited.append(rel)
            elif not self._is_dead_end(x, y):
                plain.append(rel)
        choices = unvisited or plain or [rel for rel, _ in possible]
        rel = self.rng.choice(choices)
        return rel * 90, 1

    def _seek_goal(self):
        """Not in the report: head for the goal room (unknown sides count as open)."""
        return mazemap.seek_goal_move(self.edges, self.goal, self.x, self.y, self.heading)

    def _flood_fill(self):
        """Weights = fewest 1-3-cell straight moves from the start over visited cells."""
        start = (self.x, self.y)
        weight = {start: 0}
        path_grid = {start: None}
        queue = deque([start])
        while queue:
            cell = queue.popleft()
            for d in (DOWN, LEFT, UP, RIGHT):
                x, y = cell
                for _ in range(3):
                    if self.edges[x][y][d] is not OPEN:
                        break
                    x, y = x + DELTA[d][0], y + DELTA[d][1]
                    if not self.visited[x][y]:
                        break
                    if (x, y) not in weight:
                        weight[(x, y)] = weight[cell] + 1
                        path_grid[(x, y)] = cell
                        queue.append((x, y))
        reached = [c for c in sorted(self.goal) if c in weight]
        if not reached:
            return None
        target = min(reached, key=lambda c: weight[c])
        segments = []
        cell = target
        while path_grid[cell] is not None:
            prev = path_grid[cell]
            dx, dy = cell[0] - prev[0], cell[1] - prev[1]
            cells = abs(dx) + abs(dy)
            d = DELTA.index((dx // cells, dy // cells))
            segments.append((d, cells))
            cell = prev
        segments.reverse()
        return segments

    # --- the bot interface -----------------------------------------------------------
    def next_move(self, sensors, run, step):
        if run != self.run:  # the reset was accepted: back at the start
            self.run = run
            self._home()
        if run == 0:
            self._cell_value(sensors)
            self._count_cell()
            if self.found_goal and (self.unique >= self.n * self.n or step >= FORCED_RESET_STEP):
                return mazebot.RESET
            move = None
            if not self.found_goal and step >= SEEK_GOAL_STEP:
                move = self._seek_goal()
            if move is None:
                move = self._explore(sensors)
        else:
            if self.route is None:
                self.route = self._flood_fill() or []
            if self.route:
                move = mazemap.move_towards(self.heading, *self.route.pop(0))
            else:  # cannot happen after an accepted reset; stay safe anyway
                move = self._explore(sensors)
        self._apply(*move)
        if run == 0 and (self.x, self.y) in self.goal:
            self.found_goal = True
        return move

    def _apply(self, rotation, movement):
        """Dead reckoning; exact because moves only cross sides known to be open."""
        self.x, self.y, self.heading = mazemap.apply_move(
            self.x, self.y, self.heading, rotation, movement)

    def end(self, message):
        print("seed002_random_dfs: %s" % (message,))


if __name__ == "__main__":
    mazebot.run(RandomDfsBot())
