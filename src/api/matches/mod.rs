//! Matches: queue one (owner or admin), see its result, its replay, and its log.
//!
//! A match on a hidden (ranking) maze shows non-admins its status, score and step
//! counts only: no maze hash or side, no warnings or timings (bot-chosen values), no
//! replay, and of its log only the status and the failure's step. Its bot could
//! otherwise print, time or act out the layout it sensed.

mod replays;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppJson, AppPath, AppQuery, ErrorBody};
use super::lists::{MatchListQuery, MatchPage, MatchView, next_before};
use super::mazes::{find_maze, hidden_error};
use crate::storage::bots::build_status;
use crate::storage::matches::MatchRow;
use crate::storage::matches::queue::{QueueLimits, QueueRefusal};
use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_match, list_matches))
        .routes(routes!(get_match))
        .merge(replays::router())
}

/// Seconds a client is told to wait when the queue is full.
pub const RETRY_AFTER_SECS: u64 = 30;

/// A match to queue.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MatchRequest {
    /// The bot (its latest version plays).
    pub bot_id: i64,
    /// The maze (public, unless the admin asks).
    pub maze_id: i64,
    /// Seed sent to the bot; random if omitted.
    #[serde(default)]
    pub seed: Option<u32>,
}

/// The answer to a queued match.
#[derive(Debug, Serialize, ToSchema)]
pub struct MatchQueued {
    /// The new match.
    pub match_id: i64,
    /// Always `queued`.
    pub status: &'static str,
    /// The version that will play.
    pub bot_version: i64,
    /// The seed.
    pub seed: u32,
}

/// Queue a match of a bot's latest version on a maze (owner token or admin).
#[utoipa::path(post, path = "/api/matches", tag = "matches",
    request_body = MatchRequest,
    security(("bearer" = [])),
    responses(
        (status = 202, body = MatchQueued),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody, description = "the bot is paused"),
        (status = 429, body = ErrorBody, description = "the queue, or the owner's share of it, is full; see Retry-After"),
    ))]
async fn create_match(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(body): AppJson<MatchRequest>,
) -> ApiResult<(StatusCode, axum::Json<MatchQueued>)> {
    let queued = queue_match(&state, &caller, body).await?;
    Ok((StatusCode::ACCEPTED, axum::Json(queued)))
}

