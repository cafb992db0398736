#!/usr/bin/env bash
# Ranking throughput: the time from a version's upload to its full public and private
# standing in a competition with 20 ranking mazes (10 public, 10 private, 12 x 12,
# generated with secret seeds) x 3 repeats (60 matches), beside the same 60 matches
# queued at once as a plain tournament on the same server in the same round: the floor
# (what the workers need to play them). The difference is what automatic ranking adds
# (the server's clock, the queue, the boards).
#
#   bash benches/competition.sh [ROUNDS]   (default 3)
#
# One server, `--jobs 2`, the default sandbox, SQLite; the shipped simple Python bot.
# Each round plays the tournament, then uploads a version (one unreported warm-up round
# first: the first matches after the server starts are slower, whichever kind).
# Prints a markdown table on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-3}
BIN=target/release/mazearena
PORT=18184
[ -x "$BIN" ] || cargo build --release --locked
WORK=$(mktemp -d)
SERVER=
cleanup() {
  [ -n "$SERVER" ] && kill "$SERVER" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
ADMIN=bench-admin-token-0123456789
MAZEARENA_ADMIN_TOKEN=$ADMIN "$BIN" serve --bind "127.0.0.1:$PORT" \
  --database "sqlite://$WORK/db.sqlite" --data-dir "$WORK/data" --jobs 2 >"$WORK/server.log" 2>&1 &
SERVER=$!
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null && break; sleep 0.1; done
for i in $(seq 20); do "$BIN" maze generate --dim 12 -o "$WORK/maze-$i.txt"; done

python3 - "$PORT" "$ADMIN" "$WORK" "$ROUNDS" <<'PY'
import json, sys, time, urllib.request, urllib.error
port, admin, work, rounds = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
base = f"http://127.0.0.1:{port}"
def call(method, path, body=None, token=None):
    req = urllib.request.Request(base + path, method=method,
                                 data=None if body is None else json.dumps(body).encode())
    req.add_header("content-type", "application/json")
    if token: req.add_header("authorization", "Bearer " + token)
    try:
        with urllib.request.urlopen(req) as r: return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e: return e.code, json.loads(e.read() or b"null")
def iso(ms): return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(ms / 1000))
now = time.time() * 1000
_, o = call("POST", "/api/organisers", {"name": "bench"}, admin)
org = o["key"]
mazes = [{"name": f"m{i}", "layout": open(f"{work}/maze-{i}.txt").read()} for i in range(1, 21)]
s, c = call("POST", "/api/competitions", {
    "name": "bench", "title": "bench", "opens_at": iso(now - 60_000), "closes_at": iso(now + 86_400_000),
    "repeats": 3, "versions_per_day": 1000,
    "mazes": {"public": mazes[:10], "private": mazes[10:]}}, org)
assert s == 201, c
ids = [m["maze_id"] for m in c["mazes"]]
_, e = call("POST", "/api/entrants", {"name": "bench"})
key = e["key"]
files = {f: open("bots/python/" + f).read() for f in ["simple_bot.py", "mazebot.py"]}
s, b = call("POST", "/api/bots", {"name": "bench-bot", "command": "python3 simple_bot.py", "files": files}, key)
assert s == 201, b
bot = b["bot_id"]
call("POST", "/api/competitions/bench/entries", {"bot_id": bot}, key)
def standing(board, version):
    _, v = call("GET", f"/api/competitions/bench/leaderboard?board={board}", None, org)
    return any(l["version"] == version and l["played"] == 30 for l in v["standings"])
def wait_idle():
    while True:
        _, q = call("GET", "/api/matches?status=queued&limit=1")
        _, r = call("GET", "/api/matches?status=running&limit=1")
        if q["total"] == 0 and r["total"] == 0: return
        time.sleep(0.05)
wait_idle()
print("| round | upload to full public standing | to full private standing | the same 60 matches as a tournament | ratio (private / tournament) |")
print("|---:|---:|---:|---:|---:|")
rows = []
for r in range(0, rounds + 1):
    wait_idle()
    t0 = time.monotonic()
    s, t = call("POST", "/api/tournaments", {"name": f"floor {r}", "bot_ids": [bot], "maze_ids": ids, "repeats": 3}, admin)
    assert 200 <= s < 300, t
    while True:
        _, t2 = call("GET", f"/api/tournaments/{t['tournament_id']}", None, admin)
        if t2["done"] == t2["total"] == 60: break
        time.sleep(0.05)
    floor = time.monotonic() - t0
    wait_idle()
    t0 = time.monotonic()
    s, v = call("POST", f"/api/bots/{bot}/versions", {"command": "python3 simple_bot.py", "files": files}, key)
    assert s == 201, v
    version = v["version"]
    public = private = None
    while private is None or public is None:
        if public is None and standing("public", version): public = time.monotonic() - t0
        if private is None and standing("private", version): private = time.monotonic() - t0
        time.sleep(0.05)
    if r == 0:
        continue  # warm-up: the first matches after the server starts are slower, whichever kind
    rows.append((public, private, floor, private / floor))
    print(f"| {r} | {public:.2f} s | {private:.2f} s | {floor:.2f} s | {private / floor:.2f} |", flush=True)
med = lambda xs: sorted(xs)[len(xs) // 2]
print(f"| median | {med([x[0] for x in rows]):.2f} s | {med([x[1] for x in rows]):.2f} s | {med([x[2] for x in rows]):.2f} s | {med([x[3] for x in rows]):.2f} |")
PY
