#!/usr/bin/env bash
# HTTP requests per second and p99 latency under load, with wrk, for the leaderboard, a
# match and queueing a match, beside the server's own /healthz in the same run, under 32
# and 200 connections, on databases of each size in SIZES matches.
#
#   bash benches/http.sh [SIZES] [RUNS] [SECONDS]   (defaults: "1000 100000", 3, 5)
#   bash benches/http.sh 1000 1 2                   (a quick check)
#
# Prints one markdown section on stdout (progress goes to stderr). Each figure is the
# median of RUNS wrk runs of SECONDS (after a 1 s warm-up at the same load), the routes
# taken in turn so that /healthz and each route are measured side by side. The GETs come
# first; then each POST /api/matches measurement, with a /healthz just before it, runs on
# a fresh copy of the database and a fresh server, so the matches it queues touch neither
# the GET figures nor the next POST's. It posts with the owner token of a bot registered
# through the API whose bot only sleeps: each match it gets holds the one worker for the
# 10 s start-up limit without using the CPU, so the queued matches are not played during
# the measurement. Any non-2xx answer or socket error fails the run.
#
# The databases are made once by benches/fill_db.py under target/bench/ and reused; the
# server runs on copies, thrown away afterwards. Needs wrk (apt-get install wrk) and the
# release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
SIZES=${1:-1000 100000}
RUNS=${2:-3}
SECS=${3:-5}
CONNS=(32 200)
BIN=target/release/mazearena
DIR=target/bench
PORT=18182
BASE=http://127.0.0.1:$PORT
ADMIN=bench-admin-token-0123456789

log() { echo "http.sh: $*" >&2; }
die() {
  log "error: $*"
  exit 1
}
command -v wrk >/dev/null || die "needs wrk (apt-get install -y wrk)"
mkdir -p "$DIR"
[ -x "$BIN" ] || cargo build --release --locked
WORK=$(mktemp -d "$DIR/http-run.XXXXXX")
SERVER=
stop_server() {
  if [ -n "$SERVER" ]; then
    kill "$SERVER" 2>/dev/null || true
    wait "$SERVER" 2>/dev/null || true
    SERVER=
  fi
}
trap 'stop_server; rm -rf "$WORK"' EXIT
trap 'exit 130' INT TERM
RESULTS=$WORK/results.tsv # size, matches, phase, conns, route, run, requests/s, p99 ms
: >"$RESULTS"

# Milliseconds from wrk's time (850.00us, 1.23ms, 2.00s, 1.50m).
to_ms() {
  awk -v t="$1" 'BEGIN {
    n = t + 0; u = t; sub(/^[0-9.]+/, "", u)
    if (u == "us") n /= 1000; else if (u == "s") n *= 1000; else if (u == "m") n *= 60000
    else if (u != "ms") { print "bad time " t > "/dev/stderr"; exit 1 }
    printf "%.3f\n", n }'
}

# measure SIZE MATCHES PHASE CONNS ROUTE RUN URL [wrk args]: one warm-up, one measurement.
measure() {
  local size=$1 matches=$2 phase=$3 conns=$4 route=$5 run=$6 url=$7
  shift 7
  local out rps p99 non2xx errors
  wrk -t 2 -c "$conns" -d 1s "$@" "$url" >/dev/null || die "wrk failed on $url"
  out=$(wrk -t 2 -c "$conns" -d "${SECS}s" --latency "$@" "$url") || die "wrk failed on $url"
  rps=$(awk '/^Requests\/sec:/ { print $2 }' <<<"$out")
  p99=$(awk '$1 == "99%" { print $2 }' <<<"$out")
  non2xx=$(awk -F': *' '/Non-2xx or 3xx responses/ { print $2 }' <<<"$out")
  errors=$(grep 'Socket errors' <<<"$out" || true)
  if [ -n "$non2xx" ] || [ -n "$errors" ] || [ -z "$rps" ] || [ -z "$p99" ]; then
    echo "$out" >&2
    log "--- server log (tail) ---"
    tail -n 20 "$WORK/server.log" >&2 || true
    die "$route at $conns connections: ${non2xx:-0} non-2xx answers${errors:+; $errors}"
  fi
  p99=$(to_ms "$p99")
  log "$size matches, $conns connections, run $run: $route: $rps requests/s, p99 $p99 ms"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' \
    "$size" "$matches" "$phase" "$conns" "$route" "$run" "$rps" "$p99" >>"$RESULTS"
}

