#!/usr/bin/env bash
# Runs every benchmark and writes BENCHMARKS.md (date, machine, commit, then one section
# a benchmark, each figure beside its floor or baseline measured in the same run), and
# from it the capacity plan of docs/DEPLOY.md (benches/capacity.py). BENCHMARKS.md is
# wholly this script's: the analysis of the figures, with earlier runs' figures
# (dated), lives in docs/PERFORMANCE.md.
#
#   bash benches/run.sh            (about an hour on 2 cores)
#   bash benches/run.sh --quick    (a few minutes: fewer runs, smaller databases and
#                                   samples; to check the scripts, not for the figures)
#
# Needs gcc, python3, bubblewrap, wrk, nginx and PostgreSQL's server binaries
# (`apt-get install -y bubblewrap wrk nginx postgresql`; Locust comes from PyPI),
# and ../shared/mazes beside the checkout. Run it on a quiet machine:
# the figures are medians of runs taken in turn, but a busy core still shows.
set -euo pipefail
cd "$(dirname "$0")/.."
QUICK=${1:-}
if [ "$QUICK" = --quick ]; then
  RUNS=3 STEP_RUNS=3 PAGE_SIZES="1000" PAGE_RUNS=5 EVERY=17 T_RUNS=1 OVERHEAD=5
  HTTP_ARGS=(1000 1 2) RUSH_STUDENTS=30 ADAPTER_RUNS=1 WORKER_ARGS=(1 2) IDLE_ARGS=(1 2) CLAIM_RUNS=20 KIT_ARGS=(1 5)
else
  RUNS=5 STEP_RUNS=11 PAGE_SIZES="1000 100000 1000000" PAGE_RUNS=21 EVERY=1 T_RUNS=3 OVERHEAD=20
  HTTP_ARGS=() RUSH_STUDENTS=300 ADAPTER_RUNS=11 WORKER_ARGS=(3 12) IDLE_ARGS=(3 5) CLAIM_RUNS=200 KIT_ARGS=(3 40)
fi
out=$(mktemp)
trap 'rm -f "$out"' EXIT
log() { echo "== $*" >&2; }