/// Queues a match of a bot's latest version for `caller` (its owner or the admin): the
/// API's and the "practice" button's one way, with every check and quota.
///
/// # Errors
/// No such bot or maze; not its owner; a paused or unplayable bot; a hidden maze; the
/// queue, the owner's share of it, the practice quota or the stored bytes' cap.
pub(crate) async fn queue_match(
    state: &AppState,
    caller: &Caller,
    body: MatchRequest,
) -> ApiResult<MatchQueued> {
    let bot = state
        .storage
        .get_bot(body.bot_id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no bot {}", body.bot_id)))?;
    caller.require_owner(state, bot.bot_id).await?;
    if let Some(reason) = &bot.paused_reason {
        return Err(paused_error(bot.bot_id, reason));
    }
    if build_status::never_plays(&bot.build_status) {
        let what = if bot.build_status == build_status::INVALID {
            "failed its validation match"
        } else {
            "failed to build"
        };
        return Err(ApiError::Conflict(format!(
            "version {} of bot {} {what}, so it cannot play; its owner sees why at \
             GET /api/bots/{}/versions/{}/build-log",
            bot.version, bot.bot_id, bot.bot_id, bot.version
        )));
    }
    let maze = find_maze(state, body.maze_id).await?;
    if maze.hidden && !caller.is_admin() {
        return Err(hidden_error(maze.maze_id, caller));
    }
    check_capacity(state, 1).await?;
    let now = crate::storage::now_ms();
    let practice = match crate::registry::competitions::check_practice(
        &state.storage,
        bot.bot_id,
        maze.maze_id,
        now,
    )
    .await?
    {
        Ok(quotas) => quotas,
        Err((message, quota)) => {
            return Err(ApiError::TooManyRequests {
                message,
                retry_after_secs: quota.retry_after_secs(now),
            });
        }
    };
    if !caller.is_admin() {
        if let Some(cap) = state.settings.max_stored_bytes_per_owner {
            let stored = state.storage.stored_bytes_of_owner_of(bot.bot_id).await?;
            if stored >= cap {
                return Err(ApiError::Conflict(format!(
                    "the owner of bot {} has {:.2} MiB of stored matches, its cap ({:.2} MiB): \
                     new matches are refused until old practice matches' traces are \
                     removed (`mazearena prune`, or the server's \
                     --prune-practice-after-days)",
                    bot.bot_id,
                    stored as f64 / 1_048_576.0,
                    cap as f64 / 1_048_576.0
                )));
            }
        }
        let waiting = state.storage.queued_for_owner_of(bot.bot_id).await?;
        if waiting >= state.settings.max_queued_per_owner {
            return Err(owner_queue_full(bot.bot_id, waiting, state));
        }
    }
    let seed = match body.seed {
        Some(s) => s,
        None => random_seed()?,
    };
    // The quotas and the owner's limit counted again where the match is queued:
    // requests sent at once all pass the checks above before any is queued.
    // A competition's practice match plays under that competition's limits, which its
    // page publishes (with the match's wall-clock ceiling).
    let match_limits =
        crate::registry::competitions::practice_limits(&state.storage, bot.bot_id, maze.maze_id)
            .await?
            .map(|l| serde_json::to_string(&l))
            .transpose()
            .map_err(|e| ApiError::Internal(format!("limits: {e}")))?;
    let limits = QueueLimits {
        bot_id: bot.bot_id,
        most_queued: (!caller.is_admin()).then_some(state.settings.max_queued_per_owner),
        practice,
        match_limits,
    };
    let match_id = match state
        .storage
        .queue_match_within(bot.bot_version_id, maze.maze_id, i64::from(seed), &limits)
        .await?
    {
        Ok(id) => id,
        Err(QueueRefusal::Queued(waiting)) => {
            return Err(owner_queue_full(bot.bot_id, waiting, state));
        }
        Err(QueueRefusal::Practice(q)) => {
            let (message, quota) =
                crate::registry::competitions::practice_refusal(&state.storage, q, now).await?;
            return Err(ApiError::TooManyRequests {
                message,
                retry_after_secs: quota.retry_after_secs(now),
            });
        }
    };
    state.wake.notify_waiters();
    Ok(MatchQueued {
        match_id,
        status: "queued",
        bot_version: bot.version,
        seed,
    })
}

/// The refusal of a match whose bot's owner has `waiting` matches queued, its limit.
fn owner_queue_full(bot_id: i64, waiting: i64, state: &AppState) -> ApiError {
    ApiError::TooManyRequests {
        message: format!(
            "the owner of bot {bot_id} has {waiting} matches waiting, its limit ({}); \
             queue more once some have been played",
            state.settings.max_queued_per_owner
        ),
        retry_after_secs: RETRY_AFTER_SECS,
    }
}

/// A match: status, score, steps, warnings, limits, seed, maze hash, engine version,
/// timings (a hidden maze's match: no warnings, timings, maze hash or side, unless the
/// caller is the admin).
#[utoipa::path(get, path = "/api/matches/{id}", tag = "matches",
    params(("id" = i64, Path, description = "match id")),
    responses((status = 200, body = MatchView), (status = 404, body = ErrorBody)))]
