-- mazearena schema, version 12: competitions and organisers. Never edit an applied
-- migration: add a new file.
--
-- A competition has three maze sets (practice: public layouts; public ranking and
-- private ranking: hidden layouts), a timeline (opens, freeze, closes), a quota, a final
-- selection rule and a final run. Its ranking matches live in tournaments of its own
-- (one for the public set, one for the private set, one for the final run), so that the
-- running sums of `standing` give its boards. A sealed tournament's matches and numbers
-- are shown to the admin and organisers only.

-- An organiser: manages competitions; holds no other secret.
create table organiser (
    organiser_id integer primary key,
    name text not null unique,
    -- sha-256 (hex) of the organiser's key
    key_hash text not null unique,
    created_at integer not null
);

create table competition (
    competition_id integer primary key,
    -- unique short name, used in addresses
    name text not null unique,
    title text not null,
    -- Markdown-ish text shown on the page as text
    description text not null default '',
    rules text not null default '',
    -- 'default': the server's general ranking (every hidden maze outside competitions,
    -- each bot's latest version, no timeline); 'competition': a competition
    kind text not null default 'competition' check (kind in ('default', 'competition')),
    -- repeats of each (version, ranking maze); the final run's repeats (0: no final run)
    repeats integer not null,
    final_repeats integer not null default 0,
    -- the match limits, JSON {move_timeout_ms, startup_timeout_ms, memory_limit_mb}
    limits text not null default '{}',
    -- unix ms; null only for the default competition
    opens_at integer,
    closes_at integer,
    -- the public board is frozen this long before the close (null: never)
    freeze_ms integer,
    -- versions per entrant per 24 hours, practice matches per entrant per 24 hours
    versions_per_day integer not null,
    practice_per_day integer not null,
    -- 'latest', 'best_public' or 'choice' (the entrant's choice of up to max_selected)
    selection text not null check (selection in ('latest', 'best_public', 'choice')),
    max_selected integer not null default 1,
    -- whether the private mazes' layouts and replays are shown after the results
    reveal_private_mazes integer not null default 0,
    -- the secret seeds (JSON array of integers), one per repeat index
    seeds text not null default '[]',
    -- null while open; 'final_run' (the final run is playing); 'final' (results written)
    state text,
    public_tournament_id integer,
    private_tournament_id integer,
    final_tournament_id integer,
    finalized_at integer,
    created_at integer not null
);

create table competition_maze (
    competition_id integer not null references competition (competition_id),
    maze_id integer not null references maze (maze_id),
    maze_set text not null check (maze_set in ('practice', 'public', 'private')),
    position integer not null,
    primary key (competition_id, maze_id)
);

-- A bot entered by its entrant (one per entrant); its versions from `first_version_id`
-- on are ranked.
create table competition_entry (
    competition_id integer not null references competition (competition_id),
    bot_id integer not null references bot (bot_id),
    entrant_id integer not null references entrant (entrant_id),
    first_version_id integer not null,
    entered_at integer not null,
    primary key (competition_id, bot_id),
    unique (competition_id, entrant_id)
);

-- A version queued on the ranking sets; `chosen`: the entrant chose it for the final;
-- `selected`: the final selection took it.
create table competition_version (
    competition_id integer not null references competition (competition_id),
    bot_version_id integer not null references bot_version (bot_version_id),
    ranked_at integer not null,
    chosen integer not null default 0,
    selected integer not null default 0,
    primary key (competition_id, bot_version_id)
);

-- The final standings: written once, never changed.
create table competition_result (
    competition_id integer not null references competition (competition_id),
    rank integer not null,
    entrant_id integer not null,
    entrant_name text not null,
    bot_id integer not null,
    bot_name text not null,
    bot_version_id integer not null,
    version integer not null,
    played integer not null,
    finished integer not null,
    mean_score double precision not null,
    finish_rate double precision not null,
    -- JSON: bundle hash, referee version, maze hashes, seeds, limits, recount
    manifest text not null,
    primary key (competition_id, entrant_id)
);

alter table tournament add column competition_id integer;
-- 1 while the tournament's matches and numbers are for the admin and organisers only
alter table tournament add column sealed integer not null default 0;
-- the match limits of its matches (JSON, as competition.limits); null: the server's
alter table tournament add column limits text;

-- Today's ranking: the default competition.
insert into competition (name, title, description, kind, repeats, versions_per_day,
                         practice_per_day, selection, created_at)
values ('ranking', 'Ranking',
        'Every bot''s latest version on the hidden mazes outside competitions.',
        'default', 1, 0, 0, 'latest', 0);
