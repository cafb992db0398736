-- mazearena schema, version 11: entrants. Never edit an applied migration: add a new file.
--
-- An entrant is a person or a team with an API key (shown once, stored hashed,
-- rotatable) that acts for every bot it registers; bots registered without one keep
-- their own owner token only. Who may become an entrant is the server's registration
-- mode: open, closed, or by invite code (its hash kept).

create table entrant (
    entrant_id integer primary key,
    -- unique display name
    name text not null unique,
    -- the members' names, a JSON array of strings
    members text not null,
    -- sha-256 (hex) of the entrant's key
    key_hash text not null unique,
    created_at integer not null,
    -- when the key was last replaced (null: never)
    key_rotated_at integer
);

-- The entrant a bot belongs to (null: a bot of its own owner token only).
alter table bot add column entrant_id integer references entrant (entrant_id);
create index bot_entrant on bot (entrant_id);

-- The registration mode: one row. `invite_hash`: sha-256 (hex) of the invite code.
create table registration (
    registration_id integer primary key check (registration_id = 1),
    mode text not null check (mode in ('open', 'closed', 'invite')),
    invite_hash text
);
insert into registration (registration_id, mode, invite_hash) values (1, 'open', null);
