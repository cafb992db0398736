#!/usr/bin/env bash
# Per-step latency of a trivial compiled bot against the pipe round-trip floor, in the
# same run, taken in turn RUNS times (medians):
#   - floor: benches/pingpong.c, one short line each way through pipes, both processes
#     on one core ("same") and on two ("split");
#   - `mazearena run` of benches/trivial_bot.c (a 1000-step match), with and without the
#     sandbox, started the way a user starts it (no pinning by the caller):
#       whole run   = the process's wall time, start to exit, / 1000 steps;
#       per step    = (the match's wall time - the first answer, which includes the
#                     bot's start) / 999;
#       exchange    = the mean answer time of steps 2-1000 as the referee measures it
#                     (sense written to answer read).
#
#   bash benches/step_latency.sh [RUNS]      (default 11; needs gcc and bubblewrap)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-11}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/bot"
gcc -O2 -o "$tmp/bot/trivial_bot" benches/trivial_bot.c
gcc -O2 -o "$tmp/pingpong" benches/pingpong.c
maze=$PWD/mazes/gen-16-s1.txt

run_match() { # $1: sandbox; prints "whole_us per_step_us exchange_us"
  local a b
  a=$(date +%s%N)
  ./target/release/mazearena run --maze "$maze" --bot ./trivial_bot --bot-dir "$tmp/bot" \
    --sandbox "$1" --replay "$tmp/r.json" --json >/dev/null 2>&1
  b=$(date +%s%N)
  python3 - "$tmp/r.json" $(( (b - a) / 1000 )) <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["trace"]
assert r["status"] == "step_limit" and len(t) == 1000, r["status"]
whole = int(sys.argv[2]) / 1000
per_step = (r["timings"]["wall_ms"] * 1000 - t[0]["answer_us"]) / 999
exchange = sum(s["answer_us"] for s in t[1:]) / 999
print(f"{whole:.1f} {per_step:.1f} {exchange:.1f}")
EOF
}

for _ in $(seq "$RUNS"); do
  echo "same $("$tmp/pingpong" same)"
  echo "split $("$tmp/pingpong" split)"
  echo "none $(run_match none)"
  echo "full $(run_match full)"
done >"$tmp/all.txt"

python3 - "$tmp/all.txt" <<'EOF'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    k, *v = line.split()
    rows.setdefault(k, []).append([float(x) for x in v])
med = lambda k, i=0: statistics.median(r[i] for r in rows[k])
floor = med("same")
n = len(rows["same"])
print(f"| measure ({n} runs each, medians) | µs per step | × same-core floor |")
print("|---|---:|---:|")
print(f"| pipe round trip, one core (the floor) | {floor:.1f} | 1.0 |")
print(f"| pipe round trip, two cores | {med('split'):.1f} | {med('split') / floor:.1f} |")
for k, name in (("none", "--sandbox none"), ("full", "--sandbox full")):
    for i, what in ((0, "whole run / 1000"), (1, "per step in the match"), (2, "exchange (answer time)")):
        print(f"| `mazearena run` {name}: {what} | {med(k, i):.1f} | {med(k, i) / floor:.1f} |")
EOF
