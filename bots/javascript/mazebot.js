'use strict';
/**
 * mazebot.js: the protocol side of a mazearena bot written in JavaScript (Node 20,
 * no dependencies). It knows nothing about strategy.
 *
 * The server talks to a bot through line-delimited JSON on stdin/stdout
 * (docs/PROTOCOL.md). This module does all of that, so a bot is just an object:
 *
 *     const mazebot = require('./mazebot');
 *
 *     class MyBot {
 *       start(info) {                       // optional
 *         this.n = info.maze_dim;           // info is the whole start message
 *       }
 *       nextMove(sensors, run, step) {
 *         const [left, front, right] = sensors;
 *         if (front > 0) return { rotation: 0, movement: 1 };
 *         return { rotation: 90, movement: 0 };
 *       }
 *       end(msg) {                          // optional
 *         console.log('result:', msg);      // goes to stderr, see below
 *       }
 *     }
 *
 *     mazebot.run(new MyBot());
 *
 * start(info)
 *   Called once before the first move with the start message:
 *   {type, protocol, maze_dim, max_steps, seed, move_timeout_ms}. Use
 *   `mazebot.prng(info.seed)` for reproducible randomness.
 *
 * nextMove(sensors, run, step)
 *   `sensors` is [left, front, right]: open cells to the nearest wall, relative
 *   to the heading. `run` is 0 (exploration) then 1 (the timed run); `step` is the
 *   shared 1-based step counter. Return one of:
 *   - {rotation, movement}: rotation -90, 0 or 90 (clockwise positive), then
 *     movement -3..3 cells (negative = backward). Both must be integers.
 *     Extra fields (e.g. {rotation: 0, movement: 1, note: 'exploring'}) are sent
 *     as-is; the server ignores them.
 *   - [rotation, movement]: the same as an array.
 *   - mazebot.move(rotation, movement, debug) / mazebot.reset(debug): a move or a
 *     reset with a debug object for the replay viewer (see "Debug drawing" below).
 *   - mazebot.RESET (the string 'reset', any case; the original task's
 *     ['Reset', 'Reset'] and {reset: true} work too): end run 0. Only accepted
 *     in run 0 once the robot has ended a step in the goal room; otherwise the
 *     step is spent and nothing happens.
 *
 * end(msg)
 *   Called once with the server's final message, e.g.
 *   {type: 'end', status: 'finished', score: 18.133, run0_steps: 34, run1_steps: 17}.
 *
 * Debug drawing (docs/PROTOCOL.md, "Debug drawing"): the replay viewer draws what
 * a bot believes, step by step, as a layer over the maze. Build it with a Debug and
 * attach it to the answer:
 *
 *     const dbg = new mazebot.Debug().text('to the goal').grid(dist).path([[0, 0], [0, 1]]);
 *     if (mapChanged) dbg.walls(knownWalls);  // fields are sticky: send when changed
 *     return mazebot.move(0, 1, dbg);         // or mazebot.reset(dbg)
 *
 * Debug methods return the builder, so calls chain:
 *   text(s)                  a line shown with the step
 *   wall(x, y, side)         a wall the bot believes in; side 'up', 'right', 'down',
 *                            'left' or 0..3 in that order (UP, RIGHT, DOWN, LEFT)
 *   walls([[x, y, side], ...])  several (walls([]) sends an empty list: clears)
 *   cell(x, y, value)        a number or short text in one cell
 *   grid(columns)            values for the whole maze, columns[x][y] (one array per
 *                            column, like the maze file): numbers, short strings, null
 *   color(x, y, '#rrggbb')   a cell colour ('#rgb' or '#rrggbb', else a BotError)
 *   path([[x, y], ...])      a planned path
 * (0, 0) is the bottom-left cell, x to the right, y up. Strings always go out as
 * valid JSON; NaN and infinities become null. A debug object over 16 KiB of JSON is
 * not sent (a warning goes to stderr), nor is any once the match has sent 64 KiB:
 * the server would drop them anyway.
 *
 * Printing is safe: once run() is called, console.log/info/debug and
 * process.stdout.write go to stderr, which the server keeps as the bot's log.
 * Protocol lines go through a private handle on the real stdout.
 *
 * An exception in the bot (or an answer that is not one of the above) is printed
 * to stderr and the process exits with status 1 (the server records a crash).
 * The process exits with status 0 on the end message or when stdin closes.
 */

const util = require('util');

/** Return this from nextMove to end run 0. */
const RESET = 'reset';

class BotError extends Error {
  constructor(message) {
    super(message);
    this.name = 'BotError';
  }
}

function integer(v, name) {
  if (typeof v !== 'number' || !Number.isInteger(v)) {
    throw new BotError(`${name} must be an integer, got ${util.inspect(v)}`);
  }
  return v;
}

