#!/usr/bin/env bash
# The container image, run for real with podman: the runtime stage of the Dockerfile
# (the one users get) around a binary built on this machine, started with the security
# options of docker-compose.yml's `mazearena` service, then checked: `doctor` reports the
# full sandbox; `serve` answers /healthz with it; a bot uploaded over HTTP plays a match to
# the score `mazearena run` gives on the host; /api/runtimes reports the image's Python
# packages and Node.js; SIGTERM stops it within the grace period; the data survives a
# restart on the same volume.
#
#   bash .ci/image.sh [BINARY]     (default: target/debug/mazearena, built if missing)
#
# Outside CI a missing podman, runc or debootstrap skips it with the reason; with CI=true
# it is a failure. The Debian base (debootstrap --variant=minbase bookworm, imported as
# localhost/debian:bookworm-slim) is made once per machine and kept.
#
# This VM's container facts (docs/SECURITY.md, "Running in a container"): builds need
# `--isolation=chroot` and runs `--runtime runc --cgroup-manager cgroupfs` (hybrid
# cgroups), and root cannot raise RLIMIT_NOFILE/NPROC, so containers.conf sets no
# default ulimits.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/debug/mazearena}
PORT=18400
NAME=mazearena-ci-image
VOLUME=mazearena-ci-db
skip() {
  if [ "${CI:-}" = true ]; then
    echo "image: $* (CI=true: a failure)" >&2
    exit 1
  fi
  echo "SKIPPED the image test: $*"
  exit 0
}
for tool in podman runc debootstrap; do
  command -v "$tool" >/dev/null 2>&1 || skip "$tool is not installed (apt-get install -y podman runc debootstrap)"
done
[ -x "$BIN" ] || cargo build --locked
say() { echo "image: $*"; }
fail() {
  echo "image: FAILED: $*" >&2
  podman logs "$NAME" 2>&1 | tail -20 >&2 || true
  exit 1
}
run_podman() { podman --runtime runc --cgroup-manager cgroupfs "$@"; }
cleanup() {
  run_podman rm -f "$NAME" >/dev/null 2>&1 || true
  podman volume rm -f "$VOLUME" >/dev/null 2>&1 || true
}
trap cleanup EXIT
cleanup

if [ ! -f /etc/containers/containers.conf ] || ! grep -q default_ulimits /etc/containers/containers.conf; then
  mkdir -p /etc/containers
  printf '[containers]\ndefault_ulimits = []\n' >>/etc/containers/containers.conf
fi

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

say "building the image from the Dockerfile (runtime stage, binary $BIN)"
podman build --isolation=chroot --build-arg BINARY=prebuilt --build-arg PREBUILT="$BIN" \
  -t localhost/mazearena:ci . >/tmp/mazearena-image-build.log 2>&1 ||
  fail "podman build: $(tail -5 /tmp/mazearena-image-build.log)"

# The security options of the compose file's `mazearena` service, in podman's words.
opts=()
while read -r opt; do
  case "$opt" in
    systempaths=unconfined) opts+=(--security-opt unmask=ALL) ;;
    *) opts+=(--security-opt "$opt") ;;
  esac
done < <(awk '/^  mazearena:/ {s=1; next} /^  [a-z]/ {s=0} s && /security_opt:/ {o=1; next}
              s && o && /^      - / {print $2; next} s && o {o=0}' docker-compose.yml)
[ ${#opts[@]} -ge 3 ] || fail "no security_opt read from docker-compose.yml: ${opts[*]}"
say "options from docker-compose.yml: ${opts[*]}"

doctor=$(run_podman run --rm "${opts[@]}" localhost/mazearena:ci doctor 2>&1 || true)
grep -q "sandbox level: full" <<<"$doctor" || fail "doctor in the image: $(tail -5 <<<"$doctor")"
say "doctor: sandbox level full"

serve() {
  run_podman run -d --name "$NAME" --network host "${opts[@]}" \
    -e MAZEARENA_ADMIN_TOKEN=image-test-admin-token-0123456789 -e MAZEARENA_BIND=127.0.0.1:$PORT \
    -v "$VOLUME:/var/lib/mazearena/db" localhost/mazearena:ci >/dev/null
  for _ in $(seq 100); do
    curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  fail "the server in the image did not answer /healthz"
}
serve
health=$(curl -s "http://127.0.0.1:$PORT/healthz")
grep -q '"sandbox":"full"' <<<"$health" || fail "/healthz: $health"
# No cgroup can be made in this container: /healthz and the first line say the watchdog
# keeps the limits.
grep -q '"limits":"watchdog"' <<<"$health" || fail "/healthz does not say what keeps the limits: $health"
run_podman logs "$NAME" 2>&1 | grep -q "match limits by watchdog" || fail "the server's first line does not say what keeps the limits"
say "serve: /healthz with the full sandbox, limits by the watchdog (also in its log)"

upload=$(python3 -c '
import json
fs = ["simple_bot.py", "mazebot.py"]
print(json.dumps({"name": "py", "command": "python3 simple_bot.py",
                  "files": {f: open("bots/python/" + f).read() for f in fs}}))' |
  curl -s "http://127.0.0.1:$PORT/api/bots" -H 'content-type: application/json' -d @-)
token=$(python3 -c 'import json,sys; print(json.load(sys.stdin)["owner_token"])' <<<"$upload") ||
  fail "upload: $upload"
maze=$(curl -s "http://127.0.0.1:$PORT/api/mazes" |
  python3 -c 'import json,sys; print(next(m["maze_id"] for m in json.load(sys.stdin) if m["name"] == "gen-12-s1"))')
curl -s "http://127.0.0.1:$PORT/api/matches" -H "authorization: Bearer $token" \
  -H 'content-type: application/json' -d "{\"bot_id\": 1, \"maze_id\": $maze, \"seed\": 0}" >/dev/null
in_image=
for _ in $(seq 150); do
  in_image=$(curl -s "http://127.0.0.1:$PORT/api/matches/1" |
    python3 -c 'import json,sys; m=json.load(sys.stdin); print(m["status"], m["score"]) if m["status"] not in ("queued", "running") else None')
  [ -n "$in_image" ] && break
  sleep 0.2
done
on_host=$("$BIN" run --maze mazes/gen-12-s1.txt --bot 'python3 simple_bot.py' --bot-dir bots/python \
  --seed 0 --json | python3 -c 'import json,sys; m=json.load(sys.stdin); print(m["status"], m["score"])')
[ "$in_image" = "$on_host" ] || fail "the match in the image ($in_image) differs from the host's ($on_host)"
say "a match in the image: $in_image, as on the host"

runtimes=$(curl -s "http://127.0.0.1:$PORT/api/runtimes" | python3 -c '
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
run_podman stop -t 30 "$NAME" >/dev/null
stopped_ms=$((($(date +%s%N) - t0) / 1000000))
podman logs "$NAME" 2>&1 | grep -q "mazearena stopped" || fail "SIGTERM: no clean stop in the log"
[ "$stopped_ms" -lt 30000 ] || fail "SIGTERM: took ${stopped_ms} ms"
say "SIGTERM: stopped cleanly in ${stopped_ms} ms"
run_podman rm "$NAME" >/dev/null
serve
again=$(curl -s "http://127.0.0.1:$PORT/api/matches/1" | python3 -c 'import json,sys; m=json.load(sys.stdin); print(m["status"], m["score"])')
[ "$again" = "$in_image" ] || fail "after a restart on the same volume: $again"
say "restart on the same volume: match 1 still $again"
say "passed in $(($(date +%s) - started)) s"
