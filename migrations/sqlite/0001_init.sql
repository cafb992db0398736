-- mazearena schema, version 1. Never edit an applied migration: add a new file.
-- Times are unix milliseconds (UTC).

-- A registered bot: a name and its owner's token (stored hashed).
create table bot (
    bot_id integer primary key,
    -- unique display name
    name text not null unique,
    -- sha-256 (hex) of the owner token; the token itself is shown once at registration
    owner_token_hash text not null,
    created_at integer not null
);

-- One upload of a bot's files; matches record the version they ran.
create table bot_version (
    bot_version_id integer primary key,
    bot_id integer not null references bot (bot_id),
    -- 1, 2, ... per bot
    version integer not null,
    -- the command line, split like a shell, run in `dir`
    command text not null,
    -- absolute path of the bot's files
    dir text not null,
    -- content hash of the files (order- and timestamp-independent)
    files_sha256 text not null,
    file_count integer not null,
    created_at integer not null,
    unique (bot_id, version)
);

-- A maze: its canonical numeric text, hash and optimum.
create table maze (
    maze_id integer primary key,
    name text not null,
    -- sha-256 of the canonical numeric text: duplicates are refused
    hash text not null unique,
    dim integer not null,
    -- the canonical numeric text
    layout text not null,
    -- hidden mazes are for ranking: their layout is never served to non-admins
    hidden integer not null default 0,
    -- fewest run-1 steps with full knowledge; null if the goal is unreachable
    optimum integer,
    created_at integer not null
);

-- A tournament: every bot version on every maze, `repeats` times.
create table tournament (
    tournament_id integer primary key,
    name text not null,
    repeats integer not null,
    created_at integer not null
);

-- One match: a row from the moment it is queued until its record is written.
create table match (
    match_id integer primary key,
    bot_version_id integer not null references bot_version (bot_version_id),
    maze_id integer not null references maze (maze_id),
    seed integer not null,
    tournament_id integer references tournament (tournament_id),
    -- repetition index within a tournament (null for single matches)
    repeat integer,
    -- lower runs first: 0 single matches, 1 tournament matches
    priority integer not null,
    -- queued, running, or a final status: finished, step_limit, timeout, crashed, protocol_error
    status text not null default 'queued',
    -- the worker holding the match, and until when (unix ms)
    lease_owner text,
    lease_expires_at integer,
    -- how many times a worker has started it
    attempts integer not null default 0,
    score real,
    run0_steps integer,
    run1_steps integer,
    total_steps integer,
    -- the match record without its trace (JSON)
    record text,
    -- the per-step trace (JSON array)
    trace text,
    created_at integer not null,
    started_at integer,
    finished_at integer,
    -- a tournament holds each (bot version, maze, repeat) exactly once
    unique (tournament_id, bot_version_id, maze_id, repeat)
);

create index match_queue on match (status, priority, match_id);
create index match_tournament on match (tournament_id, status);
create index match_bot_version on match (bot_version_id, status);
