#!/usr/bin/env bash
# Matches a minute per worker core, by the bot's language: the starter kits' bots
# (bots/python: 4 bots, bots/c: 2, bots/java: 1) in a local tournament with `--jobs 1`
# (one core) on the first N playable contest mazes of ../shared/mazes/micromouseonline/classic, in
# the full sandbox and, as the baseline, without it. A run's wall time holds the kit's
# build and the start; a one-maze run of the same kit, taken in the same round, is
# subtracted, so a match's time is (T(N mazes) - T(1 maze)) / ((N - 1) x bots): what a
# worker's slot spends on each further match. The settings are taken in turn RUNS times;
# medians.
#
#   bash benches/kits.sh [RUNS] [MAZES]     (default 3 and 40)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-3}
MAZES=${2:-40}
cargo build --release --locked --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The first MAZES playable mazes, in name order (a maze whose goal room cannot be reached
# under the task's rules is skipped, as a tournament skips it).
files=()
for f in $(ls ../shared/mazes/micromouseonline/classic/*.txt | sort); do
  ./target/release/mazearena maze solve "$f" >/dev/null 2>&1 && files+=("$f")
  [ ${#files[@]} -ge "$MAZES" ] && break
done
KITS=(python c java)

run() { # $1: kit, $2: sandbox, $3...: mazes; prints "ms matches"
  local kit=$1 sandbox=$2 db=$tmp/t.db a b out
  shift 2
  rm -f "$db"*
  a=$(date +%s%N)
  out=$(./target/release/mazearena tournament --bots "bots/$kit" --mazes "$@" --jobs 1 \
    --sandbox "$sandbox" --database "sqlite://$db" --json)
  b=$(date +%s%N)
  echo "$(( (b - a) / 1000000 )) $(python3 -c 'import json, sys; d = json.load(sys.stdin); print(len(d["matches"]))' <<<"$out")"
}

declare -A PER
for ((i = 1; i <= RUNS; i++)); do
  for kit in "${KITS[@]}"; do
    for sandbox in full none; do
      read -r t1 n1 < <(run "$kit" "$sandbox" "${files[0]}")
      read -r tn nn < <(run "$kit" "$sandbox" "${files[@]}")
      per=$(python3 -c "print(($tn - $t1) / ($nn - $n1))")
      echo "round $i: $kit, sandbox $sandbox: $n1 matches in $t1 ms, $nn in $tn ms: $per ms a match" >&2
      PER[$kit-$sandbox]+="$per "
      declare -g "N_$kit=$nn"
    done
  done
done

echo "## Matches a minute per worker core, by language"
echo
echo "\`bash benches/kits.sh $RUNS $MAZES\`: the starter kits' bots (bots/python: 4 bots, bots/c: 2,"
echo "bots/java: 1) in a local tournament with \`--jobs 1\` (one core) on the first $MAZES playable contest mazes"
echo "of ../shared/mazes/micromouseonline/classic; a match's time is (T($MAZES mazes) - T(1 maze)) /"
echo "(matches more), so the kit's build and the start are not in it; beside it, the same without the"
echo "sandbox (the baseline), taken in turn; medians of $RUNS rounds."
echo
python3 - "$RUNS" "${PER[python-full]}" "${PER[python-none]}" "${PER[c-full]}" "${PER[c-none]}" \
  "${PER[java-full]}" "${PER[java-none]}" "$N_python" "$N_c" "$N_java" <<'PY'
import statistics, sys
med = lambda s: statistics.median(float(x) for x in s.split())
rows = [("Python", sys.argv[2], sys.argv[3], sys.argv[8]), ("C", sys.argv[4], sys.argv[5], sys.argv[9]),
        ("Java", sys.argv[6], sys.argv[7], sys.argv[10])]
print("| kit | matches a run | ms a match, full sandbox | matches a minute per core | ms a match, no sandbox (baseline) | matches a minute per core, no sandbox |")
print("|---|---:|---:|---:|---:|---:|")
for name, full, none, n in rows:
    f, b = med(full), med(none)
    print(f"| {name} | {n} | {f:.1f} | {60000 / f:,.0f} | {b:.1f} | {60000 / b:,.0f} |")
PY
