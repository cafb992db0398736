//! The boards and the final results, as JSON and CSV.

use super::competition::find;
use crate::api::AppState;
use crate::api::auth::Caller;
use crate::api::error::{ApiError, ApiResult, AppPath, AppQuery, ErrorBody};
use crate::competition::Timestamp;
use crate::registry::competitions::{self as ops, Board, BoardKind, BoardLine};
use crate::storage::competitions::{CompetitionRow, ResultRow};
use crate::storage::leaderboard::Scope;
use crate::storage::now_ms;
use axum::extract::State;
use axum::http::header;
use axum::response::IntoResponse;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// Which board.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct BoardQuery {
    /// `public` (default) or `private`.
    pub board: Option<BoardKind>,
}

/// A leaderboard of the competition: `public` (the public ranking set; frozen before
/// the close if the competition says so) or `private` (the final run's, played after
/// the close: sealed until the results, for its organisers until the final run has
/// played; `final_run` says how far it is). Each entrant's latest version that has played all its
/// matches there.
#[utoipa::path(get, path = "/api/competitions/{name}/leaderboard", tag = "competitions",
    params(("name" = String, Path, description = "competition name"), BoardQuery),
    responses((status = 200, body = Board), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub(super) async fn leaderboard(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppQuery(q): AppQuery<BoardQuery>,
) -> ApiResult<axum::Json<Board>> {
    let c = find(&state, &name).await?;
    let kind = q.board.unwrap_or(BoardKind::Public);
    if c.kind == "default" {
        return Ok(axum::Json(default_board(&state, &caller, kind).await?));
    }
    Ok(axum::Json(
        ops::board(&state.storage, &c, kind, caller.organises(&c), now_ms()).await?,
    ))
}

/// The default competition's board: the server's ranking (no private set).
pub(crate) async fn default_board(
    state: &AppState,
    caller: &Caller,
    kind: BoardKind,
) -> ApiResult<Board> {
    if kind == BoardKind::Private {
        return Err(ApiError::NotFound(
            "the default competition has no private set".into(),
        ));
    }
    let rows = state.storage.leaderboard(Scope::Ranking).await?;
    let rows =
        crate::api::leaderboard::settled_for_caller(state, Scope::Ranking, rows, caller).await?;
    Ok(Board {
        board: kind,
        sealed: false,
        frozen_at: None,
        final_run: None,
        final_run_playing: false,
        standings: rows.into_iter().map(BoardLine::from_standing).collect(),
    })
}

/// The final results.
#[derive(Debug, Serialize, ToSchema)]
pub struct ResultsView {
    /// The competition.
    pub competition: String,
    /// When they were written.
    pub finalized_at: Timestamp,
    /// The referee version that wrote them.
    pub referee: String,
    /// Whether every row equals a recount from the match records now.
    pub recount_equal: bool,
    /// One row per entrant, best first.
    pub results: Vec<ResultRow>,
}

async fn final_results(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<(CompetitionRow, Vec<ResultRow>)> {
    let c = find(state, name).await?;
    let held = c.state.as_deref() == Some("held");
    if held && !caller.organises(&c) {
        return Err(ApiError::Conflict(format!(
            "the results of competition {} are held by its organisers until the reveal",
            c.name
        )));
    }
    if c.state.as_deref() != Some("final") && !held {
        let progress = ops::final_progress(&state.storage, &c).await?;
        return Err(ApiError::Conflict(match (c.closes_at, progress) {
            (_, Some(_)) => format!(
                "the final run of competition {} is playing; the results come when it has played",
                c.name
            ),
            (Some(t), None) => format!(
                "the results of competition {} come after its close ({}) and its final run",
                c.name,
                Timestamp(t).words()
            ),
            (None, None) => "the default competition has no final results".into(),
        }));
    }
    let rows = ops::results(&state.storage, &c).await?;
    Ok((c, rows))
}

/// The final results (after the close and the final run): one row per entrant with its
/// manifest (bundle hash, referee version, maze hashes, seeds, limits, recount).
#[utoipa::path(get, path = "/api/competitions/{name}/results", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, body = ResultsView), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub(super) async fn results(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<ResultsView>> {
    let (c, rows) = final_results(&state, &caller, &name).await?;
    let differ = ops::recount_differences(&state.storage, &c).await?;
    Ok(axum::Json(ResultsView {
        competition: c.name.clone(),
        finalized_at: Timestamp(c.finalized_at.unwrap_or(0)),
        referee: crate::runner::ENGINE_VERSION.to_string(),
        recount_equal: differ.is_empty(),
        results: rows,
    }))
}

/// The final results as CSV (one row per entrant).
#[utoipa::path(get, path = "/api/competitions/{name}/results.csv", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, content_type = "text/csv", body = String), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody)))]
pub(super) async fn results_csv(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<impl IntoResponse> {
    let (_, rows) = final_results(&state, &caller, &name).await?;
    Ok((
        [(header::CONTENT_TYPE, "text/csv; charset=utf-8")],
        ops::results_csv(&rows),
    ))
}

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(leaderboard))
        .routes(routes!(results))
        .routes(routes!(results_csv))
}
