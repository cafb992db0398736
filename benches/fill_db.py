#!/usr/bin/env python3
"""Fills a mazearena database with N recorded matches, for the benchmarks.

    python3 benches/fill_db.py DATABASE.db N [--bin target/release/mazearena]

First it plays one real tournament into the database with the binary: every shipped bot
(bots/*/bot.toml) on every shipped maze (mazes/), in the sandbox the binary picks. Then
it copies that tournament's match rows (records and traces as the binary stored them)
into further tournaments until the database holds N finished matches, each copy a
tournament of its own, the way a busy server accumulates them. The copies go through
the database's own triggers, so the standings stay consistent.

Run it from the repository's root. An existing database is topped up, never shrunk.
"""

import argparse
import os
import sqlite3
import subprocess
import sys
import time


def play_seed_tournament(binary, database):
    bots = sorted(
        os.path.join("bots", d)
        for d in os.listdir("bots")
        if os.path.isfile(os.path.join("bots", d, "bot.toml"))
    )
    cmd = [binary, "tournament", "--bots", *bots, "--mazes", "mazes",
           "--database", "sqlite://" + database, "--name", "seed", "--json"]
    print("playing the seed tournament:", " ".join(cmd), file=sys.stderr)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("database")
    ap.add_argument("matches", type=int)
    ap.add_argument("--bin", default="target/release/mazearena")
    args = ap.parse_args()

    db = sqlite3.connect(args.database) if os.path.exists(args.database) else None
    has_seed = db is not None and db.execute(
        "select count(*) from sqlite_master where name = 'tournament'").fetchone()[0] and \
        db.execute("select count(*) from tournament").fetchone()[0]
    if not has_seed:
        if db:
            db.close()
        play_seed_tournament(args.bin, args.database)
        db = sqlite3.connect(args.database)

    seed = db.execute("select min(tournament_id) from tournament").fetchone()[0]
    per_copy = db.execute(
        "select count(*) from match where tournament_id = ?", (seed,)).fetchone()[0]
    columns = [r[1] for r in db.execute("pragma table_info(match)")
               if r[1] not in ("match_id", "tournament_id")]
    cols = ", ".join(columns)
    # Tables keyed by match id that hold a match's parts (a stored trace), if any.
    parts = [
        name for (name,) in db.execute(
            "select name from sqlite_master where type = 'table' and name like 'match\\_%' escape '\\'")
        if "match_id" in [r[1] for r in db.execute(f"pragma table_info({name})")]
    ]
    have = db.execute("select count(*) from match").fetchone()[0]
    started = time.time()
    copies = 0
    while have < args.matches:
        with db:
            now = int(time.time() * 1000)
            tid = db.execute(
                "insert into tournament (name, repeats, created_at) values (?, 1, ?)",
                (f"copy {copies + 1}", now)).lastrowid
            db.execute(
                f"insert into match (tournament_id, {cols}) select ?, {cols} from match "
                f"where tournament_id = ? order by match_id", (tid, seed))
            for part in parts:
                pcols = [r[1] for r in db.execute(f"pragma table_info({part})") if r[1] != "match_id"]
                pc = ", ".join(pcols)
                db.execute(
                    f"insert into {part} (match_id, {pc}) "
                    f"select n.match_id, {', '.join('p.' + c for c in pcols)} from {part} p "
                    f"join (select match_id as old, row_number() over (order by match_id) as k from match where tournament_id = ?) o on o.old = p.match_id "
                    f"join (select match_id, row_number() over (order by match_id) as k from match where tournament_id = ?) n on n.k = o.k",
                    (seed, tid))
            have += per_copy
            copies += 1
        if copies % 100 == 0:
            print(f"{have} matches", file=sys.stderr)
    db.execute("analyze")
    db.close()
    print(f"{args.database}: {have} matches ({copies} copies of {per_copy} in "
          f"{time.time() - started:.1f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
