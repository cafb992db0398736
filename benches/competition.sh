#!/usr/bin/env bash
# Competition throughput, two measurements on one server in one run:
#
# 1. Ranking: the time from a version's upload to its full public standing in a
#    competition with 10 public ranking mazes (12 x 12, generated with secret seeds) x 3
#    repeats (30 matches), beside the same 30 matches queued at once as a plain tournament
#    (the floor: what the workers need to play them).
# 2. The close: 100 entrants, each with a bot entered; the private set (4 mazes, one run
#    each) is played only by the final run, after the close. The time from the close
#    (`PATCH closes_at` = now) to the results, beside the same 400 matches (every entrant's
#    bot on the 4 private mazes) queued at once as a plain tournament just before the close
#    (the floor). The difference is what the close adds: the server's clock noticing it,
#    the final selection, queueing the final run, and writing the results with their
#    recount.
#
#   bash benches/competition.sh [ROUNDS]   (default 3)
#
# One server, `--jobs 2`, the default sandbox, SQLite; the shipped simple Python bot. One
# unreported warm-up round first: the first matches after the server starts are slower,
# whichever kind. Prints two markdown tables on stdout.
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
  --database "sqlite://$WORK/db.sqlite" --data-dir "$WORK/data" --jobs 2 \
  --max-queue 100000 --registrations-per-hour 0 >"$WORK/server.log" 2>&1 &
SERVER=$!
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null && break; sleep 0.1; done
# Mazes: 10 public and 1 private for the ranking, then 2 public and 4 private for each
# close round.
N=$((11 + (ROUNDS + 1) * 6))
for i in $(seq "$N"); do "$BIN" maze generate --dim 12 -o "$WORK/maze-$i.txt"; done

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
maze_no = iter(range(1, 10_000))
def mazes(n):
    out = []
    for _ in range(n):
        i = next(maze_no)
        out.append({"name": f"m{i}", "layout": open(f"{work}/maze-{i}.txt").read()})
    return out
_, o = call("POST", "/api/organisers", {"name": "bench"}, admin)
org = o["key"]
files = {f: open("bots/python/" + f).read() for f in ["simple_bot.py", "mazebot.py"]}
def competition(name, public, private, repeats):
    now = time.time() * 1000
    s, c = call("POST", "/api/competitions", {
        "name": name, "title": name, "opens_at": iso(now - 60_000), "closes_at": iso(now + 86_400_000),
        "repeats": repeats, "final_repeats": 1, "versions_per_day": 1000,
        "mazes": {"public": public, "private": private}}, org)
    assert s == 201, c
    _, v = call("GET", f"/api/competitions/{name}", None, org)
    return v
def wait_idle():
    while True:
        _, q = call("GET", "/api/matches?status=queued&limit=1", None, admin)
        _, r = call("GET", "/api/matches?status=running&limit=1", None, admin)
        if q["total"] == 0 and r["total"] == 0: return
        time.sleep(0.05)
def tournament(name, bots, maze_ids, repeats):
    wait_idle()
    t0 = time.monotonic()
    s, t = call("POST", "/api/tournaments", {"name": name, "bot_ids": bots, "maze_ids": maze_ids, "repeats": repeats}, admin)
    assert 200 <= s < 300, t
    total = len(bots) * len(maze_ids) * repeats
    while True:
        _, t2 = call("GET", f"/api/tournaments/{t['tournament_id']}", None, admin)
        if t2["done"] == t2["total"] == total: break
        time.sleep(0.05)
    return time.monotonic() - t0
med = lambda xs: sorted(xs)[len(xs) // 2]

# 1. Ranking: one entrant's new versions on 10 public mazes x 3.
c = competition("ranking-bench", mazes(10), mazes(1), 3)
ids = [m["maze_id"] for m in c["mazes"] if m["set"] == "public"]
_, e = call("POST", "/api/entrants", {"name": "bench"}, admin)
key = e["key"]
s, b = call("POST", "/api/bots", {"name": "bench-bot", "command": "python3 simple_bot.py", "files": files}, key)
assert s == 201, b
bot = b["bot_id"]
call("POST", "/api/competitions/ranking-bench/entries", {"bot_id": bot}, key)
def standing(version):
    _, v = call("GET", "/api/competitions/ranking-bench/leaderboard", None, org)
    return any(l["version"] == version and l["played"] == 30 for l in v["standings"])
print("| round | upload to full public standing | the same 30 matches as a tournament | ratio |")
print("|---:|---:|---:|---:|")
rows = []
for r in range(0, rounds + 1):
    floor = tournament(f"ranking floor {r}", [bot], ids, 3)
    wait_idle()
    t0 = time.monotonic()
    s, v = call("POST", f"/api/bots/{bot}/versions", {"command": "python3 simple_bot.py", "files": files}, key)
    assert s == 201, v
    while not standing(v["version"]):
        time.sleep(0.05)
    public = time.monotonic() - t0
    if r == 0:
        continue
    rows.append((public, floor))
    print(f"| {r} | {public:.2f} s | {floor:.2f} s | {public / floor:.2f} |", flush=True)
print(f"| median | {med([x[0] for x in rows]):.2f} s | {med([x[1] for x in rows]):.2f} s | {med([x[0] / x[1] for x in rows]):.2f} |")
print()

# 2. The close: 100 entrants, each with a bot.
entrants = []
for i in range(100):
    s, e = call("POST", "/api/entrants", {"name": f"team-{i}"}, admin)
    assert s == 201, e
    s, b = call("POST", "/api/bots", {"name": f"team-{i}-bot", "command": "python3 simple_bot.py", "files": files}, e["key"])
    assert s == 201, b
    entrants.append((e["key"], b["bot_id"]))
bots = [b for _, b in entrants]
print("| round | close to results (100 entrants, 400 final-run matches) | the same 400 matches as a tournament | ratio |")
print("|---:|---:|---:|---:|")
rows = []
for r in range(0, rounds + 1):
    name = f"close-bench-{r}"
    c = competition(name, mazes(2), mazes(4), 1)
    private = [m["maze_id"] for m in c["mazes"] if m["set"] == "private"]
    for k, b in entrants:
        s, v = call("POST", f"/api/competitions/{name}/entries", {"bot_id": b}, k)
        assert s == 201, v
    # Every entrant ranked on the public set before the close.
    while True:
        _, board = call("GET", f"/api/competitions/{name}/leaderboard", None, org)
        if len(board["standings"]) == 100: break
        time.sleep(0.1)
    floor = tournament(f"close floor {r}", bots, private, 1)
    wait_idle()
    t0 = time.monotonic()
    s, v = call("PATCH", f"/api/competitions/{name}", {"closes_at": iso(time.time() * 1000)}, org)
    assert s == 200, v
    while True:
        _, v = call("GET", f"/api/competitions/{name}", None)
        if v["state"] == "final": break
        time.sleep(0.05)
    close = time.monotonic() - t0
    s, res = call("GET", f"/api/competitions/{name}/results")
    assert s == 200 and res["recount_equal"] and len(res["results"]) == 100, res
    if r == 0:
        continue
    rows.append((close, floor))
    print(f"| {r} | {close:.2f} s | {floor:.2f} s | {close / floor:.2f} |", flush=True)
print(f"| median | {med([x[0] for x in rows]):.2f} s | {med([x[1] for x in rows]):.2f} s | {med([x[0] / x[1] for x in rows]):.2f} |")
PY
