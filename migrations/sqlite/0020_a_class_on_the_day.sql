-- mazearena schema, version 20: a class on the day. Names are one name whatever their
-- case; a practice match's replay says when it was removed to save space; each
-- competition may have an invite code of its own, and says how new versions are
-- validated. Never edit an applied migration: add
-- a new file.

-- Names that differ only in case are the same name: `bob`, `Bob` and `BOB` are one
-- entrant, one organiser, one bot, one competition. Names are ASCII (letters, digits,
-- `-`, `_`, `.`), so lower() folds them all. Rows that an earlier version let in with
-- a name another row has in another case keep their id and get it as a suffix
-- (`Bob` becomes `Bob-7`); they log in by key, not by name.
update entrant set name = name || '-' || entrant_id
where exists (select 1 from entrant e where lower(e.name) = lower(entrant.name)
              and e.entrant_id < entrant.entrant_id);
create unique index entrant_name_folded on entrant (lower(name));
update organiser set name = name || '-' || organiser_id
where exists (select 1 from organiser o where lower(o.name) = lower(organiser.name)
              and o.organiser_id < organiser.organiser_id);
create unique index organiser_name_folded on organiser (lower(name));
update bot set name = name || '-' || bot_id
where exists (select 1 from bot b where lower(b.name) = lower(bot.name)
              and b.bot_id < bot.bot_id);
create unique index bot_name_folded on bot (lower(name));
update competition set name = name || '-' || competition_id
where exists (select 1 from competition c where lower(c.name) = lower(competition.name)
              and c.competition_id < competition.competition_id);
create unique index competition_name_folded on competition (lower(name));

-- When a practice match's stored replay (trace, stderr, debug drawing) was removed to
-- save space (null: never). Matches pruned by an earlier version: the practice matches
-- that ended with steps played and have no stored record.
alter table match add column record_pruned_at integer;
update match set record_pruned_at = finished_at
where tournament_id is null and finished_at is not null and total_steps > 0
  and not exists (select 1 from match_record r where r.match_id = match.match_id);

-- A competition's own invite code (null: none), set and rotated by its organiser:
-- registering with it makes an entrant of the server whatever its registration mode,
-- and leads the new entrant to the competition. Kept as it is (its organiser sees it and
-- its link again), with its SHA-256 (hex) to find it by.
alter table competition add column invite_code text;
alter table competition add column invite_hash text;
create unique index competition_invite on competition (invite_hash);

-- The competition whose invite code an entrant registered with (null: none): its
-- organiser may give the entrant a new key.
alter table entrant add column registered_through integer references competition (competition_id);

-- How a competition checks each new version before it plays: `start` (invalid only for
-- a failure that no maze causes), `match` (invalid for any failure in its validation
-- match) or `off`.
alter table competition add column validation text not null default 'start'
    check (validation in ('start', 'match', 'off'));
