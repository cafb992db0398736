-- mazearena schema, version 16 (PostgreSQL): sums of scores kept exact, as the SQLite
-- migration of the same number. The running sums hold integer thirtieths of a step.

alter table standing add column score_sum30 bigint not null default 0;
update standing set score_sum30 = cast(round(score_sum * 30) as bigint);
alter table standing drop column score_sum;

create or replace function standing_change(v bigint, t bigint, z bigint, status text,
                                           score double precision, sign bigint) returns void
language sql as $$
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum30, ratio_sum, ratio_count)
    select v, k.t, maze.hidden, sign,
           sign * (case when status = 'finished' then 1 else 0 end),
           sign * cast(round((case when status = 'finished' then score else 1000.0 end) * 30) as bigint),
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
        score_sum30 = standing.score_sum30 + excluded.score_sum30,
        ratio_sum = standing.ratio_sum + excluded.ratio_sum,
        ratio_count = standing.ratio_count + excluded.ratio_count;
$$;

alter table competition_result add column score_sum30 bigint not null default 0;
update competition_result set score_sum30 = cast(round(mean_score * played * 30) as bigint);
