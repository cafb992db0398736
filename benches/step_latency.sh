#!/usr/bin/env bash
# Per-step latency of a trivial compiled bot against the pipe round-trip floor, in the
# same run, taken in turn RUNS times (medians):
#   - floor: benches/pingpong.c, one short line each way through pipes, both processes
#     on one core ("same") and on two ("split");
#   - `mazearena run` of benches/trivial_bot.c, with and without the sandbox, started the
#     way a user starts it (no pinning by the caller). The bot idles for IDLE steps, then
#     plays the maze's optimal path, resets and plays it again, so the match finishes:
#     once with IDLE = 0 (85 steps) and once with IDLE = 900 (985 steps). Everything but
#     the steps (the process's start and exit, the sandbox's set-up and tear-down, the
#     bot's start) is the same in both, so
#       per step = (whole run with 900 more steps - whole run) / 900,
#     each whole run timed from the process's start to its exit, played as a user plays
#     a match (`--json`, no replay file; writing one costs about 0.4 µs a step more);
#       bot's clock = the mean time from one sense to the next over the idle steps, as the
#                  bot itself clocks them (benches/trivial_bot.c): a whole step (answer,
#                  the referee's work, the next sense) with nothing of the start or the
#                  end in it, so without the run-to-run noise of the sandbox's set-up
#                  that the difference carries; and
#       exchange = the mean answer time the referee measures over the idle steps (sense
#                  written to answer read; from the replay of a third run), the rest of
#                  a step being the referee's own work.
#   - the floor of a referee's duties: benches/referee_floor.c around the same bot makes
#     only the system calls of a step (the sense's write, the wait on stdout and stderr,
#     the answer's read, the bot's CPU time) and nothing else, measured by the bot's
#     clock: without the sandbox (the CPU clock of the bot's process), and with the bot
#     behind the sandbox's walls (bubblewrap's namespaces, the jail `mazearena
#     sandbox-exec`: uid, limits, Landlock, seccomp) in a cgroup whose CPU counter is
#     read at every step, as mazearena's sandbox does. What a referee can do per step
#     is this floor plus its own work (the JSON, the game, the trace).
#
# With BASELINE=path/to/an/earlier/mazearena, the same two matches are also played by
# that binary, in turn with this one, in both kinds of sandbox (rows marked "baseline").
#
#   bash benches/step_latency.sh [RUNS]      (default 11; needs gcc, bubblewrap, root and cgroup v1)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-11}
IDLE=900
BASELINE=${BASELINE:-}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/bot"
gcc -O2 -o "$tmp/bot/trivial_bot" benches/trivial_bot.c
gcc -O2 -o "$tmp/pingpong" benches/pingpong.c
gcc -O2 -o "$tmp/referee_floor" benches/referee_floor.c
# The jailed bot runs as another uid: it must reach its folder.
chmod 755 "$tmp" "$tmp/bot"
maze=$PWD/mazes/gen-16-s1.txt
# The optimal path, a reset, the path again: one answer a line.
./target/release/mazearena maze solve "$maze" --json | python3 -c '
import json, sys
path = [json.dumps(a, separators=(",", ":")) for a in json.load(sys.stdin)["actions"]]
print("\n".join(path + ["{\"reset\":true}"] + path))' >"$tmp/bot/script.txt"

run_match() { # $1: sandbox, $2: idle steps, $3: binary; prints "whole_us steps bot_clock_us"
  local a b
  a=$(date +%s%N)
  "$3" run --maze "$maze" --bot "./trivial_bot script.txt $2" \
    --bot-dir "$tmp/bot" --sandbox "$1" --json >"$tmp/r.json" 2>/dev/null
  b=$(date +%s%N)
  python3 - "$tmp/r.json" $(( (b - a) / 1000 )) "$2" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
idle = int(sys.argv[3])
assert r["status"] == "finished", r["status"]
clock = [l.split()[1] for l in r["stderr_tail"].splitlines() if l.startswith("idle_step_ns ")]
assert clock or idle <= 2, "the bot wrote no idle_step_ns line"
inside = int(clock[0]) / 1000 if clock else 0.0
print(f"{sys.argv[2]} {r['total_steps']} {inside:.2f}")
PY
}

exchange() { # $1: sandbox, $2: binary; prints the mean answer time over the idle steps
  "$2" run --maze "$maze" --bot "./trivial_bot script.txt $IDLE" \
    --bot-dir "$tmp/bot" --sandbox "$1" --replay "$tmp/r.json" --json >/dev/null 2>&1
  python3 - "$tmp/r.json" "$IDLE" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))["trace"]
