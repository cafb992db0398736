#!/usr/bin/env python3
"""A flood-fill mouse written for the mms micromouse simulator.

It speaks mms's text commands (one a line on stdout, the answer read from stdin), so it
runs unchanged in mms and in mazearena (`protocol = "mms"`). It explores towards the
centre, flooding the maze with distances and treating unknown walls as open; comes back
to the start the same way, learning more walls; then races the shortest path it knows,
several cells at a time on straight stretches. It logs to stderr and paints the cells it
has visited.
"""
import sys
from collections import deque

NORTH, EAST, SOUTH, WEST = 0, 1, 2, 3
STEP = [(0, 1), (1, 0), (0, -1), (-1, 0)]


def ask(command):
    sys.stdout.write(command + "\n")
    sys.stdout.flush()
    answer = sys.stdin.readline()
    if not answer:
        sys.exit(0)  # the simulator is done with us
    return answer.strip()


def tell(command):
    sys.stdout.write(command + "\n")
    sys.stdout.flush()


def log(text):
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


class Mouse:
    def __init__(self):
        self.width = int(ask("mazeWidth"))
        self.height = int(ask("mazeHeight"))
        self.x, self.y, self.heading = 0, 0, NORTH
        # walls[(x, y, d)] is True (wall) or False (open); missing: unknown
        self.walls = {}
        for i in range(self.width):
            self.set_wall(i, 0, SOUTH, True)
            self.set_wall(i, self.height - 1, NORTH, True)
        for j in range(self.height):
            self.set_wall(0, j, WEST, True)
            self.set_wall(self.width - 1, j, EAST, True)
        cx, cy = self.width // 2, self.height // 2
        self.goal = {(cx - 1, cy - 1), (cx - 1, cy), (cx, cy - 1), (cx, cy)}

    def set_wall(self, x, y, d, wall):
        self.walls[(x, y, d)] = wall
        nx, ny = x + STEP[d][0], y + STEP[d][1]
        if 0 <= nx < self.width and 0 <= ny < self.height:
            self.walls[(nx, ny, (d + 2) % 4)] = wall

    def sense(self):
        for rel, command in ((3, "wallLeft"), (0, "wallFront"), (1, "wallRight")):
            d = (self.heading + rel) % 4
            self.set_wall(self.x, self.y, d, ask(command) == "true")
        tell("setColor %d %d G" % (self.x, self.y))

    def flood(self, targets, unknown_open):
        dist = {cell: 0 for cell in targets}
        queue = deque(targets)
        while queue:
            x, y = queue.popleft()
            for d in range(4):
                wall = self.walls.get((x, y, d))
                if wall or (wall is None and not unknown_open):
                    continue
                nx, ny = x + STEP[d][0], y + STEP[d][1]
                if 0 <= nx < self.width and 0 <= ny < self.height and (nx, ny) not in dist:
                    dist[(nx, ny)] = dist[(x, y)] + 1
                    queue.append((nx, ny))
        return dist

    def passable(self, x, y, d, unknown_open):
        wall = self.walls.get((x, y, d))
        return wall is False or (wall is None and unknown_open)

    def best_direction(self, dist, unknown_open):
        best = None
        for rel in (0, 3, 1, 2):  # straight first, then left, right, back
            d = (self.heading + rel) % 4
            if not self.passable(self.x, self.y, d, unknown_open):
                continue
            nx, ny = self.x + STEP[d][0], self.y + STEP[d][1]
            here = dist.get((nx, ny))
            if here is not None and (best is None or here < best[0]):
                best = (here, d)
        return best[1]

    def face(self, d):
        turn = (d - self.heading) % 4
        if turn == 1:
            ask("turnRight")
        elif turn == 3:
            ask("turnLeft")
        elif turn == 2:
            ask("turnRight")
            ask("turnRight")
        self.heading = d

    def forward(self, cells):
        answer = ask("moveForward %d" % cells if cells > 1 else "moveForward")
        if answer != "ack":
            log("crashed at (%d, %d)" % (self.x, self.y))
            sys.exit(1)
        self.x += STEP[self.heading][0] * cells
        self.y += STEP[self.heading][1] * cells

    def walk_to(self, targets):
        """Explores one cell at a time until a target cell is reached."""
        while (self.x, self.y) not in targets:
            self.sense()
            dist = self.flood(targets, unknown_open=True)
            self.face(self.best_direction(dist, unknown_open=True))
            self.forward(1)

    def race(self):
        """The shortest path through known open walls, straight stretches at once."""
        dist = self.flood(self.goal, unknown_open=False)
        while (self.x, self.y) not in self.goal:
            d = self.best_direction(dist, unknown_open=False)
            self.face(d)
            cells = 0
            x, y = self.x, self.y
            while (x, y) not in self.goal and self.passable(x, y, d, False):
                nx, ny = x + STEP[d][0], y + STEP[d][1]
                if dist.get((nx, ny), 10**9) != dist[(x, y)] - 1:
                    break
                x, y = nx, ny
                cells += 1
            self.forward(max(cells, 1))


def main():
    mouse = Mouse()
    log("maze %dx%d" % (mouse.width, mouse.height))
    mouse.walk_to(mouse.goal)
    log("reached the goal at (%d, %d)" % (mouse.x, mouse.y))
    mouse.walk_to({(0, 0)})
    log("back at the start: racing")
    mouse.race()
    log("done")


if __name__ == "__main__":
    main()
