#!/usr/bin/env bash
# The deadline rush, with Locust (PyPI): STUDENTS students, each as a browser does it
# (benches/rush_locust.py: register with the invite code, log in, upload an original-task
# robot.py through the form, wait until it is ready, play two practice matches), all
# started at once through a real nginx while a tournament keeps every worker busy:
#   1. behind one address: the server without --trusted-proxies (everyone is nginx);
#   2. from two client addresses (127.0.0.2, 127.0.0.3), the server trusting nginx;
# and the baseline: the same journey by one student on an idle server, straight to it.
#
#   bash benches/rush.sh [STUDENTS] [JOBS]   (defaults: 300 students, every core)
#
# Prints one markdown section on stdout (progress on stderr): p50 and p99 of each page
# and form post, the time from upload to ready (median and worst), and the counts that
# must be zero: right keys or codes refused, uploads lost. The server runs with its
# default limits. Needs nginx (apt-get install nginx), python3 with venv (Locust is
# installed in target/bench/locust-venv), and the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
STUDENTS=${1:-300}
JOBS=${2:-$(nproc)}
BIN=target/release/mazearena
DIR=target/bench
ADMIN=bench-admin-token-0123456789
CODE=rush-hour-2026
NGINX=$(command -v nginx || echo /usr/sbin/nginx)
log() { echo "rush.sh: $*" >&2; }
die() {
  log "error: $*"
  exit 1
}
[ -x "$NGINX" ] || die "needs nginx (apt-get install -y nginx)"
mkdir -p "$DIR"
[ -x "$BIN" ] || cargo build --release --locked
VENV=$DIR/locust-venv
if [ ! -x "$VENV/bin/locust" ]; then
  log "installing Locust in $VENV"
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet 'locust==2.47.0'
fi
WORK=$(realpath "$(mktemp -d "$DIR/rush.XXXXXX")")
PIDS=()
stop_all() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null || true; done
  PIDS=()
}
trap 'stop_all; [ -n "${RUSH_KEEP:-}" ] || rm -rf "$WORK"' EXIT
trap 'exit 130' INT TERM
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
api() { # METHOD PATH [JSON] [TOKEN]
  local args=(-sS -X "$1" "$BASE$2" -H 'content-type: application/json')
  [ -n "${3:-}" ] && args+=(-d "$3")
  [ -n "${4:-}" ] && args+=(-H "authorization: Bearer $4")
  curl "${args[@]}"
}

