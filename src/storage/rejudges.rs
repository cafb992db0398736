//! Rejudges: a competition's ranking matches of one version or one maze played again.
//! Each match goes back to the queue under its own id (its tournament, seed and repeat
//! unchanged), and its earlier outcome and record are kept in `match_superseded`. The
//! running sums of the boards follow by themselves (the triggers on `match` take the old
//! outcome away when the match is queued again, and add the new one when it is played);
//! final results that counted a rejudged match are withdrawn, and the competition's clock
//! writes them again once the matches are played.

use sqlx::FromRow;

use super::competitions::CompetitionRow;
use super::{Result, Storage, now_ms};

/// What a rejudge plays again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RejudgeTarget {
    /// Every ranking match of this bot version.
    Version(i64),
    /// Every ranking match on this maze.
    Maze(i64),
}

/// A rejudge as recorded.
#[derive(Debug, Clone, PartialEq, FromRow, serde::Serialize, utoipa::ToSchema)]
pub struct RejudgeRow {
    /// Id.
    pub rejudge_id: i64,
    /// The version played again, if it was a version's rejudge.
    pub bot_version_id: Option<i64>,
    /// The maze played again, if it was a maze's rejudge.
    pub maze_id: Option<i64>,
    /// Why (the organiser's words).
    pub reason: String,
    /// `admin` or `organiser:ID`.
    pub requested_by: String,
    /// How many matches went back to the queue.
    pub matches: i64,
    /// When (unix ms).
    pub created_at: i64,
}

/// An earlier outcome of a match, superseded by a rejudge.
#[derive(Debug, Clone, PartialEq, FromRow, serde::Serialize, utoipa::ToSchema)]
pub struct SupersededRow {
    /// The rejudge that superseded it.
    pub rejudge_id: i64,
    /// Its status then.
    pub status: String,
    /// Its score then.
    pub score: Option<f64>,
    /// Its total steps then.
    pub total_steps: Option<i64>,
    /// When it had ended (unix ms).
    pub finished_at: Option<i64>,
}

impl SupersededRow {
    /// The row as anyone but the admin may see an earlier outcome on a hidden maze,
    /// under the rules of the match's own row ([`super::matches::MatchRow::redacted`]):
    /// its status only, no score, steps or end time.
    pub fn redacted(self) -> SupersededRow {
        SupersededRow {
            score: None,
            total_steps: None,
            finished_at: None,
            ..self
        }
    }
}

impl Storage {
    /// Plays again the ended ranking matches (of the public, private and final-run sets)
    /// of competition `c` that `target` names, keeping their earlier outcomes; answers
    /// the rejudge (with how many matches went back to the queue: none is a rejudge too,
    /// recorded). Matches still queued or running are left as they are.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rejudge(
        &self,
        c: &CompetitionRow,
        target: RejudgeTarget,
        reason: &str,
        requested_by: &str,
    ) -> Result<RejudgeRow> {
        let tournaments: Vec<i64> = [
            c.public_tournament_id,
            c.private_tournament_id,
            c.final_tournament_id,
        ]
        .into_iter()
        .flatten()
        .collect();
        let (version, maze) = match target {
            RejudgeTarget::Version(v) => (Some(v), None),
            RejudgeTarget::Maze(m) => (None, Some(m)),
        };
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let now = now_ms();
        let rejudge_id: i64 = sqlx::query_scalar(
            "insert into rejudge (competition_id, bot_version_id, maze_id, reason, requested_by,
                                  matches, created_at)
             values ($1, $2, $3, $4, $5, 0, $6) returning rejudge_id",
        )
        .bind(c.competition_id)
        .bind(version)
        .bind(maze)
        .bind(reason)
        .bind(requested_by)
        .bind(now)
        .fetch_one(&mut *tx)
        .await?;
        let list = if tournaments.is_empty() {
            "null".to_string()
        } else {
            tournaments
                .iter()
                .map(i64::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        };
        let scope = format!(
            "m.tournament_id in ({list}) and m.status not in ('queued', 'running')
             and (m.bot_version_id = $2 or m.maze_id = $3)"
        );
        let moved = sqlx::query(&format!(
            "insert into match_superseded (match_id, rejudge_id, status, score, run0_steps,
                 run1_steps, total_steps, record, started_at, finished_at, encoding, data)
             select m.match_id, $1, m.status, m.score, m.run0_steps, m.run1_steps,
                    m.total_steps, m.record, m.started_at, m.finished_at, r.encoding, r.data
             from match m left join match_record r on r.match_id = m.match_id
             where {scope}"
        ))
        .bind(rejudge_id)
        .bind(version.unwrap_or(-1))
        .bind(maze.unwrap_or(-1))
        .execute(&mut *tx)
        .await?
        .rows_affected() as i64;
        let mine = "select match_id from match_superseded where rejudge_id = $1";
        sqlx::query(&format!(
            "delete from match_record where match_id in ({mine})"
        ))
        .bind(rejudge_id)
        .execute(&mut *tx)
        .await?;
        sqlx::query(&format!(
            "update match set status = 'queued', score = null, run0_steps = null,
                 run1_steps = null, total_steps = null, record = null, trace = null,
                 started_at = null, finished_at = null, lease_owner = null,
                 lease_expires_at = null, attempts = 0, lease_expiries = 0
             where match_id in ({mine})"
        ))
        .bind(rejudge_id)
        .execute(&mut *tx)
        .await?;
        // Results that counted a rejudged match are withdrawn until it is played again.
        let deciding = c.final_tournament_id.or(c.private_tournament_id);
        if let (Some("final" | "held"), Some(t)) = (c.state.as_deref(), deciding) {
            let touched: i64 = sqlx::query_scalar(&format!(
                "select count(*) from match where tournament_id = $2 and match_id in ({mine})"
            ))
            .bind(rejudge_id)
            .bind(t)
            .fetch_one(&mut *tx)
            .await?;
            if touched > 0 {
                sqlx::query("delete from competition_result where competition_id = $1")
                    .bind(c.competition_id)
                    .execute(&mut *tx)
                    .await?;
                sqlx::query(
                    "update competition set state = 'final_run', finalized_at = null
                     where competition_id = $1",
                )
                .bind(c.competition_id)
                .execute(&mut *tx)
                .await?;
            }
        }
        let row: RejudgeRow = sqlx::query_as(
            "update rejudge set matches = $2 where rejudge_id = $1
             returning rejudge_id, bot_version_id, maze_id, reason, requested_by, matches,
                       created_at",
        )
        .bind(rejudge_id)
        .bind(moved)
        .fetch_one(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(row)
    }

    /// The rejudges of competition `competition_id`, newest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rejudges(&self, competition_id: i64) -> Result<Vec<RejudgeRow>> {
        Ok(sqlx::query_as(
            "select rejudge_id, bot_version_id, maze_id, reason, requested_by, matches, created_at
             from rejudge where competition_id = $1 order by rejudge_id desc",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The earlier outcomes of match `match_id` that rejudges superseded, oldest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn superseded(&self, match_id: i64) -> Result<Vec<SupersededRow>> {
        Ok(sqlx::query_as(
            "select rejudge_id, status, score, total_steps, finished_at
             from match_superseded where match_id = $1 order by superseded_id",
        )
        .bind(match_id)
        .fetch_all(self.pool())
        .await?)
    }
}