idle = int(sys.argv[2])
print(f"{sum(s['answer_us'] for s in t[1:idle]) / (idle - 1):.1f}")
PY
}

jail=$PWD/target/release/mazearena
floor() { # $1: plain|sandbox -> the bot's clock in ns
  local bot=(./trivial_bot script.txt "$IDLE")
  if [ "$1" = plain ]; then
    (cd "$tmp/bot" && "$tmp/referee_floor" -- "${bot[@]}" 2>&1)
  else
    (cd "$tmp/bot" && "$tmp/referee_floor" --cgroup -- bwrap --unshare-ipc --unshare-pid \
      --unshare-net --unshare-uts --unshare-cgroup-try --die-with-parent --new-session \
      --ro-bind / / --dev /dev --proc /proc --chdir "$tmp/bot" -- \
      "$jail" sandbox-exec --uid 2000000000 --nproc 68 --fsize 67108864 -- "${bot[@]}" 2>&1)
  fi | awk '/^idle_step_ns /{print $2}'
}

for i in $(seq "$RUNS"); do
  echo "same $("$tmp/pingpong" same)"
  echo "split $("$tmp/pingpong" split)"
  for f in plain sandbox; do
    ns=$(floor "$f" || true)
    [ -z "$ns" ] || echo "floor-$f $ns"
  done
  for s in none full; do
    for bin in ./target/release/mazearena $BASELINE; do
      key=$s
      [ "$bin" = ./target/release/mazearena ] || key=base-$s
      # The short and the long run in turn, first one then the other, so that whatever
      # one run leaves the next (the kernel's clean-up of a sandbox) falls on both.
      if [ $((i % 2)) = 1 ]; then
        read -r short n0 _ < <(run_match "$s" 0 "$bin")
        read -r long n1 inside < <(run_match "$s" "$IDLE" "$bin")
      else
        read -r long n1 inside < <(run_match "$s" "$IDLE" "$bin")
        read -r short n0 _ < <(run_match "$s" 0 "$bin")
      fi
      [ $((n1 - n0)) = "$IDLE" ] || { echo "expected $IDLE more steps: $n0, $n1" >&2; exit 1; }
      answer=$(exchange "$s" "$bin")
      echo "$key $short $long $answer $inside"
    done
  done
done >"$tmp/all.txt"

python3 - "$tmp/all.txt" "$IDLE" <<'PY'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    k, *v = line.split()
    rows.setdefault(k, []).append([float(x) for x in v])
idle = int(sys.argv[2])
med = lambda k, f: statistics.median(f(r) for r in rows[k])
floor = med("same", lambda r: r[0])
n = len(rows["same"])
print(f"| measure ({n} runs each, medians) | µs per step | × same-core floor |")
print("|---|---:|---:|")
print(f"| pipe round trip, one core (the floor) | {floor:.1f} | 1.00 |")
split = med("split", lambda r: r[0])
print(f"| pipe round trip, two cores | {split:.1f} | {split / floor:.2f} |")
for k, name in [("floor-plain", "a referee of the step's system calls alone (benches/referee_floor.c): the bot's clock"),
                 ("floor-sandbox", "the same, the bot behind the sandbox's walls and in a cgroup whose CPU counter is read")]:
    if k not in rows:
        # referee_floor.c makes its cgroup as root, with cgroup v1.
        print(f"| {name} | not measured here (needs root and cgroup v1) | |")
        continue
    v = med(k, lambda r: r[0]) / 1000
    print(f"| {name} | {v:.1f} | {v / floor:.2f} |")
kinds = [("none", "--sandbox none"), ("full", "--sandbox full")]
if "base-none" in rows:
    kinds += [("base-none", "--sandbox none, the baseline binary"),
              ("base-full", "--sandbox full, the baseline binary")]
for k, name in kinds:
    step = med(k, lambda r: (r[1] - r[0]) / idle)
    inside = med(k, lambda r: r[3])
    exchange = med(k, lambda r: r[2])
    short = med(k, lambda r: r[0]) / 1000
    print(f"| `mazearena run` {name}: per step, the bot's clock | {inside:.1f} | {inside / floor:.2f} |")
    print(f"| `mazearena run` {name}: per step, difference of whole runs | {step:.1f} | {step / floor:.2f} |")
    print(f"| `mazearena run` {name}: exchange (answer time) | {exchange:.1f} | {exchange / floor:.2f} |")
    print(f"| `mazearena run` {name}: the 85-step match, whole run | {short:.1f} ms | |")
PY
