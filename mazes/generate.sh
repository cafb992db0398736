#!/usr/bin/env bash
# Regenerates the shipped mazes from their seeds (same seed, same maze).
set -euo pipefail
cd "$(dirname "$0")/.."
for dim in 12 14 16; do
  for seed in 1 2 3; do
    cargo run --quiet -- maze generate --dim "$dim" --seed "$seed" -o "mazes/gen-${dim}-s${seed}.txt"
  done
done
