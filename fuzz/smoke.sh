#!/usr/bin/env bash
# A short run of every fuzz target (SECONDS each, default 20), from the committed seeds
# into a scratch corpus; fails on the first crash.
#   bash fuzz/smoke.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-20}
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for target in maze_numeric maze_ascii protocol_line archive mms_command; do
  mkdir -p "$scratch/$target"
  echo "== fuzz $target ($secs s)"
  status=0
  cargo +nightly fuzz run "$target" "$scratch/$target" "corpus/$target" -- \
    -max_total_time="$secs" >"$scratch/$target.log" 2>&1 || status=$?
  grep -E "^Done|ERROR|panicked" "$scratch/$target.log" || true
  if [ "$status" != 0 ]; then
    tail -40 "$scratch/$target.log" >&2
    echo "fuzz target $target crashed (see fuzz/artifacts/$target)" >&2
    exit 1
  fi
done