# serve N: the server on a fresh copy of target/bench/http-N.db; sets MATCHES.
serve() {
  stop_server
  rm -rf "$WORK/db.sqlite"* "$WORK/data"
  # A consistent copy (the database is in WAL mode): what the server adds is thrown away.
  # Synced, or SQLite's first checkpoint would wait for the whole copy to reach the disk.
  MATCHES=$(python3 - "$DIR/http-$1.db" "$WORK/db.sqlite" <<'EOF'
import os, sqlite3, sys
src, dst = sqlite3.connect(sys.argv[1]), sqlite3.connect(sys.argv[2])
src.backup(dst)
print(dst.execute("select count(*) from match").fetchone()[0])
dst.close()
fd = os.open(sys.argv[2], os.O_RDONLY)
os.fsync(fd)
os.close(fd)
EOF
)
  if curl -s -o /dev/null "$BASE/healthz"; then die "something already answers on port $PORT"; fi
  MAZEARENA_ADMIN_TOKEN=$ADMIN "$BIN" serve --bind "127.0.0.1:$PORT" \
    --database "sqlite://$WORK/db.sqlite" --data-dir "$WORK/data" --jobs 1 \
    --max-queue 100000000 --max-queued-per-owner 100000000 --shutdown-grace-secs 1 >"$WORK/server.log" 2>&1 &
  SERVER=$!
  until curl -s -o /dev/null "$BASE/healthz"; do
    kill -0 "$SERVER" 2>/dev/null || { cat "$WORK/server.log" >&2; die "the server did not start"; }
    sleep 0.2
  done
}

