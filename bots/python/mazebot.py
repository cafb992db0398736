"""mazebot: the protocol side of a mazearena bot written in Python 3.

The server talks to a bot through line-delimited JSON on stdin/stdout
(docs: PROTOCOL-v1.md). This module does all of that, so a bot is just a
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
    * a ``dict``: sent as-is (for extra fields such as debug annotations;
      it must still hold ``rotation`` and ``movement``, or ``"reset": true``).

``end(message)``
    Called once with the server's final message, a dict such as
    ``{"type": "end", "status": "finished", "score": 18.133,
    "run0_steps": 34, "run1_steps": 17}``.

Printing is safe: while ``run`` is active, ``print`` (and anything else that
writes to stdout, even a child process) goes to stderr, which the server keeps
as the bot's log. Protocol lines go through a private copy of the real stdout.

An exception in the bot (or an answer that is not one of the above) is
printed to stderr and the process exits with status 1 (the server records
the match as crashed). ``run`` returns on the end message or when stdin
closes; stdout stays redirected to stderr after that.
"""

import json
import numbers
import os
import sys
import traceback

__all__ = ["RESET", "run", "BotError"]

#: Return this from ``next_move`` to end run 0 (see the module doc).
RESET = "reset"


class BotError(Exception):
    """The bot returned something ``run`` cannot send (a bug in the bot)."""


def _integer(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise BotError("%s must be an integer, got %r" % (name, value))
    return int(value)


def _is_reset(value):
    return isinstance(value, str) and value.lower() == RESET


def encode_answer(answer):
    """Turn a ``next_move`` result into the JSON object to send.

    Raises ``BotError`` for anything that is not a valid answer.
    """
    if isinstance(answer, str):
        if _is_reset(answer):
            return {"reset": True}
        raise BotError("next_move returned the string %r; only %r is allowed" % (answer, RESET))
    if isinstance(answer, dict):
        return answer
    try:
        rotation, movement = answer
    except (TypeError, ValueError):
        raise BotError("next_move must return (rotation, movement), RESET or a dict; got %r"
                       % (answer,)) from None
    if _is_reset(rotation) and _is_reset(movement):  # the original task's ('Reset', 'Reset')
        return {"reset": True}
    return {"rotation": _integer(rotation, "rotation"), "movement": _integer(movement, "movement")}


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
