#!/usr/bin/env bash
# The cost of one whole match, with and without the sandbox, in the same run: a full
# 1000-step match (step_limit) against a trivial compiled bot, process start to exit of
# `mazearena run`, with the release binary. The difference is the sandbox's overhead.
# Usage: benches/match_overhead.sh [REPEATS]   (needs gcc and bubblewrap)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-20}
cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gcc -O2 -o "$tmp/trivial_bot" benches/trivial_bot.c
maze=$PWD/mazes/gen-16-s1.txt
measure() { # $1: full or none
  local total=0 best= ms start end out
  for _ in $(seq "$repeats"); do
    start=$(date +%s%N)
    out=$(./target/release/mazearena run --maze "$maze" --bot ./trivial_bot --bot-dir "$tmp" \
          --sandbox "$1" --json 2>/dev/null)
    end=$(date +%s%N)
    echo "$out" | grep '"status":"step_limit"' >/dev/null || { echo "unexpected result: $out" >&2; exit 1; }
    ms=$(( (end - start) / 1000000 ))
    total=$(( total + ms ))
    if [ -z "$best" ] || [ "$ms" -lt "$best" ]; then best=$ms; fi
  done
  echo "sandbox $1: mean $(( total / repeats )) ms, best ${best} ms per 1000-step match ($repeats runs)"
}
# Interleave nothing else: none first (baseline), then full, then none again.
measure none
measure full
measure none
