-- mazearena schema, version 14: the ranking's own running sums. The rows of `standing`
-- with tournament_id -1 now hold the matches the ranking counts (every match outside a
-- competition's tournaments), so the leaderboard reads two rows per bot version instead
-- of summing every tournament's rows: that sum grew with the number of tournaments
-- (2.9 ms a request at 100,000 matches in 794 tournaments).

drop trigger standing_change_apply;

create trigger standing_change_apply instead of insert on standing_change
begin
    insert into standing (bot_version_id, tournament_id, hidden, played, finished,
                          score_sum, ratio_sum, ratio_count)
    select new.bot_version_id, k.t, z.hidden, new.sign,
           new.sign * (new.status = 'finished'),
           new.sign * (case when new.status = 'finished' then new.score else 1000.0 end),
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
        score_sum = score_sum + excluded.score_sum,
        ratio_sum = ratio_sum + excluded.ratio_sum,
        ratio_count = ratio_count + excluded.ratio_count;
end;

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
