#!/usr/bin/env python
"""Play an original-task robot.py the way the task's own tester.py did: in one process.

usage: tester_loop.py ROBOT_PY MAZE_FILE [--trace FILE]

The robot module is imported from its path, ``Robot(maze_dim)`` is built, and a plain
Python loop referees both runs by ../shared/design/RULES.md (as src/engine/game.rs
does): at every step the counter t goes up (the match ends when it would pass 1000),
the sensors [left, front, right] are computed, ``robot.next_move(sensors)`` answers,
then the rotation is applied (-90, 0 or 90; anything else: no rotation) and the
movement (clamped to [-3, 3]) one cell at a time until a wall stops it.
``('Reset', 'Reset')`` ends run 0 once a step of run 0 has ended in the goal room
(run-0 time = t, the reset step included); any other reset only costs its step.
Run 1 ends when a movement ends in the goal room. Score = run1 + run0 / 30, rounded
half up to three decimals (src/engine/score.rs).

As under bots/python/udacity_adapter.py with mazearena's default ``--seed 0``:
``random`` (and ``numpy.random`` when importable) is seeded with 0 before the import,
the robot's folder goes first on sys.path, no bytecode is written next to it, answers
are read as the adapter sends them (integral floats and bools as integers; any other
value ends the match as a protocol error, as the referee would), and whatever the robot
prints goes to stderr. The robot sees ``sys.argv == [ROBOT_PY, MAZE_FILE]``, as under
``tester.py MAZE_FILE``.

Prints one JSON line on stdout: status, run0_steps, run1_steps, total_steps, score
(null unless finished), loop_ms (wall time of Robot(maze_dim) and both runs) and
load_ms (reading the maze, seeding and importing the robot). ``--trace FILE`` also
writes every step (run, step, sensors, action, position, heading) as a JSON list,
in the shape of a mazearena replay's trace.

Exit status: 0 when the match was refereed (whatever the robot did), 1 when the robot
raised (status "crashed", traceback on stderr), 2 for bad arguments or a bad maze.
Runs under Python 3 and 2.7.
"""
from __future__ import print_function

import json
import numbers
import os
import sys
import time
import traceback

# The robot is loaded and seeded the way the adapter does it, so that both play it alike.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bots", "python"))
from udacity_adapter import is_reset, load_robot_class, seed_randomness  # noqa: E402

try:
    clock = time.perf_counter  # Python 3
except AttributeError:
    clock = time.time  # Python 2.7

MAX_STEPS = 1000
MAX_MOVEMENT = 3
RUN0_DIVISOR = 30
MAX_FILE_BYTES = 1024 * 1024
HEADINGS = ["up", "right", "down", "left"]  # index: clockwise from up
BITS = [1, 2, 4, 8]  # open side bits of a cell: up, right, down, left
DELTA = [(0, 1), (1, 0), (0, -1), (-1, 0)]


class MazeError(Exception):
    pass


def read_maze(path):
    """The numeric maze format, parsed as src/engine/mazefile/numeric.rs does.

    Returns (dim, open) where open[x][y] is cell (x, y)'s open-side bits.
    """
    with open(path, "rb") as f:
        data = f.read(MAX_FILE_BYTES + 1)
    if len(data) > MAX_FILE_BYTES:
        raise MazeError("the file is over the 1 MiB limit")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise MazeError("the file is not valid UTF-8 text")
    if not text:
        raise MazeError("line 1: the file is empty")
    if text.lstrip()[:1] in ("o", "+"):
        raise MazeError("an ASCII (mazefiles) maze: this loop reads the numeric format only")
    if text.endswith("\n"):
        text = text[:-1]
    lines = text.split("\n")
    for i, line in enumerate(lines):
        if "\r" in line:
            raise MazeError("line %d: carriage return found (LF line endings only)" % (i + 1))
    if not lines[0] or any(c not in "0123456789" for c in lines[0]):
        raise MazeError("line 1: the first line must be the maze side n (digits only)")
    dim = int(lines[0])
    if dim < 2 or dim % 2:
        raise MazeError("line 1: the maze side must be an even number >= 2, got %d" % dim)
    if len(lines) != dim + 1:
        raise MazeError("expected %d rows of cells after the dimension, found %d"
                        % (dim, len(lines) - 1))
    cells = []
    for x in range(dim):
        fields = lines[x + 1].split(",")
        if len(fields) != dim:
            raise MazeError("line %d: expected %d comma-separated values, found %d"
                            % (x + 2, dim, len(fields)))
        row = []
        for field in fields:
            if not field or any(c not in "0123456789" for c in field):
                raise MazeError("line %d: %r is not a plain decimal number" % (x + 2, field))
            value = int(field)
            if value > 15:
                raise MazeError("line %d: value %s is out of range 0..15" % (x + 2, field))
            row.append(value)
        cells.append(row)
    for x in range(dim):
        for y in range(dim):
            for d in range(4):
                nx, ny = x + DELTA[d][0], y + DELTA[d][1]
                is_open = cells[x][y] & BITS[d] != 0
                if not (0 <= nx < dim and 0 <= ny < dim):
                    if is_open:
                        raise MazeError("cell (%d,%d) is open %s, off the grid"
                                        % (x, y, HEADINGS[d]))
                elif is_open != (cells[nx][ny] & BITS[(d + 2) % 4] != 0):
                    raise MazeError("inconsistent wall between cells (%d,%d) and (%d,%d)"
                                    % (x, y, nx, ny))
    return dim, cells


