#!/usr/bin/env bash
# The container image, run for real with podman, as the README's "With podman" section
# says (.ci/readme_podman.py reads its two blocks and checks that their options are
# docker-compose.yml's):
#  1. the single server: the README's block as written (only `podman build` takes the
#     binary built on this machine: the Rust image cannot be pulled here), then: `doctor`
#     reports the full sandbox; /healthz and the first log line say the sandbox is full and
#     what keeps the limits; a bot uploaded over HTTP plays a match to the score `mazearena
#     run` gives on the host; /api/runtimes reports the image's Python packages and Node.js;
#     `podman stop` ends it cleanly within the grace period; the README's `podman run`
#     again on the same volumes still has the match;
#  2. the scale profile: the README's second block as written on a database of the test
#     PostgreSQL (MAZEARENA_TEST_POSTGRES, host network): one API container and two worker
#     containers play a tournament of a Python and a JavaScript bot to the end, every match
#     equal to `mazearena run` on the host and both workers taking part.
#
#   bash .ci/image.sh [BINARY]     (default: target/debug/mazearena, built if missing)
#
# Outside CI a missing podman, runc, debootstrap or PostgreSQL skips (a part) with the
# reason; with CI=true it is a failure. The Debian base (debootstrap --variant=minbase
# bookworm, imported as localhost/debian:bookworm-slim) is made once per machine and kept.
# The README's names are used (containers mazearena, mazearena-api, mazearena-worker-N;
# volumes mazearena-db, mazearena-bots; ports 8080 and 8081): outside CI the test refuses
# to run over ones that exist.
#
# This VM's container facts (docs/SECURITY.md, "Running in a container"): builds need
# chroot isolation and runs runc with cgroupfs (hybrid cgroups), and root cannot raise
# RLIMIT_NOFILE/NPROC, so containers.conf.d/mazearena-ci.conf sets those engine defaults
# and no default ulimits.
set -euo pipefail
# Pipes are read to their end (`grep PATTERN >/dev/null`, not `grep -q`): under pipefail a
# reader that stops early ends the writer with SIGPIPE, and the check fails though it matched.
cd "$(dirname "$0")/.."
BIN=${1:-target/debug/mazearena}
CONTAINERS=(mazearena mazearena-api mazearena-worker-1 mazearena-worker-2 mazearena-k8s-worker mazearena-k8s-api)
VOLUMES=(mazearena-db mazearena-bots)
SCALE_DB=mazearena_image_scale
ours=
skip() {
  if [ "${CI:-}" = true ]; then
    echo "image: $* (CI=true: a failure)" >&2
    exit 1
  fi
  echo "SKIPPED the image test: $*"
  exit 0
}
for tool in podman runc debootstrap openssl curl; do
  command -v "$tool" >/dev/null 2>&1 || skip "$tool is not installed (apt-get install -y podman runc debootstrap)"
done
[ -x "$BIN" ] || cargo build --locked
say() { echo "image: $*"; }
fail() {
  echo "image: FAILED: $*" >&2
  for c in "${CONTAINERS[@]}"; do
    podman container exists "$c" 2>/dev/null && { echo "--- podman logs $c" >&2; podman logs "$c" 2>&1 | tail -15 >&2; }
  done
  exit 1
}
cleanup() {
  [ -n "$ours" ] || return 0
  podman rm -f -v -t 5 "${CONTAINERS[@]}" >/dev/null 2>&1 || true
  podman volume rm -f "${VOLUMES[@]}" >/dev/null 2>&1 || true
  if [ -n "${MAZEARENA_TEST_POSTGRES:-}" ]; then
    psql -q "$MAZEARENA_TEST_POSTGRES" -c "drop database if exists $SCALE_DB" >/dev/null 2>&1 || true
  fi
}
trap cleanup EXIT
STEP_LOG=/tmp/mazearena-image-step.log
: >"$STEP_LOG"
set -E
trap 'fail "line $LINENO: $BASH_COMMAND: $(tail -5 "$STEP_LOG")"' ERR

mkdir -p /etc/containers/containers.conf.d
cat >/etc/containers/containers.conf.d/mazearena-ci.conf <<'EOF'
# Written by mazearena's .ci/image.sh for this kind of VM: hybrid cgroups (crun and
# systemd cgroups refuse them) and no CAP_SYS_RESOURCE (the default ulimits cannot be set).
[containers]
default_ulimits = []

