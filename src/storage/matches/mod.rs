//! The match queue: matches are rows; workers claim them with a lease, and write the
//! record in one transaction only while they still hold the lease.
//! A match whose lease expired (its server died while it ran) is retried a bounded
//! number of times ([`super::retries`]).

pub mod lists;
pub mod match_records;
pub mod queue;

use sqlx::FromRow;

use super::{Backend, Result, Storage, StorageError};
use crate::runner::outcome::{MatchState, MatchStatus, MatchSummary};

/// Priority of single matches: they run before tournament matches.
pub const PRIORITY_SINGLE: i64 = 0;
/// Priority of tournament matches.
pub const PRIORITY_TOURNAMENT: i64 = 1;

/// A stored match (without its trace).
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct MatchRow {
    /// Id.
    pub match_id: i64,
    /// The bot version that plays.
    pub bot_version_id: i64,
    /// Its bot.
    pub bot_id: i64,
    /// The bot's name.
    pub bot_name: String,
    /// The bot version's number.
    pub version: i64,
    /// The maze.
    pub maze_id: i64,
    /// The maze's name.
    pub maze_name: String,
    /// Whether the maze is hidden.
    #[sqlx(try_from = "super::Flag")]
    pub maze_hidden: bool,
    /// SHA-256 of the maze's canonical text.
    pub maze_hash: String,
    /// The maze's side.
    pub maze_dim: i64,
    /// The seed sent to the bot.
    pub seed: i64,
    /// The tournament, if any.
    pub tournament_id: Option<i64>,
    /// Repetition index within the tournament.
    pub repeat: Option<i64>,
    /// Queued, running, or its final status.
    #[sqlx(try_from = "String")]
    pub status: MatchState,
    /// How many times a worker started it.
    pub attempts: i64,
    /// How many times its lease expired while it ran (its server died).
    pub lease_expiries: i64,
    /// Score when finished.
    pub score: Option<f64>,
    /// Run-0 steps.
    pub run0_steps: Option<i64>,
    /// Run-1 steps.
    pub run1_steps: Option<i64>,
    /// The step counter at the end.
    pub total_steps: Option<i64>,
    /// The record without its trace (JSON), once played.
    pub record: Option<String>,
    /// Queued at (unix ms).
    pub created_at: i64,
    /// Last started at (unix ms).
    pub started_at: Option<i64>,
    /// Finished at (unix ms).
    pub finished_at: Option<i64>,
    /// When its stored replay was removed to save space (an old practice match; none:
    /// never).
    pub record_pruned_at: Option<i64>,
    /// Whether its tournament is sealed (a competition's private set before the close,
    /// its final run before the results): for the admin and organisers only.
    #[sqlx(try_from = "super::Flag")]
    pub sealed: bool,
}

impl MatchRow {
    /// The row as anyone but the admin may see it: on a hidden maze, whether it finished
    /// and else the kind of failure (its status), nothing more: no score, no steps, no
    /// failure step or text, no start or end time (each of these could carry a few bits
    /// of the maze, chosen by the bot). A public maze's row is unchanged.
    pub fn redacted(mut self) -> MatchRow {
        if self.maze_hidden {
            self.score = None;
            self.run0_steps = None;
            self.run1_steps = None;
            self.total_steps = None;
            self.started_at = None;
            self.finished_at = None;
            if let Some(summary) = self
                .record
                .as_deref()
                .and_then(|r| serde_json::from_str::<crate::runner::outcome::MatchSummary>(r).ok())
            {
                let kept = crate::runner::outcome::MatchSummary {
                    engine_version: summary.engine_version,
                    limits: summary.limits,
                    status: summary.status,
                    ..Default::default()
                };
                self.record = serde_json::to_string(&kept).ok();
            }
        }
        self
    }

    /// Whether its stored replay was removed to save space (an old practice match,
    /// pruned): only then, not for a match that ended before its bot's first move.
    pub fn trace_removed(&self) -> bool {
        self.record_pruned_at.is_some()
    }

    /// The row's summary of the record (empty while the match is not played; a summary
    /// that cannot be read counts as empty).
    pub fn summary(&self) -> MatchSummary {
        self.record
            .as_deref()
            .and_then(|r| serde_json::from_str(r).ok())
            .unwrap_or_default()
    }
}

/// A match's columns with its names (for [`Storage::match_select`]).
const MATCH_COLUMNS: &str = "m.match_id, m.bot_version_id, v.bot_id, b.name as bot_name, v.version, m.maze_id,
        z.name as maze_name, z.hidden as maze_hidden, z.hash as maze_hash, z.dim as maze_dim, m.seed, m.tournament_id, m.repeat, m.status, m.attempts, m.lease_expiries, m.score,
        m.run0_steps, m.run1_steps, m.total_steps, m.record, m.created_at, m.started_at, m.finished_at,
        m.record_pruned_at, coalesce((select t.sealed from tournament t where t.tournament_id = m.tournament_id), 0) as sealed";

/// Bot `b` has the same owner as bot `$1`: the same entrant, or (for bots of no
/// entrant) the same owner token.
pub(super) const SAME_OWNER: &str = "b.bot_id in (
    select o.bot_id from bot o, bot x where x.bot_id = $1 and (
        (x.entrant_id is not null and o.entrant_id = x.entrant_id)
        or (x.entrant_id is null and o.entrant_id is null
            and o.owner_token_hash = x.owner_token_hash)))";

impl Storage {
    /// The select of a match with its names, for a where clause on `match m` to follow.
    /// The match table leads: on SQLite, `cross join` keeps the planner from starting
    /// elsewhere, so that a filtered list walks the filter's index.
    fn match_select(&self) -> String {
        let join = match self.backend() {
            Backend::Sqlite => "cross join",
            Backend::Postgres => "join",
        };
        format!(
            "select {MATCH_COLUMNS}
             from match m {join} bot_version v on v.bot_version_id = m.bot_version_id
             {join} bot b on b.bot_id = v.bot_id
             {join} maze z on z.maze_id = m.maze_id"
        )
    }
}

/// The summary (JSON, for the row) of a match the server ended without playing it.
pub(super) fn failure_record(status: MatchStatus, reason: &str) -> Result<String> {
    serde_json::to_string(&MatchSummary::unplayed(status, reason)).map_err(|e| {
        StorageError::Encode {
            what: "a match summary",
            message: e.to_string(),
        }
    })
}

#[cfg(test)]
mod tests;
