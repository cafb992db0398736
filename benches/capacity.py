"""The capacity plan of docs/DEPLOY.md, computed from BENCHMARKS.md's own figures.

    python3 benches/capacity.py            writes the plan into docs/DEPLOY.md (between
                                           its `capacity:begin` and `capacity:end` marks)
    python3 benches/capacity.py --check    fails unless docs/DEPLOY.md holds the plan that
                                           BENCHMARKS.md gives now, and the worker scaler's
                                           targetQueryValue and maxReplicaCount are the plan's

Every figure the plan reads names the BENCHMARKS.md section and row it comes from (a
figure that is not there fails the script); the assumptions (how often entrants submit,
how long a new worker takes to start) are the constants below, said in the plan.
"""

import math
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BENCHMARKS = ROOT / "BENCHMARKS.md"
DEPLOY = ROOT / "docs" / "DEPLOY.md"
SCALER = ROOT / "deploy" / "kubernetes" / "worker-scaler.yaml"
WORKER = ROOT / "deploy" / "kubernetes" / "worker.yaml"

ENTRANTS = (100, 1_000, 10_000)
LANGUAGES = ("Python", "C", "Java")
# The deadline rush: every entrant submits this many versions in the competition's last
# hour (each is ranked on the public set as soon as it is built).
RUSH_VERSIONS_PER_HOUR = 2
# Versions an entrant submits over the whole competition (for the database's size).
VERSIONS_PER_ENTRANT = 20
# The share of the workers' cores kept busy in the rush: a queue that is 70% busy still
# starts a new version's matches within seconds.
RUSH_UTILIZATION = 0.7
# The time a new worker takes from KEDA's decision to its first claim on a node that has
# the image (KEDA's 15 s polling, the pod's start, the worker's start).
SCALE_UP_SECONDS = 60
# The targets.
RANK_WITHIN_SECONDS = 60
RESULTS_WITHIN_SECONDS = 600


class Figures:
    """BENCHMARKS.md, read by section and row."""

    def __init__(self, text):
        self.sections = {}
        name = None
        for line in text.splitlines():
            if line.startswith("## "):
                name = line[3:].strip()
                self.sections[name] = []
            elif name:
                self.sections[name].append(line)
        self.cited = []

    def section(self, name):
        if name not in self.sections:
            sys.exit(f"capacity: BENCHMARKS.md has no section '{name}'")
        return self.sections[name]

    def row(self, section, first_cell, column):
        """The number in `column` (0-based) of the table row of `section` whose first
        cell is `first_cell`."""
        for line in self.section(section):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if line.startswith("|") and cells[0] == first_cell:
                return number(cells[column], section, first_cell)
        sys.exit(f"capacity: BENCHMARKS.md's '{section}' has no row '{first_cell}'")

    def text(self, section, pattern):
        """The first group of `pattern` in `section`'s text."""
        found = re.search(pattern, "\n".join(self.section(section)))
        if not found:
            sys.exit(f"capacity: BENCHMARKS.md's '{section}' does not say /{pattern}/")
        return number(found.group(1), section, pattern)

    def cite(self, what, value, section, row):
        self.cited.append((what, value, section, row))
        return value


def number(cell, section, row):
    found = re.search(r"-?[\d,]+(?:\.\d+)?", cell)
    if not found:
        sys.exit(f"capacity: no number in '{cell}' ({section}, {row})")
    return float(found.group(0).replace(",", ""))


