-- mazearena schema, version 14 (PostgreSQL): the ranking's own running sums, as the
-- SQLite migration of the same number. The rows of `standing` with tournament_id -1 hold
-- the matches the ranking counts (every match outside a competition's tournaments).

create or replace function standing_change(v bigint, t bigint, z bigint, status text,
                                           score double precision, sign bigint) returns void
language sql as $$
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum, ratio_sum, ratio_count)
    select v, k.t, maze.hidden, sign,
           sign * (case when status = 'finished' then 1 else 0 end),
           sign * (case when status = 'finished' then score else 1000.0 end),
           sign * coalesce((case when status = 'finished' then score else 1000.0 end) / maze.optimum, 0),
           sign * (case when maze.optimum is not null then 1 else 0 end)
    from maze,
         (select coalesce(t, 0) as t
          union all
          select -1 where not exists (select 1 from tournament c
                                      where c.tournament_id = t
                                          and c.competition_id is not null)) k
    where maze.maze_id = z
    on conflict (bot_version_id, tournament_id, hidden) do update set
        played = standing.played + excluded.played,
        finished = standing.finished + excluded.finished,
        score_sum = standing.score_sum + excluded.score_sum,
        ratio_sum = standing.ratio_sum + excluded.ratio_sum,
        ratio_count = standing.ratio_count + excluded.ratio_count;
$$;

-- The ranking's sums of the matches recorded before this version.
delete from standing where tournament_id = -1;
insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                      score_sum, ratio_sum, ratio_count)
select bot_version_id, -1, hidden, sum(played), sum(finished), sum(score_sum),
       sum(ratio_sum), sum(ratio_count)
from standing
where tournament_id >= 0
    and tournament_id not in (select tournament_id from tournament where competition_id is not null)
group by bot_version_id, hidden;
