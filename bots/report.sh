#!/usr/bin/env bash
# Rebuilds the result tables of bots/README.md: every bot under bots/ on the three classic
# mazes (10 seeds each), then on the contest mazes and on 60 freshly generated mazes
# (standings only).
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
echo
echo "### Freshly generated mazes (60 no bot was tuned on: seeds 5000-5019 at 12x12, 5020-5039 at 14x14, 5040-5059 at 16x16)"
echo
mkdir "$tmp/generated"
seed=5000
for dim in 12 14 16; do
    for _ in $(seq 20); do
        "$arena" maze generate --dim "$dim" --seed "$seed" -o "$tmp/generated/gen-$dim-$seed.txt"
        seed=$((seed + 1))
    done
done
"$arena" tournament --bots bots --mazes "$tmp/generated" \
    --database "sqlite://$tmp/report.db" --name generated --markdown | sed -n '/^| rank |/,$p'
