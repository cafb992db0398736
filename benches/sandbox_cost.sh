#!/usr/bin/env bash
# Where the sandbox's cost per match goes, and what it costs a tournament:
#
# 1. A 100-step `mazearena run` of benches/trivial_bot.c (it idles 15 steps, then plays
#    gen-16-s1's optimal path twice), with and without the sandbox, taken in turn RUNS
#    times (medians; the cost is the median of the paired differences).
# 2. The sandboxed run's stages from the kernel's own timestamps (perf's sched and
#    syscall tracepoints, which cost nothing between events), medians of RUNS runs:
#      start      process start to the first cgroup folder (the same without the sandbox)
#      probe      the start-up test command in a whole sandbox (bubblewrap, the jail,
#                 `cat /proc/self/status`), when there is one
#      cgroup     the match's cgroups made and limited
#      enter      `mazearena sandbox-enter` (joins the cgroups) until bubblewrap's exec
#      bwrap      bubblewrap: namespaces, the view's mounts, until the jail's exec
#      jail       `mazearena sandbox-exec`: limits, uid, no_new_privs, Landlock, seccomp
#      match      the bot's exec to its exit (the steps)
#      exit       the bot's exit to bubblewrap's (the sandbox's processes end)
#      teardown   bubblewrap's exit to the runner's (cgroups removed, the record written)
# 3. A small tournament: the C starter kit's two bots (bots/c, built with make) on the
#    first 120 contest mazes (240 matches), `--jobs 2`, with and without the sandbox, and
#    in the sandbox with the pool off (MAZEARENA_SANDBOX_AHEAD=0: each match's network
#    namespace made on its start), in turn 5 times: wall time and the CPU the whole
#    machine was busy (/proc/stat: the kernel's own work for the sandbox, e.g. a network
#    namespace's clean-up, is done by kernel threads outside the match's processes).
#
# 4. A warm sandbox's cost per match (what servers, workers and tournaments pay, as root
#    with cgroups): the same 100-step match in a `tournament` of one slot (`--jobs 1`),
#    repeated 10 and 100 times, with and without the sandbox (and with the pool off), in
#    turn RUNS times; a match's cost is (100 repeats - 10 repeats) / 90 of each, so the
#    tournament's own start (and the sandbox's first start and test) is not in it.
# 5. The floor of a one-shot sandbox: bubblewrap making the same namespaces (PID,
#    network, IPC, UTS, mount) with only /usr in the view and running /usr/bin/true,
#    against /usr/bin/true alone, in turn (medians of the paired differences).
# 6. The floor of a warm match: benches/warm_floor.c starts /usr/bin/true 500 times
#    plainly, 500 times in a world of its own with the warm sandbox's mounts and walls
#    (and nothing of mazearena's), and 500 times in the same with a network namespace of
#    its own, in turn RUNS times: what the kernel's own work for a warm match's isolation
#    costs, beside what the C kit's tournament allows.
#
# With BASELINE=path/to/an/earlier/mazearena, each sandboxed measure is also taken with it,
# in turn with the others (its stages too).
#
#   bash benches/sandbox_cost.sh [RUNS]      (default 11; needs gcc, make, bubblewrap,
#                                             perf, root, and ../shared/mazes)
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
BASELINE=${BASELINE:-}
match() { # $1: sandbox, $2: binary -> whole run in µs
  local a b out
  a=$(date +%s%N)
  out=$("${2:-$bin}" run --maze "$maze" --bot "./trivial_bot script.txt $IDLE" --bot-dir "$tmp/bot" \
    --sandbox "$1" --json 2>/dev/null)
  b=$(date +%s%N)
  grep -q '"status":"finished"' <<<"$out" || { echo "unexpected: $out" >&2; exit 1; }
  echo $(((b - a) / 1000))
}
for i in $(seq "$RUNS"); do
  if [ $((i % 2)) = 1 ]; then n=$(match none) f=$(match full); else f=$(match full) n=$(match none); fi
  b=0
  [ -n "$BASELINE" ] && b=$(match full "$BASELINE")
  echo "$n $f $b"
done >"$tmp/whole.txt"

