//! Standings: mean score (a did-not-finish, `aborted` included, counts as 1000), finish
//! rate, mean ratio of score to the maze's optimum, matches played.

use sqlx::FromRow;

use super::{Result, Storage};
use crate::engine::score::DNF_SCORE;

/// Which matches a leaderboard counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// One tournament's matches, per bot version in it.
    Tournament(i64),
    /// Each bot's latest version, on hidden (ranking) mazes.
    Ranking,
    /// Each bot's latest version, on every maze.
    All,
}

/// One bot's line (also the API's and the CLI's JSON shape).
#[derive(Debug, Clone, PartialEq, FromRow, serde::Serialize, utoipa::ToSchema)]
pub struct Standing {
    /// 1 for the best mean score.
    #[sqlx(skip)]
    pub rank: i64,
    /// Bot id.
    pub bot_id: i64,
    /// Bot name.
    pub name: String,
    /// The version counted.
    pub version: i64,
    /// Matches counted.
    pub played: i64,
    /// Matches finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000.
    pub mean_score: f64,
    /// finished / played.
    pub finish_rate: f64,
    /// Mean of score / optimum (over mazes with a known optimum). The API leaves it out
    /// for non-admins when `hidden_played > 0`: over one hidden maze it gives the
    /// maze's optimum away.
    pub mean_ratio: Option<f64>,
    /// How many of the matches counted were on hidden mazes (not serialized).
    #[serde(skip)]
    pub hidden_played: i64,
}

impl Storage {
    /// The standings, best mean score first (ties: higher finish rate, then name).
    ///
    /// # Errors
    /// Database failures.
    pub async fn leaderboard(&self, scope: Scope) -> Result<Vec<Standing>> {
        let filter = match scope {
            Scope::Tournament(_) => "m.tournament_id = ?",
            Scope::Ranking => {
                "z.hidden = 1 and ? is null and v.version = (select max(version) from bot_version where bot_id = b.bot_id)"
            }
            Scope::All => {
                "? is null and v.version = (select max(version) from bot_version where bot_id = b.bot_id)"
            }
        };
        let sql = format!(
            "select b.bot_id, b.name, v.version, count(*) as played,
                 sum(m.status = 'finished') as finished,
                 avg(case when m.status = 'finished' then m.score else {DNF_SCORE} end) as mean_score,
                 avg(case when m.status = 'finished' then 1.0 else 0.0 end) as finish_rate,
                 avg((case when m.status = 'finished' then m.score else {DNF_SCORE} end) / z.optimum) as mean_ratio,
                 sum(z.hidden) as hidden_played
             from match m
             join bot_version v on v.bot_version_id = m.bot_version_id
             join bot b on b.bot_id = v.bot_id
             join maze z on z.maze_id = m.maze_id
             where m.status not in ('queued', 'running') and {filter}
             group by v.bot_version_id
             order by mean_score asc, finish_rate desc, b.name asc"
        );
        let tournament = match scope {
            Scope::Tournament(id) => Some(id),
            _ => None,
        };
        let mut rows: Vec<Standing> = sqlx::query_as(&sql)
            .bind(tournament)
            .fetch_all(self.pool())
            .await?;
        for (i, row) in rows.iter_mut().enumerate() {
            row.rank = i as i64 + 1;
        }
        Ok(rows)
    }
}