cargo build --release --locked --quiet
commit=$(git rev-parse --short HEAD)
git diff --quiet HEAD -- src migrations Cargo.toml Cargo.lock || commit="$commit (with local changes)"
cpu=$(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo)
mem=$(awk '/^MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)
virt=$(systemd-detect-virt 2>/dev/null || echo "unknown")
{
  echo "# Benchmarks"
  echo
  echo "Written by \`bash benches/run.sh\` on $(date -u +%Y-%m-%d) at commit $commit:"
  echo "$(nproc) cores ($cpu), $mem, Linux $(uname -r) (virtualization: $virt),"
  echo "$(rustc --version | cut -d' ' -f1-2), release build, as $(id -un)."
  echo "Each figure stands beside its floor or baseline, measured in the same run, taken in"
  echo "turn with it; the scripts named in each section reproduce it alone."
  echo
} >"$out"

log "engine and solver (criterion)"
cargo bench --locked --bench engine -- --warm-up-time 1 --measurement-time 3 >&2
python3 - >>"$out" <<'PY'
import json, os
def median_ns(group, name):
    path = os.path.join("target", "criterion", group, name, "new", "estimates.json")
    return json.load(open(path))["median"]["point_estimate"]
engine = median_ns("game_1000_steps", "engine")
both = median_ns("game_1000_steps", "engine_and_protocol")
print("## The referee alone (criterion)")
print()
print("`cargo bench --bench engine` (benches/engine.rs): medians of criterion's samples.")
print()
print("| measure | time | per step | steps per second |")
print("|---|---:|---:|---:|")
print(f"| a 1000-step game (engine only) | {engine / 1000:.1f} µs | {engine / 1000:.0f} ns | {1e12 / engine:,.0f} |")
print(f"| the same with each step's protocol lines (sense encoded, answer decoded) | {both / 1000:.1f} µs | {both / 1000:.0f} ns | {1e12 / both:,.0f} |")
print()
print("| classic maze | reading the file (baseline) | solving it (fewest run-1 steps) |")
print("|---|---:|---:|")
for m in ("test_maze_01", "test_maze_02", "test_maze_03"):
    print(f"| {m} | {median_ns('solver', m + '_read') / 1000:.1f} µs | {median_ns('solver', m + '_solve') / 1000:.1f} µs |")
print()
PY

log "per-step latency"
{
  echo "## Per-step latency against the pipe floor"
  echo
  echo "\`bash benches/step_latency.sh $STEP_RUNS\`: benches/trivial_bot.c in \`mazearena run\`, started as a"
  echo "user starts it (no pinning by the caller), beside benches/pingpong.c (one short line each"
  echo "way through pipes between two processes), taken in turn. The bot idles, then plays the"
  echo "optimal path twice, so the match finishes: once after 85 steps, once after 985. Per step"
  echo "is measured two ways: by the bot's own clock (the mean time from one sense to the next"
  echo "over its idle steps: a whole step, with nothing of the start or the end in it), and as"
  echo "the difference of the two whole runs (process start to exit, played as a user plays a"
  echo "match: \`--json\`, no replay file) over the 900 more steps, which also holds everything the"
  echo "referee does per step but carries the run-to-run noise of the start and the sandbox's"
  echo "set-up. \"Exchange\" is the answer time the referee measures (sense written to answer"
  echo "read). Beside the pipe floor, the floor of a referee's duties: benches/referee_floor.c"
  echo "around the same bot makes only a step's system calls (the sense's write, the wait on"
  echo "stdout and stderr, the answer's read, the bot's CPU time), without and with the"
  echo "sandbox's walls and cgroup. Targets: per step at most 1.5x the same-core floor by the"
  echo "bot's clock and 2x by the difference of whole runs."
  echo
  bash benches/step_latency.sh "$STEP_RUNS"
  echo
} >>"$out"

log "the original tester's way against the adapter"
{ bash benches/adapter.sh "$ADAPTER_RUNS"; echo; } >>"$out"

log "tournaments"
{ bash benches/tournament.sh "$T_RUNS"; echo; } >>"$out"

log "matches a minute per core, by language"
{ bash benches/kits.sh "${KIT_ARGS[@]}"; echo; } >>"$out"

log "throughput across worker processes on PostgreSQL"
{ bash benches/workers.sh "${WORKER_ARGS[@]}"; echo; } >>"$out"

log "the sandbox's cost per match"
{
  echo "## The sandbox's cost per match"
  echo
  echo "\`bash benches/match_overhead.sh $OVERHEAD\`: one whole \`mazearena run\` of a trivial compiled"
  echo "bot (a 1000-step match, process start to exit), baseline first and last."
  echo
  bash benches/match_overhead.sh "$OVERHEAD" | sed 's/^/    /'
  echo
  echo "### Where it goes"
  echo
  echo "\`bash benches/sandbox_cost.sh $STEP_RUNS\`: a 100-step \`mazearena run\` (a one-shot sandbox) with and"
  echo "without the sandbox in turn, the sandboxed run's stages from perf's tracepoints, a 240-match"
  echo "tournament of the C kit, the same 100-step match played over and over in a one-slot"
  echo "tournament (a warm sandbox: its cost per match), and the floor of any one-shot sandbox"
  echo "(bubblewrap's namespaces around \`/usr/bin/true\`). The script's header says what each holds."
  echo
  if command -v perf >/dev/null 2>&1; then
    bash benches/sandbox_cost.sh "$STEP_RUNS"
  else
    echo "(not measured: perf is not installed)"
  fi
  echo
  echo "\`bash benches/oneshot_floor.sh\`: bubblewrap's bare start beside the least view any bot runs"
  echo "in and a one-shot match's whole view, each around \`/usr/bin/true\`."
  echo
  bash benches/oneshot_floor.sh
  echo
} >>"$out"

log "a race of 100 robots in Chromium"
{
  echo "## A race of 100 robots in Chromium"
  echo
  echo "\`bash benches/race.sh 100\`: a tournament of 100 bots on one 16 x 16 maze, its race as one offline"
  echo "file, beside the same file with one robot (the baseline); the script's header says what each holds."
  echo
  if command -v chromedriver >/dev/null 2>&1; then
    bash benches/race.sh 100
  else
    echo "(not measured: chromedriver is not installed)"
  fi
  echo
} >>"$out"

log "HTTP under load"
{ bash benches/http.sh "${HTTP_ARGS[@]}"; echo; } >>"$out"

log "the deadline rush"
{ bash benches/rush.sh "$RUSH_STUDENTS"; echo; } >>"$out"

log "idle connections"
{
  echo "## With 1,000 idle connections open"
  echo
  echo "\`bash benches/idle.sh ${IDLE_ARGS[*]}\`: \`GET /healthz\` and \`GET /api/leaderboard?scope=all\` on a"
  echo "fresh server (SQLite, the default mazes, one match worker), wrk \`-t 2 -c 32\` from 127.0.0.1,"
  echo "without and then with 1,000 idle connections held open from 127.0.0.2-127.0.0.5 (250 each,"
  echo "under the per-address cap; each sent half a request line and is opened again when the"
  echo "server closes it at its 10 s head timeout), in turn in one run:"
  echo
  bash benches/idle.sh "${IDLE_ARGS[@]}"
  echo
} >>"$out"

log "the fair claim"
{ python3 benches/claim.py "$CLAIM_RUNS"; echo; } >>"$out"

log "ranking throughput"
{
  echo "## Competitions: ranking and the close"
  echo
  echo "\`bash benches/competition.sh $T_RUNS\`, \`--jobs 2\`, full sandbox, one server. First: the time from a"
  echo "version's upload to its full public standing (10 public mazes x 3 repeats), beside the same 30"
  echo "matches queued as a plain tournament on the same server in the same round (the floor). Then the"
  echo "close: 100 entrants with a bot each; the private set (4 mazes) is played only by the final run,"
  echo "after the close: the time from the close to the results, beside the same 400 matches as a plain"
  echo "tournament in the same round (the floor)."
  echo
  bash benches/competition.sh "$T_RUNS"
  echo
} >>"$out"

log "pages one request at a time"
{
  echo "## Pages, one request at a time"
  echo
  echo "\`bash benches/pages.sh N $PAGE_RUNS\`: a database of N matches filled by benches/fill_db.py"
  echo "(copies of one real tournament of the shipped bots on the shipped mazes); one request at"
  echo "a time with curl, the routes taken in turn; \`/healthz\` is the floor."
  echo
  for n in $PAGE_SIZES; do
    bash benches/pages.sh "$n" "$PAGE_RUNS"
    echo
  done
} >>"$out"

log "ranked standings"
{
  echo "## Ranked standings: making the table and keeping it"
  echo
  echo "\`bash benches/rankings.sh N $RUNS\`: on the database of benches/pages.sh, a fresh server per"
  echo "run; the first answer makes the table (intervals, possible ranks, tie groups: every"
  echo "counted match read, grouped by version, maze and seed, and bootstrapped), the next ones"
  echo "reuse it until a match ends; \`/healthz\` is the floor."
  echo
  for n in $PAGE_SIZES; do
    bash benches/rankings.sh "$n" "$RUNS"
    echo
  done
} >>"$out"

log "the page cache"
{
  echo "## The page cache: what a read-latency probe still carries"
  echo
  echo "\`bash benches/page_cache.sh $T_RUNS\`: \`mincore\`, \`cachestat\`, \`preadv2\`/\`pwritev2\` with"
  echo "\`RWF_NOWAIT\` and Linux AIO are refused in matches and builds; what remains is timing a read."
  echo "A sender match (\`mazearena run\`, full sandbox) reads page 16k of a large file of /usr for each"
  echo "1 of a random message (readahead off); a later receiver match, in another sandbox, times a"
  echo "one-byte read of each such page. The file is dropped from the cache before each round (as"
  echo "root, outside the sandbox: a stand-in for a file nobody read lately). The bits a match carries"
  echo "are N x (1 - H(error rate)). What this means for sealed results: docs/SECURITY.md."
  echo
  bash benches/page_cache.sh "$T_RUNS"
  echo
} >>"$out"

log "bytes per stored match"
{
  echo "## Bytes per stored match"
  echo
  which="every contest maze"
  [ "$EVERY" = 1 ] || which="every ${EVERY}th contest maze"
  echo "\`bash benches/storage.sh $EVERY\`: a tournament of every shipped bot on $which"
  echo "of ../shared/mazes/micromouseonline/classic, then the database's bytes per match. Target:"
  echo "at most 4 KB a match. Release 0.1.0 stored 122,400 B a match here (record and trace as"
  echo "JSON in the match row; measured on a 30-maze sample)."
  echo
  bash benches/storage.sh "$EVERY" | sed 's/^/    /'
  echo
} >>"$out"

{
  echo "## Reading these figures"
  echo
  echo "Where a match's time goes in the sandbox, what was changed for it and what was tried"
  echo "and dropped, with the figures of earlier runs (each dated, with its commit), is in"
  echo "docs/PERFORMANCE.md."
} >>"$out"

mv "$out" BENCHMARKS.md
chmod 644 BENCHMARKS.md
trap - EXIT
log "wrote BENCHMARKS.md"

# The capacity plan in docs/DEPLOY.md and the scaler's ceiling are read from these figures
# (a test checks that they agree): written again from a whole run, not from --quick's.
if [ "$QUICK" != --quick ]; then
  python3 benches/capacity.py >&2
fi
