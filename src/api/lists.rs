//! What the list routes share: the match filters, pages (`offset`, `limit`) and their
//! checks, so a bad query string is a 400 that names the parameter.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use utoipa::{IntoParams, ToSchema};

use super::error::{ApiError, ApiResult};
use crate::runner::MatchState;
use crate::storage::matches::MatchRow;
use crate::storage::matches::lists::{MatchFilter, Page};

/// Filters and page of `GET /api/matches`.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct MatchListQuery {
    /// Only this bot's matches (every version).
    pub bot_id: Option<i64>,
    /// Only this tournament's.
    pub tournament_id: Option<i64>,
    /// Only this maze's.
    pub maze_id: Option<i64>,
    /// Only this status: queued, running, finished, step_limit, timeout, crashed,
    /// protocol_error, memory_limit, process_limit, scratch_limit, aborted.
    pub status: Option<String>,
    /// Only matches older than this match id: the next page after one that ended with
    /// it (pass the page's `next_before`). It costs the same however deep the page,
    /// unlike `offset`.
    pub before: Option<i64>,
    /// Rows to skip (default 0).
    pub offset: Option<i64>,
    /// Rows per page, 1 to 200 (default 50).
    pub limit: Option<i64>,
}

/// One page of a list.
#[derive(Debug, Serialize, ToSchema)]
pub struct MatchPage {
    /// The matches, newest first.
    pub items: Vec<MatchView>,
    /// How many matches pass the filters (without `before`), counted up to 10,000.
    pub total: i64,
    /// False when more than `total` pass: counting stops at 10,000.
    pub total_exact: bool,
    /// The `before` of the next page: the last match's id when the page is full.
    pub next_before: Option<i64>,
    /// Rows skipped.
    pub offset: i64,
    /// Rows per page.
    pub limit: i64,
}

impl MatchListQuery {
    /// The storage filter and page, or a 400 naming the bad parameter.
    pub fn parse(&self) -> ApiResult<(MatchFilter, Page)> {
        let status = match &self.status {
            Some(s) => Some(s.parse::<MatchState>().map_err(ApiError::BadRequest)?),
            None => None,
        };
        Ok((
            MatchFilter {
                bot_id: self.bot_id,
                tournament_id: self.tournament_id,
                maze_id: self.maze_id,
                status,
                before: self.before,
                hide_sealed: true,
            },
            page(self.offset, self.limit)?,
        ))
    }
}

/// The page of a list from `offset` and `limit` (default 50, at most 200).
pub fn page(offset: Option<i64>, limit: Option<i64>) -> ApiResult<Page> {
    let offset = offset.unwrap_or(0);
    let limit = limit.unwrap_or(DEFAULT_PAGE);
    if offset < 0 {
        return Err(ApiError::BadRequest("`offset` must be 0 or more".into()));
    }
    if !(1..=MAX_PAGE).contains(&limit) {
        return Err(ApiError::BadRequest(format!(
            "`limit` must be 1 to {MAX_PAGE}"
        )));
    }
    Ok(Page { offset, limit })
}

/// The `before` of the page after `rows` (a page of `page`): its last match's id, when
/// the page is full.
pub fn next_before(rows: &[MatchRow], page: Page) -> Option<i64> {
    rows.last()
        .filter(|_| rows.len() as i64 == page.limit)
        .map(|r| r.match_id)
}

/// Rows per page of a list, unless asked.
pub const DEFAULT_PAGE: i64 = 50;
/// The most rows per page.
pub const MAX_PAGE: i64 = 200;

/// A match as anyone may see it.
#[derive(Debug, Serialize, ToSchema)]
pub struct MatchView {
    /// Id.
    pub match_id: i64,
    /// The bot.
    pub bot_id: i64,
    /// The bot version that played.
    pub bot_version: i64,
    /// The maze.
    pub maze_id: i64,
    /// The tournament, if any.
    pub tournament_id: Option<i64>,
    /// The seed (null on a hidden maze's match, unless the caller is the admin: a
    /// competition's seeds are secret until its results).
    pub seed: Option<i64>,
    /// queued, running, finished, step_limit, timeout, crashed, protocol_error,
    /// memory_limit, process_limit, scratch_limit, aborted.
    pub status: String,
    /// Score when finished.
    pub score: Option<f64>,
    /// Run-0 steps (once a reset was accepted).
    pub run0_steps: Option<i64>,
    /// Run-1 steps (when finished).
    pub run1_steps: Option<i64>,
    /// The step counter when the match ended.
    pub total_steps: Option<i64>,
    /// How many times a worker started it.
    pub attempts: i64,
    /// Queued at (unix ms).
    pub created_at: i64,
    /// Last started at (unix ms).
    pub started_at: Option<i64>,
    /// Finished at (unix ms).
    pub finished_at: Option<i64>,
    /// Whether the maze is hidden: then `warnings`, `timings`, `maze_hash` and
    /// `maze_dim` are null unless the caller is the admin.
    pub maze_hidden: bool,
    /// Lenient-rule warnings.
    #[schema(value_type = Vec<Object>)]
    pub warnings: Value,
    /// The limits it was played under.
    #[schema(value_type = Object)]
    pub limits: Value,
    /// SHA-256 of the maze layout.
    pub maze_hash: Option<String>,
    /// The maze's side.
    pub maze_dim: Option<i64>,
    /// The referee's version.
    pub engine_version: Option<String>,
    /// Wall time, bot CPU time, answer times.
    #[schema(value_type = Object)]
    pub timings: Value,
    /// Earlier outcomes of this match that rejudges superseded (they no longer count),
    /// oldest first; only in `GET /api/matches/{id}`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub superseded: Vec<crate::storage::rejudges::SupersededRow>,
}
