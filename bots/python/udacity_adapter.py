#!/usr/bin/env python
"""Run an unchanged robot.py from the original micromouse task as a mazearena bot.

usage: udacity_adapter.py ROBOT_PY [ARGS...]

ROBOT_PY is the path of a file defining ``class Robot`` with ``Robot(maze_dim)``
and ``next_move(sensors) -> (rotation, movement)`` or ``('Reset', 'Reset')``,
as in the "Plot and Navigate a Virtual Maze" task. This adapter speaks
protocol v1 (line-delimited JSON on stdin/stdout) on the robot's behalf:

* Arguments: the original tester ran as ``tester.py MAZE [ARGS]``, and some
  robots read ``sys.argv``. The robot sees ``sys.argv == [ROBOT_PY, "maze",
  ARGS...]`` (from its import on), so the arguments given after ROBOT_PY
  reach it as ``sys.argv[2:]``; "maze" stands for the maze file, which a bot
  never sees. Put them in the bot's command:
  ``mazearena run --bot 'python3 udacity_adapter.py robot.py --alpha 0.5' ...``
  gives the robot ``sys.argv[2:] == ['--alpha', '0.5']``.

* The robot's own folder goes first on sys.path, so its sibling imports work
  whatever the current directory is; the file is loaded by path as module
  ``robot`` (or its own file name).
* Everything the robot writes to stdout (print, child processes) goes to
  stderr, the bot's log; the adapter keeps a private copy of the real stdout
  for protocol lines, and the robot's stdin is /dev/null.
* ``random`` and, when importable, ``numpy.random`` (seed modulo 2**32) are
  seeded from the start message's seed before ``Robot(maze_dim)`` is built.
* Integral floats (1.0, numpy.float64(2.0)), numpy integers and bools (as the
  original tester reads them: True = 1) are sent as plain integers; any other
  value (1.5, NaN, a string, None) is passed through so the referee reports it.
  ``('Reset', 'Reset')`` becomes ``{"reset": true}``.
* An exception in the robot: traceback on stderr, exit status 1.
  The adapter exits (status 0) on the end message or when stdin closes.

Written in the common subset of Python 2.7 and Python 3, so a robot.py that
needs either interpreter can be run with it: ``python2.7 udacity_adapter.py
robot.py`` or ``python3 udacity_adapter.py robot.py``.
"""
from __future__ import print_function

import json
import numbers
import os
import random
import sys
import traceback

USAGE = "usage: udacity_adapter.py ROBOT_PY [ARGS...]\n" \
        "  Runs the original-task robot in ROBOT_PY (class Robot(maze_dim) with\n" \
        "  next_move(sensors)) as a mazearena protocol-v1 bot on stdin/stdout.\n" \
        "  The robot sees sys.argv = [ROBOT_PY, 'maze', ARGS...], as under the\n" \
        "  original 'tester.py MAZE ARGS...'.\n"


def private_stdio():
    """Return private (stdin, stdout) protocol streams; point fds 0/1 elsewhere.

    fd 1 becomes a copy of stderr and fd 0 reads /dev/null, so nothing the
    robot (or a child process it starts) does can touch the protocol.
    """
    sys.stdout.flush()
    proto_in = os.fdopen(os.dup(0), "rb")
    proto_out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    sys.stdout = sys.stderr
    return proto_in, proto_out


def load_robot_class(path):
    """Import the file at ``path`` (its folder first on sys.path); return its Robot."""
    path = os.path.abspath(path)
    folder = os.path.dirname(path)
    name = os.path.splitext(os.path.basename(path))[0]
    sys.path.insert(0, folder)
    sys.dont_write_bytecode = True  # leave no .pyc / __pycache__ next to the robot
    try:
        import importlib.util  # Python 3
    except ImportError:
        import imp  # Python 2.7
        module = imp.load_source(name, path)
    else:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module.Robot


def seed_randomness(seed):
    if seed is None:
        return
    random.seed(seed)
    try:
        import numpy
    except Exception:  # not installed (or broken): nothing to seed
        return
    numpy.random.seed(int(seed) % (2 ** 32))


def plain(value):
    """A plain int for an integral value (int, numpy int, integral float); else unchanged."""
    if isinstance(value, bool):
        return int(value)  # the original tester treats True/False as 1/0
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, float) and value.is_integer():  # also numpy.float64
        return int(value)
    if isinstance(value, numbers.Real):
        try:
            as_float = float(value)
        except (TypeError, ValueError, OverflowError):
            return value
        if as_float.is_integer():  # e.g. numpy.float32
            return int(as_float)
        return as_float  # non-integral: passed through, the referee rejects it
    return value


def is_reset(answer):
    try:
        return tuple(answer) == ("Reset", "Reset")
    except TypeError:
        return False


def encode(answer):
    if is_reset(answer):
        return {"reset": True}
    try:
        rotation, movement = answer
    except (TypeError, ValueError):
        raise TypeError("Robot.next_move returned %r, not (rotation, movement)" % (answer,))
    return {"rotation": plain(rotation), "movement": plain(movement)}


def to_json_line(obj):
    # Values json cannot encode become their repr (a string): the referee reports them.
    text = json.dumps(obj, separators=(",", ":"), default=repr)
    return text.encode("ascii") + b"\n"


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        sys.stderr.write(USAGE)
        return 0 if len(argv) >= 2 else 2
    robot_path = argv[1]
    if not os.path.isfile(robot_path):
        sys.stderr.write("udacity_adapter: no such file: %s\n%s" % (robot_path, USAGE))
        return 2
    # What the robot sees, as under the original "tester.py MAZE ARGS...".
    sys.argv = [robot_path, "maze"] + list(argv[2:])

    proto_in, proto_out = private_stdio()
    robot = None
    try:
        while True:
            raw = proto_in.readline()
            if not raw:
                return 0  # EOF
            raw = raw.strip()
            if not raw:
                continue
            msg = json.loads(raw.decode("utf-8"))
            kind = msg.get("type") if isinstance(msg, dict) else None
            if kind == "start":
                # Seed first, so even randomness used at import time is reproducible.
                seed_randomness(msg.get("seed"))
                robot = load_robot_class(robot_path)(msg["maze_dim"])
            elif kind == "sense":
                if robot is None:
                    raise RuntimeError("sense message before the start message")
                sensors = [int(s) for s in msg["sensors"]]
                line = to_json_line(encode(robot.next_move(sensors)))
                sys.stdout.flush()  # keep the robot's log in order with the moves
                proto_out.write(line)
                proto_out.flush()
            elif kind == "end":
                sys.stderr.write("udacity_adapter: end: %s\n" % json.dumps(msg, sort_keys=True))
                return 0
            # other message types: ignored (room for later protocol versions)
    except IOError as err:  # includes BrokenPipeError on Python 3
        import errno
        if getattr(err, "errno", None) == errno.EPIPE:
            try:
                proto_out.close()
            except (IOError, OSError):
                pass
            return 0  # the server stopped listening
        traceback.print_exc()
        return 1
    except Exception:
        traceback.print_exc()
        return 1


if __name__ == "__main__":
    status = main(list(sys.argv))
    sys.stderr.flush()
    sys.exit(status)