def plan(figures, jobs):
    kits = "Matches a minute per worker core, by language"
    per_core = {
        lang: figures.cite(
            f"{lang} matches a minute per core",
            # "matches a minute per core: sandbox / no sandbox": the first.
            figures.row(kits, lang, 7),
            kits,
            f"{lang}: matches a minute per core (full sandbox)",
        )
        for lang in LANGUAGES
    }
    comp = "Competitions: ranking and the close"
    public = figures.cite(
        "matches to rank a version on the public set",
        figures.text(comp, r"full public standing \((\d+) public mazes")
        * figures.text(comp, r"public mazes x (\d+) repeats"),
        comp,
        "upload to full public standing (public mazes x repeats)",
    )
    private = figures.cite(
        "final-run matches per entrant (the private set)",
        figures.text(comp, r"private set \((\d+) mazes\)"),
        comp,
        "the private set's mazes, played by the final run",
    )
    overhead = figures.cite(
        "a server's time over the same matches as a plain tournament (close to results)",
        close_ratio(figures, comp),
        comp,
        "close to results / the same matches as a tournament: median ratio",
    )
    pg = "Throughput across worker processes (PostgreSQL)"
    claims = figures.cite(
        "claim statements per match", figures.row(pg, "claim statements (idle workers' empty claims included)", 1), pg,
        "claim statements per match",
    )
    writes = figures.cite(
        "writing statements per match", figures.row(pg, "writing statements (insert, update, delete)", 1), pg,
        "writing statements per match",
    )
    wal = figures.cite("WAL bytes per match", figures.row(pg, "WAL bytes", 1), pg, "WAL bytes per match")
    db_bytes = figures.cite(
        "database bytes per match (PostgreSQL)",
        figures.row(pg, "database bytes (tables and indexes)", 1),
        pg,
        "database bytes (tables and indexes) per match",
    )
    sqlite_bytes = figures.cite(
        "bytes per stored match (SQLite file)",
        figures.text("Bytes per stored match", r"(?m)= (\d+) B per match$"),
        "Bytes per stored match",
        "file bytes per match",
    )

    rows = []
    for n in ENTRANTS:
        for lang in LANGUAGES:
            seconds_per_match = 60 / per_core[lang] * overhead
            version = public + 1  # the public set and the validation match
            rush_rate = n * RUSH_VERSIONS_PER_HOUR / 3600 * version  # matches a second
            rush_cores = math.ceil(rush_rate * seconds_per_match / RUSH_UTILIZATION)
            lone = version * seconds_per_match / jobs  # one version on one worker
            final = round(n * private)
            final_cores = math.ceil(final * seconds_per_match / (RESULTS_WITHIN_SECONDS - SCALE_UP_SECONDS))
            cores = max(rush_cores, final_cores, jobs)
            workers = math.ceil(cores / jobs)
            peak_rate = max(rush_rate, final / (RESULTS_WITHIN_SECONDS - SCALE_UP_SECONDS))
            stored = n * (VERSIONS_PER_ENTRANT * version + private)
            rows.append(
                {
                    "entrants": n,
                    "lang": lang,
                    "lone": lone,
                    "rush_rate": rush_rate,
                    "rush_cores": rush_cores,
                    "final": final,
                    "final_cores": final_cores,
                    "workers": workers,
                    "peak_rate": peak_rate,
                    "claims": peak_rate * claims,
                    "writes": peak_rate * writes,
                    "wal": peak_rate * wal / 1024,
                    "stored": stored,
                    "pg_gib": stored * db_bytes / 2**30,
                    "sqlite_gib": stored * sqlite_bytes / 2**30,
                }
            )
    target = 30 * jobs  # the scaler's work is in seconds of a slot: 30 s a slot
    return rows, target, public, private


def most_workers(rows):
    """The scaler's ceiling: the plan's largest competition, in its slowest language."""
    return max(r["workers"] for r in rows)


def close_ratio(figures, comp):
    # The second table's median row (close to results): its ratio column.
    medians = [line for line in figures.section(comp) if line.startswith("| median |")]
    if len(medians) < 2:
        sys.exit(f"capacity: BENCHMARKS.md's '{comp}' has no median row for the close")
    return number(medians[1].strip().strip("|").split("|")[3], comp, "median")


def jobs_of_worker():
    text = WORKER.read_text()
    found = re.search(r"name: MAZEARENA_JOBS\s*\n\s*value: \"(\d+)\"", text)
    if not found:
        sys.exit("capacity: worker.yaml sets no MAZEARENA_JOBS")
    return int(found.group(1))


