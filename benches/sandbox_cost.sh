#!/usr/bin/env bash
# Where the sandbox's cost per match goes: a 100-step `mazearena run` of
# benches/trivial_bot.c (it idles 15 steps, then plays gen-16-s1's optimal path twice),
# with and without the sandbox, taken in turn RUNS times (medians; the cost is the median
# of the paired differences), then the sandboxed run's stages from the kernel's own
# timestamps (perf's sched and syscall tracepoints, which cost nothing between events):
#
#   start        process start to the first cgroup made (the same without the sandbox)
#   probe        the start-up check: a cgroup made and removed, then a command run in a
#                whole sandbox (bubblewrap, the jail, `cat /proc/self/status`)
#   cgroup       the match's cgroups made and limited
#   enter        `mazearena sandbox-enter` (joins the cgroups) until bubblewrap's exec
#   bwrap        bubblewrap: namespaces, the view's mounts, until the jail's exec
#   jail         `mazearena sandbox-exec`: limits, uid, no_new_privs, Landlock, seccomp
#   match        the bot's exec to its exit (the steps)
#   exit         the bot's exit to bubblewrap's (the sandbox's processes end)
#   teardown     bubblewrap's exit to the runner's (cgroups removed, the record written)
#
#   bash benches/sandbox_cost.sh [RUNS]      (default 11; needs gcc, bubblewrap, perf, root)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-11}
IDLE=15
cargo build --release --locked --quiet
bin=$PWD/target/release/mazearena
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/bot"
gcc -O2 -o "$tmp/bot/trivial_bot" benches/trivial_bot.c
maze=$PWD/mazes/gen-16-s1.txt
"$bin" maze solve "$maze" --json | python3 -c '
import json, sys
path = [json.dumps(a, separators=(",", ":")) for a in json.load(sys.stdin)["actions"]]
print("\n".join(path + ["{\"reset\":true}"] + path))' >"$tmp/bot/script.txt"
match() { # $1: sandbox -> whole run in µs
  local a b out
  a=$(date +%s%N)
  out=$("$bin" run --maze "$maze" --bot "./trivial_bot script.txt $IDLE" --bot-dir "$tmp/bot" \
    --sandbox "$1" --json 2>/dev/null)
  b=$(date +%s%N)
  grep -q '"status":"finished"' <<<"$out" || { echo "unexpected: $out" >&2; exit 1; }
  echo $(((b - a) / 1000))
}
for i in $(seq "$RUNS"); do
  if [ $((i % 2)) = 1 ]; then n=$(match none) f=$(match full); else f=$(match full) n=$(match none); fi
  echo "$n $f"
done >"$tmp/whole.txt"

for i in $(seq "$RUNS"); do
  perf record -q -o "$tmp/perf.data" -e sched:sched_process_exec,sched:sched_process_exit \
    -e sched:sched_process_fork,syscalls:sys_enter_exit_group,syscalls:sys_enter_mkdir \
    -e syscalls:sys_enter_rmdir -- "$bin" run --maze "$maze" --bot "./trivial_bot script.txt $IDLE" \
    --bot-dir "$tmp/bot" --sandbox full --json >/dev/null 2>&1
  perf script -i "$tmp/perf.data" -F comm,pid,time,event 2>/dev/null >"$tmp/events.$i"
done

python3 - "$tmp" "$RUNS" <<'PY'
import statistics, sys
tmp, runs = sys.argv[1], int(sys.argv[2])
whole = [tuple(int(x) for x in l.split()) for l in open(f"{tmp}/whole.txt")]
med = statistics.median
none, full = med(w[0] for w in whole), med(w[1] for w in whole)
cost = med(w[1] - w[0] for w in whole)
print(f"| measure ({runs} runs each, in turn, medians) | ms |")
print("|---|---:|")
print(f"| `mazearena run`, 100 steps, `--sandbox none` | {none / 1000:.2f} |")
print(f"| `mazearena run`, 100 steps, `--sandbox full` | {full / 1000:.2f} |")
print(f"| the sandbox's cost per match (paired differences) | **{cost / 1000:.2f}** |")
print()

def stages(path):
    ev = []
    for line in open(path):
        parts = line.split()
        comm, pid, t, event = parts[0], int(parts[1]), float(parts[2].rstrip(":")), parts[3].rstrip(":")
        ev.append((t, comm, pid, event))
    t0 = ev[0][0]  # the runner's exec
    runner = ev[0][2]
    first = lambda f, after=0.0: next(e for e in ev if e[0] >= after and f(e))
    mk = first(lambda e: e[2] == runner and e[3].endswith("sys_enter_mkdir"))
    # The match's sandbox is the last fork of the runner; the probe's is before it.
    forks = [e for e in ev if e[2] == runner and e[3].endswith("sched_process_fork")]
    spawn = forks[-1]
    # The match cgroup's first mkdir after the probe's sandbox ended.
    before = [e for e in ev if e[2] == runner and e[3].endswith("sys_enter_mkdir") and e[0] < spawn[0]]
    # The last run of consecutive mkdirs before the spawn are the match's cgroups.
    cg = before[-1]
    i = len(before) - 1
    while i > 0 and before[i][0] - before[i - 1][0] < 0.002:
        i -= 1
    cg_start = before[i]
    execs = [e for e in ev if e[3].endswith("sched_process_exec") and e[0] > spawn[0]]
    bwrap = next(e for e in execs if e[1] == "bwrap")
    jail = next(e for e in execs if e[0] > bwrap[0] and e[1] == "mazearena")
    bot = next(e for e in execs if e[0] > jail[0] and e[1] != "mazearena")
    bot_exit = first(lambda e: e[2] == bot[2] and e[3].endswith("sys_enter_exit_group"), bot[0])
    exits = [e for e in ev if e[3].endswith("sched_process_exit") and e[0] > bot_exit[0] and e[1] == "bwrap"]
    bw_exit = exits[-1]
    end = ev[-1][0]
    return {
        "start": mk[0] - t0,
        "probe": cg_start[0] - mk[0],
        "cgroup": spawn[0] - cg_start[0],
        "enter": bwrap[0] - spawn[0],
        "bwrap": jail[0] - bwrap[0],
        "jail": bot[0] - jail[0],
        "match": bot_exit[0] - bot[0],
        "exit": bw_exit[0] - bot_exit[0],
        "teardown": end - bw_exit[0],
    }

rows = [stages(f"{tmp}/events.{i}") for i in range(1, runs + 1)]
print(f"| stage of a sandboxed 100-step run ({runs} runs, medians) | ms |")
print("|---|---:|")
for k in rows[0]:
    print(f"| {k} | {med(r[k] for r in rows) * 1000:.2f} |")
print(f"| the whole run, by the trace | {med(sum(r.values()) for r in rows) * 1000:.2f} |")
PY
