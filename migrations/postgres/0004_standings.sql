-- mazearena schema, version 4 (PostgreSQL): standings kept as running sums, as the
-- SQLite migration of the same number. A trigger on `match` applies each match's part
-- in the same transaction as the write that gives it its final status (or takes it
-- away), whatever statement does it.

create table standing (
    bot_version_id bigint not null references bot_version (bot_version_id),
    -- the tournament, 0 for matches outside any tournament, -1 for all matches
    tournament_id bigint not null,
    -- 1: the matches on hidden mazes; 0: on public ones
    hidden bigint not null,
    played bigint not null default 0,
    finished bigint not null default 0,
    score_sum double precision not null default 0,
    ratio_sum double precision not null default 0,
    ratio_count bigint not null default 0,
    primary key (bot_version_id, tournament_id, hidden)
);

-- A match's part of the sums, applied with `sign` (1: add, -1: take away).
create function standing_change(v bigint, t bigint, z bigint, status text,
                                score double precision, sign bigint) returns void
language sql as $$
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum, ratio_sum, ratio_count)
    select v, k.t, maze.hidden, sign,
           sign * (case when status = 'finished' then 1 else 0 end),
           sign * (case when status = 'finished' then score else 1000.0 end),
           sign * coalesce((case when status = 'finished' then score else 1000.0 end) / maze.optimum, 0),
           sign * (case when maze.optimum is not null then 1 else 0 end)
    from maze, (select coalesce(t, 0) as t union all select -1) k
    where maze.maze_id = z
    on conflict (bot_version_id, tournament_id, hidden) do update set
        played = standing.played + excluded.played,
        finished = standing.finished + excluded.finished,
        score_sum = standing.score_sum + excluded.score_sum,
        ratio_sum = standing.ratio_sum + excluded.ratio_sum,
        ratio_count = standing.ratio_count + excluded.ratio_count;
$$;

create function standing_on_match() returns trigger
language plpgsql as $$
begin
    if tg_op in ('UPDATE', 'DELETE') and old.status not in ('queued', 'running') then
        perform standing_change(old.bot_version_id, old.tournament_id, old.maze_id,
                                old.status, old.score, -1);
    end if;
    if tg_op in ('UPDATE', 'INSERT') and new.status not in ('queued', 'running') then
        perform standing_change(new.bot_version_id, new.tournament_id, new.maze_id,
                                new.status, new.score, 1);
    end if;
    return null;
end;
$$;

create trigger standing_on_insert_or_delete after insert or delete on match
for each row execute function standing_on_match();

create trigger standing_on_update
after update of status, score, bot_version_id, maze_id, tournament_id on match
for each row execute function standing_on_match();

-- The matches recorded before this version.
select standing_change(bot_version_id, tournament_id, maze_id, status, score, 1)
from match where status not in ('queued', 'running');