/** The server keeps at most this many bytes of debug JSON per step, and per match. */
const MAX_DEBUG_STEP_BYTES = 16 * 1024;
const MAX_DEBUG_MATCH_BYTES = 64 * 1024;

/** Wall sides, in the order of the direction numbers 0..3 (UP, RIGHT, DOWN, LEFT). */
const SIDES = ['up', 'right', 'down', 'left'];

/** A string that encodes to valid UTF-8 (lone surrogates become U+FFFD). */
function wellFormed(s) {
  s = String(s);
  return typeof s.toWellFormed === 'function'
    ? s.toWellFormed()
    : s.replace(/[\uD800-\uDBFF](?![\uDC00-\uDFFF])|(?<![\uD800-\uDBFF])[\uDC00-\uDFFF]/g, '\uFFFD');
}

/** A cell value as JSON can carry it: a finite number, a string or null. */
function cellValue(v) {
  if (v === null || v === undefined) return null;
  if (typeof v === 'boolean') return v ? 1 : 0;
  if (typeof v === 'number' || typeof v === 'bigint') {
    const n = Number(v);
    return Number.isFinite(n) ? n : null;
  }
  return wellFormed(v);
}

function wallSide(side) {
  if (Number.isInteger(side) && side >= 0 && side < 4) return SIDES[side];
  if (typeof side === 'string' && SIDES.includes(side.toLowerCase())) return side.toLowerCase();
  throw new BotError(`a wall side is 'up', 'right', 'down', 'left' or 0..3; got ${util.inspect(side)}`);
}

function coord(v, name) {
  if (typeof v !== 'number' || !Number.isInteger(v)) {
    throw new BotError(`${name} must be an integer, got ${util.inspect(v)}`);
  }
  return v;
}

/**
 * A debug object for the replay viewer (docs/PROTOCOL.md, "Debug drawing"). Every
 * method returns the builder; attach it with move(r, m, debug) or reset(debug).
 * JSON.stringify turns it into its plain object (toJSON).
 */
class Debug {
  constructor() {
    this.fields = {};
  }

  text(s) {
    this.fields.text = wellFormed(s);
    return this;
  }

  wall(x, y, side) {
    (this.fields.walls ||= []).push([coord(x, 'x'), coord(y, 'y'), wallSide(side)]);
    return this;
  }

  walls(list) {
    this.fields.walls ||= [];
    for (const [x, y, side] of list) this.wall(x, y, side);
    return this;
  }

  cell(x, y, value) {
    (this.fields.cells ||= []).push([coord(x, 'x'), coord(y, 'y'), cellValue(value)]);
    return this;
  }

  grid(columns) {
    this.fields.grid = Array.from(columns, (column) => Array.from(column, cellValue));
    return this;
  }

  color(x, y, color) {
    if (typeof color !== 'string' || !/^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$/.test(color)) {
      throw new BotError(`a colour is '#rgb' or '#rrggbb'; got ${util.inspect(color)}`);
    }
    (this.fields.colors ||= []).push([coord(x, 'x'), coord(y, 'y'), color]);
    return this;
  }

  path(cells) {
    this.fields.path = Array.from(cells, ([x, y]) => [coord(x, 'x'), coord(y, 'y')]);
    return this;
  }

  isEmpty() {
    return Object.keys(this.fields).length === 0;
  }

  toJSON() {
    return this.fields;
  }
}

/** A move answer, with an optional Debug (or plain object) attached. */
function move(rotation, movement, debug) {
  const answer = { rotation: integer(rotation, 'rotation'), movement: integer(movement, 'movement') };
  if (debug !== undefined && debug !== null) answer.debug = debug;
  return answer;
}

/** A reset answer, with an optional Debug (or plain object) attached. */
function reset(debug) {
  const answer = { reset: true };
  if (debug !== undefined && debug !== null) answer.debug = debug;
  return answer;
}

/** Leaves out debug objects the server would drop (over 16 KiB, or past 64 KiB). */
function debugBudget() {
  let used = 0;
  const warned = new Set();
  const warn = (kind, message) => {
    if (!warned.has(kind)) {
      warned.add(kind);
      process.stderr.write(`mazebot: ${message}\n`);
    }
  };
  return (answer, step) => {
    const size = Buffer.byteLength(JSON.stringify(answer.debug) ?? '');
    if (size > MAX_DEBUG_STEP_BYTES) {
      warn('step', `step ${step}: debug object of ${size} bytes, over ${MAX_DEBUG_STEP_BYTES}: not sent`);
    } else if (used + size > MAX_DEBUG_MATCH_BYTES) {
      warn('match', `step ${step}: the match's debug objects reached ${MAX_DEBUG_MATCH_BYTES} bytes: no more are sent`);
    } else {
      used += size;
      return answer;
    }
    const { debug, ...rest } = answer; // eslint-disable-line no-unused-vars
    return rest;
  };
}