# run LABEL TRUSTED(yes|no) ADDRESSES STUDENTS BUSY(yes|no) PROXY(yes|no)
run() {
  local label=$1 trusted=$2 addresses=$3 students=$4 busy=$5 proxy=$6
  local run=$WORK/$label port nport extra=() busy_id=
  mkdir -p "$run"
  port=$(free_port)
  [ "$trusted" = yes ] && extra=(--trusted-proxies 127.0.0.1)
  MAZEARENA_ADMIN_TOKEN=$ADMIN "$BIN" serve --bind "127.0.0.1:$port" \
    --database "sqlite://$run/db.sqlite" --data-dir "$run/data" --jobs "$JOBS" \
    "${extra[@]}" >"$run/server.log" 2>&1 &
  PIDS+=($!)
  BASE=http://127.0.0.1:$port
  for _ in $(seq 100); do curl -sf "$BASE/healthz" >/dev/null && break; sleep 0.1; done
  local target=$BASE
  if [ "$proxy" = yes ]; then
    nport=$(free_port)
    mkdir -p "$run/nginx"
    cat >"$run/nginx/nginx.conf" <<CONF
daemon off;
worker_processes 1;
pid $run/nginx/nginx.pid;
error_log $run/nginx/error.log;
events { worker_connections 4096; }
http {
  access_log off;
  client_body_temp_path $run/nginx/body; proxy_temp_path $run/nginx/proxy;
  fastcgi_temp_path $run/nginx/fastcgi; uwsgi_temp_path $run/nginx/uwsgi; scgi_temp_path $run/nginx/scgi;
  client_max_body_size 64m;
  upstream mazearena { server 127.0.0.1:$port; keepalive 64; }
  server {
    listen 127.0.0.1:$nport;
    location / {
      proxy_pass http://mazearena;
      proxy_http_version 1.1;
      proxy_set_header Connection "";
      proxy_set_header Host \$http_host;
      proxy_set_header X-Forwarded-For \$proxy_add_x_forwarded_for;
      proxy_set_header X-Forwarded-Proto \$scheme;
    }
  }
}
CONF
    "$NGINX" -c "$run/nginx/nginx.conf" -p "$run/nginx" >/dev/null 2>&1 &
    PIDS+=($!)
    target=http://127.0.0.1:$nport
    for _ in $(seq 100); do curl -sf "$target/healthz" >/dev/null && break; sleep 0.1; done
  fi
  # The class's competition, by invite.
  api PUT /api/registration "{\"mode\": \"invite\", \"invite_code\": \"$CODE\"}" "$ADMIN" >/dev/null
  local organiser
  organiser=$(api POST /api/organisers '{"name": "teacher"}' "$ADMIN" | python3 -c 'import json,sys; print(json.load(sys.stdin)["key"])')
  for i in 1 2 3; do "$BIN" maze generate --dim 12 --seed "$((4900 + i))" -o "$run/maze-$i.txt" >/dev/null; done
  python3 - "$run" >"$run/competition.json" <<'PY'
import json, sys, time
run = sys.argv[1]
now = time.time()
stamp = lambda t: time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))
maze = lambda i: {"name": f"rush-{i}", "layout": open(f"{run}/maze-{i}.txt").read()}
print(json.dumps({
    "name": "rush", "title": "Rush hour", "opens_at": stamp(now - 60),
    "closes_at": stamp(now + 7200), "repeats": 1, "versions_per_day": 5, "practice_per_day": 5,
    "mazes": {"practice": [maze(1)], "public": [maze(2)], "private": [maze(3)]},
}))
PY
  api POST /api/competitions "$(cat "$run/competition.json")" "$organiser" >/dev/null
  if [ "$busy" = yes ]; then
    # Every worker busy all along: four bots on every shipped maze, a hundred times
    # each, far more matches than the rush lasts.
    local ids=()
    for b in busy-a busy-b busy-c busy-d; do
      ids+=("$(api POST /api/bots "$(python3 -c 'import json,sys; n=sys.argv[1]; print(json.dumps({"name": n, "command": "python3 simple_bot.py", "files": {f: open("bots/python/" + f).read() for f in ["simple_bot.py", "mazebot.py"]}}))' "$b")" "$ADMIN" \
        | python3 -c 'import json,sys; print(json.load(sys.stdin)["bot_id"])')")
    done
    busy_id=$(api POST /api/tournaments "{\"name\": \"busy\", \"bot_ids\": [$(IFS=,; echo "${ids[*]}")], \"maze_ids\": [1,2,3,4,5,6,7,8,9], \"repeats\": 100}" "$ADMIN" \
      | python3 -c 'import json,sys; print(json.load(sys.stdin)["tournament_id"])')
  fi
  log "$label: $students students through $target"
  RUSH_CODE=$CODE RUSH_COMPETITION=rush RUSH_ROBOT=tests/fixtures/robot_py/robot.py \
    RUSH_ADDRESSES=$addresses "$VENV/bin/locust" -f benches/rush_locust.py --headless \
    -u "$students" -r "$students" --host "$target" --run-time 60m --only-summary \
    --csv "$run/locust" >"$run/locust.log" 2>&1 || true
  if [ "$busy" = yes ]; then
    local t
    t=$(curl -s "$BASE/api/tournaments/$busy_id")
    python3 -c 'import json,sys; t=json.loads(sys.argv[1]); sys.exit(0 if t["done"] < t["total"] else 1)' "$t" \
      || log "warning: the busy tournament ended before the rush did"
  fi
  stop_all
  cp "$run/locust_stats.csv" "$WORK/$label.csv"
  cp "$run/locust_failures.csv" "$WORK/$label-failures.csv"
}

