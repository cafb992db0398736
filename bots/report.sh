#!/usr/bin/env bash
# Rebuilds the result tables of bots/README.md: every bot under bots/ on the three classic
# mazes (10 seeds each), then on the contest mazes (standings only).
# Usage: bots/report.sh > report.md    (from the repository; needs ../shared/mazes)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
arena=./target/release/mazearena
echo "### Classic mazes (mean of seeds 0-9; $(date -u +%Y-%m-%d))"
echo
"$arena" tournament --bots bots --mazes ../shared/mazes/classic --repeats 10 \
    --database "sqlite://$tmp/report.db" --name classic --markdown
echo
echo "### Contest mazes (every file of ../shared/mazes/micromouseonline/classic whose goal room can be reached, duplicates once)"
echo
"$arena" tournament --bots bots --mazes ../shared/mazes/micromouseonline/classic \
    --database "sqlite://$tmp/report.db" --name contest --markdown | sed -n '/^| rank |/,$p'
