#!/usr/bin/env bash
# Time to answer one request, one at a time, for the web pages and the leaderboard on a
# database of N matches, beside the server's own /healthz in the same run.
#
#   bash benches/pages.sh [N] [RUNS]      (defaults: 100000 matches, 21 runs each)
#
# The database is made once by benches/fill_db.py under target/bench/ and reused. Each
# figure is the median (and the slowest) of RUNS requests with curl, the routes taken in
# turn so that none is favoured by a warm cache. Needs the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-100000}
RUNS=${2:-21}
BIN=target/release/mazearena
DIR=target/bench
DB=$DIR/pages-$N.db
PORT=18181
mkdir -p "$DIR"
[ -x "$BIN" ] || cargo build --release --locked
[ -f "$DB" ] || python3 benches/fill_db.py "$DB" "$N" --bin "$BIN"

MAZEARENA_ADMIN_TOKEN=bench-admin-token-0123456789 "$BIN" serve --bind 127.0.0.1:$PORT \
  --database "sqlite://$DB" --data-dir "$DIR/data" --jobs 1 >"$DIR/pages-server.log" 2>&1 &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
until curl -s -o /dev/null "http://127.0.0.1:$PORT/healthz"; do sleep 0.2; done

ROUTES=(/healthz / "/api/leaderboard?scope=all" "/api/leaderboard?tournament=2" /tournaments/1
  /matches "/matches?bot_id=3" "/api/matches?status=crashed" "/api/matches?maze_id=4&before=500"
  /bots/3 /api/bots /api/matches/5)
declare -A TIMES
for ((i = 0; i < RUNS; i++)); do
  for r in "${ROUTES[@]}"; do
    answer=$(curl -s -o /dev/null -w '%{http_code} %{time_total}' "http://127.0.0.1:$PORT$r")
    code=${answer% *} t=${answer#* }
    [ "$code" = 200 ] || { echo "GET $r answered $code" >&2; exit 1; }
    TIMES[$r]+="$t "
  done
done
MATCHES=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('select count(*) from match').fetchone()[0])" "$DB")
echo "| route ($MATCHES matches, $RUNS requests each) | median | slowest |"
echo "|---|---:|---:|"
for r in "${ROUTES[@]}"; do
  # shellcheck disable=SC2086
  python3 - "$r" ${TIMES[$r]} <<'EOF'
import statistics, sys
route, times = sys.argv[1], [float(t) * 1000 for t in sys.argv[2:]]
print(f"| `GET {route}` | {statistics.median(times):.1f} ms | {max(times):.1f} ms |")
EOF
done
