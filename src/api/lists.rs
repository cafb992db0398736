//! What the list routes share: the match filters, pages (`offset`, `limit`) and their
//! checks, so a bad query string is a 400 that names the parameter.

use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};

use super::error::{ApiError, ApiResult};
use super::matches::MatchView;
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
