-- mazearena schema, version 16: sums of scores kept exact. A score is a whole number of
-- thirtieths of a step, so the running sums hold integer thirtieths (a did-not-finish:
-- 30,000) instead of floats: equal scores added in any order give equal sums, and equal
-- means rank equal by construction. The final results keep their sum too.

drop trigger standing_change_apply;

alter table standing add column score_sum30 integer not null default 0;
update standing set score_sum30 = cast(round(score_sum * 30) as integer);
alter table standing drop column score_sum;

create trigger standing_change_apply instead of insert on standing_change
begin
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum30, ratio_sum, ratio_count)
    select new.bot_version_id, k.t, z.hidden, new.sign,
           new.sign * (new.status = 'finished'),
           new.sign * cast(round((case when new.status = 'finished' then new.score else 1000.0 end) * 30) as integer),
           new.sign * coalesce((case when new.status = 'finished' then new.score else 1000.0 end) / z.optimum, 0),
           new.sign * (z.optimum is not null)
    from maze z,
         (select coalesce(new.tournament_id, 0) as t
          union all
          select -1 where not exists (select 1 from tournament c
                                      where c.tournament_id = new.tournament_id
                                          and c.competition_id is not null)) k
    where z.maze_id = new.maze_id
    on conflict (bot_version_id, tournament_id, hidden) do update set
        played = played + excluded.played,
        finished = finished + excluded.finished,
        score_sum30 = score_sum30 + excluded.score_sum30,
        ratio_sum = ratio_sum + excluded.ratio_sum,
        ratio_count = ratio_count + excluded.ratio_count;
end;

alter table competition_result add column score_sum30 integer not null default 0;
update competition_result set score_sum30 = cast(round(mean_score * played * 30) as integer);