def render(figures, rows, target, public, private, jobs):
    out = []
    say = out.append
    say("What the plan reads from BENCHMARKS.md (each figure with its section and row):")
    say("")
    say("| figure | value | BENCHMARKS.md section: row |")
    say("|---|---:|---|")
    for what, value, section, row in figures.cited:
        shown = f"{value:,.0f}" if value == int(value) else f"{value:,.2f}"
        say(f"| {what} | {shown} | *{section}*: {row} |")
    say("")
    say(
        f"The plan, for workers of {jobs} slot{'s' if jobs != 1 else ''} (`MAZEARENA_JOBS` in "
        f"worker.yaml, a core each), "
        f"if every entrant's bot were written in the language of the row. A version is ranked "
        f"after {public:.0f} public matches and its validation match; the rush is every entrant "
        f"submitting {RUSH_VERSIONS_PER_HOUR} versions in the last hour, kept at "
        f"{RUSH_UTILIZATION:.0%} of the cores; the final run is {private:.0f} matches an entrant, "
        f"played in the {RESULTS_WITHIN_SECONDS // 60} minutes after the close less "
        f"{SCALE_UP_SECONDS} s for new workers to start. A match's time is the kit's time a "
        f"match on one core times the server's overhead over a plain tournament."
    )
    say("")
    say(
        "| entrants | bots in | one version alone on one worker | rush: matches a second | "
        "cores for the rush | final run: matches | cores for results in 10 min | workers "
        "(maxReplicaCount) | PostgreSQL at the peak: claims a second | writing statements a second | "
        "WAL a second | stored over the competition (PostgreSQL / SQLite) |"
    )
    say("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        say(
            f"| {r['entrants']:,} | {r['lang']} | {r['lone']:.1f} s | {r['rush_rate']:.1f} | "
            f"{r['rush_cores']} | {r['final']:,} | {r['final_cores']} | {r['workers']} | "
            f"{r['claims']:.1f} | {r['writes']:.0f} | {r['wal']:,.0f} KiB | "
            f"{r['pg_gib']:.2f} / {r['sqlite_gib']:.2f} GiB |"
        )
    say("")
    say(
        f"The scaler (worker-scaler.yaml): `targetQueryValue`, 30 seconds of work for each of "
        f"a worker's {jobs} slot{'s' if jobs != 1 else ''}: **{target}**; `maxReplicaCount`, the most workers "
        f"above: **{most_workers(rows)}**."
    )
    return "\n".join(out)


def main():
    figures = Figures(BENCHMARKS.read_text())
    jobs = jobs_of_worker()
    rows, target, public, private = plan(figures, jobs)
    block = render(figures, rows, target, public, private, jobs)
    doc = DEPLOY.read_text()
    begin, end = "<!-- capacity:begin -->\n", "<!-- capacity:end -->"
    if begin not in doc or end not in doc:
        sys.exit("capacity: docs/DEPLOY.md has no capacity:begin / capacity:end marks")
    head, rest = doc.split(begin, 1)
    _, tail = rest.split(end, 1)
    new = head + begin + block + "\n" + end + tail
    scaler = re.search(r'targetQueryValue: "(\d+)"', SCALER.read_text())
    if "--check" in sys.argv[1:]:
        problems = []
        if new != doc:
            problems.append("docs/DEPLOY.md's plan is not the one BENCHMARKS.md gives: run python3 benches/capacity.py")
        if not scaler or int(scaler.group(1)) != target:
            problems.append(f"worker-scaler.yaml's targetQueryValue is not the plan's {target}")
        ceiling = re.search(r"maxReplicaCount: (\d+)", SCALER.read_text())
        if not ceiling or int(ceiling.group(1)) != most_workers(rows):
            problems.append(f"worker-scaler.yaml's maxReplicaCount is not the plan's {most_workers(rows)}")
        if problems:
            sys.exit("capacity: " + "; ".join(problems))
        print(f"capacity: docs/DEPLOY.md's plan and the scaler's target ({target}) are BENCHMARKS.md's")
        return
    DEPLOY.write_text(new)
    text = SCALER.read_text()
    if scaler:
        text = text.replace(scaler.group(0), f'targetQueryValue: "{target}"')
    text = re.sub(r"maxReplicaCount: \d+", f"maxReplicaCount: {most_workers(rows)}", text)
    SCALER.write_text(text)
    print(f"capacity: wrote the plan into docs/DEPLOY.md; the scaler's target is {target}")


if __name__ == "__main__":
    main()