class ProtocolError(Exception):
    pass


def integer(value, what):
    """An answer value as the adapter sends it and the referee accepts it, or ProtocolError."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        try:
            as_float = float(value)
        except (TypeError, ValueError, OverflowError):
            as_float = None
        if as_float is not None and as_float.is_integer():
            return int(as_float)
    raise ProtocolError("%s %r is not an integer" % (what, value))


def play(robot_class, dim, cells, trace):
    """Referee both runs; returns the result fields (without the timings)."""
    goal = (dim // 2 - 1, dim // 2)
    t = 0
    run = 0
    x, y, heading = 0, 0, 0
    hit_goal = False
    run0_steps = None
    run1_steps = None
    status = None
    error = None
    try:
        robot = robot_class(dim)
    except Exception:
        traceback.print_exc()
        robot, status, error = None, "crashed", "Robot(%d) raised" % dim
    while status is None:
        if t >= MAX_STEPS:
            status = "step_limit"
            break
        t += 1
        sensors = []
        for turn in (-1, 0, 1):
            d = (heading + turn) % 4
            dx, dy = DELTA[d]
            cx, cy, n = x, y, 0
            while cells[cx][cy] & BITS[d]:  # a closed perimeter keeps this on the grid
                cx += dx
                cy += dy
                n += 1
            sensors.append(n)
        try:
            answer = robot.next_move(list(sensors))
        except Exception:
            traceback.print_exc()
            status, error = "crashed", "step %d: next_move raised" % t
            break
        step_run = run
        if is_reset(answer):
            action = {"reset": True}
            if run == 0 and hit_goal:
                run0_steps = t
                run = 1
                x, y, heading = 0, 0, 0
                event = "reset_accepted"
            else:
                event = "reset_rejected"
        else:
            try:
                rotation, movement = answer
                rotation = integer(rotation, "rotation")
                movement = integer(movement, "movement")
            except (TypeError, ValueError, ProtocolError) as err:
                status = "protocol_error"
                error = "step %d: %s (answer %r)" % (t, err, answer)
                break
            action = {"rotation": rotation, "movement": movement}
            if rotation == -90:
                heading = (heading + 3) % 4
            elif rotation == 90:
                heading = (heading + 1) % 4
            movement = max(-MAX_MOVEMENT, min(MAX_MOVEMENT, movement))
            d = heading if movement >= 0 else (heading + 2) % 4
            dx, dy = DELTA[d]
            for _ in range(abs(movement)):
                if not cells[x][y] & BITS[d]:
                    break  # a wall stops the movement
                x += dx
                y += dy
            event = "move"
            if x in goal and y in goal:
                hit_goal = True
                if run == 1:
                    run1_steps = t - run0_steps
                    status = "finished"
                    event = "goal_reached"
        if trace is not None:
            trace.append({"run": step_run, "step": t,
                          "sensors": sensors, "action": action, "event": event,
                          "position": {"x": x, "y": y}, "heading": HEADINGS[heading]})
    score = None
    if status == "finished":
        millis = ((RUN0_DIVISOR * run1_steps + run0_steps) * 1000 + RUN0_DIVISOR // 2) \
            // RUN0_DIVISOR
        score = millis / 1000.0
    return {"status": status, "run0_steps": run0_steps, "run1_steps": run1_steps,
            "total_steps": t, "score": score, "error": error}


def main(argv):
    args = list(argv[1:])
    trace_file = None
    if "--trace" in args:
        i = args.index("--trace")
        if i + 1 >= len(args):
            sys.stderr.write("tester_loop: --trace needs a file\n")
            return 2
        trace_file = args[i + 1]
        del args[i:i + 2]
    if len(args) != 2:
        sys.stderr.write(__doc__.split("\n\n")[1] + "\n")
        return 2
    robot_path, maze_path = args
    if not os.path.isfile(robot_path):
        sys.stderr.write("tester_loop: no such file: %s\n" % robot_path)
        return 2

    started = clock()
    try:
        dim, cells = read_maze(maze_path)
    except (IOError, OSError, MazeError) as err:
        sys.stderr.write("tester_loop: bad maze %s: %s\n" % (maze_path, err))
        return 2
    sys.argv = [robot_path, maze_path]  # as under "tester.py MAZE_FILE"
    real_stdout = sys.stdout
    sys.stdout = sys.stderr  # the robot's prints: stderr, as under the adapter
    trace = [] if trace_file else None
    try:
        seed_randomness(0)
        try:
            robot_class = load_robot_class(robot_path)
        except Exception:
            traceback.print_exc()
            sys.stderr.write("tester_loop: could not import Robot from %s\n" % robot_path)
            return 1
        loaded = clock()
        result = play(robot_class, dim, cells, trace)
        done = clock()
    finally:
        sys.stdout.flush()
        sys.stdout = real_stdout
    result["loop_ms"] = round((done - loaded) * 1000, 3)
    result["load_ms"] = round((loaded - started) * 1000, 3)
    result["python"] = "%d.%d.%d" % sys.version_info[:3]
    if trace_file:
        with open(trace_file, "w") as f:
            json.dump(trace, f)
    print(json.dumps(result, sort_keys=True))
    sys.stdout.flush()
    return 1 if result["status"] == "crashed" else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
