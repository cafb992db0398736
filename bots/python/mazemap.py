"""mazemap: maze bookkeeping shared by the Python reference bots.

Plain Python 3, no dependencies. A bot imports it from its own folder, the
same way it imports ``mazebot``::

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import mazemap

Conventions
-----------
* Cells are ``(x, y)`` with ``(0, 0)`` the start cell in the lower left corner;
  ``x`` grows to the right, ``y`` upwards.
* Directions (absolute headings) are ``UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3``
  (clockwise); ``DELTA[d]`` is the ``(dx, dy)`` of one cell in direction ``d``
  and ``(d + 2) % 4`` is the opposite direction.
* The wall map ``edges[x][y][d]`` holds ``UNKNOWN`` (None), ``OPEN`` (True) or
  ``WALL`` (False) for the side ``d`` of cell ``(x, y)``. The two cells that
  share an edge always hold the same value for it (``set_edge`` writes both).
  The maze size ``n`` is ``len(edges)``.
* Moves are the game's ``(rotation, movement)``: rotation -90, 0 or 90
  degrees (clockwise positive), then ``movement`` cells (-3..3, negative =
  backward) along the new heading.

Everything here is strategy-neutral; each bot keeps its own planner.
"""

from collections import deque

__all__ = [
    "UP", "RIGHT", "DOWN", "LEFT", "DELTA", "UNKNOWN", "OPEN", "WALL",
    "inside", "goal_room", "new_edges", "set_edge", "sense_cell",
    "apply_move", "move_towards", "seek_goal_move",
]

UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3
DELTA = ((0, 1), (1, 0), (0, -1), (-1, 0))
UNKNOWN, OPEN, WALL = None, True, False


def inside(n, x, y):
    """True if ``(x, y)`` is a cell of an ``n`` x ``n`` maze."""
    return 0 <= x < n and 0 <= y < n


def goal_room(n):
    """The set of the four centre cells of an ``n`` x ``n`` maze."""
    g = (n // 2 - 1, n // 2)
    return {(x, y) for x in g for y in g}


def new_edges(n):
    """A fresh wall map: every edge ``UNKNOWN`` except the outer walls (``WALL``)."""
    edges = [[[UNKNOWN] * 4 for _ in range(n)] for _ in range(n)]
    for i in range(n):
        set_edge(edges, i, 0, DOWN, WALL)
        set_edge(edges, i, n - 1, UP, WALL)
        set_edge(edges, 0, i, LEFT, WALL)
        set_edge(edges, n - 1, i, RIGHT, WALL)
    return edges


def set_edge(edges, x, y, d, state):
    """Set side ``d`` of cell ``(x, y)`` and the same edge of the neighbour, if any."""
    edges[x][y][d] = state
    nx, ny = x + DELTA[d][0], y + DELTA[d][1]
    if inside(len(edges), nx, ny):
        edges[nx][ny][(d + 2) % 4] = state


def sense_cell(edges, x, y, heading, sensors):
    """Map only the robot's own cell from ``sensors`` = [left, front, right]:
    a side is ``OPEN`` when its reading is > 0, else ``WALL``."""
    for rel, dist in zip((-1, 0, 1), sensors):
        set_edge(edges, x, y, (heading + rel) % 4, OPEN if dist > 0 else WALL)


def apply_move(x, y, heading, rotation, movement):
    """Dead reckoning: the ``(x, y, heading)`` after the move ``(rotation, movement)``.

    Exact as long as the move only crosses edges known to be open.
    """
    heading = (heading + rotation // 90) % 4
    d = heading if movement >= 0 else (heading + 2) % 4
    x += DELTA[d][0] * abs(movement)
    y += DELTA[d][1] * abs(movement)
    return x, y, heading


def move_towards(heading, d, cells):
    """The move that goes ``cells`` cells in absolute direction ``d``.

    Ahead: no rotation; to the right / left: rotate +90 / -90 first; behind:
    move backward without rotating.
    """
    rel = (d - heading) % 4
    if rel == 2:
        return 0, -cells
    return {0: 0, 1: 90, 3: -90}[rel], cells


def goal_distances(edges, goal):
    """Optimistic flood fill from the goal room: ``{cell: cells to the goal}``
    over every edge not known to be a wall (``UNKNOWN`` counts as open)."""
    n = len(edges)
    dist = {c: 0 for c in goal}
    queue = deque(sorted(goal))
    while queue:
        x, y = queue.popleft()
        for d in range(4):
            if edges[x][y][d] is WALL:
                continue
            nxt = (x + DELTA[d][0], y + DELTA[d][1])
            if inside(n, *nxt) and nxt not in dist:
                dist[nxt] = dist[(x, y)] + 1
                queue.append(nxt)
    return dist


def seek_goal_move(edges, goal, x, y, heading):
    """One cell towards the goal room along ``goal_distances`` (fewest cells,
    unknown sides counted as open), or None if the goal cannot be reached.

    Among forward, left, right and back (ties in that order) it picks the
    neighbour closest to the goal. If that side was never sensed it answers
    ``(90, 0)`` (turn and look); a cell behind is reached by a backward move.
    """
    dist = goal_distances(edges, goal)
    if (x, y) not in dist:
        return None  # the goal cannot be reached: keep exploring
    best = None
    for rel in (0, -1, 1, 2):  # forward, left, right, back
        d = (heading + rel) % 4
        nxt = (x + DELTA[d][0], y + DELTA[d][1])
        if edges[x][y][d] is not WALL and nxt in dist \
                and (best is None or dist[nxt] < best[0]):
            best = (dist[nxt], rel, d)
    if best is None:
        return None  # walled in
    _, rel, d = best
    if edges[x][y][d] is UNKNOWN:
        return 90, 0  # the side behind was never sensed: turn and look
    return (0, -1) if rel == 2 else (rel * 90, 1)
