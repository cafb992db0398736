"""mazebot: the protocol side of a mazearena bot written in Python 3.

The server talks to a bot through line-delimited JSON on stdin/stdout
(docs/PROTOCOL.md). This module does all of that, so a bot is just a
class with one method::

    import mazebot

    class MyBot:
        def start(self, maze_dim, seed, max_steps):   # optional
            self.n = maze_dim

        def next_move(self, sensors, run, step):
            left, front, right = sensors
            if front > 0:
                return (0, 1)          # (rotation, movement)
            return (90, 0)

        def end(self, message):                       # optional
            print("result:", message)                 # goes to stderr, see below

    if __name__ == "__main__":
        mazebot.run(MyBot())

What each method receives and returns:

``start(maze_dim, seed, max_steps)``
    Called once before the first move. ``seed`` is there so a randomized bot
    can be reproducible (e.g. ``random.seed(seed)``).

``next_move(sensors, run, step)``
    ``sensors`` is ``[left, front, right]``: the number of open cells from the
    robot's cell to the nearest wall, relative to its heading. ``run`` is 0
    (exploration) then 1 (the timed run); ``step`` is the shared 1-based step
    counter over both runs. Return one of:

    * ``(rotation, movement)``: rotation -90, 0 or 90 (degrees, clockwise
      positive), then movement -3..3 cells (negative = backward). Both must be
      integers (``int`` or anything ``numbers.Integral``, but not ``bool``).
    * ``mazebot.RESET`` (the string ``"reset"``, any case; the original task's
      ``('Reset', 'Reset')`` works too): end run 0. Only accepted in run 0
      after the robot has ended a step in the goal room; otherwise the step is
      spent and nothing happens.
    * ``mazebot.move(rotation, movement, debug=...)`` or
      ``mazebot.reset(debug=...)``: the same, with a debug object for the
      replay viewer (see "Debug drawing" below).
    * a ``dict``: sent as-is (for extra fields such as notes; it must still
      hold ``rotation`` and ``movement``, or ``"reset": true``). A ``Debug``
      under its ``"debug"`` key is turned into its object.

``end(message)``
    Called once with the server's final message, a dict such as
    ``{"type": "end", "status": "finished", "score": 18.133,
    "run0_steps": 34, "run1_steps": 17}``.

Debug drawing (docs/PROTOCOL.md, "Debug drawing"): the replay viewer draws
what a bot believes, step by step, as a layer over the maze. Build it with
``Debug`` and attach it to the answer::

    dbg = mazebot.Debug().text("to the goal").grid(distances).path([(0, 0), (0, 1)])
    if map_changed:
        dbg.walls(known_walls)               # fields are sticky: send when changed
    return mazebot.move(0, 1, debug=dbg)     # or mazebot.reset(debug=dbg)

``Debug`` methods return the builder, so calls chain:

* ``text(s)``: a line shown with the step.
* ``wall(x, y, side)`` / ``walls(iterable of (x, y, side))``: walls the bot
  believes in; ``side`` is ``"up"``, ``"right"``, ``"down"``, ``"left"`` or
  0..3 in that order (UP, RIGHT, DOWN, LEFT).
* ``cell(x, y, value)``: a number or short text in one cell.
* ``grid(columns)``: values for the whole maze, ``columns[x][y]`` (a list per
  column, like the maze file); numbers, short strings or ``None``.
* ``color(x, y, "#rrggbb")``: a cell colour (``#rgb`` or ``#rrggbb``, else
  ``ValueError``).
* ``path(cells)``: a planned path, a sequence of ``(x, y)``.

(0, 0) is the bottom-left cell, x to the right, y up. Strings are sent as
valid JSON whatever they hold; NaN and infinities become ``null``. A debug
object over 16 KiB of JSON is not sent (a warning goes to stderr), nor is any
once the match has sent 64 KiB: the server would drop them anyway.

Printing is safe: while ``run`` is active, ``print`` (and anything else that
writes to stdout, even a child process) goes to stderr, which the server keeps
as the bot's log. Protocol lines go through a private copy of the real stdout.

An exception in the bot (or an answer that is not one of the above) is
printed to stderr and the process exits with status 1 (the server records
the match as crashed). ``run`` returns on the end message or when stdin
closes; stdout stays redirected to stderr after that.
"""

