//! Entries: which bots are entered, their versions as their entrants see them, the
//! versions they choose, and what counts against the quotas.

use super::{
    COMPETITION_COLUMNS, COUNTED_VERSIONS, CompetitionRow, EntryRow, PRACTICE_MATCHES,
    SubmissionRow,
};
use crate::storage::{Result, Storage, StorageError, is_unique_violation, now_ms};

impl Storage {
    /// The competitions entrant `entrant_id` has a bot entered in.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competitions_of_entrant(&self, entrant_id: i64) -> Result<Vec<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where competition_id in
                 (select competition_id from competition_entry where entrant_id = $1)"
        ))
        .bind(entrant_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// Enters `bot_id` of `entrant_id` into a competition: its versions from its latest
    /// on (or its first, if it has none yet) are ranked.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the entrant has a bot entered already; database
    /// failures.
    pub async fn enter_competition(
        &self,
        competition_id: i64,
        bot_id: i64,
        entrant_id: i64,
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query(
            "insert into competition_entry (competition_id, bot_id, entrant_id, first_version_id, entered_at)
             values ($1, $2, $3,
                 coalesce((select max(bot_version_id) from bot_version where bot_id = $2), 0), $4)",
        )
        .bind(competition_id)
        .bind(bot_id)
        .bind(entrant_id)
        .bind(now_ms())
        .execute(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(
                    "this entrant has a bot in this competition already (one bot per entrant)".into(),
                )
            } else {
                e.into()
            }
        })?;
        Ok(())
    }

    /// The entrant bot `bot_id` belongs to, if any.
    ///
    /// # Errors
    /// Database failures.
    pub async fn entrant_of_bot(&self, bot_id: i64) -> Result<Option<i64>> {
        Ok(
            sqlx::query_scalar::<_, Option<i64>>("select entrant_id from bot where bot_id = $1")
                .bind(bot_id)
                .fetch_optional(self.pool())
                .await?
                .flatten(),
        )
    }

    /// The entrant that entered bot `bot_id` in competition `competition_id`, if it is.
    ///
    /// # Errors
    /// Database failures.
    pub async fn entrant_of_entry(&self, competition_id: i64, bot_id: i64) -> Result<Option<i64>> {
        Ok(sqlx::query_scalar(
            "select entrant_id from competition_entry where competition_id = $1 and bot_id = $2",
        )
        .bind(competition_id)
        .bind(bot_id)
        .fetch_optional(self.pool())
        .await?)
    }

    /// The versions the final selection of a competition took.
    ///
    /// # Errors
    /// Database failures.
    pub async fn selected_versions(&self, competition_id: i64) -> Result<Vec<i64>> {
        Ok(sqlx::query_scalar(
            "select bot_version_id from competition_version where competition_id = $1 and selected = 1",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The bots entered in a competition, by entrant name.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_entries(&self, competition_id: i64) -> Result<Vec<EntryRow>> {
        Ok(sqlx::query_as(
            "select e.bot_id, b.name as bot_name, e.entrant_id, n.name as entrant_name,
                 e.first_version_id, e.entered_at
             from competition_entry e join bot b on b.bot_id = e.bot_id
             join entrant n on n.entrant_id = e.entrant_id
             where e.competition_id = $1 order by n.name",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The competitions (not the default one) bot `bot_id` is entered in.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competitions_of_bot(&self, bot_id: i64) -> Result<Vec<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where competition_id in
                 (select competition_id from competition_entry where bot_id = $1)"
        ))
        .bind(bot_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// How many of an entrant's versions in a competition since `since` count against
    /// its quota (as [`Storage::counted_version_times`]), read in transaction `tx`.
    pub(crate) async fn count_counted_versions_in(
        tx: &mut sqlx::AnyConnection,
        competition_id: i64,
        entrant_id: i64,
        since: i64,
    ) -> Result<i64> {
        Ok(sqlx::query_scalar(&format!(
            "select cast(count(*) as bigint) {COUNTED_VERSIONS}"
        ))
        .bind(competition_id)
        .bind(entrant_id)
        .bind(since)
        .fetch_one(&mut *tx)
        .await?)
    }

    /// The upload times of an entrant's versions in a competition since `since` that
    /// count against its quota: not failed to build, none of their ranking matches
    /// aborted.
    ///
    /// # Errors
    /// Database failures.
    pub async fn counted_version_times(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
        since: i64,
    ) -> Result<Vec<i64>> {
        Ok(
            sqlx::query_scalar(&format!("select v.created_at {COUNTED_VERSIONS}"))
                .bind(c.competition_id)
                .bind(entrant_id)
                .bind(since)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// When an entrant's practice matches on a competition's practice mazes since
    /// `since` were queued.
    ///
    /// # Errors
    /// Database failures.
    pub async fn practice_times(
        &self,
        competition_id: i64,
        entrant_id: i64,
        since: i64,
    ) -> Result<Vec<i64>> {
        Ok(
            sqlx::query_scalar(&format!("select m.created_at {PRACTICE_MATCHES}"))
                .bind(competition_id)
                .bind(entrant_id)
                .bind(since)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// An entrant's versions in a competition, newest first, with where each stands.
    ///
    /// # Errors
    /// Database failures.
    pub async fn submissions(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
    ) -> Result<Vec<SubmissionRow>> {
        Ok(sqlx::query_as(
            "select v.bot_version_id, v.bot_id, v.version, v.created_at, v.build_status,
                 case when x.bot_version_id is null then 0 else 1 end as ranked,
                 coalesce(x.chosen, 0) as chosen, coalesce(x.selected, 0) as selected,
                 case when exists (select 1 from match m join tournament t on t.tournament_id = m.tournament_id
                     where t.competition_id = $1 and m.bot_version_id = v.bot_version_id
                         and m.status = 'aborted') then 1 else 0 end as aborted
             from bot_version v
             join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
             left join competition_version x on x.competition_id = e.competition_id
                 and x.bot_version_id = v.bot_version_id
             where e.competition_id = $1 and e.entrant_id = $2
             order by v.bot_version_id desc",
        )
        .bind(c.competition_id)
        .bind(entrant_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// Marks an entrant's chosen versions for the final (the others unchosen).
    ///
    /// # Errors
    /// Database failures.
    pub async fn choose_versions(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
        version_ids: &[i64],
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        sqlx::query(
            "update competition_version set chosen = 0 where competition_id = $1 and bot_version_id in
                 (select v.bot_version_id from bot_version v join competition_entry e on e.bot_id = v.bot_id
                  where e.competition_id = $1 and e.entrant_id = $2)",
        )
        .bind(c.competition_id)
        .bind(entrant_id)
        .execute(&mut *tx)
        .await?;
        for id in version_ids {
            sqlx::query(
                "update competition_version set chosen = 1 where competition_id = $1 and bot_version_id = $2",
            )
            .bind(c.competition_id)
            .bind(id)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(())
    }
}
