#!/usr/bin/env python3
"""The fair claim's choice of the next match at 10,000 queued matches.

    python3 benches/claim.py [RUNS] [--bin target/release/mazearena]

Plays a small tournament into a fresh SQLite database with the binary (so the schema is
the binary's own, migrations and all), adds 20 bots of 20 owners, then fills the queue
two ways and times the claim's choice of the next match (`FAIR_ORDER` in
src/storage/matches/queue.rs, read from the source, as the claim runs it: `limit 1`) with
Python's sqlite3, RUNS times after 3 warm-ups (medians):

  - 200 single matches (10 per owner) and a tournament of 9,800;
  - 5,000 single matches (250 per owner: queued by the admin, past every owner's limit)
    and a tournament of 5,000;

beside the plain order of the queue (`status = 'queued' order by match_id limit 1`, an
index seek) on the same database. Prints a markdown section on stdout. Run it from the
repository's root.
"""

import argparse
import os
import re
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import time

OWNERS = 20


def fair_order():
    source = open(os.path.join("src", "storage", "matches", "queue.rs")).read()
    found = re.search(r'const FAIR_ORDER: &str = "(.*?)";', source, re.S)
    if not found:
        sys.exit("claim.py: FAIR_ORDER not found in src/storage/matches/queue.rs")
    # $4 is the claim's tournament (none for a server's claim).
    return found.group(1).replace("$4", "NULL") + " limit 1"


def seed_database(binary, path):
    cmd = [binary, "tournament", "--bots", "bots/python", "--mazes", "mazes",
           "--database", "sqlite://" + path, "--name", "seed", "--sandbox", "none", "--json"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def add_owners(db):
    """20 bots of 20 owners, each with one ready version (a copy of a played one)."""
    now = int(time.time() * 1000)
    version = db.execute(
        "select bot_version_id from bot_version where build_status = 'ready' limit 1").fetchone()[0]
    cols = [r[1] for r in db.execute("pragma table_info(bot_version)")
            if r[1] not in ("bot_version_id", "bot_id")]
    versions = []
    for i in range(OWNERS):
        bot = db.execute(
            "insert into bot (name, owner_token_hash, created_at) values (?, ?, ?)",
            (f"claim-bench-{i}", f"{i:064x}", now)).lastrowid
        db.execute(
            f"insert into bot_version (bot_id, {', '.join(cols)}) "
            f"select ?, {', '.join(cols)} from bot_version where bot_version_id = ?",
            (bot, version))
        versions.append((db.execute("select last_insert_rowid()").fetchone()[0], bot))
    return versions


def fill(db, versions, singles, tournament):
    """Replaces the queue with `singles` single matches (spread over the owners) and a
    tournament of `tournament` queued matches."""
    now = int(time.time() * 1000)
    db.execute("delete from match where status = 'queued'")
    mazes = [r[0] for r in db.execute("select maze_id from maze order by maze_id")]
    rows = []
    for i in range(singles):
        v, b = versions[i % len(versions)]
        rows.append((v, mazes[i % len(mazes)], i, None, None, 0, now, b))
    t = db.execute("insert into tournament (name, repeats, created_at) values (?, ?, ?)",
                   (f"claim-bench-{tournament}", 1, now)).lastrowid
    n = 0
    repeat = 0
    while n < tournament:
        for v, b in versions:
            for m in mazes:
                if n < tournament:
                    rows.append((v, m, n, t, repeat, 1, now, b))
                    n += 1
        repeat += 1
    db.executemany(
        "insert into match (bot_version_id, maze_id, seed, tournament_id, repeat, priority, "
        "status, created_at, bot_id) values (?, ?, ?, ?, ?, ?, 'queued', ?, ?)", rows)
    db.commit()


def per_choice_ms(db, sql, runs):
    for _ in range(3):
        assert db.execute(sql).fetchone() is not None
    times = []
    for _ in range(runs):
        a = time.perf_counter()
        db.execute(sql).fetchone()
        times.append(time.perf_counter() - a)
    return statistics.median(times) * 1000


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="?", type=int, default=200)
    ap.add_argument("--bin", default="target/release/mazearena")
    args = ap.parse_args()
    sql = fair_order()
    plain = "select match_id from match where status = 'queued' order by match_id limit 1"
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "claim.db")
        seed_database(args.bin, path)
        db = sqlite3.connect(path)
        versions = add_owners(db)
        rows = []
        for singles, tournament, what in [
            (200, 9800, f"200 single matches of {OWNERS} owners and a tournament of 9,800"),
            (5000, 5000, "5,000 single matches (queued by the admin, past every owner's "
                         "limit) and a tournament of 5,000"),
        ]:
            fill(db, versions, singles, tournament)
            queued = db.execute("select count(*) from match where status = 'queued'").fetchone()[0]
            assert queued == singles + tournament, queued
            rows.append((what, per_choice_ms(db, sql, args.runs), per_choice_ms(db, plain, args.runs)))
    print("## The fair claim at 10,000 queued matches")
    print()
    print(f"`python3 benches/claim.py {args.runs}`: the claim's choice of the next match "
          "(`FAIR_ORDER` in src/storage/matches/queue.rs: the first waiting match of each owner's "
          "lane and each tournament, then the least recently served class and lane), timed "
          "by Python's sqlite3 on a server's database (SQLite) holding 10,000 queued matches, "
          f"{args.runs} runs after 3 warm-ups, medians; beside it the plain order of the "
          "queue (by id, an index seek) on the same database.")
    print()
    print("| queue | fair choice | plain order (baseline) |")
    print("|---|---:|---:|")
    for what, fair, base in rows:
        print(f"| {what} | {fair:.3f} ms | {base:.3f} ms |")
    print()
    print("A tournament's first waiting match is an index seek; the single matches are "
          "scanned, and an owner may have 50 waiting (`--max-queued-per-owner`), so the "
          "choice stays near the first row at any realistic queue. A local `tournament` "
          "claims in its own order (its one lane) and does not pay for it.")


if __name__ == "__main__":
    main()
