#!/usr/bin/env bash
# Measures the referee's per-step overhead: a full 1000-step match (step_limit) against
# a trivial compiled bot, repeated, with the release binary.
# Usage: benches/match_overhead.sh [REPEATS]   (needs gcc)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-20}
cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gcc -O2 -o "$tmp/trivial_bot" benches/trivial_bot.c
maze=mazes/gen-16-s1.txt
total_ms=0
best_ms=
for _ in $(seq "$repeats"); do
  start=$(date +%s%N)
  out=$(./target/release/mazearena run --maze "$maze" --bot "$tmp/trivial_bot" --json)
  end=$(date +%s%N)
  echo "$out" | grep -q '"status":"step_limit"' || { echo "unexpected result: $out" >&2; exit 1; }
  ms=$(( (end - start) / 1000000 ))
  total_ms=$(( total_ms + ms ))
  if [ -z "$best_ms" ] || [ "$ms" -lt "$best_ms" ]; then best_ms=$ms; fi
done
mean_ms=$(( total_ms / repeats ))
echo "1000-step match, trivial C bot, $repeats runs: mean ${mean_ms} ms, best ${best_ms} ms wall per match (process start to exit)"
echo "per-step round trip: mean $(( mean_ms * 1000 / 1000 )) us, best $(( best_ms * 1000 / 1000 )) us"
