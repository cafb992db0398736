#!/usr/bin/env bash
# Requests per second of GET /healthz and GET /api/leaderboard with 1,000 idle
# connections held open beside them, and the same without, taken in turn on one server
# in one run: what idle or slow clients cost everyone else.
#
#   bash benches/idle.sh [ROUNDS] [SECONDS]   (defaults: 3, 5)
#
# The idle connections come from 127.0.0.2-127.0.0.5 (250 each: under the per-address
# cap), each having sent half a request line; a holder opens them again as the server
# closes them at its head timeout, so 1,000 stay open through each measurement. wrk
# runs with 32 connections from 127.0.0.1, 2 threads. Prints a markdown table on stdout.
# Needs wrk (apt-get install wrk) and the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-3}
SECS=${2:-5}
BIN=target/release/mazearena
PORT=18183
BASE=http://127.0.0.1:$PORT
command -v wrk >/dev/null || { echo "needs wrk (apt-get install -y wrk)" >&2; exit 1; }
[ -x "$BIN" ] || cargo build --release --locked
WORK=$(mktemp -d)
SERVER= HOLDER=
cleanup() {
  [ -n "$HOLDER" ] && kill "$HOLDER" 2>/dev/null || true
  [ -n "$SERVER" ] && kill "$SERVER" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
MAZEARENA_ADMIN_TOKEN=bench-admin-token-0123456789 "$BIN" serve --bind "127.0.0.1:$PORT" \
  --database "sqlite://$WORK/db.sqlite" --data-dir "$WORK/data" --jobs 1 >"$WORK/server.log" 2>&1 &
SERVER=$!
for _ in $(seq 100); do curl -sf "$BASE/healthz" >/dev/null && break; sleep 0.1; done

cat >"$WORK/hold.py" <<'PY'
import selectors, socket, sys, time
port = int(sys.argv[1]); per = 250
sel = selectors.DefaultSelector()
def open_one(src):
    s = socket.socket(); s.bind((src, 0)); s.connect(("127.0.0.1", port))
    s.sendall(b"GET /healthz HT"); s.setblocking(False)
    sel.register(s, selectors.EVENT_READ, src)
for src in ["127.0.0.2", "127.0.0.3", "127.0.0.4", "127.0.0.5"]:
    for _ in range(per):
        open_one(src)
print("holding", len(sel.get_map()), flush=True)
while True:
    for key, _ in sel.select(timeout=1):
        s = key.fileobj
        try:
            data = s.recv(4096)
        except OSError:
            data = b""
        if not data:
            sel.unregister(s); s.close(); open_one(key.data)
PY

rps() { # route -> requests/s
  wrk -t 2 -c 32 -d "${SECS}s" "$BASE$1" | awk '/^Requests\/sec/ {printf "%d", $2}'
}
echo "| round | route | requests/s without | with 1,000 idle | ratio |"
echo "|---:|---|---:|---:|---:|"
for r in $(seq "$ROUNDS"); do
  for route in /healthz "/api/leaderboard?scope=all"; do
    without=$(rps "$route")
    python3 "$WORK/hold.py" "$PORT" >"$WORK/hold.log" 2>&1 &
    HOLDER=$!
    for _ in $(seq 100); do grep -q holding "$WORK/hold.log" && break; sleep 0.1; done
    with=$(rps "$route")
    kill "$HOLDER"; wait "$HOLDER" 2>/dev/null || true; HOLDER=
    echo "| $r | \`GET $route\` | $without | $with | $(awk -v a="$with" -v b="$without" 'BEGIN{printf "%.2f", a/b}') |"
  done
done