async fn get_match(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<MatchView>> {
    let row = find_match(&state, &caller, id).await?;
    let reveal = !row.maze_hidden || caller.is_admin();
    let superseded = superseded(&state, id, reveal).await?;
    Ok(axum::Json(MatchView {
        superseded,
        ..match_view(row, reveal)
    }))
}

/// The earlier outcomes of match `id` that rejudges superseded, under the rules of the
/// match's own row (`reveal`: not a hidden maze's, or the admin): on a hidden maze their
/// status only, no score, steps or end time. The API's and the match page's one way.
///
/// # Errors
/// The database.
pub(super) async fn superseded(
    state: &AppState,
    id: i64,
    reveal: bool,
) -> ApiResult<Vec<crate::storage::rejudges::SupersededRow>> {
    let rows = state.storage.superseded(id).await?;
    Ok(if reveal {
        rows
    } else {
        rows.into_iter().map(|s| s.redacted()).collect()
    })
}

/// A match as the caller may see it (`reveal`: not a hidden maze's, or the admin).
pub(super) fn match_view(row: MatchRow, reveal: bool) -> MatchView {
    let row = if reveal { row } else { row.redacted() };
    let summary = row.summary();
    let json = |v: Option<serde_json::Result<Value>>| v.and_then(Result::ok).unwrap_or(Value::Null);
    MatchView {
        match_id: row.match_id,
        bot_id: row.bot_id,
        bot_version: row.version,
        maze_id: row.maze_id,
        tournament_id: row.tournament_id,
        seed: reveal.then_some(row.seed),
        score: row.score,
        run0_steps: row.run0_steps,
        run1_steps: row.run1_steps,
        total_steps: row.total_steps,
        attempts: row.attempts,
        created_at: row.created_at,
        started_at: row.started_at,
        finished_at: row.finished_at,
        maze_hidden: row.maze_hidden,
        warnings: json(reveal.then(|| serde_json::to_value(&summary.warnings))),
        limits: json(summary.limits.as_ref().map(serde_json::to_value)),
        maze_hash: reveal.then_some(row.maze_hash),
        maze_dim: reveal.then_some(row.maze_dim),
        engine_version: summary.engine_version,
        timings: json(
            summary
                .timings
                .filter(|_| reveal)
                .as_ref()
                .map(serde_json::to_value),
        ),
        status: row.status.to_string(),
        superseded: Vec::new(),
    }
}

/// Matches, newest first, filtered by bot, tournament, maze and status (a hidden
/// maze's matches show what `GET /api/matches/{id}` shows of them).
#[utoipa::path(get, path = "/api/matches", tag = "matches",
    params(MatchListQuery),
    responses((status = 200, body = MatchPage), (status = 400, body = ErrorBody)))]
async fn list_matches(
    State(state): State<AppState>,
    caller: Caller,
    AppQuery(q): AppQuery<MatchListQuery>,
) -> ApiResult<axum::Json<MatchPage>> {
    let (mut filter, page) = q.parse()?;
    // Sealed matches (a final run before the results) are listed to the admin only; a
    // competition's organiser reads its boards.
    filter.hide_sealed = !caller.is_admin();
    let (rows, count) = state.storage.list_matches(&filter, page).await?;
    let next_before = next_before(&rows, page);
    let admin = caller.is_admin();
    Ok(axum::Json(MatchPage {
        items: rows
            .into_iter()
            .map(|r| {
                let reveal = !r.maze_hidden || admin;
                match_view(r, reveal)
            })
            .collect(),
        total: count.total,
        total_exact: count.exact,
        next_before,
        offset: page.offset,
        limit: page.limit,
    }))
}

/// The 409 for a paused bot's new matches.
pub(super) fn paused_error(bot_id: i64, reason: &str) -> ApiError {
    ApiError::Conflict(format!(
        "bot {bot_id} is paused: {reason}; the admin can resume it (POST /api/bots/{bot_id}/resume), \
         or upload a new version"
    ))
}

/// Match `id` if `caller` may see it: a sealed tournament's match (a competition's
/// final run before the results) is not found for anyone but the admin and that
/// competition's organiser.
async fn find_match(state: &AppState, caller: &Caller, id: i64) -> ApiResult<MatchRow> {
    let not_found = || ApiError::NotFound(format!("no match {id}"));
    let m = state.storage.get_match(id).await?.ok_or_else(not_found)?;
    if m.sealed {
        let competition = match m.tournament_id {
            Some(t) => state
                .storage
                .get_tournament(t)
                .await?
                .and_then(|t| t.competition_id),
            None => None,
        };
        if !caller.organises_competition_of(state, competition).await? {
            return Err(not_found());
        }
    }
    Ok(m)
}

/// Refuses new matches beyond the queue's capacity (429 with Retry-After).
pub(super) async fn check_capacity(state: &AppState, adding: i64) -> ApiResult<()> {
    let queued = state.storage.queued_count().await?;
    if queued + adding > state.settings.max_queue {
        return Err(ApiError::TooManyRequests {
            message: format!(
                "the match queue is full (capacity {}); try again later",
                state.settings.max_queue
            ),
            retry_after_secs: RETRY_AFTER_SECS,
        });
    }
    Ok(())
}

fn random_seed() -> ApiResult<u32> {
    let mut b = [0u8; 4];
    getrandom::fill(&mut b).map_err(|e| ApiError::Internal(format!("no randomness: {e}")))?;
    Ok(u32::from_le_bytes(b))
}
