//! The close: the private set unsealed, the final selection and run queued in a shuffled
//! order, the results written, held and published.

use super::{CompetitionRow, MatchToQueue, ResultRow};
use crate::storage::matches::PRIORITY_TOURNAMENT;
use crate::storage::{Result, Storage, now_ms};

impl Storage {
    /// Unseals a competition's private set (its close has passed). Reads first, so that
    /// the clock's every tick after the close writes nothing once it is done.
    ///
    /// # Errors
    /// Database failures.
    pub async fn unseal_private_set(&self, c: &CompetitionRow) -> Result<()> {
        let Some(t) = c.private_tournament_id else {
            return Ok(());
        };
        if !self.get_tournament(t).await?.is_some_and(|t| t.sealed) {
            return Ok(());
        }
        let _turn = self.write_turn().await;
        sqlx::query("update tournament set sealed = 0 where tournament_id = $1 and sealed = 1")
            .bind(c.private_tournament_id)
            .execute(self.pool())
            .await?;
        Ok(())
    }

    /// Records the final selection and queues the final run of the `selected` versions
    /// on the private mazes ([`CompetitionRow::final_run_repeats`] each, with seeds of
    /// their own: the repeat indexes after the public set's), in a sealed tournament:
    /// the private set's only matches, queued in an order shuffled by `order` (a random
    /// number: matches are played in the order they were queued, so that no one can
    /// tell which entrant's match is playing from how far the run is). Returns false if
    /// another server did it first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn start_final(
        &self,
        c: &CompetitionRow,
        selected: &[i64],
        private: &[i64],
        order: u64,
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        if !move_state(&mut tx, c.competition_id, None, "final_run").await? {
            return Ok(false);
        }
        for id in selected {
            sqlx::query(
                "update competition_version set selected = 1 where competition_id = $1 and bot_version_id = $2",
            )
            .bind(c.competition_id)
            .bind(id)
            .execute(&mut *tx)
            .await?;
        }
        let repeats = c.final_run_repeats();
        if !selected.is_empty() && !private.is_empty() {
            let t: i64 = sqlx::query_scalar(
                "insert into tournament (name, repeats, created_at, sealed, limits, competition_id)
                 values ($1, $2, $3, 1, $4, $5) returning tournament_id",
            )
            .bind(format!("{}: final run", c.name))
            .bind(repeats)
            .bind(now)
            .bind(&c.limits)
            .bind(c.competition_id)
            .fetch_one(&mut *tx)
            .await?;
            let seeds = c.seed_list();
            let mut rows: Vec<MatchToQueue> = selected
                .iter()
                .flat_map(|&id| match_rows(id, private, c.repeats..c.repeats + repeats, &seeds))
                .collect();
            shuffle(&mut rows, order);
            insert_matches(&mut tx, t, &rows, now).await?;
            sqlx::query(
                "update competition set final_tournament_id = $2 where competition_id = $1",
            )
            .bind(c.competition_id)
            .bind(t)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// Writes the results of competition `c` (in its final run) in one transaction:
    /// `held` for its organisers alone when it holds them (`hold_results`), else published
    /// at once ([`Storage::publish_results`]'s work: `final`, its tournaments unsealed,
    /// `reveal`'s mazes shown). False when another server wrote them first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn write_results(
        &self,
        c: &CompetitionRow,
        rows: &[ResultRow],
        reveal: &[i64],
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let state = if c.hold_results { "held" } else { "final" };
        if !move_state(&mut tx, c.competition_id, Some("final_run"), state).await? {
            return Ok(false);
        }
        sqlx::query("update competition set finalized_at = $2 where competition_id = $1")
            .bind(c.competition_id)
            .bind(now_ms())
            .execute(&mut *tx)
            .await?;
        for r in rows {
            sqlx::query(
                "insert into competition_result (competition_id, rank, entrant_id, entrant_name, bot_id,
                     bot_name, bot_version_id, version, played, finished, mean_score, finish_rate, manifest,
                     score_sum30)
                 values ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)",
            )
            .bind(c.competition_id)
            .bind(r.rank)
            .bind(r.entrant_id)
            .bind(&r.entrant_name)
            .bind(r.bot_id)
            .bind(&r.bot_name)
            .bind(r.bot_version_id)
            .bind(r.version)
            .bind(r.played)
            .bind(r.finished)
            .bind(r.mean_score)
            .bind(r.finish_rate)
            .bind(&r.manifest)
            .bind(r.score_sum30)
            .execute(&mut *tx)
            .await?;
        }
        if !c.hold_results {
            open_results(&mut tx, c.competition_id, reveal).await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// Publishes the held results of competition `c`: `final`, its tournaments unsealed,
    /// `reveal`'s mazes shown. False when they were not held (published already, or not
    /// written).
    ///
    /// # Errors
    /// Database failures.
    pub async fn publish_results(&self, c: &CompetitionRow, reveal: &[i64]) -> Result<bool> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        if !move_state(&mut tx, c.competition_id, Some("held"), "final").await? {
            return Ok(false);
        }
        open_results(&mut tx, c.competition_id, reveal).await?;
        tx.commit().await?;
        Ok(true)
    }

    /// A competition's final results, best first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_results(&self, competition_id: i64) -> Result<Vec<ResultRow>> {
        let mut rows: Vec<ResultRow> = sqlx::query_as(
            "select rank, entrant_id, entrant_name, bot_id, bot_name, bot_version_id, version, played,
                 finished, score_sum30, manifest
             from competition_result where competition_id = $1 order by rank, entrant_name",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?;
        for r in &mut rows {
            r.fill_shown();
        }
        Ok(rows)
    }

    /// How far tournament `tournament_id` has played: (matches played, matches in it).
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_progress(&self, tournament_id: i64) -> Result<(i64, i64)> {
        Ok(sqlx::query_as(
            "select cast(coalesce(sum(case when status in ('queued', 'running') then 0 else 1 end), 0) as bigint),
                 cast(count(*) as bigint)
             from match where tournament_id = $1",
        )
        .bind(tournament_id)
        .fetch_one(self.pool())
        .await?)
    }

    /// The seeds of a tournament's matches, by repeat index.
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_seeds(&self, tournament_id: i64) -> Result<Vec<(i64, i64)>> {
        Ok(sqlx::query_as(
            "select distinct repeat, seed from match where tournament_id = $1 order by repeat",
        )
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }
}

