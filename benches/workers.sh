#!/usr/bin/env bash
# Throughput across worker processes on one PostgreSQL: an API server (`serve --jobs 0`)
# and 1, 2 or 3 `mazearena worker --jobs 1` processes play a tournament of the shipped
# simple Python bot on the 9 shipped mazes (REPEATS times each), in the full sandbox
# (each worker with a data folder of its own: the bot's files come from the database);
# matches per minute from the tournament's creation to its last record, the settings
# taken in turn RUNS times (medians). Then the claim itself, timed in the database:
# PostgreSQL's own statistics (pg_stat_statements) give the mean time of the claim
# statement over every claim of the runs; and what PostgreSQL sees of a match (claims,
# writing statements, rows written, WAL and database bytes), per match and a second at
# the best rate measured.
#
#   bash benches/workers.sh [RUNS] [REPEATS]     (default 3 and 12: 108 matches a run)
# Starts a throw-away PostgreSQL cluster with .ci/postgres.sh (root: as user postgres).
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-3}
REPEATS=${2:-12}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
pg=$tmp/pg
chmod 755 "$tmp" # PostgreSQL runs as its own user
cleanup() {
  jobs -p | xargs -r kill 2>/dev/null || true
  wait 2>/dev/null || true
  .ci/postgres.sh stop "$pg" >/dev/null 2>&1 || true
  rm -rf "$tmp"
}
trap cleanup EXIT
eval "$(.ci/postgres.sh start "$pg")"
base_url=${MAZEARENA_TEST_POSTGRES%/*}
# Statement statistics for the claim timing.
echo "shared_preload_libraries = 'pg_stat_statements'" >>"$pg/data/postgresql.conf"
.ci/postgres.sh restart "$pg"
psql -q "$MAZEARENA_TEST_POSTGRES" -c "create database bench"
db=$base_url/bench
psql -q "$db" -c "create extension pg_stat_statements"

port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
api=http://127.0.0.1:$port
MAZEARENA_ADMIN_TOKEN=bench-admin-token-0123456789 ./target/release/mazearena serve --jobs 0 --bind "127.0.0.1:$port" \
  --database "$db" --data-dir "$tmp/data" >"$tmp/api.log" 2>&1 &
for _ in $(seq 100); do curl -fs "$api/healthz" >/dev/null && break; sleep 0.1; done

bot=$(python3 - "$api" <<'PY'
import json, sys, urllib.request
files = {f: open("bots/python/" + f).read() for f in ("simple_bot.py", "mazebot.py")}
req = urllib.request.Request(sys.argv[1] + "/api/bots", method="POST",
    data=json.dumps({"name": "simple", "command": "python3 simple_bot.py", "files": files}).encode(),
    headers={"Content-Type": "application/json"})
print(json.load(urllib.request.urlopen(req))["bot_id"])
PY
)

run() { # $1: workers; prints "ms matches"
  local pids=() id total a b
  for ((w = 0; w < $1; w++)); do
    ./target/release/mazearena worker --jobs 1 --database "$db" --data-dir "$tmp/data-worker$w" \
      >>"$tmp/worker$w.log" 2>&1 &
    pids+=($!)
  done
  sleep 1 # the workers are up and idle
  a=$(date +%s%N)
  read -r id total < <(python3 - "$api" "$bot" "$REPEATS" <<'PY'
import json, sys, urllib.request
api, bot, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
mazes = [m["maze_id"] for m in json.load(urllib.request.urlopen(api + "/api/mazes"))]
req = urllib.request.Request(api + "/api/tournaments", method="POST",
    data=json.dumps({"name": "bench", "bot_ids": [bot], "maze_ids": mazes, "repeats": repeats}).encode(),
    headers={"Content-Type": "application/json", "Authorization": "Bearer bench-admin-token-0123456789"})
t = json.load(urllib.request.urlopen(req))
print(t["tournament_id"], t["total"])
PY
)
  while :; do
    done_=$(curl -fs "$api/api/tournaments/$id" | python3 -c 'import json,sys; print(json.load(sys.stdin)["done"])')
    [ "$done_" = "$total" ] && break
    sleep 0.05
  done
  b=$(date +%s%N)
  kill -TERM "${pids[@]}"
  wait "${pids[@]}" 2>/dev/null || true
  echo "$(( (b - a) / 1000000 )) $total"
}

# What PostgreSQL sees of the matches: counters from here to the end of the runs.
psql -qtA "$db" -c "select pg_stat_statements_reset()" >/dev/null
before=$(psql -qtA "$db" -c "select tup_inserted + tup_updated + tup_deleted, pg_current_wal_lsn(),
  pg_database_size('bench') from pg_stat_database where datname = 'bench'")
declare -A WALL
for ((i = 1; i <= RUNS; i++)); do
  for k in 1 2 3; do
    read -r ms n < <(run "$k")
    echo "round $i: $k workers: $ms ms for $n matches" >&2
    WALL[$k]+="$ms "
    MATCHES=$n
  done
done
claim=$(psql -qtA "$db" -c "select calls, round(mean_exec_time::numeric, 3), round(max_exec_time::numeric, 3), rows
  from pg_stat_statements where query ilike '%for update of m skip locked%'
  order by calls desc limit 1")
IFS='|' read -r rows0 lsn0 size0 <<<"$before"
load=$(psql -qtA "$db" -c "select
  (select sum(calls) from pg_stat_statements where query ~* '^\s*(insert|update|delete)'),
  (select tup_inserted + tup_updated + tup_deleted - $rows0 from pg_stat_database where datname = 'bench'),
  pg_wal_lsn_diff(pg_current_wal_lsn(), '$lsn0'),
  pg_database_size('bench') - $size0")

echo "## Throughput across worker processes (PostgreSQL)"
echo
echo "\`bash benches/workers.sh $RUNS $REPEATS\`: one API server (\`serve --jobs 0\`) and 1, 2 or 3"
echo "\`mazearena worker --jobs 1\` processes on one PostgreSQL 15 (a local throw-away cluster),"
echo "playing a tournament of the simple Python bot on the 9 shipped mazes ($MATCHES matches) in"
echo "the full sandbox; from the tournament's creation to its last record; medians of $RUNS"
echo "rounds, the settings taken in turn. The machine has $(nproc) cores: a third worker shares"
echo "them with the other two (its matches still run one at a time on a core of their own)."
echo
python3 - "$MATCHES" "${WALL[1]}" "${WALL[2]}" "${WALL[3]}" "$claim" "$load" "$RUNS" <<'PY'
import statistics, sys
n = int(sys.argv[1])
walls = [statistics.median(map(int, a.split())) for a in sys.argv[2:5]]
print("| workers | wall | matches per minute | × one worker |")
print("|---:|---:|---:|---:|")
for k, w in enumerate(walls, 1):
    print(f"| {k} | {w / 1000:.1f} s | {n * 60000 / w:.0f} | {walls[0] / w:.2f} |")
calls, mean, top, claimed = (sys.argv[5].split("|") + ["?"] * 4)[:4]
print()
print(f"The claim, timed by PostgreSQL (pg_stat_statements): {calls} claims, mean {mean} ms, "
      f"longest {top} ms (the claim statement alone: one `UPDATE ... WHERE match_id = "
      f"(SELECT ... FOR UPDATE SKIP LOCKED)`).")
writes, rows, wal, size = (float(x) for x in sys.argv[6].split("|"))
played = n * 3 * int(sys.argv[7])
best = max(n * 60 / (w / 1000) for w in walls) / 60  # matches a second, the best setting
per = lambda x: x / played
print()
print(f"What PostgreSQL sees of a match ({played} matches in all the rounds; counters of "
      f"pg_stat_statements and pg_stat_database over the runs), and the same at the best rate "
      f"measured here ({best:.1f} matches a second):")
print()
print("| per match | measure | a second at the best rate |")
print("|---|---:|---:|")
print(f"| claim statements (idle workers' empty claims included) | {per(float(calls)):.2f} | {per(float(calls)) * best:.1f} |")
print(f"| claims that took a match | {per(float(claimed)):.2f} | {per(float(claimed)) * best:.1f} |")
print(f"| writing statements (insert, update, delete) | {per(writes):.1f} | {per(writes) * best:.0f} |")
print(f"| rows written | {per(rows):.1f} | {per(rows) * best:.0f} |")
print(f"| WAL bytes | {per(wal):,.0f} | {per(wal) * best / 1024:,.0f} KiB |")
print(f"| database bytes (tables and indexes) | {per(size):,.0f} | {per(size) * best / 1024:,.0f} KiB |")
PY