stages() { # $1: binary, $2: file prefix
  for i in $(seq "$RUNS"); do
    perf record -q -o "$tmp/perf.data" -e sched:sched_process_exec,sched:sched_process_exit \
      -e sched:sched_process_fork,syscalls:sys_enter_exit_group,syscalls:sys_enter_mkdir \
      -e syscalls:sys_enter_rmdir -- "$1" run --maze "$maze" --bot "./trivial_bot script.txt $IDLE" \
      --bot-dir "$tmp/bot" --sandbox full --json >/dev/null 2>&1
    perf script -i "$tmp/perf.data" -F comm,pid,time,event 2>/dev/null >"$tmp/$2.$i"
  done
}
stages "$bin" events
[ -z "$BASELINE" ] || stages "$BASELINE" before

# The tournament: the C kit's bots on the first 120 contest mazes.
make -s -C bots/c >/dev/null
mkdir "$tmp/mazes"
for f in $(ls ../shared/mazes/micromouseonline/classic | head -120); do
  ln -s "$PWD/../shared/mazes/micromouseonline/classic/$f" "$tmp/mazes/$f"
done
tournament() { # $1: sandbox, $2: binary, $3: networks made ahead -> "wall_ms busy_ms matches"
  local a b s0 s1 busy
  rm -f "$tmp"/t.db*
  s0=($(head -1 /proc/stat))
  a=$(date +%s%N)
  MAZEARENA_SANDBOX_AHEAD=${3:-1} "$2" tournament --bots bots/c --mazes "$tmp/mazes" --jobs 2 --sandbox "$1" \
    --database "sqlite://$tmp/t.db" --json >"$tmp/t.json" 2>/dev/null
  b=$(date +%s%N)
  s1=($(head -1 /proc/stat))
  busy=$(( (s1[1] + s1[2] + s1[3] + s1[6] + s1[7]) - (s0[1] + s0[2] + s0[3] + s0[6] + s0[7]) ))
  echo "$(( (b - a) / 1000000 )) $(( busy * 1000 / $(getconf CLK_TCK) )) $(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["matches"]))' "$tmp/t.json")"
}
for i in 1 2 3 4 5; do
  echo "none $(tournament none "$bin")"
  echo "full $(tournament full "$bin")"
  echo "pooloff $(tournament full "$bin" 0)"
  [ -z "$BASELINE" ] || echo "before $(tournament full "$BASELINE")"
done >"$tmp/tournament.txt"

# A warm sandbox's cost per match: one slot, 10 and 100 repeats of the 100-step match.
printf 'name = "trivial"\ncommand = "./trivial_bot script.txt %s"\n' "$IDLE" >"$tmp/bot/bot.toml"
repeats() { # $1: sandbox, $2: repeats, $3: networks made ahead -> wall µs
  local a b
  rm -f "$tmp"/w.db*
  a=$(date +%s%N)
  MAZEARENA_SANDBOX_AHEAD=${3:-1} "$bin" tournament --bots "$tmp/bot/bot.toml" --mazes "$maze" --repeats "$2" --jobs 1 \
    --sandbox "$1" --database "sqlite://$tmp/w.db" >"$tmp/w.out" 2>&1
  b=$(date +%s%N)
  grep -q "^$2/$2 matches" "$tmp/w.out" || { cat "$tmp/w.out" >&2; exit 1; }
  echo $(( (b - a) / 1000 ))
}
for i in $(seq "$RUNS"); do
  n10=$(repeats none 10) n100=$(repeats none 100) f10=$(repeats full 10) f100=$(repeats full 100)
  o10=$(repeats full 10 0) o100=$(repeats full 100 0)
  echo "$n10 $n100 $f10 $f100 $o10 $o100"
done >"$tmp/warm.txt"
# The one-shot floor: bubblewrap's namespaces around /usr/bin/true.
floor_ns=(--unshare-pid --unshare-net --unshare-ipc --unshare-uts --ro-bind /usr /usr)
for d in /bin /lib /lib64 /sbin; do
  if [ -L "$d" ]; then floor_ns+=(--symlink "$(readlink "$d")" "$d"); fi
