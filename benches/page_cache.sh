#!/usr/bin/env bash
# What a read-latency probe of the host's page cache still carries from one match to a
# later one, now that the kernel's own answers (mincore, cachestat, preadv2 with
# RWF_NOWAIT, Linux AIO) are refused: a sender match reads page k*16 of a large file of
# /usr for each 1 in a random N-bit message (readahead off); a receiver match, later and in
# another sandbox, times a one-byte read of each such page. Both are `mazearena run` in the
# full sandbox (the bots: benches/page_cache/). Before each round the file is dropped from
# the cache (as root, outside any sandbox: a stand-in for a file nobody has read lately).
#
#   bash benches/page_cache.sh [ROUNDS] [BITS]   (default 3 rounds of 4096 bits)
#
# Prints a markdown table: the bit errors, and the bits a match carries (N x (1 - H(e))).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-3}
BITS=${2:-4096}
STRIDE=16
THRESHOLD_US=${THRESHOLD_US:-20}
BIN=target/release/mazearena
[ -x "$BIN" ] || cargo build --release --locked
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
# The largest file of /usr/lib that anyone may read, that holds the pages needed and that
# no process maps (a mapped page is not dropped from the cache).
need=$((BITS * STRIDE * 4096))
mapped=$(cat /proc/[0-9]*/maps 2>/dev/null | awk 'NF >= 6 {print $6}' | sort -u || true)
candidates=$(find /usr/lib -xdev -type f -perm -o=r -size +$((need / 1048576 + 1))M -printf '%s %p\n' 2>/dev/null \
  | sort -rn | cut -d' ' -f2- | grep -vxF -e "$mapped" || true)
FILE=${candidates%%$'\n'*}
[ -n "$FILE" ] || { echo "no file of $need bytes under /usr/lib" >&2; exit 1; }
echo "file: \`$FILE\`, $BITS bits a round, a page every $STRIDE, threshold ${THRESHOLD_US} µs"
echo
echo "| round | bits | errors | error rate | bits a match carries | fast read (median) | slow read (median) |"
echo "|---:|---:|---:|---:|---:|---:|---:|"
for r in $(seq "$ROUNDS"); do
  python3 - "$FILE" <<'PY'
import os, sys
fd = os.open(sys.argv[1], os.O_RDONLY)
os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
PY
  message=$(python3 -c "import random,sys; print(''.join(random.choice('01') for _ in range($BITS)))")
  "$BIN" run --maze mazes/gen-12-s1.txt --bot-dir benches/page_cache --json \
    --bot "python3 send.py $FILE $message $STRIDE" >/dev/null
  "$BIN" run --maze mazes/gen-12-s1.txt --bot-dir benches/page_cache --json \
    --bot "python3 recv.py $FILE $BITS $STRIDE $THRESHOLD_US" >"$WORK/record.json"
  python3 - "$message" "$r" "$WORK/record.json" <<'PY'
import json, math, sys
message, r = sys.argv[1], sys.argv[2]
record = json.load(open(sys.argv[3]))
tail = record.get("stderr_tail", "")
value = int([l for l in tail.splitlines() if l.startswith("BITS ")][0].split()[1], 16)
times = [l for l in tail.splitlines() if l.startswith("MEDIAN_US")][0].split()
n = len(message)
errors = sum(1 for k, b in enumerate(message) if ((value >> k) & 1) != int(b))
e = errors / n
h = 0 if e in (0, 1) else -(e * math.log2(e) + (1 - e) * math.log2(1 - e))
print(f"| {r} | {n} | {errors} | {e:.4f} | {n * (1 - h):.0f} | {times[2]} µs | {times[4]} µs |")
PY
done
