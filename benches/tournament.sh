#!/usr/bin/env bash
# Tournament throughput and memory: the two shipped Rust bots (bots/rust: the champion
# and the minimal bot) on every contest maze of ../shared/mazes/micromouseonline/classic
# (1,012 matches: 506 distinct mazes, duplicates once), with `--jobs 1` and `--jobs 2`,
# with and without the sandbox. The four settings are taken in turn RUNS times (medians
# of the wall time, start to exit); the peak resident memory of the mazearena process
# (VmHWM, read from /proc while it runs) is the largest of each setting's runs. The CPU
# time of the process and its bots (user + system, read from /proc/PID/stat at the last
# look before its exit; without the sandbox only: sandboxed bots are reaped inside the
# sandbox, so their CPU time does not reach the count) shows whether the same work cost
# more CPU in a run: on the project's 2-core VM, some `--jobs 2` runs take 10-20% more
# CPU seconds than others for the same matches (no steal time is reported).
# The machine's own scaling is measured beside it, in each round: benches/spin.c (CPU
# work only, no I/O) once alone and as two copies at once, one per core.
#
#   bash benches/tournament.sh [RUNS]      (default 3; about 2 minutes a round)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-3}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd bots/rust && CARGO_TARGET_DIR="$PWD/target" cargo build --release --quiet)
gcc -O2 -o "$tmp/spin" benches/spin.c
SPIN_STEPS=300000000

spin() { # $1: copies at once; prints the wall ms until the last ends
  local a b pids=()
  a=$(date +%s%N)
  for ((c = 0; c < $1; c++)); do "$tmp/spin" "$SPIN_STEPS" & pids+=($!); done
  wait "${pids[@]}"
  b=$(date +%s%N)
  echo $(( (b - a) / 1000000 ))
}

run() { # $1: jobs, $2: sandbox; prints "ms peak_kib matches cpu_ticks"
  local db=$tmp/t-$1-$2.db a b pid peak=0 hwm ticks=0 t
  rm -f "$db"*
  a=$(date +%s%N)
  ./target/release/mazearena tournament --bots bots/rust \
    --mazes ../shared/mazes/micromouseonline/classic --jobs "$1" --sandbox "$2" \
    --database "sqlite://$db" --json >"$tmp/out.json" 2>"$tmp/err.log" &
  pid=$!
  while kill -0 "$pid" 2>/dev/null; do
    hwm=$(awk '/^VmHWM/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    [ -n "$hwm" ] && [ "$hwm" -gt "$peak" ] && peak=$hwm
    t=$(awk '{print $14 + $15 + $16 + $17}' "/proc/$pid/stat" 2>/dev/null || true)
    [ -n "$t" ] && ticks=$t
    sleep 0.05
  done
  wait "$pid" || { cat "$tmp/err.log" >&2; exit 1; }
  b=$(date +%s%N)
  matches=$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['matches']))" "$tmp/out.json")
  echo "$(( (b - a) / 1000000 )) $peak $matches $ticks"
}

HZ=$(getconf CLK_TCK)
declare -A WALL PEAK CPU SPIN
SETTINGS=("1 none" "2 none" "1 full" "2 full")
for ((i = 1; i <= RUNS; i++)); do
  for k in 1 2; do
    ms=$(spin "$k")
    echo "round $i: spin, $k at once: $ms ms" >&2
    SPIN[$k]+="$ms "
  done
  for s in "${SETTINGS[@]}"; do
    # shellcheck disable=SC2086
    read -r ms kib n ticks < <(run $s)
    echo "round $i: jobs ${s% *}, sandbox ${s#* }: ${ms} ms, peak ${kib} KiB, $n matches, cpu $ticks ticks" >&2
    WALL[$s]+="$ms "
    PEAK[$s]+="$kib "
    CPU[$s]+="$((ticks * 1000 / HZ)) "
    MATCHES=$n
  done
done

echo "## Tournament throughput and memory"
echo
echo "\`bash benches/tournament.sh $RUNS\`: the two shipped Rust bots on every contest maze"
echo "($MATCHES matches a tournament), the four settings taken in turn $RUNS times; medians"
echo "of the whole command's wall time and of its CPU time (the process and its bots,"
echo "user + system); peak resident memory (VmHWM) of the mazearena process, the largest of"
echo "the runs. Each run's figures are in the log of \`benches/run.sh\`."
echo
python3 - "$MATCHES" "${WALL[1 none]}" "${WALL[2 none]}" "${WALL[1 full]}" "${WALL[2 full]}" \
  "${PEAK[1 none]}" "${PEAK[2 none]}" "${PEAK[1 full]}" "${PEAK[2 full]}" \
  "${CPU[1 none]}" "${CPU[2 none]}" "${CPU[1 full]}" "${CPU[2 full]}" "${SPIN[1]}" "${SPIN[2]}" <<'PY'
import statistics, sys
n = int(sys.argv[1])
walls = [statistics.median(map(int, a.split())) for a in sys.argv[2:6]]
peaks = [max(map(int, a.split())) for a in sys.argv[6:10]]
cpus = [statistics.median(map(int, a.split())) for a in sys.argv[10:14]]
spin1, spin2 = (statistics.median(map(int, a.split())) for a in sys.argv[14:16])
names = ["--jobs 1, --sandbox none", "--jobs 2, --sandbox none",
         "--jobs 1, --sandbox full", "--jobs 2, --sandbox full"]
print("| setting | wall | matches per minute | CPU time | peak memory |")
print("|---|---:|---:|---:|---:|")
for name, w, c, p in zip(names, walls, cpus, peaks):
    cpu = f"{c / 1000:.1f} s" if "none" in name else "(in the sandbox)"
    print(f"| {name} | {w / 1000:.1f} s | {n * 60000 / w:.0f} | {cpu} | {p / 1024:.1f} MiB |")
print()
print(f"The machine's own scaling, measured in the same rounds: benches/spin.c (CPU work, "
      f"no I/O) takes {spin1 / 1000:.2f} s alone and {spin2 / 1000:.2f} s as two copies at once: "
      f"{2 * spin1 / spin2:.2f}x.")
print()
def rounds(one, two):
    pairs = zip(map(int, sys.argv[one].split()), map(int, sys.argv[two].split()))
    return ", ".join(f"{a / b:.2f}x" for a, b in pairs)
spins = [2 * a / b for a, b in zip(map(int, sys.argv[14].split()), map(int, sys.argv[15].split()))]
print(f"Round by round (each round's `--jobs 1` over its `--jobs 2`): without the sandbox "
      f"{rounds(2, 3)}; with it {rounds(4, 5)}; spin.c {', '.join(f'{x:.2f}x' for x in spins)}.")
print()
print(f"Scaling `--jobs 2` / `--jobs 1`: {walls[0] / walls[1]:.2f}x without the sandbox, "
      f"{walls[2] / walls[3]:.2f}x with it (target: at least 1.9x). The sandbox costs "
      f"{(walls[3] / walls[1] - 1) * 100:.0f}% of the wall time with two jobs "
      f"({(walls[3] - walls[1]) * 2 / n:.1f} ms of a core per match). Without the sandbox the "
      f"same matches took {(cpus[1] / cpus[0] - 1) * 100:+.0f}% CPU time at `--jobs 2` against "
      f"`--jobs 1`.")
PY