function isReset(v) {
  return typeof v === 'string' && v.toLowerCase() === RESET;
}


/** Turns a nextMove result into the object to send; throws BotError if it is not valid. */
function encodeAnswer(answer) {
  if (typeof answer === 'string') {
    if (isReset(answer)) return { reset: true };
    throw new BotError(`nextMove returned the string ${util.inspect(answer)}; only '${RESET}' is allowed`);
  }
  if (Array.isArray(answer)) {
    if (answer.length !== 2) {
      throw new BotError(`nextMove must return [rotation, movement]; got ${util.inspect(answer)}`);
    }
    if (isReset(answer[0]) && isReset(answer[1])) return { reset: true };
    return { rotation: integer(answer[0], 'rotation'), movement: integer(answer[1], 'movement') };
  }
  if (answer !== null && typeof answer === 'object') {
    if (answer.reset === true) return answer;
    integer(answer.rotation, 'rotation');
    integer(answer.movement, 'movement');
    return answer;
  }
  throw new BotError(`nextMove must return {rotation, movement}, [rotation, movement] or RESET; got ${util.inspect(answer)}`);
}

/**
 * A small seeded PRNG (mulberry32 over a 32-bit hash of the seed's decimal text),
 * for bots that want randomness but must be reproducible for a given seed.
 * Returns a function giving floats in [0, 1); `.int(n)` gives integers in [0, n).
 */
function prng(seed) {
  let h = 2166136261 >>> 0; // FNV-1a over the text of the seed
  for (const ch of String(seed === undefined || seed === null ? 0 : seed)) {
    h ^= ch.charCodeAt(0);
    h = Math.imul(h, 16777619) >>> 0;
  }
  let a = h;
  const next = () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  next.int = (n) => Math.floor(next() * n);
  return next;
}

/** Sends every console.log / process.stdout.write to stderr; returns a writer for protocol lines. */
function privateStdout() {
  const stdout = process.stdout;
  const write = stdout.write.bind(stdout);
  stdout.on('error', (e) => {
    // The server stopped listening (EPIPE): nothing left to do.
    process.stderr.write(`mazebot: stdout: ${e.message}\n`);
    process.exit(0);
  });
  const toErr = (...args) => process.stderr.write(util.format(...args) + '\n');
  console.log = toErr;
  console.info = toErr;
  console.debug = toErr;
  stdout.write = (chunk, encoding, cb) => process.stderr.write(chunk, encoding, cb);
  return (line) => write(line + '\n');
}

function fail(err) {
  process.stderr.write(`mazebot: the bot failed: ${err && err.stack ? err.stack : err}\n`);
  process.exit(1);
}

/**
 * Plays one match with `bot` over stdin/stdout. `bot` is an object (or a class,
 * instantiated with no arguments) with nextMove(sensors, run, step) and optionally
 * start(info) and end(msg).
 */
function run(bot) {
  const send = privateStdout();
  const budget = debugBudget();
  try {
    if (typeof bot === 'function') bot = new bot(); // eslint-disable-line new-cap
  } catch (e) {
    fail(e);
  }
  let buffer = '';
  let done = false;

  const handle = (line) => {
    line = line.trim();
    if (!line) return;
    const msg = JSON.parse(line);
    const kind = msg && typeof msg === 'object' ? msg.type : undefined;
    if (kind === 'start') {
      if (typeof bot.start === 'function') bot.start(msg);
    } else if (kind === 'sense') {
      let answer = encodeAnswer(bot.nextMove(msg.sensors.slice(), msg.run, msg.step));
      if (answer.debug !== undefined) answer = budget(answer, msg.step);
      send(JSON.stringify(answer));
    } else if (kind === 'end') {
      done = true;
      if (typeof bot.end === 'function') bot.end(msg);
      process.exit(0);
    }
    // Unknown message types are ignored (room for later protocol versions).
  };

  process.stdin.setEncoding('utf8');
  process.stdin.on('data', (chunk) => {
    buffer += chunk;
    let nl;
    while (!done && (nl = buffer.indexOf('\n')) >= 0) {
      const line = buffer.slice(0, nl);
      buffer = buffer.slice(nl + 1);
      try {
        handle(line);
      } catch (e) {
        fail(e);
      }
    }
  });
  process.stdin.on('end', () => {
    if (!done && buffer.trim()) {
      try {
        handle(buffer);
      } catch (e) {
        fail(e);
      }
    }
    process.exit(0); // EOF: the server is done with us
  });
}

module.exports = { RESET, BotError, run, encodeAnswer, prng, Debug, move, reset, SIDES };
