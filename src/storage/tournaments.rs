//! Tournaments: every bot version on every maze, `repeats` times, queued at once.

use sqlx::FromRow;

use super::matches::PRIORITY_TOURNAMENT;
use super::matches::lists::Page;
use super::{Result, Storage, now_ms};

/// A stored tournament with its progress.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct TournamentRow {
    /// Id.
    pub tournament_id: i64,
    /// Name.
    pub name: String,
    /// Repeats of each (bot, maze) pair.
    pub repeats: i64,
    /// Created at (unix ms).
    pub created_at: i64,
    /// Matches in all.
    pub total: i64,
    /// Matches played (any final status).
    pub done: i64,
    /// The competition it ranks for, if any.
    pub competition_id: Option<i64>,
    /// Whether its matches and numbers are for the admin and organisers only.
    #[sqlx(try_from = "super::Flag")]
    pub sealed: bool,
}

const TOURNAMENT_SELECT: &str =
    "select t.tournament_id, t.name, t.repeats, t.created_at, t.competition_id, t.sealed,
         (select count(*) from match where tournament_id = t.tournament_id) as total,
         (select count(*) from match where tournament_id = t.tournament_id
             and status not in ('queued', 'running')) as done
     from tournament t";

impl Storage {
    /// Creates a tournament and queues all its matches, in one transaction. Repeat `r`
    /// of every pair uses seed `r`, so every bot meets the same seeds.
    ///
    /// # Errors
    /// Database failures (including unknown ids).
    pub async fn create_tournament(
        &self,
        name: &str,
        bot_version_ids: &[i64],
        maze_ids: &[i64],
        repeats: i64,
    ) -> Result<TournamentRow> {
        let mut tx = self.begin_write().await?;
        let now = now_ms();
        let id: i64 = sqlx::query_scalar(
            "insert into tournament (name, repeats, created_at) values ($1, $2, $3) returning tournament_id",
        )
        .bind(name)
        .bind(repeats)
        .bind(now)
        .fetch_one(&mut *tx)
        .await?;
        // Interleave bots so that partial progress is comparable across bots.
        let mut matches = Vec::new();
        for repeat in 0..repeats {
            for &maze_id in maze_ids {
                for &bot_version_id in bot_version_ids {
                    matches.push((bot_version_id, maze_id, repeat));
                }
            }
        }
        // A few statements of many rows (7 parameters a row), queued in this order.
        for chunk in matches.chunks(super::ROWS_PER_INSERT) {
            let sql = format!(
                "insert into match (bot_version_id, maze_id, seed, tournament_id, repeat, priority, created_at)
                 values {}",
                super::placeholders(chunk.len(), 7)
            );
            let mut query = sqlx::query(&sql);
            for &(bot_version_id, maze_id, repeat) in chunk {
                query = query
                    .bind(bot_version_id)
                    .bind(maze_id)
                    .bind(repeat)
                    .bind(id)
                    .bind(repeat)
                    .bind(PRIORITY_TOURNAMENT)
                    .bind(now);
            }
            query.execute(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(self
            .get_tournament(id)
            .await?
            .expect("the tournament was just created"))
    }

    /// A tournament with its progress.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_tournament(&self, tournament_id: i64) -> Result<Option<TournamentRow>> {
        Ok(
            sqlx::query_as(&format!("{TOURNAMENT_SELECT} where t.tournament_id = $1"))
                .bind(tournament_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// One page of tournaments, newest first, and how many there are; with
    /// `hide_sealed`, without the sealed ones.
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_tournaments(
        &self,
        page: Page,
        hide_sealed: bool,
    ) -> Result<(Vec<TournamentRow>, i64)> {
        let filter = if hide_sealed {
            "where t.sealed = 0"
        } else {
            ""
        };
        let rows = sqlx::query_as(&format!(
            "{TOURNAMENT_SELECT} {filter} order by t.tournament_id desc limit $1 offset $2"
        ))
        .bind(page.limit)
        .bind(page.offset)
        .fetch_all(self.pool())
        .await?;
        let total = sqlx::query_scalar(&format!("select count(*) from tournament t {filter}"))
            .fetch_one(self.pool())
            .await?;
        Ok((rows, total))
    }
}