run one-address no "" "$STUDENTS" yes yes
run two-addresses yes "127.0.0.2,127.0.0.3" "$STUDENTS" yes yes
run baseline no "" 1 no no

python3 - "$WORK" "$STUDENTS" "$JOBS" <<'PY'
import csv, sys
work, students, jobs = sys.argv[1], sys.argv[2], sys.argv[3]
def rows(label):
    with open(f"{work}/{label}.csv") as f:
        return {(r["Type"], r["Name"]): r for r in csv.DictReader(f)}
runs = {label: rows(label) for label in ("baseline", "one-address", "two-addresses")}
routes = [
    ("GET", "GET /register"), ("POST", "POST /register"), ("POST", "POST /login"),
    ("GET", "GET /competitions/[c]/submit"), ("POST", "POST /competitions/[c]/submit"),
    ("GET", "GET /me"), ("POST", "POST /me/practice"),
]
def cell(label, key, col):
    r = runs[label].get(key)
    return r[col] if r and r["Request Count"] != "0" else "-"
print("## The deadline rush")
print()
print(f"`bash benches/rush.sh {students}`: {students} students at once through nginx, each as a browser does")
print("it (benches/rush_locust.py, Locust): register with the invite code, log in, upload an")
print("original-task robot.py through the form, wait until ready, play two practice matches, while")
print(f"a tournament keeps every worker busy (`--jobs {jobs}`, the server's default limits). Behind one")
print("address: the server without `--trusted-proxies`, so every student is nginx's address; from two")
print("addresses: half the class from 127.0.0.2, half from 127.0.0.3, the server trusting nginx.")
print("The baseline is one student on an idle server, straight to it. Times in ms (Locust rounds")
print("times over 100 ms to 10 ms, over 1 s to 100 ms).")
print()
print("| request | baseline p50 | p99 | one address p50 | p99 | two addresses p50 | p99 |")
print("|---|---:|---:|---:|---:|---:|---:|")
for method, name in routes:
    key = (method, name)
    print(f"| {name} | " + " | ".join(
        cell(l, key, c) for l in ("baseline", "one-address", "two-addresses") for c in ("50%", "99%")) + " |")
ready = ("RUSH", "upload to ready")
print()
print("| per student | baseline | one address | two addresses |")
print("|---|---:|---:|---:|")
print("| upload to ready, median | " + " | ".join(cell(l, ready, "50%") for l in runs) + " |")
print("| upload to ready, worst | " + " | ".join(cell(l, ready, "Max Response Time").split(".")[0] for l in runs) + " |")
def count(label, name):
    r = runs[label].get(("RUSH", name))
    return r["Request Count"] if r else "0"
print("| students ready (of each run's) | " + " | ".join(cell(l, ready, "Request Count") for l in runs) + " |")
print("| right keys or codes refused (must be 0) | " + " | ".join(count(l, "refused right key") for l in runs) + " |")
print("| uploads lost (must be 0) | " + " | ".join(count(l, "lost upload") for l in runs) + " |")
print("| students stopped before the end | " + " | ".join(count(l, "stopped") for l in runs) + " |")
for label in runs:
    with open(f"{work}/{label}-failures.csv") as f:
        failures = [r for r in csv.DictReader(f)]
    if failures:
        print()
        print(f"Failures in the {label} run (Locust's: a request whose answer was an error, and each")
        print("student stopped, with its step and HTTP status):")
        print()
        for r in failures:
            print(f"- {r['Method']} {r['Name']}: {r['Error']} ({r['Occurrences']} times)")
PY
