#!/usr/bin/env bash
# An original-task robot.py played two ways, on the classic mazes, taken in turn RUNS
# times (medians):
#   - the original tester's way: benches/tester_loop.py, one Python process that imports
#     the robot and referees both runs in a loop (RULES.md), timed start to exit (the
#     interpreter's start included) and by its own clock around Robot(maze_dim) and the
#     two runs ("loop");
#   - `mazearena run --json` of `PYTHON bots/python/udacity_adapter.py ROBOT`, with
#     --sandbox none and --sandbox full, timed start to exit.
# Both ways must play the same game: before the timing, every step of the tester loop
# (sensors, answer, position, heading) is compared with mazearena's replay trace, and
# every timed run's status, steps and score with that game; any difference stops the
# bench. The robot (default: tests/fixtures/robot_py/robot.py, deterministic: its
# `random` only feeds its log and is seeded by both ways alike) prints a line on every
# step, which goes to stderr in both ways (/dev/null here; a pipe that mazearena reads
# under mazearena).
#
#   bash benches/adapter.sh [RUNS]      (default 11; needs python3 and, for the
#                                        --sandbox full column, bubblewrap)
# Environment: ROBOT (a robot.py), PYTHON (default python3: a pyenv shim is resolved to
# its interpreter, so that pyenv's own start is not measured), PY2 (a Python 2.7 to play
# too; default: python2.7 when it can be found, also in pyenv; PY2= to skip).
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-11}
ROBOT=${ROBOT:-tests/fixtures/robot_py/robot.py}
MAZES=(../shared/mazes/classic/test_maze_01.txt ../shared/mazes/classic/test_maze_02.txt
       ../shared/mazes/classic/test_maze_03.txt)
ARENA=./target/release/mazearena
[ -x "$ARENA" ] || cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

