//! Ranking: new versions queued on the public set, the boards' rows, the work left.

use super::final_run::queue_matches;
use super::{BoardRow, CompetitionRow};
use crate::storage::{Result, Storage, now_ms};

impl Storage {
    /// The ready versions of entered bots that open competitions (opened by `now`, not
    /// yet selected) have still to queue on their ranking sets: (competition, version).
    /// A version uploaded after the close never is.
    ///
    /// # Errors
    /// Database failures.
    pub async fn versions_to_rank(&self, now: i64) -> Result<Vec<(i64, i64)>> {
        Ok(sqlx::query_as(
            "select c.competition_id, v.bot_version_id from competition c
             join competition_entry e on e.competition_id = c.competition_id
             join bot_version v on v.bot_id = e.bot_id and v.bot_version_id >= e.first_version_id
             where c.kind = 'competition' and c.state is null and c.opens_at <= $1
                 and v.created_at < c.closes_at and v.build_status = 'ready'
                 and not exists (select 1 from competition_version x
                     where x.competition_id = c.competition_id and x.bot_version_id = v.bot_version_id)
             order by v.bot_version_id",
        )
        .bind(now)
        .fetch_all(self.pool())
        .await?)
    }

    /// Queues version `bot_version_id` on a competition's public ranking set (`public`
    /// maze ids), every repeat with its secret seed. The private set is never played
    /// before the close: its only matches are the final run's ([`Storage::start_final`]).
    /// Returns false if it was queued already.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rank_version(
        &self,
        c: &CompetitionRow,
        bot_version_id: i64,
        public: &[i64],
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        let added = sqlx::query(
            "insert into competition_version (competition_id, bot_version_id, ranked_at)
             values ($1, $2, $3) on conflict do nothing",
        )
        .bind(c.competition_id)
        .bind(bot_version_id)
        .bind(now)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if added == 0 {
            return Ok(false);
        }
        if let Some(tournament) = c.public_tournament_id {
            queue_matches(
                &mut tx,
                tournament,
                bot_version_id,
                public,
                0..c.repeats,
                &c.seed_list(),
                now,
            )
            .await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// Every version's line in tournament `tournament_id`, from the running sums; with
    /// `recount`, counted from the match table itself instead (to check the sums).
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_board(
        &self,
        tournament_id: i64,
        recount: bool,
    ) -> Result<Vec<BoardRow>> {
        let sums = if recount {
            format!(
                "select m.bot_version_id, count(*) as played,
                     sum(case when m.status = 'finished' then 1 else 0 end) as finished,
                     sum(case when m.status = 'finished' then cast(round(m.score * 30) as bigint)
                         else {dnf} end) as score_sum30
                 from match m where m.tournament_id = $1 and m.status not in ('queued', 'running')
                 group by m.bot_version_id",
                dnf = crate::ranking::mean::DNF_THIRTIETHS
            )
        } else {
            "select bot_version_id, sum(played) as played, sum(finished) as finished,
                 sum(score_sum30) as score_sum30
             from standing where tournament_id = $1 group by bot_version_id"
                .to_string()
        };
        Ok(sqlx::query_as(&format!(
            "select v.bot_version_id, v.bot_id, b.name as bot_name, b.entrant_id, n.name as entrant_name,
                 v.version, v.created_at, cast(s.played as bigint) as played,
                 cast(s.finished as bigint) as finished,
                 cast(s.score_sum30 as bigint) as score_sum30,
                 case when exists (select 1 from match p where p.tournament_id = $1
                     and p.bot_version_id = v.bot_version_id and p.status in ('queued', 'running'))
                     then 1 else 0 end as pending
             from ({sums}) s
             join bot_version v on v.bot_version_id = s.bot_version_id
             join bot b on b.bot_id = v.bot_id
             left join entrant n on n.entrant_id = b.entrant_id
             where s.played > 0
             order by 1.0 * s.score_sum30 / s.played asc, 1.0 * s.finished / s.played desc,
                 b.name asc, v.version desc"
        ))
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// How much of a closed competition is still to happen before its selection: matches
    /// of its tournaments queued or running, and for each entered bot, its newest version
    /// uploaded before the close if that is still waiting for its build (the builders
    /// take those first: [`crate::storage::builds::FAIR_BUILD_ORDER`]). An older version still
    /// building is superseded and does not hold the close: an entrant who uploads several
    /// versions at the deadline holds it for one build at most.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_work_left(&self, c: &CompetitionRow) -> Result<i64> {
        Ok(sqlx::query_scalar(
            "select (select count(*) from match m join tournament t on t.tournament_id = m.tournament_id
                     where t.competition_id = $1 and m.status in ('queued', 'running'))
                  + (select count(*) from bot_version v
                     join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
                     where e.competition_id = $1 and v.build_status = 'building' and v.created_at < $2
                         and v.bot_version_id = (select max(w.bot_version_id) from bot_version w
                                                 where w.bot_id = v.bot_id and w.created_at < $2))",
        )
        .bind(c.competition_id)
        .bind(c.closes_at.unwrap_or(0))
        .fetch_one(self.pool())
        .await?)
    }
}
