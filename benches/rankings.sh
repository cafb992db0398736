#!/usr/bin/env bash
# Ranked standings (intervals, possible ranks, tie groups: docs/RANKINGS.md) on a database
# of N matches: the first answer after the server starts, which makes the table (every
# counted match read, grouped by version, maze and seed, and bootstrapped), and the next
# answers, which reuse it until a match ends; beside /healthz in the same run.
#
#   bash benches/rankings.sh [N] [RUNS]      (defaults: 100000 matches, 5 runs)
#
# Each run starts a fresh server on the database (made once by benches/fill_db.py under
# target/bench/, the same file as benches/pages.sh), then takes /healthz, the route's
# first answer and 5 more answers, with curl, one at a time. Figures: medians over the
# runs. Needs the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-100000}
RUNS=${2:-5}
BIN=target/release/mazearena
DIR=target/bench
DB=$DIR/pages-$N.db
PORT=18183
mkdir -p "$DIR"
[ -x "$BIN" ] || cargo build --release --locked
[ -f "$DB" ] || python3 benches/fill_db.py "$DB" "$N" --bin "$BIN"
ROUTES=("/api/leaderboard?scope=all" "/api/leaderboard?tournament=2" "/tournaments/1")
t() {
  local answer
  answer=$(curl -s -o /dev/null -w '%{http_code} %{time_total}' "http://127.0.0.1:$PORT$1")
  [ "${answer% *}" = 200 ] || { echo "GET $1 answered ${answer% *}" >&2; exit 1; }
  echo "${answer#* }"
}
declare -A FIRST LATER FLOOR
for ((i = 0; i < RUNS; i++)); do
  for r in "${ROUTES[@]}"; do
    MAZEARENA_ADMIN_TOKEN=bench-admin-token-0123456789 "$BIN" serve --bind 127.0.0.1:$PORT \
      --database "sqlite://$DB" --data-dir "$DIR/data" --jobs 0 >"$DIR/rankings-server.log" 2>&1 &
    server=$!
    until curl -s -o /dev/null "http://127.0.0.1:$PORT/healthz"; do sleep 0.1; done
    FLOOR[$r]+="$(t /healthz) "
    FIRST[$r]+="$(t "$r") "
    for ((k = 0; k < 5; k++)); do LATER[$r]+="$(t "$r") "; done
    kill "$server"
    wait "$server" 2>/dev/null || true
  done
done
MATCHES=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('select count(*) from match').fetchone()[0])" "$DB")
echo "| route ($MATCHES matches, $RUNS fresh servers) | first answer (table made) | later answers (kept) | \`/healthz\` in the same runs |"
echo "|---|---:|---:|---:|"
for r in "${ROUTES[@]}"; do
  python3 - "$r" "${FIRST[$r]}" "${LATER[$r]}" "${FLOOR[$r]}" <<'PY'
import statistics, sys
route, first, later, floor = sys.argv[1:]
ms = lambda s: statistics.median(float(x) for x in s.split()) * 1000
print(f"| `GET {route}` | {ms(first):.1f} ms | {ms(later):.1f} ms | {ms(floor):.1f} ms |")
PY
done