import json
import math
import numbers
import os
import re
import sys
import traceback

__all__ = ["RESET", "run", "BotError", "Debug", "move", "reset"]

#: Return this from ``next_move`` to end run 0 (see the module doc).
RESET = "reset"

#: The server keeps at most this many bytes of debug JSON per step, and per match.
MAX_DEBUG_STEP_BYTES = 16 * 1024
MAX_DEBUG_MATCH_BYTES = 64 * 1024

#: Wall sides, in the order of the direction numbers 0..3 (UP, RIGHT, DOWN, LEFT).
SIDES = ("up", "right", "down", "left")

_COLOR = re.compile(r"^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$")


class BotError(Exception):
    """The bot returned something ``run`` cannot send (a bug in the bot)."""


def _integer(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise BotError("%s must be an integer, got %r" % (name, value))
    return int(value)


def _is_reset(value):
    return isinstance(value, str) and value.lower() == RESET


def _text(value):
    """A str that encodes to valid UTF-8 (lone surrogates become '?')."""
    return str(value).encode("utf-8", "replace").decode("utf-8")


def _value(value):
    """A cell value as JSON can carry it: int, finite float, str or None."""
    if value is None:
        return None
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        value = float(value)
        return value if math.isfinite(value) else None
    return _text(value)


def _side(side):
    if isinstance(side, numbers.Integral) and not isinstance(side, bool) and 0 <= side < 4:
        return SIDES[side]
    if isinstance(side, str) and side.lower() in SIDES:
        return side.lower()
    raise ValueError("a wall side is 'up', 'right', 'down', 'left' or 0..3; got %r" % (side,))


class Debug:
    """A debug object for the replay viewer (docs/PROTOCOL.md, "Debug drawing").

    Every method returns the builder. Attach it with ``move(r, m, debug=d)``
    or ``reset(debug=d)``; ``to_dict()`` gives the plain object.
    """

    def __init__(self):
        self._d = {}

    def text(self, text):
        """A line of text shown with the step (replaces an earlier one)."""
        self._d["text"] = _text(text)
        return self

    def wall(self, x, y, side):
        """A wall the bot believes in, on ``side`` of cell (x, y)."""
        self._d.setdefault("walls", []).append([int(x), int(y), _side(side)])
        return self

    def walls(self, walls):
        """Several walls, ``(x, y, side)`` each; ``walls([])`` sends an empty list (clears)."""
        self._d.setdefault("walls", [])
        for x, y, side in walls:
            self.wall(x, y, side)
        return self

    def cell(self, x, y, value):
        """A number or short text written in cell (x, y)."""
        self._d.setdefault("cells", []).append([int(x), int(y), _value(value)])
        return self

    def grid(self, columns):
        """Values for the whole maze: ``columns[x][y]``, one sequence per column."""
        self._d["grid"] = [[_value(v) for v in column] for column in columns]
        return self

    def color(self, x, y, color):
        """A cell colour, ``#rgb`` or ``#rrggbb``."""
        if not isinstance(color, str) or not _COLOR.match(color):
            raise ValueError("a colour is '#rgb' or '#rrggbb'; got %r" % (color,))
        self._d.setdefault("colors", []).append([int(x), int(y), color])
        return self

    def path(self, cells):
        """A planned path through the cells ``(x, y)``, in order (replaces an earlier one)."""
        self._d["path"] = [[int(x), int(y)] for x, y in cells]
        return self

    def to_dict(self):
        return self._d

    def __bool__(self):
        return bool(self._d)

    def __repr__(self):
        return "Debug(%r)" % (self._d,)


def move(rotation, movement, debug=None):
    """A move answer, with an optional ``Debug`` (or plain dict) attached."""
    answer = {"rotation": _integer(rotation, "rotation"), "movement": _integer(movement, "movement")}
    if debug is not None:
        answer["debug"] = debug
    return answer


def reset(debug=None):
    """A reset answer, with an optional ``Debug`` (or plain dict) attached."""
    answer = {"reset": True}
    if debug is not None:
        answer["debug"] = debug
    return answer


def encode_answer(answer):
    """Turn a ``next_move`` result into the JSON object to send.

    Raises ``BotError`` for anything that is not a valid answer.
    """
    if isinstance(answer, str):
        if _is_reset(answer):
            return {"reset": True}
        raise BotError("next_move returned the string %r; only %r is allowed" % (answer, RESET))
    if isinstance(answer, dict):
        if isinstance(answer.get("debug"), Debug):
            answer = dict(answer, debug=answer["debug"].to_dict())
        return answer
    try:
        rotation, movement = answer
    except (TypeError, ValueError):
        raise BotError("next_move must return (rotation, movement), RESET or a dict; got %r"
                       % (answer,)) from None
    if _is_reset(rotation) and _is_reset(movement):  # the original task's ('Reset', 'Reset')
        return {"reset": True}
    return {"rotation": _integer(rotation, "rotation"), "movement": _integer(movement, "movement")}


class _DebugBudget:
    """Leaves out debug objects the server would drop (over 16 KiB, or past 64 KiB)."""

    def __init__(self):
        self.used = 0
        self.warned = set()

    def _warn(self, kind, message):
        if kind not in self.warned:
            self.warned.add(kind)
            sys.stderr.write("mazebot: %s\n" % message)

    def check(self, answer, step):
        size = len(json.dumps(answer["debug"], separators=(",", ":")).encode("utf-8"))
        if size > MAX_DEBUG_STEP_BYTES:
            self._warn("step", "step %s: debug object of %d bytes, over %d: not sent"
                       % (step, size, MAX_DEBUG_STEP_BYTES))
        elif self.used + size > MAX_DEBUG_MATCH_BYTES:
            self._warn("match", "step %s: the match's debug objects reached %d bytes: "
                       "no more are sent" % (step, MAX_DEBUG_MATCH_BYTES))
        else:
            self.used += size
            return answer
        return {k: v for k, v in answer.items() if k != "debug"}


def _private_stdio():
    """Keep private handles to the real stdin/stdout, then point fd 1 at stderr.

    After this, nothing the bot prints (Python ``print``, C extensions, child
    processes) can reach the protocol channel, and the bot cannot read the
    server's messages by accident (fd 0 becomes /dev/null).
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


def run(bot):
    """Play one match with ``bot`` over stdin/stdout; return when it ends.

    ``bot`` is an object (or a class, which is instantiated with no
    arguments) with ``next_move(sensors, run, step)`` and optionally
    ``start(maze_dim, seed, max_steps)`` and ``end(message)``.
    On an exception in the bot: traceback on stderr, ``sys.exit(1)``.
    """
    proto_in, proto_out = _private_stdio()
    budget = _DebugBudget()
    try:
        if isinstance(bot, type):
            bot = bot()
        while True:
            raw = proto_in.readline()
            if not raw:
                return  # EOF: the server is done with us
            raw = raw.strip()
            if not raw:
                continue
            msg = json.loads(raw.decode("utf-8"))
            kind = msg.get("type") if isinstance(msg, dict) else None
            if kind == "start":
                start = getattr(bot, "start", None)
                if start is not None:
                    start(msg.get("maze_dim"), msg.get("seed"), msg.get("max_steps"))
            elif kind == "sense":
                answer = encode_answer(bot.next_move(list(msg["sensors"]), msg["run"], msg["step"]))
                if "debug" in answer:
                    answer = budget.check(answer, msg["step"])
                proto_out.write(json.dumps(answer, separators=(",", ":")).encode("utf-8") + b"\n")
                proto_out.flush()
            elif kind == "end":
                end = getattr(bot, "end", None)
                if end is not None:
                    end(msg)
                return
            # Unknown message types are ignored (room for later protocol versions).
    except BrokenPipeError:
        return  # the server stopped listening; nothing left to do
    except Exception:
        traceback.print_exc()
        sys.stderr.flush()
        sys.exit(1)