done
timed() { local a b; a=$(date +%s%N); "$@" >/dev/null 2>&1; b=$(date +%s%N); echo $(( (b - a) / 1000 )); }
for i in $(seq $((RUNS * 3))); do
  echo "$(timed /usr/bin/true) $(timed bwrap "${floor_ns[@]}" /usr/bin/true)"
done >"$tmp/floor.txt"

# The floor of a warm match (benches/warm_floor.c): 500 rounds of /usr/bin/true in the
# C kit's folder, started plainly and in a world of its own with the warm sandbox's
# walls, in turn; wall time and the machine's CPU time a round.
gcc -O2 -o "$tmp/warm_floor" benches/warm_floor.c
mkdir "$tmp/wf"
chmod 755 "$tmp" "$tmp/wf"
for i in $(seq "$RUNS"); do
  echo "$("$tmp/warm_floor" plain 500 "$tmp/wf" "$PWD/bots/c" /usr/bin/true) $("$tmp/warm_floor" isolated 500 "$tmp/wf" "$PWD/bots/c" /usr/bin/true) $("$tmp/warm_floor" isolated-net 500 "$tmp/wf" "$PWD/bots/c" /usr/bin/true)"
done >"$tmp/warm_floor.txt"

python3 - "$tmp" "$RUNS" "$BASELINE" <<'PY'
import os, statistics, sys
tmp, runs, baseline = sys.argv[1], int(sys.argv[2]), sys.argv[3]
whole = [tuple(int(x) for x in l.split()) for l in open(f"{tmp}/whole.txt")]
med = statistics.median
none, full = med(w[0] for w in whole), med(w[1] for w in whole)
cost = med(w[1] - w[0] for w in whole)
print(f"| measure ({runs} runs each, in turn, medians) | ms |")
print("|---|---:|")
print(f"| `mazearena run`, 100 steps, `--sandbox none` | {none / 1000:.2f} |")
print(f"| `mazearena run`, 100 steps, `--sandbox full` | {full / 1000:.2f} |")
print(f"| the sandbox's cost per match (paired differences) | **{cost / 1000:.2f}** |")
if baseline:
    print(f"| `--sandbox full`, the baseline binary | {med(w[2] for w in whole) / 1000:.2f} |")
    print(f"| the baseline's cost per match (paired differences) | {med(w[2] - w[0] for w in whole) / 1000:.2f} |")
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
before = [stages(f"{tmp}/before.{i}") for i in range(1, runs + 1)] if baseline else None
print(f"| stage of a sandboxed 100-step run ({runs} runs, medians) | ms |" + (" baseline (ms) |" if before else ""))
print("|---|---:|" + ("---:|" if before else ""))
for k in rows[0]:
    b = f" {med(r[k] for r in before) * 1000:.2f} |" if before else ""
    print(f"| {k} | {med(r[k] for r in rows) * 1000:.2f} |{b}")
b = f" {med(sum(r.values()) for r in before) * 1000:.2f} |" if before else ""
print(f"| the whole run, by the trace | {med(sum(r.values()) for r in rows) * 1000:.2f} |{b}")
print()
t = {}
for line in open(f"{tmp}/tournament.txt"):
    k, *v = line.split()
    t.setdefault(k, []).append([int(x) for x in v])
print(f"| tournament: C kit, 240 matches, `--jobs 2` ({len(t['none'])} runs each, in turn, medians) | wall (s) | matches/s | × without the sandbox | machine busy (CPU s) |")
print("|---|---:|---:|---:|---:|")
base = med(r[0] for r in t["none"])
names = {"none": "`--sandbox none`", "full": "`--sandbox full`", "pooloff": "`--sandbox full`, the pool off (`MAZEARENA_SANDBOX_AHEAD=0`)", "before": "`--sandbox full`, the baseline binary"}
for k in t:
    wall = med(r[0] for r in t[k])
    n = t[k][0][2]
    print(f"| {names[k]} | {wall / 1000:.2f} | {n / wall * 1000:.0f} | {base / wall:.2f} | {med(r[1] for r in t[k]) / 1000:.2f} |")
