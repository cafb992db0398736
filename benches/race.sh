#!/usr/bin/env bash
# A race of N robots in Chromium: frames and memory. A local tournament of N bots on one
# 16 x 16 maze (tests/fixtures/bots/dawdler.py around the Python kit's simple_bot.py,
# each standing still a different number of steps, so that the runs last from about a
# hundred steps to about a thousand), its race written as one offline file by the
# server's page, and the same race with its longest-running robot alone (the baseline), each
# opened in headless Chromium (chromedriver, driven by benches/race_driver.py): frames a
# second while it plays at 200 steps a second, the time to draw one frame stepping
# forward and jumping anywhere (the trails drawn again), and the script's heap.
#
#   bash benches/race.sh [N]      (default 100)
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-100}
cargo build --release --locked --quiet
bin=$PWD/target/release/mazearena
tmp=$(mktemp -d)
trap 'kill $SERVER 2>/dev/null || true; rm -rf "$tmp"' EXIT
SERVER=
cp tests/fixtures/bots/dawdler.py bots/python/simple_bot.py bots/python/mazebot.py "$tmp/"
"$bin" maze generate --dim 16 --seed 4102 -o "$tmp/maze.txt" >/dev/null
{
  for ((i = 0; i < N; i++)); do
    echo "[[bot]]"
    echo "name = \"robot-$i\""
    echo "language = \"python\""
    echo "command = \"python3 dawdler.py $(( (i * 37) % 800 )) $(( i % 7 ))\""
    echo
  done
} >"$tmp/bot.toml"
"$bin" tournament --bots "$tmp/bot.toml" --mazes "$tmp/maze.txt" --jobs 2 --sandbox none \
  --database "sqlite://$tmp/race.db" >"$tmp/tournament.log" 2>&1
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
MAZEARENA_ADMIN_TOKEN=bench-admin-token-0123456789 "$bin" serve --bind "127.0.0.1:$port" \
  --database "sqlite://$tmp/race.db" --data-dir "$tmp/data" --jobs 0 >"$tmp/server.log" 2>&1 &
SERVER=$!
until curl -s -o /dev/null "http://127.0.0.1:$port/healthz"; do sleep 0.2; done
maze=$(curl -s "http://127.0.0.1:$port/api/matches?limit=1" | python3 -c 'import json, sys; print(json.load(sys.stdin)["items"][0]["maze_id"])')
curl -sf -o "$tmp/race.html" "http://127.0.0.1:$port/tournaments/1/race/$maze/0?download=1"
kill $SERVER
# The baseline: the same file with its longest-running robot alone (as many frames).
python3 - "$tmp/race.html" "$tmp/one.html" <<'PY'
import json, re, sys
text = open(sys.argv[1]).read()
m = re.search(r'(<script type="application/json" id="finale-data">)(.*?)(</script>)', text, re.S)
data = json.loads(m.group(2))
runners = data["race"]["runners"]
data["race"]["runners"] = [max(runners, key=lambda r: max(len(r["run0"]), 1) + len(r["run1"]))]
one = json.dumps(data).replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
open(sys.argv[2], "w").write(text[:m.start(2)] + one + text[m.end(2):])
PY
python3 benches/race_driver.py "$tmp/one.html" "$tmp/race.html"