/// Queues `bot_version_id` on `mazes` in tournament `tournament`, repeat indexes
/// `repeats` with `seeds[r]` (the repeat index itself past the list's end).
pub(super) async fn queue_matches(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    tournament: i64,
    bot_version_id: i64,
    mazes: &[i64],
    repeats: std::ops::Range<i64>,
    seeds: &[i64],
    now: i64,
) -> Result<()> {
    let rows = match_rows(bot_version_id, mazes, repeats, seeds);
    insert_matches(tx, tournament, &rows, now).await
}

/// The matches of version `bot_version_id` on `mazes`, each repeat in `repeats` with
/// its seed (the repeat's index in `seeds`).
pub(super) fn match_rows(
    bot_version_id: i64,
    mazes: &[i64],
    repeats: std::ops::Range<i64>,
    seeds: &[i64],
) -> Vec<MatchToQueue> {
    repeats
        .flat_map(|r| {
            let seed = seeds.get(r as usize).copied().unwrap_or(r);
            mazes.iter().map(move |&z| (bot_version_id, z, r, seed))
        })
        .collect()
}

/// Shuffles `rows` (Fisher-Yates) with a generator seeded by `order`.
pub(super) fn shuffle<T>(rows: &mut [T], order: u64) {
    let mut rng = oorandom::Rand64::new(u128::from(order));
    for i in (1..rows.len()).rev() {
        let j = rng.rand_range(0..(i as u64 + 1)) as usize;
        rows.swap(i, j);
    }
}

/// Queues `rows` in tournament `tournament`, in their order (matches are played in the
/// order they were queued).
async fn insert_matches(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    tournament: i64,
    rows: &[MatchToQueue],
    now: i64,
) -> Result<()> {
    for chunk in rows.chunks(crate::storage::ROWS_PER_INSERT) {
        let sql = format!(
            "insert into match (bot_version_id, maze_id, seed, tournament_id, repeat, priority, created_at)
             values {} on conflict do nothing",
            crate::storage::placeholders(chunk.len(), 7)
        );
        let mut query = sqlx::query(&sql);
        for &(bot_version_id, maze_id, repeat, seed) in chunk {
            query = query
                .bind(bot_version_id)
                .bind(maze_id)
                .bind(seed)
                .bind(tournament)
                .bind(repeat)
                .bind(PRIORITY_TOURNAMENT)
                .bind(now);
        }
        query.execute(&mut **tx).await?;
    }
    Ok(())
}

/// Moves competition `competition_id` from state `from` (`None`: open) to `to`, in
/// `tx`; false when it was not in `from` (another server moved it first).
async fn move_state(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    competition_id: i64,
    from: Option<&str>,
    to: &str,
) -> Result<bool> {
    let moved = sqlx::query(
        "update competition set state = $2
         where competition_id = $1 and coalesce(state, '') = coalesce($3, '')",
    )
    .bind(competition_id)
    .bind(to)
    .bind(from)
    .execute(&mut **tx)
    .await?
    .rows_affected();
    Ok(moved == 1)
}

/// What publishing results opens: the competition's tournaments unsealed, `reveal`'s
/// mazes shown.
async fn open_results(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    competition_id: i64,
    reveal: &[i64],
) -> Result<()> {
    sqlx::query("update tournament set sealed = 0 where competition_id = $1")
        .bind(competition_id)
        .execute(&mut **tx)
        .await?;
    for maze_id in reveal {
        sqlx::query("update maze set hidden = 0 where maze_id = $1")
            .bind(maze_id)
            .execute(&mut **tx)
            .await?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{match_rows, shuffle};

    #[test]
    fn the_final_runs_order_is_a_permutation_that_its_random_number_decides() {
        let rows: Vec<_> = [11, 12, 13]
            .iter()
            .flat_map(|&v| match_rows(v, &[1, 2], 4..6, &[0, 0, 0, 0, 40, 50]))
            .collect();
        assert_eq!(rows.len(), 12);
        assert_eq!(rows[0], (11, 1, 4, 40));
        assert_eq!(rows[3], (11, 2, 5, 50));
        let mut a = rows.clone();
        shuffle(&mut a, 7);
        let mut b = rows.clone();
        shuffle(&mut b, 8);
        assert_ne!(a, rows, "the order moved");
        assert_ne!(a, b, "another number, another order");
        let mut again = rows.clone();
        shuffle(&mut again, 7);
        assert_eq!(a, again, "the same number, the same order");
        // Not one version's matches after another's: the run's progress would say
        // whose match is playing.
        let grouped = a.chunks(4).all(|c| c.iter().all(|r| r.0 == c[0].0));
        assert!(!grouped, "{a:?}");
        let mut sorted = rows.clone();
        sorted.sort_unstable();
        a.sort_unstable();
        assert_eq!(a, sorted, "every match once");
    }
}