print()
warm = [tuple(int(x) for x in l.split()) for l in open(f"{tmp}/warm.txt")]
per = lambda a, b: [(w[b] - w[a]) / 90 for w in warm]
n_match, f_match, o_match = per(0, 1), per(2, 3), per(4, 5)
print(f"| a warm sandbox: the 100-step match in a one-slot tournament, (100 - 10 repeats) / 90 ({runs} runs, in turn, medians) | ms a match |")
print("|---|---:|")
print(f"| `--sandbox none` | {med(n_match) / 1000:.2f} |")
print(f"| `--sandbox full` (a warm sandbox) | {med(f_match) / 1000:.2f} |")
print(f"| the warm sandbox's cost per match (paired differences) | **{med(f - n for f, n in zip(f_match, n_match)) / 1000:.2f}** |")
print(f"| `--sandbox full`, the pool off (`MAZEARENA_SANDBOX_AHEAD=0`) | {med(o_match) / 1000:.2f} |")
print(f"| the warm sandbox's cost per match, the pool off (paired differences) | {med(o - n for o, n in zip(o_match, n_match)) / 1000:.2f} |")
print()
wf = [tuple(float(x) for x in l.split()) for l in open(f"{tmp}/warm_floor.txt")]
wf_wall = med(r[2] - r[0] for r in wf)
wf_cpu = med(r[3] - r[1] for r in wf)
wfn_wall = med(r[4] - r[0] for r in wf)
wfn_cpu = med(r[5] - r[1] for r in wf)
print(f"| the floor of a warm match: benches/warm_floor.c, 500 rounds of `/usr/bin/true` ({len(wf)} runs, in turn, medians) | wall (ms a round) | the machine's CPU (ms a round) |")
print("|---|---:|---:|")
print(f"| started plainly (`posix_spawn`) | {med(r[0] for r in wf):.3f} | {med(r[1] for r in wf):.3f} |")
print(f"| in new PID, mount and IPC namespaces with the warm sandbox's mounts and walls | {med(r[2] for r in wf):.3f} | {med(r[3] for r in wf):.3f} |")
print(f"| the floor of a warm match's isolation (paired differences) | **{wf_wall:.3f}** | **{wf_cpu:.3f}** |")
print(f"| the same in a network namespace of its own (loopback up) | {med(r[4] for r in wf):.3f} | {med(r[5] for r in wf):.3f} |")
print(f"| the floor with a network namespace of its own (paired differences) | **{wfn_wall:.3f}** | **{wfn_cpu:.3f}** |")
print()
none_cpu = med(r[1] for r in t["none"]) / t["none"][0][2]
full_cpu = med(r[1] for r in t["full"]) / t["full"][0][2]
print(f"The C kit's match takes {none_cpu:.2f} ms of the machine's CPU without the sandbox and {full_cpu:.2f} ms in it (the tournament above): "
      f"0.95x its throughput allows {none_cpu / 0.95 - none_cpu:.2f} ms more a match; "
      f"a sandbox that did only the floor's work would be at {none_cpu / (none_cpu + wf_cpu):.2f}x without a network namespace of each match's own "
      f"and at {none_cpu / (none_cpu + wfn_cpu):.2f}x with one.")
print()
floor = [tuple(int(x) for x in l.split()) for l in open(f"{tmp}/floor.txt")]
print(f"| the one-shot floor ({len(floor)} runs, in turn, medians) | ms |")
print("|---|---:|")
print(f"| `/usr/bin/true` | {med(f[0] for f in floor) / 1000:.2f} |")
print(f"| `bwrap` (PID, network, IPC, UTS, mount namespaces; `/usr` only) `/usr/bin/true` | {med(f[1] for f in floor) / 1000:.2f} |")
print(f"| bubblewrap's namespaces alone (paired differences) | **{med(f[1] - f[0] for f in floor) / 1000:.2f}** |")
print()
print(f"A one-shot match's sandbox ({cost / 1000:.2f} ms, the first table) is {cost / med(f[1] - f[0] for f in floor):.2f}x bubblewrap's own start.")
PY
