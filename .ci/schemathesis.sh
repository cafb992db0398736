#!/usr/bin/env bash
# Schemathesis (PyPI) against a live server's /api/openapi.json: generated requests to
# every operation (valid and invalid, then stateful sequences), with a bounded number of
# examples; fails on any 5xx and on any answer that does not match the document
# (status code, content type, headers, body schema).
#
#   bash .ci/schemathesis.sh DATABASE_URL [EXAMPLES]
# Needs a built target/debug/mazearena and python3 (schemathesis goes in a venv).
set -euo pipefail
cd "$(dirname "$0")/.."
database=${1:?a database URL}
examples=${2:-20}
venv=${SCHEMATHESIS_VENV:-/tmp/mazearena-schemathesis}
if [ ! -x "$venv/bin/st" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q 'schemathesis>=4,<5'
fi
work=$(mktemp -d)
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
MAZEARENA_ADMIN_TOKEN=schemathesis-admin ./target/debug/mazearena serve \
  --bind "127.0.0.1:$port" --database "$database" --data-dir "$work/data" --jobs 1 \
  >"$work/server.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -rf "$work"' EXIT
for _ in $(seq 100); do
  curl -fs "http://127.0.0.1:$port/healthz" >/dev/null && break
  sleep 0.1
done
# Run from the scratch folder: schemathesis keeps a cache where it runs.
(cd "$work" && "$venv/bin/st" run "http://127.0.0.1:$port/api/openapi.json" \
  --checks not_a_server_error,response_schema_conformance,status_code_conformance,content_type_conformance,response_headers_conformance \
  --max-examples "$examples" --seed 1 --generation-database none \
  -H "Authorization: Bearer schemathesis-admin") || {
  echo "--- server log" >&2
  tail -50 "$work/server.log" >&2
  exit 1
}
