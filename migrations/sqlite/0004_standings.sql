-- mazearena schema, version 4: standings kept as running sums, so that reading a
-- leaderboard never aggregates the match table. Never edit an applied migration: add a
-- new file.
--
-- One row per bot version, tournament (0: matches outside any tournament; -1: all of
-- the version's matches) and kind of maze (hidden or public), over the matches with a
-- final status (not queued, not running). Triggers on `match` keep it in step in the same transaction as the write
-- that gives a match its final status (or takes it away), whatever statement does it.

create table standing (
    bot_version_id integer not null references bot_version (bot_version_id),
    -- the tournament, 0 for matches outside any tournament, -1 for all matches
    tournament_id integer not null,
    -- 1: the matches on hidden mazes; 0: on public ones
    hidden integer not null,
    -- matches counted
    played integer not null default 0,
    -- of which finished
    finished integer not null default 0,
    -- sum of their scores, a match that did not finish counting as 1000
    score_sum real not null default 0,
    -- sum of score / optimum over the matches on mazes with a known optimum, and how
    -- many they are
    ratio_sum real not null default 0,
    ratio_count integer not null default 0,
    primary key (bot_version_id, tournament_id, hidden)
);

-- A match's part of the sums, with the sign to apply it with (1: add, -1: take away).
-- The triggers on `match` insert into this view; its own trigger does the arithmetic,
-- in one place.
create view standing_change (bot_version_id, tournament_id, maze_id, status, score, sign) as
    select null, null, null, null, null, null where 0;

create trigger standing_change_apply instead of insert on standing_change
begin
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum, ratio_sum, ratio_count)
    select new.bot_version_id, k.t, z.hidden, new.sign,
           new.sign * (new.status = 'finished'),
           new.sign * (case when new.status = 'finished' then new.score else 1000.0 end),
           new.sign * coalesce((case when new.status = 'finished' then new.score else 1000.0 end) / z.optimum, 0),
           new.sign * (z.optimum is not null)
    from maze z, (select coalesce(new.tournament_id, 0) as t union all select -1) k
    where z.maze_id = new.maze_id
    on conflict (bot_version_id, tournament_id, hidden) do update set
        played = played + excluded.played,
        finished = finished + excluded.finished,
        score_sum = score_sum + excluded.score_sum,
        ratio_sum = ratio_sum + excluded.ratio_sum,
        ratio_count = ratio_count + excluded.ratio_count;
end;

create trigger standing_on_insert after insert on match
when new.status not in ('queued', 'running')
begin
    insert into standing_change
    values (new.bot_version_id, new.tournament_id, new.maze_id, new.status, new.score, 1);
end;

create trigger standing_on_delete after delete on match
when old.status not in ('queued', 'running')
begin
    insert into standing_change
    values (old.bot_version_id, old.tournament_id, old.maze_id, old.status, old.score, -1);
end;

-- An update that changes what a match counts as: take the old away, add the new.
create trigger standing_on_update_remove after update of status, score, bot_version_id, maze_id, tournament_id on match
when old.status not in ('queued', 'running')
begin
    insert into standing_change
    values (old.bot_version_id, old.tournament_id, old.maze_id, old.status, old.score, -1);
end;

create trigger standing_on_update_add after update of status, score, bot_version_id, maze_id, tournament_id on match
when new.status not in ('queued', 'running')
begin
    insert into standing_change
    values (new.bot_version_id, new.tournament_id, new.maze_id, new.status, new.score, 1);
end;

-- The matches recorded before this version.
insert into standing_change
select bot_version_id, tournament_id, maze_id, status, score, 1
from match where status not in ('queued', 'running');
