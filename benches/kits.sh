#!/usr/bin/env bash
# Matches a minute per worker core, by the bot's language: the starter kits' bots
# (bots/python: 4 bots, bots/c: 2, bots/java: 1) in a local tournament with `--jobs 1`
# (one core) on the first N playable contest mazes of ../shared/mazes/micromouseonline/classic, in
# the full sandbox (its warm sandboxes making each match's network namespace ahead, as
# they do by default), in the full sandbox making it on each match's start
# (MAZEARENA_SANDBOX_AHEAD=0: the pool off) and, as the baseline, without the sandbox.
# A run's wall time holds the kit's
# build and the start; a one-maze run of the same kit, taken in the same round, is
# subtracted, so a match's time is (T(N mazes) - T(1 maze)) / ((N - 1) x bots): what a
# worker's slot spends on each further match. The settings are taken in turn RUNS times;
# medians.
#
#   bash benches/kits.sh [RUNS] [MAZES]     (default 3 and 40)
#
# KITS and SETTINGS narrow a run (e.g. `KITS=python SETTINGS="full none"` for more rounds of
# one kit's ratio); a setting not taken is shown as "-".
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
read -r -a KITS <<<"${KITS:-python c java}"
read -r -a SETTINGS <<<"${SETTINGS:-full pooloff none}"

run() { # $1: kit, $2: setting (full, pooloff, none), $3...: mazes; prints "ms matches"
  local kit=$1 setting=$2 db=$tmp/t.db a b out sandbox=$2 ahead=1
  shift 2
  [ "$setting" = pooloff ] && sandbox=full ahead=0
  rm -f "$db"*
  a=$(date +%s%N)
  out=$(MAZEARENA_SANDBOX_AHEAD=$ahead ./target/release/mazearena tournament --bots "bots/$kit" \
    --mazes "$@" --jobs 1 --sandbox "$sandbox" --database "sqlite://$db" --json)
  b=$(date +%s%N)
  echo "$(( (b - a) / 1000000 )) $(python3 -c 'import json, sys; d = json.load(sys.stdin); print(len(d["matches"]))' <<<"$out")"
}

declare -A PER
for ((i = 1; i <= RUNS; i++)); do
  for kit in "${KITS[@]}"; do
    for sandbox in "${SETTINGS[@]}"; do
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
echo "(matches more), so the kit's build and the start are not in it; in the full sandbox (each"
echo "match's network namespace made ahead: the default), in it with the pool off"
echo "(\`MAZEARENA_SANDBOX_AHEAD=0\`: made on each match's start), and without the sandbox (the"
echo "baseline), taken in turn; medians of $RUNS rounds. \"x\" is the throughput beside the baseline's."
echo
python3 - "$RUNS" "${N_python:-}" "${N_c:-}" "${N_java:-}" \
  "${PER[python-full]:-}" "${PER[python-pooloff]:-}" "${PER[python-none]:-}" \
  "${PER[c-full]:-}" "${PER[c-pooloff]:-}" "${PER[c-none]:-}" \
  "${PER[java-full]:-}" "${PER[java-pooloff]:-}" "${PER[java-none]:-}" <<'PY'
import statistics, sys
med = lambda s: statistics.median(float(x) for x in s.split()) if s.split() else None
fmt = lambda v, f: "-" if v is None else format(v, f)
ratio = lambda b, v: "-" if b is None or v is None else f"{b / v:.2f}"
a = sys.argv
rows = [("Python", a[2], a[5:8]), ("C", a[3], a[8:11]), ("Java", a[4], a[11:14])]
print("| kit | matches a run | ms a match, sandbox | x | ms a match, sandbox, pool off | x | ms a match, no sandbox (baseline) | matches a minute per core: sandbox / no sandbox |")
print("|---|---:|---:|---:|---:|---:|---:|---:|")
for name, n, (full, off, none) in rows:
    if not n:
        continue
    f, o, b = med(full), med(off), med(none)
    per_min = "-" if f is None or b is None else f"{60000 / f:,.0f} / {60000 / b:,.0f}"
    print(f"| {name} | {n} | {fmt(f, '.1f')} | {ratio(b, f)} | {fmt(o, '.1f')} | {ratio(b, o)} | {fmt(b, '.1f')} | {per_min} |")
PY