[engine]
runtime = "runc"
cgroup_manager = "cgroupfs"
EOF
export BUILDAH_ISOLATION=chroot

# The README's names must be free (on a CI machine, leftovers of an earlier run go).
taken=()
for c in "${CONTAINERS[@]}"; do podman container exists "$c" && taken+=("container $c"); done
for v in "${VOLUMES[@]}"; do podman volume exists "$v" && taken+=("volume $v"); done
for port in 8080 8081; do
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && taken+=("port $port")
done
if [ ${#taken[@]} -gt 0 ]; then
  [ "${CI:-}" = true ] || skip "the README's ${taken[*]} exist(s) here: remove them to run it"
  podman rm -f -v "${CONTAINERS[@]}" >/dev/null 2>&1 || true
  podman volume rm -f "${VOLUMES[@]}" >/dev/null 2>&1 || true
fi
ours=1

python3 .ci/readme_podman.py check >/tmp/mazearena-image-options.log 2>&1 ||
  fail "$(cat /tmp/mazearena-image-options.log)"
say "the README's podman options are docker-compose.yml's (security options, memory, processes, grace)"

started=$(date +%s)
if ! podman image exists localhost/debian:bookworm-slim; then
  cache=/var/cache/mazearena-ci
  mkdir -p "$cache"
  if [ ! -f "$cache/bookworm-minbase.tar" ]; then
    say "making the Debian base (debootstrap, once per machine)"
    rm -rf "$cache/rootfs"
    debootstrap --variant=minbase bookworm "$cache/rootfs" http://deb.debian.org/debian >"$cache/debootstrap.log" 2>&1 ||
      fail "debootstrap: $(tail -3 "$cache/debootstrap.log")"
    tar -C "$cache/rootfs" -cf "$cache/bookworm-minbase.tar" .
    rm -rf "$cache/rootfs"
  fi
  podman import "$cache/bookworm-minbase.tar" localhost/debian:bookworm-slim >/dev/null
fi

# A README `curl` of a server just started: retried until it answers (by hand, a second later).
answer_of() {
  local out
  for _ in $(seq 150); do
    if out=$("$@" 2>/dev/null) && [ -n "$out" ]; then
      printf '%s\n' "$out"
      return 0
    fi
    sleep 0.2
  done
  fail "no answer to: $*"
}
json() { python3 -c "import json, sys; d = json.load(sys.stdin); print($1)"; }

say "running the README's single-server block (binary $BIN)"
podman rmi -f mazearena:latest >/dev/null 2>&1 || true
block=$(python3 .ci/readme_podman.py script 0)
eval "$block" >/tmp/mazearena-image-block.out 2>"$STEP_LOG"
health=$(tail -1 /tmp/mazearena-image-block.out)
[ -n "${MAZEARENA_ADMIN_TOKEN:-}" ] || fail "the README's block exports no MAZEARENA_ADMIN_TOKEN"
grep -q '"sandbox":"full"' <<<"$health" || fail "/healthz: $health"
# No cgroup can be made in this container: /healthz and the first line say the watchdog
# keeps the limits.
grep -q '"limits":"watchdog"' <<<"$health" || fail "/healthz does not say what keeps the limits: $health"
podman logs mazearena 2>&1 | grep "match limits by watchdog" >/dev/null || fail "the server's first line does not say what keeps the limits"
say "serve: /healthz with the full sandbox, limits by the watchdog (also in its log)"

mapfile -t security < <(python3 .ci/readme_podman.py commands 0 | grep -- '--name mazearena ' |
  grep -o -- '--security-opt [^ ]*')
doctor=$(podman run --rm $(printf '%s ' "${security[@]}") mazearena:latest doctor 2>&1 || true)
grep -q "sandbox level: full" <<<"$doctor" || fail "doctor in the image: $(tail -5 <<<"$doctor")"
say "doctor with the README's options: sandbox level full"

api=http://127.0.0.1:8080
upload() { # NAME COMMAND DIR FILE... -> the owner token
  local name=$1 command=$2 dir=$3
  shift 3
  python3 - "$name" "$command" "$dir" "$@" <<'EOF' | curl -s "$api/api/bots" -H 'content-type: application/json' -d @- | json 'd["owner_token"]'
import json, sys
name, command, folder, *files = sys.argv[1:]
print(json.dumps({"name": name, "command": command,
                  "files": {f: open(folder + "/" + f).read() for f in files}}))
EOF
}
maze_id() { curl -s "$api/api/mazes" | json "next(m['maze_id'] for m in d if m['name'] == '$1')"; }
on_host() { # MAZE BOT DIR SEED -> "status score"
  "$BIN" run --maze "mazes/$1.txt" --bot "$2" --bot-dir "$3" --seed "$4" --json | json '"%s %s" % (d["status"], d["score"])'
}

token=$(upload py "python3 simple_bot.py" bots/python simple_bot.py mazebot.py) || fail "upload"
curl -s "$api/api/matches" -H "authorization: Bearer $token" -H 'content-type: application/json' \
  -d "{\"bot_id\": 1, \"maze_id\": $(maze_id gen-12-s1), \"seed\": 0}" >/dev/null
in_image=
for _ in $(seq 150); do
  in_image=$(curl -s "$api/api/matches/1" | json '"%s %s" % (d["status"], d["score"]) if d["status"] not in ("queued", "running") else ""')
  [ -n "$in_image" ] && break
  sleep 0.2
done
host=$(on_host gen-12-s1 "python3 simple_bot.py" bots/python 0)
[ "$in_image" = "$host" ] || fail "the match in the image ($in_image) differs from the host's ($host)"
say "a match in the image: $in_image, as on the host"

runtimes=$(curl -s "$api/api/runtimes" | python3 -c '
import json, sys
system = next(r for r in json.load(sys.stdin) if r["name"] == "system")
have = {p["name"]: p["version"] for p in system["packages"]}
programs = {p["program"]: p["version"] for p in system["programs"]}
missing = [n for n in ("numpy", "pandas", "scipy") if n not in have] + [n for n in ("python3", "node") if n not in programs]
print("missing " + " ".join(missing) if missing else
      "python3 %s, numpy %s, pandas %s, scipy %s, node %s" % (programs["python3"], have["numpy"], have["pandas"], have["scipy"], programs["node"]))')
[[ "$runtimes" != missing* ]] || fail "/api/runtimes: $runtimes"
say "runtimes: $runtimes"

t0=$(date +%s%N)
podman stop mazearena >/dev/null
stopped_ms=$((($(date +%s%N) - t0) / 1000000))
podman logs mazearena 2>&1 | grep "mazearena stopped" >/dev/null || fail "podman stop: no clean stop in the log"
[ "$stopped_ms" -lt 30000 ] || fail "podman stop: took ${stopped_ms} ms"
say "podman stop: stopped cleanly in ${stopped_ms} ms"
podman rm mazearena >/dev/null
run=$(python3 .ci/readme_podman.py commands 0 | grep -- '--name mazearena ')
eval "$run" >/dev/null 2>"$STEP_LOG"
answer_of curl -s "$api/healthz" >/dev/null
again=$(curl -s "$api/api/matches/1" | json '"%s %s" % (d["status"], d["score"])')
[ "$again" = "$in_image" ] || fail "after a restart on the same volume: $again"
say "the README's podman run again on the same volumes: match 1 still $again"
podman stop mazearena >/dev/null
say "the single server passed in $(($(date +%s) - started)) s"

# Waits for tournament ID (TOTAL matches) to end; fails unless each match is as on the host.
check_tournament() {
  local id=$1 total=$2 progress= bad
  for _ in $(seq 600); do
    progress=$(curl -s "$api/api/tournaments/$id" | json '"%d/%d" % (d["done"], d["total"])' 2>/dev/null || true)
    [ -n "$progress" ] && [ "${progress%/*}" = "${progress#*/}" ] && break
    sleep 0.2
  done
  [ "$progress" = "$total/$total" ] || fail "tournament $id did not end: $progress"
  bad=$(curl -s "$api/api/matches?tournament_id=$id&limit=200" | python3 -c '
import json, subprocess, sys
bots = {1: ("python3 simple_bot.py", "bots/python"), 2: ("node minimal_bot.js", "bots/javascript")}
mazes = dict(zip(sys.argv[2].split(","), sys.argv[4:]))
items = json.load(sys.stdin)["items"]
bad = [] if len(items) == int(sys.argv[3]) else ["%d matches listed" % len(items)]
for m in items:
    command, folder = bots[m["bot_id"]]
    host = json.loads(subprocess.run([sys.argv[1], "run", "--maze", "mazes/%s.txt" % mazes[str(m["maze_id"])],
        "--bot", command, "--bot-dir", folder, "--seed", str(m["seed"]), "--json"],
        check=True, capture_output=True, text=True).stdout)
    if (m["status"], m["score"]) != (host["status"], host["score"]):
        bad.append("match %d: %s %s, on the host %s %s" % (m["match_id"], m["status"], m["score"], host["status"], host["score"]))
print("; ".join(bad))' "$BIN" "$ids" "$total" "${mazes[@]}")
  [ -z "$bad" ] || fail "tournament $id's matches: $bad"
}

# --- the scale profile --------------------------------------------------------------
if [ -z "${MAZEARENA_TEST_POSTGRES:-}" ]; then
  skip "the scale profile: MAZEARENA_TEST_POSTGRES is not set (.ci/postgres.sh start DIR)"
fi
started=$(date +%s)
PGOPTIONS=--client-min-messages=warning psql -q "$MAZEARENA_TEST_POSTGRES" -c "drop database if exists $SCALE_DB" -c "create database $SCALE_DB" >/dev/null
export MAZEARENA_DATABASE="${MAZEARENA_TEST_POSTGRES%/*}/$SCALE_DB"
say "running the README's scale block (one API server, two workers) on $SCALE_DB"
block=$(python3 .ci/readme_podman.py script 1)
eval "$block" >/tmp/mazearena-image-block.out 2>"$STEP_LOG"
api=http://127.0.0.1:8081
for _ in $(seq 100); do
  workers=$(curl -s "$api/healthz" -H "authorization: Bearer $MAZEARENA_ADMIN_TOKEN" | json 'sum(1 for w in d["workers"] if w["role"] == "worker" and w["sandbox"] == "full")' 2>/dev/null || true)
  [ "$workers" = 2 ] && break
  sleep 0.2
done
[ "$workers" = 2 ] || fail "two sandboxed workers in /healthz: $(curl -s "$api/healthz" -H "authorization: Bearer $MAZEARENA_ADMIN_TOKEN")"
say "API up, two workers with the full sandbox"

upload py "python3 simple_bot.py" bots/python simple_bot.py mazebot.py >/dev/null || fail "upload"
upload js "node minimal_bot.js" bots/javascript minimal_bot.js mazebot.js >/dev/null || fail "upload"
mazes=(gen-12-s1 gen-12-s2 gen-14-s1)
ids=$(for m in "${mazes[@]}"; do maze_id "$m"; done | paste -sd,)
curl -s "$api/api/tournaments" -H "authorization: Bearer $MAZEARENA_ADMIN_TOKEN" -H 'content-type: application/json' \
  -d "{\"name\": \"image-scale\", \"bot_ids\": [1, 2], \"maze_ids\": [$ids], \"repeats\": 2}" >/dev/null
check_tournament 1 12
# Each worker reports its count every few seconds.
for _ in $(seq 60); do
  done_by=$(curl -s "$api/healthz" -H "authorization: Bearer $MAZEARENA_ADMIN_TOKEN" | json '" ".join(str(w["matches_done"]) for w in d["workers"] if w["role"] == "worker")')
  [ $((${done_by// /+})) = 12 ] && break
  sleep 0.25
done
for n in $done_by; do [ "$n" -gt 0 ] || fail "a worker played no match: $done_by"; done
[ $((${done_by// /+})) = 12 ] || fail "the workers report $done_by matches, not 12"
say "a tournament of 12 matches played to the end, each as on the host; matches by worker: $done_by"
podman stop mazearena-worker-1 mazearena-worker-2 >/dev/null
for w in 1 2; do
  podman logs "mazearena-worker-$w" 2>&1 | grep "mazearena worker stopped" >/dev/null || fail "worker $w: no clean stop"
done
say "the scale profile passed in $(($(date +%s) - started)) s"

# --- the Kubernetes worker's pod ----------------------------------------------------
# deploy/kubernetes/worker.yaml's pod spec, given to podman option for option by
# .ci/kube_podman.py (a user namespace of the pod's own, the lifted seccomp and AppArmor
# profiles and /proc masking, no capability, no_new_privs, a read-only root with its two
# emptyDirs, its CPU and memory, its variables): with the README's workers stopped, this
# worker alone plays a second tournament, every match as on the host, and stops cleanly
# on SIGTERM within the pod's terminationGracePeriodSeconds.
started=$(date +%s)
python3 -c 'import yaml' 2>/dev/null || python3 -m pip install -q pyyaml 2>/dev/null ||
  { apt-get update -qq && apt-get install -y -qq python3-yaml; }
kopts=$(python3 .ci/kube_podman.py deploy/kubernetes/worker.yaml 2>&1) || fail "$kopts"
say "the Kubernetes worker's pod as podman options: $kopts"
eval "podman run -d --name mazearena-k8s-worker --network host --no-healthcheck $kopts \
  -e MAZEARENA_DATABASE=\"\$MAZEARENA_DATABASE\" localhost/mazearena:latest worker" >/dev/null 2>"$STEP_LOG" ||
  fail "podman run of the Kubernetes worker: $(cat "$STEP_LOG")"
curl -s "$api/api/tournaments" -H "authorization: Bearer $MAZEARENA_ADMIN_TOKEN" -H 'content-type: application/json' \
  -d "{\"name\": \"image-k8s\", \"bot_ids\": [1, 2], \"maze_ids\": [$ids], \"repeats\": 1}" >/dev/null
check_tournament 2 6
podman logs mazearena-k8s-worker 2>&1 | grep "sandbox full" >/dev/null || fail "the Kubernetes worker did not say 'sandbox full'"
grace=$(python3 -c 'import sys, yaml; d = next(x for x in yaml.safe_load_all(open(sys.argv[1])) if x["kind"] == "Deployment"); print(d["spec"]["template"]["spec"]["terminationGracePeriodSeconds"])' deploy/kubernetes/worker.yaml)
t0=$(date +%s%N)
podman stop -t "$grace" mazearena-k8s-worker >/dev/null
stopped_ms=$((($(date +%s%N) - t0) / 1000000))
podman logs mazearena-k8s-worker 2>&1 | grep "mazearena worker stopped" >/dev/null || fail "the Kubernetes worker: no clean stop"
[ "$stopped_ms" -lt $((grace * 1000)) ] || fail "the Kubernetes worker took ${stopped_ms} ms to stop (grace ${grace} s)"
say "the Kubernetes worker's pod played 6 matches alone, each as on the host (sandbox full), and stopped in ${stopped_ms} ms ($(($(date +%s) - started)) s)"
podman stop mazearena-api >/dev/null

# The API server's pod (deploy/kubernetes/api.yaml) the same way: read-only root, no
# capability, no_new_privs, its emptyDirs; it starts, answers, and takes an upload (checked
# in its data folder) on the same database.
aopts=$(python3 .ci/kube_podman.py deploy/kubernetes/api.yaml 2>&1) || fail "$aopts"
eval "podman run -d --name mazearena-k8s-api --network host --no-healthcheck $aopts \
  -e MAZEARENA_BIND=127.0.0.1:8082 -e MAZEARENA_DATABASE=\"\$MAZEARENA_DATABASE\" \
  -e MAZEARENA_ADMIN_TOKEN=\"\$MAZEARENA_ADMIN_TOKEN\" localhost/mazearena:latest serve --jobs 0" >/dev/null 2>"$STEP_LOG" ||
  fail "podman run of the Kubernetes API server: $(cat "$STEP_LOG")"
api=http://127.0.0.1:8082
answer_of curl -sf "$api/healthz" >/dev/null
upload py-k8s "python3 simple_bot.py" bots/python simple_bot.py mazebot.py >/dev/null || fail "an upload to the Kubernetes API server's pod"
podman stop mazearena-k8s-api >/dev/null
podman logs mazearena-k8s-api 2>&1 | grep "API only" >/dev/null || fail "the Kubernetes API server's pod: $(podman logs mazearena-k8s-api 2>&1 | tail -3)"
say "the Kubernetes API server's pod answers and takes an upload"
