-- mazearena schema, version 17: browser sessions, and rejudges (matches played again
-- with their earlier records kept, marked superseded). Never edit an applied
-- migration: add a new file.

-- A signed-in browser. The cookie holds a random secret; only its SHA-256 is stored, so
-- a copy of the database opens no session. `key_hash` is the hash of the key the
-- visitor gave at /login (the admin token, an organiser's, an entrant's or a bot
-- owner's): rotating that key deletes its sessions.
create table web_session (
    session_hash text primary key,
    key_hash text not null,
    created_at integer not null,
    expires_at integer not null
);
create index web_session_key on web_session (key_hash);
create index web_session_expiry on web_session (expires_at);

-- One rejudge: the ranking matches of a competition's version or maze played again.
create table rejudge (
    rejudge_id integer primary key,
    competition_id integer not null references competition (competition_id),
    -- what was played again: a version, or a maze (one of the two)
    bot_version_id integer references bot_version (bot_version_id),
    maze_id integer references maze (maze_id),
    reason text not null,
    -- who asked: `admin` or `organiser:ID`
    requested_by text not null,
    matches integer not null,
    created_at integer not null
);

-- A match's earlier outcome, kept when a rejudge played it again (the match row itself
-- went back to the queue and holds the new outcome).
create table match_superseded (
    superseded_id integer primary key,
    match_id integer not null references match (match_id) on delete cascade,
    rejudge_id integer not null references rejudge (rejudge_id),
    status text not null,
    score real,
    run0_steps integer,
    run1_steps integer,
    total_steps integer,
    record text,
    started_at integer,
    finished_at integer,
    -- the whole earlier record (as match_record), when there was one
    encoding integer,
    data blob
);
create index match_superseded_match on match_superseded (match_id);
