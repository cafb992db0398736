//! A match's replay (its record as JSON, and as one HTML file that plays from disk) and
//! its log, each with the same checks: a hidden maze's, a sealed tournament's and the
//! owner's stderr stay with whom they belong to.

use super::find_match;
use crate::api::AppState;
use crate::api::auth::Caller;
use crate::api::error::{ApiError, ApiResult, AppPath, ErrorBody};
use crate::api::mazes::find_maze;
use crate::runner::MatchRecord;
use crate::storage::matches::MatchRow;
use crate::storage::mazes::MazeRow;
use crate::web::viewer::ViewerData;
use axum::extract::State;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use serde_json::Value;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// A match's per-step trace, with the maze to replay it on.
#[derive(Debug, Serialize, ToSchema)]
pub struct ReplayView {
    /// Id.
    pub match_id: i64,
    /// Final status.
    pub status: String,
    /// The maze.
    pub maze_id: i64,
    /// Side.
    pub maze_dim: i64,
    /// The maze's canonical numeric text (omitted for a hidden maze unless the caller is
    /// the admin: a hidden maze's layout is never served to anyone else).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maze_layout: Option<String>,
    /// Every step: run, step, sensors, action, event, position, heading, warnings,
    /// answer_us, debug, and stderr (the bot's owner and the admin only).
    #[schema(value_type = Vec<Object>)]
    pub trace: Value,
    /// False when the steps' stderr lines were left out: they are the bot owner's (send
    /// the owner token to get them).
    pub stderr_shown: bool,
}

/// A match's failure details and the bot's stderr tail (owner or admin). For a hidden
/// maze's match the owner gets the status and the failure's step only (`redacted`).
#[derive(Debug, Serialize, ToSchema)]
pub struct LogView {
    /// Id.
    pub match_id: i64,
    /// Final status (for a failure, its kind).
    pub status: String,
    /// The step the failure happened at, when known.
    pub step: Option<u64>,
    /// True when `error` and `stderr_tail` are left out: a hidden maze's match, and
    /// the caller is not the admin (the bot could print the layout it sensed).
    pub redacted: bool,
    /// Reason, offending line, exit code, signal; null if the bot did nothing wrong.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub error: Option<Value>,
    /// The last 64 KiB of the bot's stderr.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stderr_tail: Option<String>,
}

/// The per-step trace and the maze (a hidden maze's match: the admin only); the bot's
/// stderr lines only for its owner and the admin.
#[utoipa::path(get, path = "/api/matches/{id}/replay", tag = "matches",
    params(("id" = i64, Path, description = "match id")),
    responses(
        (status = 200, body = ReplayView),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody, description = "not played yet"),
    ))]
async fn get_match_replay(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<ReplayView>> {
    let (row, record, maze, stderr_shown) = replay_parts(&state, &caller, id).await?;
    Ok(axum::Json(ReplayView {
        match_id: id,
        status: row.status.to_string(),
        maze_id: maze.maze_id,
        maze_dim: maze.dim,
        maze_layout: (!maze.hidden || caller.is_admin()).then_some(maze.layout),
        trace: serde_json::to_value(&record.trace).unwrap_or(Value::Array(vec![])),
        stderr_shown,
    }))
}

/// A played match's record as `caller` may see it, with its maze, and whether the
/// bot's stderr is in it: a hidden maze's replay is the admin's only (it would show the
/// maze); a removed trace or a match not played yet is a 409; the stderr is left out
/// for all but the bot's owner and the admin.
async fn replay_parts(
    state: &AppState,
    caller: &Caller,
    id: i64,
) -> ApiResult<(MatchRow, MatchRecord, MazeRow, bool)> {
    let row = find_match(state, caller, id).await?;
    if row.maze_hidden && !caller.is_admin() {
        let msg = format!(
            "match {id} was played on a hidden (ranking) maze: its replay would show the maze, \
             so only the admin may see it; GET /api/matches/{id} has its status"
        );
        return Err(match caller {
            Caller::Anonymous => ApiError::Unauthorized(msg),
            _ => ApiError::Forbidden(msg),
        });
    }
    let record = state.storage.get_record(id).await?;
    if row.trace_removed() {
        return Err(ApiError::Conflict(format!(
            "the trace of match {id} was removed to save space (an old practice match); \
             GET /api/matches/{id} still has its result"
        )));
    }
    let record = record
        .filter(|r| !r.trace.is_empty() || row.total_steps.is_some())
        .ok_or_else(|| {
            ApiError::Conflict(format!(
                "match {id} has not been played yet ({})",
                row.status
            ))
        })?;
    // The bot's stderr is its owner's: left out for everyone else, public maze or not.
    let stderr_shown = caller.owns(state, row.bot_id).await?;
    let record = if stderr_shown {
        record
    } else {
        record.without_stderr()
    };
    let maze = find_maze(state, row.maze_id).await?;
    Ok((row, record, maze, stderr_shown))
}

/// The replay as one HTML file that opens from disk (the viewer with the match inside),
/// sent as a download; the same checks as the replay.
#[utoipa::path(get, path = "/api/matches/{id}/replay.html", tag = "matches",
    params(("id" = i64, Path, description = "match id")),
    responses(
        (status = 200, content_type = "text/html", body = String),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody, description = "not played yet"),
    ))]
async fn get_match_replay_html(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Response> {
    let (row, record, maze, _) = replay_parts(&state, &caller, id).await?;
    let shown = crate::engine::mazefile::parse(maze.layout.as_bytes()).ok();
    let title = format!(
        "{} v{} on {} (seed {})",
        row.bot_name, row.version, row.maze_name, row.seed
    );
    let data = ViewerData::new(title, &record, shown.as_ref(), format!("match-{id}.json"));
    let mut response = crate::web::viewer::standalone(&data).into_response();
    let headers = response.headers_mut();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("text/html; charset=utf-8"),
    );
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"match-{id}.html\"")) {
        headers.insert(header::CONTENT_DISPOSITION, v);
    }
    for (name, value) in crate::web::policy::headers() {
        if let Ok(v) = HeaderValue::from_str(&value) {
            headers.insert(name, v);
        }
    }
    Ok(response)
}

/// The bot's stderr tail and failure details (the bot's owner or the admin; a hidden
/// maze's match: the owner gets the status and the failure's step only).
#[utoipa::path(get, path = "/api/matches/{id}/log", tag = "matches",
    params(("id" = i64, Path, description = "match id")),
    security(("bearer" = [])),
    responses(
        (status = 200, body = LogView),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
    ))]
async fn get_match_log(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<LogView>> {
    let row = find_match(&state, &caller, id).await?;
    caller.require_owner(&state, row.bot_id).await?;
    let error = row.summary().error;
    let redacted = row.maze_hidden && !caller.is_admin();
    // The stderr tail is kept with the whole record, not in the row's summary.
    let stderr_tail = if redacted {
        String::new()
    } else {
        state
            .storage
            .get_record(id)
            .await?
            .map(|r| r.stderr_tail)
            .unwrap_or_default()
    };
    Ok(axum::Json(LogView {
        match_id: id,
        status: row.status.to_string(),
        step: error
            .as_ref()
            .and_then(|e| e.step)
            .map(u64::from)
            .filter(|_| !redacted),
        redacted,
        stderr_tail: (!redacted).then_some(stderr_tail),
        error: (!redacted).then(|| serde_json::to_value(&error).unwrap_or(Value::Null)),
    }))
}

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(get_match_replay))
        .routes(routes!(get_match_replay_html))
        .routes(routes!(get_match_log))
}