# prepare_post: registers the bot to post for and writes $WORK/post.lua with its owner
# token. The bot sleeps, so its matches time out at start-up without using a core.
prepare_post() {
  local bot mazes bot_id token maze_id body status
  bot=$(curl -sf "$BASE/api/bots" -H 'content-type: application/json' -d '{"name": "http-bench",
    "command": "python3 idle_bot.py", "files": {"idle_bot.py": "import time\ntime.sleep(3600)\n"}}') ||
    die "cannot register the bench bot"
  mazes=$(curl -sf "$BASE/api/mazes") || die "GET /api/mazes failed"
  read -r bot_id token maze_id < <(python3 -c '
import json, sys
bot, mazes = json.loads(sys.argv[1]), json.loads(sys.argv[2])
print(bot["bot_id"], bot["owner_token"], next(m["maze_id"] for m in mazes if not m["hidden"]))
' "$bot" "$mazes") || die "no bot id, token or public maze in: $bot $mazes"
  body="{\"bot_id\": $bot_id, \"maze_id\": $maze_id, \"seed\": 7}"
  cat >"$WORK/post.lua" <<EOF
wrk.method = "POST"
wrk.body = '$body'
wrk.headers["Content-Type"] = "application/json"
wrk.headers["Authorization"] = "Bearer $token"
EOF
  # One by hand first, for the server's own words if it refuses.
  status=$(curl -s -o "$WORK/answer.json" -w '%{http_code}' "$BASE/api/matches" \
    -H "authorization: Bearer $token" -H 'content-type: application/json' -d "$body")
  [[ $status == 2?? ]] || die "POST /api/matches answered $status: $(cat "$WORK/answer.json")"
}

: >"$WORK/queued.tsv"
for N in $SIZES; do
  [ -f "$DIR/http-$N.db" ] || python3 benches/fill_db.py "$DIR/http-$N.db" "$N" --bin "$BIN"
  serve "$N"
  log "$N: serving a copy of $DIR/http-$N.db ($MATCHES matches)"
  curl -sf -o /dev/null "$BASE/api/matches/5" || die "GET /api/matches/5 does not answer 2xx"
  for ((run = 1; run <= RUNS; run++)); do
    for c in "${CONNS[@]}"; do
      measure "$N" "$MATCHES" get "$c" "GET /healthz" "$run" "$BASE/healthz"
      measure "$N" "$MATCHES" get "$c" "GET /api/leaderboard?scope=all" "$run" "$BASE/api/leaderboard?scope=all"
      measure "$N" "$MATCHES" get "$c" "GET /api/matches/5" "$run" "$BASE/api/matches/5"
    done
  done
  # Each POST measurement on a fresh copy, so that each starts with an empty queue.
  for ((run = 1; run <= RUNS; run++)); do
    for c in "${CONNS[@]}"; do
      serve "$N"
      prepare_post
      measure "$N" "$MATCHES" post "$c" "GET /healthz" "$run" "$BASE/healthz"
      measure "$N" "$MATCHES" post "$c" "POST /api/matches" "$run" "$BASE/api/matches" -s "$WORK/post.lua"
      queued=$(curl -sf -H "authorization: Bearer $ADMIN" "$BASE/healthz" | python3 -c 'import json, sys; print(json.load(sys.stdin)["queued"])') ||
        die "GET /healthz failed after the POSTs"
      log "$N matches, $c connections, run $run: $queued matches queued after the POSTs"
      printf '%s\t%s\t%s\n' "$N" "$c" "$queued" >>"$WORK/queued.tsv"
    done
  done
  stop_server
done

WRK=$(wrk --version 2>&1 | awk 'NR == 1 { print $2 }' || true)
python3 - "$RESULTS" "$WORK/queued.tsv" "$WRK" "$RUNS" "$SECS" <<'EOF'
import statistics, sys
from collections import defaultdict

results, queued_file, wrk, runs, secs = sys.argv[1:6]
rows = [line.rstrip("\n").split("\t") for line in open(results)]
queued = defaultdict(list)  # (size, conns) -> queue depth after each POST measurement
for line in open(queued_file):
    size, conns, q = line.split("\t")
    queued[(size, conns)].append(int(q))
rps, p99, matches, order = defaultdict(list), defaultdict(list), {}, []
base = {}  # (size, phase, conns, run) -> /healthz requests/s
for size, n, phase, conns, route, run, r, p in rows:
    key = (size, phase, conns, route)
    if key not in rps:
        order.append(key)
    rps[key].append(float(r))
    p99[key].append(float(p))
    matches[size] = int(n)
    if route == "GET /healthz":
        base[(size, phase, conns, run)] = float(r)
ratio = defaultdict(list)
for size, n, phase, conns, route, run, r, p in rows:
    ratio[(size, phase, conns, route)].append(float(r) / base[(size, phase, conns, run)])

def span(values):
    return f"{min(values):,}" if min(values) == max(values) else f"{min(values):,}-{max(values):,}"


print("## HTTP under load\n")
print(f"`bash benches/http.sh`: wrk {wrk}, `-t 2`, {secs} s per measurement after a 1 s "
      f"warm-up at the same load, median of {runs} run{'s' if runs != '1' else ''}; the "
      "routes taken in turn beside the server's own `GET /healthz`, and x /healthz the ratio "
      "of requests/s to it in the same run; the server with one match worker (`--jobs 1`).\n")
print("| database | connections | route | requests/s (median) | p99 (median) | x /healthz |")
print("|---:|---:|---|---:|---:|---:|")
order.sort(key=lambda k: (int(k[0]), int(k[2]), k[1] == "post"))
for key in order:
    size, phase, conns, route = key
    name = f"`{route}`" + (" (beside POST)" if phase == "post" and route == "GET /healthz" else "")
    print(f"| {matches[size]:,} matches | {conns} | {name} | {statistics.median(rps[key]):,.0f} "
          f"| {statistics.median(p99[key]):.1f} ms | {statistics.median(ratio[key]):.2f} |")
print()
print("POST comes after the GETs, each measurement on a fresh copy of the database and a "
      "fresh server (so it starts with an empty queue), with its own `/healthz` taken just "
      "before it. It posts as the owner of a bot registered through the API (its owner "
      "token) whose bot only sleeps: each match it gets holds the one worker for the 10 s "
      "start-up limit without using a core, so the queued matches are not played "
      "meanwhile. The queue limit is raised (`--max-queue`) so that none is refused; after "
      "each POST measurement the queue held "
      + "; ".join(f"{span(q)} matches ({c} connections, database of {matches[s]:,})"
                  for (s, c), q in queued.items())
      + ". Every POST counts the queued matches (to check the queue's room), so it slows "
      "as the queue fills; `/healthz` (anonymous: a query of the database, no count) does "
      "not.\n")

route = "GET /api/leaderboard?scope=all"
big = [s for s in matches if int(s) >= 100000]
target = ("Leaderboard GET at 100k matches: at least 0.5x the requests/s of /healthz; "
          "p99 under 20 ms at 32 connections")
if not big:
    print(f"- {target}: not measured (no database of 100,000 matches in this run).")
else:
    s = max(big, key=int)
    conns = sorted({k[2] for k in rps if k[0] == s and k[3] == route}, key=int)
    ratios = {c: statistics.median(ratio[(s, "get", c, route)]) for c in conns}
    p = statistics.median(p99[(s, "get", "32", route)])
    holds = all(r >= 0.5 for r in ratios.values()) and p < 20
    print(f"- {target}: {'holds' if holds else 'does not hold'} ("
          + ", ".join(f"{r:.2f}x at {c} connections" for c, r in ratios.items())
          + f"; p99 {p:.1f} ms at 32 connections, {matches[s]:,} matches).")
EOF
