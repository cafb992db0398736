#!/usr/bin/env bash
# The floor of a one-shot sandbox made by bubblewrap: `/usr/bin/true` alone, in
# bubblewrap's bare start (the namespaces and `/usr`: the start issue 48's target is
# measured against), in the least view any bot runs in (that, plus `/proc`, `/dev`, a
# scratch tmpfs and the bot's folder) and in a one-shot match's whole view (as
# `mazearena run --sandbox full` asks bubblewrap for it, with `/usr/bin/true` in place of
# the jail). Taken in turn RUNS times; medians of the paired differences over
# `/usr/bin/true`, and each view's ratio to the bare start.
#
#   bash benches/oneshot_floor.sh [RUNS]     (default 41)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-41}
cargo build --release --locked --quiet
bin=$PWD/target/release/mazearena
bot=$(mktemp -d)
trap 'rm -rf "$bot"' EXIT
printf '#!/bin/sh\nexit 0\n' >"$bot/bot.sh"
chmod +x "$bot/bot.sh"
base=(--unshare-ipc --unshare-pid --unshare-net --unshare-uts --unshare-cgroup-try --die-with-parent
  --new-session --ro-bind /usr /usr)
for d in /bin /sbin /lib /lib64; do
  if [ -L "$d" ]; then base+=(--symlink "$(readlink "$d")" "$d"); fi
done
least=("${base[@]}" --proc /proc --dev /dev --tmpfs /sandbox --ro-bind "$bot" /run/mazearena/bot)
whole=("${base[@]}")
for f in /etc/ld.so.cache /etc/ld.so.conf /etc/ld.so.conf.d /etc/alternatives /etc/localtime \
  /etc/nsswitch.conf /etc/ssl/openssl.cnf /etc/java-17-openjdk; do
  whole+=(--ro-bind-try "$f" "$f")
done
whole+=(--proc /proc --ro-bind /proc/sys /proc/sys --ro-bind-try /proc/sysrq-trigger /proc/sysrq-trigger
  --dev /dev --size 67108864 --tmpfs /sandbox --dir /sandbox/tmp --dir /sandbox/work
  --ro-bind "$bot" /run/mazearena/bot --symlink /sandbox/tmp /tmp --ro-bind "$bin" /run/mazearena/mazearena
  --chmod 0755 /etc --chmod 0755 /run --clearenv --chdir /sandbox/work)
timed() { local a b; a=$(date +%s%N); "$@" >/dev/null 2>&1; b=$(date +%s%N); echo $(( (b - a) / 1000 )); }
rows=$(for i in $(seq "$RUNS"); do
  echo "$(timed /usr/bin/true) $(timed bwrap "${base[@]}" /usr/bin/true)" \
    "$(timed bwrap "${least[@]}" /usr/bin/true) $(timed bwrap "${whole[@]}" /usr/bin/true)"
done)
python3 - "$RUNS" <<PY
import statistics as s, sys
rows = [list(map(int, l.split())) for l in """$rows""".splitlines() if l.strip()]
d = lambda i: s.median(r[i] - r[0] for r in rows) / 1000
bare = d(1)
print(f"| bubblewrap around \`/usr/bin/true\` ({sys.argv[1]} runs, in turn, medians over \`/usr/bin/true\`) | ms | x the bare start |")
print("|---|---:|---:|")
print(f"| the bare start: namespaces and \`/usr\` | {bare:.2f} | 1.00 |")
print(f"| the least view any bot runs in: and \`/proc\`, \`/dev\`, a scratch tmpfs, the bot's folder | {d(2):.2f} | {d(2) / bare:.2f} |")
print(f"| a one-shot match's whole view | {d(3):.2f} | {d(3) / bare:.2f} |")
PY
