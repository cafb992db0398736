#!/usr/bin/env bash
# Bytes per stored match: a tournament of every shipped bot (bots/*/bot.toml) on every
# EVERY-th contest maze of ../shared/mazes/micromouseonline/classic (default: every
# 17th, 31 mazes), then the database's bytes per match: the stored record and summary
# (payload), and the whole file after VACUUM (with SQLite's pages and indexes).
#
#   bash benches/storage.sh [EVERY]
set -euo pipefail
cd "$(dirname "$0")/.."
EVERY=${1:-17}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/mazes"
ls ../shared/mazes/micromouseonline/classic/*.txt | awk -v e="$EVERY" '(NR - 1) % e == 0' |
  while read -r f; do cp "$f" "$tmp/mazes/"; done
bots=$(for d in bots/*/; do [ -f "$d/bot.toml" ] && echo "${d%/}"; done)
# shellcheck disable=SC2086
./target/release/mazearena tournament --bots $bots --mazes "$tmp/mazes" \
  --database "sqlite://$tmp/t.db" --json >"$tmp/t.json"
python3 - "$tmp/t.db" <<'EOF'
import os, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
n, data, summary = db.execute(
    "select count(*), avg(length(r.data)), avg(length(m.record)) from match m "
    "join match_record r on r.match_id = m.match_id").fetchone()
steps = db.execute("select avg(total_steps) from match").fetchone()[0]
db.execute("vacuum")
db.close()
size = os.path.getsize(sys.argv[1])
print(f"{n} matches (mean {steps:.0f} steps): record {data:.0f} B + summary {summary:.0f} B "
      f"= {data + summary:.0f} B payload per match; file {size} B = {size / n:.0f} B per match")
EOF