interpreter() { # $1: a command name or path; prints the interpreter behind it, or nothing
  local p
  p=$(command -v "$1" 2>/dev/null) || return 0
  if [[ $p == */shims/* ]] && command -v pyenv >/dev/null; then
    p=$(pyenv which "$(basename "$p")" 2>/dev/null) || return 0
  fi
  "$p" -c 'import sys' 2>/dev/null && echo "$p"
  return 0
}
PY3=$(interpreter "${PYTHON:-python3}")
[ -n "$PY3" ] || { echo "adapter.sh: no ${PYTHON:-python3} found" >&2; exit 1; }
PYS=("$PY3")
if [ -n "${PY2-auto}" ]; then
  if [ "${PY2-auto}" = auto ]; then
    py2=$(interpreter python2.7)
    if [ -z "$py2" ] && command -v pyenv >/dev/null; then
      for v in "$(pyenv root)"/versions/2.7*/bin/python2.7; do
        [ -x "$v" ] && py2=$v
      done
    fi
  else
    py2=$(interpreter "$PY2")
    [ -n "$py2" ] || { echo "adapter.sh: PY2=$PY2 is not a usable interpreter" >&2; exit 1; }
  fi
  [ -n "$py2" ] && PYS+=("$py2")
fi

# Prints the wall time of "$@" in microseconds (stdout to $OUT, stderr to /dev/null).
timed() {
  local a b
  a=$EPOCHREALTIME
  "$@" >"$OUT" 2>/dev/null
  b=$EPOCHREALTIME
  echo $(( ${b/[.,]/} - ${a/[.,]/} ))
}

# The sandbox, if it works here: one short match; otherwise the full column is skipped.
SANDBOXES=(none full)
if ! "$ARENA" run --maze "${MAZES[0]}" --bot "$PY3 bots/python/udacity_adapter.py $ROBOT" \
     --sandbox full --json >"$tmp/probe.json" 2>"$tmp/probe.err" \
   || ! grep -q '"status":"finished"' "$tmp/probe.json"; then
  echo "adapter.sh: --sandbox full does not work here, skipped:" >&2
  tail -n 3 "$tmp/probe.err" "$tmp/probe.json" >&2 || true
  SANDBOXES=(none)
fi

# The same game both ways, step by step (untimed).
for p in "${!PYS[@]}"; do
  py=${PYS[$p]}
  for m in "${!MAZES[@]}"; do
    maze=${MAZES[$m]}
    echo "checking $(basename "$maze") with $py: tester loop against mazearena's trace" >&2
    "$py" benches/tester_loop.py "$ROBOT" "$maze" --trace "$tmp/trace-$p-$m.json" \
      >"$tmp/ref-$p-$m.json" 2>"$tmp/err" || {
      echo "adapter.sh: benches/tester_loop.py failed on $maze:" >&2
      tail -n 5 "$tmp/err" "$tmp/ref-$p-$m.json" >&2
      exit 1
    }
    "$ARENA" run --maze "$maze" --bot "$py bots/python/udacity_adapter.py $ROBOT" \
      --sandbox none --replay "$tmp/replay-$p-$m.json" --json >/dev/null 2>"$tmp/err" || {
      echo "adapter.sh: mazearena run failed on $maze:" >&2
      tail -n 5 "$tmp/err" >&2
      exit 1
    }
    python3 - "$tmp/ref-$p-$m.json" "$tmp/trace-$p-$m.json" "$tmp/replay-$p-$m.json" <<'EOF'
import json, sys
ref, trace, replay = (json.load(open(f)) for f in sys.argv[1:])
keys = ("run", "step", "sensors", "action", "event", "position", "heading")
for mine, theirs in zip(trace, replay["trace"]):
    a, b = ({k: s[k] for k in keys} for s in (mine, theirs))
    if a != b:
        sys.exit(f"adapter.sh: MISMATCH at step {a['step']}:\n  tester loop {a}\n  mazearena   {b}")
if len(trace) != len(replay["trace"]):
    sys.exit(f"adapter.sh: MISMATCH: {len(trace)} steps in the tester loop, "
             f"{len(replay['trace'])} under mazearena")
for k in ("status", "run0_steps", "run1_steps", "total_steps", "score"):
    if ref[k] != replay[k]:
        sys.exit(f"adapter.sh: MISMATCH in {k}: tester loop {ref[k]!r}, mazearena {replay[k]!r}")
EOF
  done
done

for i in $(seq "$RUNS"); do
  echo "run $i of $RUNS" >&2
  for p in "${!PYS[@]}"; do
    py=${PYS[$p]}
    for m in "${!MAZES[@]}"; do
      maze=${MAZES[$m]}
      OUT=$tmp/out-$i-$p-$m-loop.json
      echo "$p $m loop $(timed "$py" benches/tester_loop.py "$ROBOT" "$maze") $OUT"
      for s in "${SANDBOXES[@]}"; do
        OUT=$tmp/out-$i-$p-$m-$s.json
        echo "$p $m $s $(timed "$ARENA" run --maze "$maze" \
          --bot "$py bots/python/udacity_adapter.py $ROBOT" --sandbox "$s" --json) $OUT"
      done
    done
  done
done >"$tmp/all.txt"

python3 - "$tmp" "$RUNS" "$ROBOT" "${#MAZES[@]}" "${MAZES[@]}" "${PYS[@]}" <<'EOF'
import json, os, statistics, subprocess, sys
tmp, runs, robot, n = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
mazes, pys = sys.argv[5:5 + n], sys.argv[5 + n:]
times, loops = {}, {}
for line in open(os.path.join(tmp, "all.txt")):
    p, m, kind, us, out = line.split()
    r = json.load(open(out))
    ref = json.load(open(os.path.join(tmp, f"ref-{p}-{m}.json")))
    for k in ("status", "run0_steps", "run1_steps", "total_steps", "score"):
        if r[k] != ref[k]:
            sys.exit(f"adapter.sh: MISMATCH in {k} ({out}): {r[k]!r}, expected {ref[k]!r}")
    times.setdefault((p, m, kind), []).append(int(us) / 1000)
    if kind == "loop":
        loops.setdefault((p, m), []).append(r["loop_ms"])
version = lambda py: subprocess.run([py, "-c", "import sys; print('%d.%d.%d' % sys.version_info[:3])"],
                                    capture_output=True, text=True).stdout.strip()
names = [f"Python {version(py)}" for py in pys]
full = any(k[2] == "full" for k in times)
med = lambda k: statistics.median(times[k]) if k in times else None
ms = lambda v: "n/a" if v is None else f"{v:.0f}" if v >= 10 else f"{v:.1f}"
ratio = lambda a, b: "n/a" if a is None else f"{a / b:.2f}"
print("## The original tester's way against the adapter")
print()
where = ", ".join(f"`{os.path.basename(m)}`" for m in mazes)
if len({os.path.dirname(m) for m in mazes}) == 1:
    where += f" (in `{os.path.dirname(mazes[0])}`)"
print(f"`bash benches/adapter.sh {runs}`: `{robot}` on {where}, "
      f"with {' and '.join(f'{nm} (`{py}`)' for nm, py in zip(names, pys))}; "
      f"{runs} run{'s' if runs != 1 else ''} of each, taken in turn, medians. *In-process* is `benches/tester_loop.py ROBOT MAZE`, one "
      "Python process that imports the robot and referees both runs in a loop as the "
      "original `tester.py` did (whole process: start to exit; loop: its own clock around "
      "`Robot(maze_dim)` and both runs); *mazearena* is `mazearena run --maze MAZE --bot "
      "'PYTHON bots/python/udacity_adapter.py ROBOT' --json`, start to exit.")
print()
print("| maze | Python | steps (run 0 + run 1) | score | in-process, whole process (ms) "
      "| in-process, loop (ms) | `mazearena run --sandbox none` (ms) | `--sandbox full` (ms) "
      "| none ÷ in-process | full ÷ in-process |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for p, name in enumerate(names):
    for m, maze in enumerate(mazes):
        ref = json.load(open(os.path.join(tmp, f"ref-{p}-{m}.json")))
        whole = med((str(p), str(m), "loop"))
        none, fl = med((str(p), str(m), "none")), med((str(p), str(m), "full"))
        steps = f"{ref['run0_steps']} + {ref['run1_steps']} = {ref['total_steps']}"
        score = "—" if ref["score"] is None else f"{ref['score']:.3f}"
        print(f"| {os.path.basename(maze)} | {name} | {steps} | {score} | {ms(whole)} "
              f"| {ms(statistics.median(loops[(str(p), str(m))]))} | {ms(none)} | {ms(fl)} "
              f"| {ratio(none, whole)} | {ratio(fl, whole)} |")
print()
checked = sum(len(v) for k, v in times.items() if k[2] != "loop")
print(f"Steps and scores matched: on every maze the tester loop's game was the same as "
      f"mazearena's step by step (sensors, answers, positions, headings against the "
      f"replay trace), and all {sum(len(v) for v in times.values())} timed runs "
      f"({checked} of them `mazearena run`) gave the same status, steps and score."
      + ("" if full else " (`--sandbox full` did not work on this machine: not measured.)"))
EOF
