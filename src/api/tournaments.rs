//! Tournaments: every listed bot's latest version on every listed maze, `repeats` times.

use std::collections::BTreeSet;

use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppJson, AppPath, AppQuery, ErrorBody};
use super::matches::check_capacity;
use crate::storage::leaderboard::{Scope, Standing};

/// Most repeats of each (bot, maze) pair.
pub const MAX_REPEATS: i64 = 100;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_tournament, list_tournaments))
        .routes(routes!(get_tournament))
}

/// A tournament to run.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TournamentRequest {
    /// A name.
    pub name: String,
    /// The bots (their latest versions play).
    pub bot_ids: Vec<i64>,
    /// The mazes.
    pub maze_ids: Vec<i64>,
    /// How many times each bot plays each maze (seeds 0, 1, ...). Default 1.
    #[serde(default = "one")]
    pub repeats: i64,
}

fn one() -> i64 {
    1
}

/// A tournament's progress and standings.
#[derive(Debug, Serialize, ToSchema)]
pub struct TournamentView {
    /// Id.
    pub tournament_id: i64,
    /// Name.
    pub name: String,
    /// Repeats.
    pub repeats: i64,
    /// Matches played.
    pub done: i64,
    /// Matches in all.
    pub total: i64,
    /// Standings so far, best first (empty while sealed).
    pub standings: Vec<Standing>,
    /// True while the standings are withheld: the tournament has hidden mazes and is
    /// not complete (anyone but the admin sees them once every match is played).
    pub standings_sealed: bool,
}

/// Start a tournament (admin token).
#[utoipa::path(post, path = "/api/tournaments", tag = "tournaments",
    request_body = TournamentRequest,
    security(("bearer" = [])),
    responses(
        (status = 202, body = TournamentView),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody, description = "a bot is paused"),
        (status = 422, body = ErrorBody), (status = 429, body = ErrorBody),
    ))]
async fn create_tournament(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(body): AppJson<TournamentRequest>,
) -> ApiResult<(StatusCode, axum::Json<TournamentView>)> {
    caller.require_admin()?;
    if body.name.trim().is_empty() {
        return Err(ApiError::Unprocessable("a tournament needs a name".into()));
    }
    if !(1..=MAX_REPEATS).contains(&body.repeats) {
        return Err(ApiError::Unprocessable(format!(
            "repeats must be 1 to {MAX_REPEATS}"
        )));
    }
    let bots: BTreeSet<i64> = body.bot_ids.iter().copied().collect();
    let mazes: BTreeSet<i64> = body.maze_ids.iter().copied().collect();
    if bots.is_empty() || mazes.is_empty() {
        return Err(ApiError::Unprocessable(
            "a tournament needs at least one bot and one maze".into(),
        ));
    }
    if bots.len() != body.bot_ids.len() || mazes.len() != body.maze_ids.len() {
        return Err(ApiError::Unprocessable(
            "bot_ids and maze_ids must not repeat an id".into(),
        ));
    }
    let mut versions = Vec::new();
    for &id in &body.bot_ids {
        let bot = state
            .storage
            .get_bot(id)
            .await?
            .ok_or_else(|| ApiError::NotFound(format!("no bot {id}")))?;
        if let Some(reason) = &bot.paused_reason {
            return Err(super::matches::paused_error(id, reason));
        }
        if crate::storage::bots::build_status::never_plays(&bot.build_status) {
            return Err(ApiError::Conflict(format!(
                "the latest version of bot {id} is {}, so it cannot play",
                bot.build_status
            )));
        }
        versions.push(bot.bot_version_id);
    }
    for &id in &body.maze_ids {
        super::mazes::find_maze(&state, id).await?;
    }
    let total = (versions.len() * body.maze_ids.len()) as i64 * body.repeats;
    check_capacity(&state, total).await?;
    let t = state
        .storage
        .create_tournament(&body.name, &versions, &body.maze_ids, body.repeats)
        .await?;
    state.wake.notify_waiters();
    Ok((
        StatusCode::ACCEPTED,
        axum::Json(TournamentView {
            tournament_id: t.tournament_id,
            name: t.name,
            repeats: t.repeats,
            done: t.done,
            total: t.total,
            standings: Vec::new(),
            standings_sealed: false,
        }),
    ))
}

/// A tournament's progress (done/total) and standings (for non-admins without the
/// score/optimum ratio when a hidden maze is counted).
#[utoipa::path(get, path = "/api/tournaments/{id}", tag = "tournaments",
    params(("id" = i64, Path, description = "tournament id")),
    responses((status = 200, body = TournamentView), (status = 404, body = ErrorBody)))]
async fn get_tournament(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<TournamentView>> {
    let t = caller.tournament(&state, id).await?;
    let organises = caller
        .organises_competition_of(&state, t.competition_id)
        .await?;
    let (standings, standings_sealed) = super::leaderboard::tournament_for_caller(
        state
            .ranker
            .leaderboard(&state.storage, Scope::Tournament(id))
            .await?,
        &caller,
        t.done >= t.total,
        t.competition_id.is_some(),
        organises,
    );
    Ok(axum::Json(TournamentView {
        tournament_id: t.tournament_id,
        name: t.name,
        repeats: t.repeats,
        done: t.done,
        total: t.total,
        standings,
        standings_sealed,
    }))
}

/// The page of `GET /api/tournaments`.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct TournamentListQuery {
    /// Rows to skip (default 0).
    pub offset: Option<i64>,
    /// Rows per page, 1 to 200 (default 50).
    pub limit: Option<i64>,
}

/// A tournament in a list.
#[derive(Debug, Serialize, ToSchema)]
pub struct TournamentLine {
    /// Id.
    pub tournament_id: i64,
    /// Name.
    pub name: String,
    /// Repeats of each bot x maze pair.
    pub repeats: i64,
    /// Matches played.
    pub done: i64,
    /// Matches in all.
    pub total: i64,
    /// Created at (unix ms).
    pub created_at: i64,
}

/// One page of tournaments.
#[derive(Debug, Serialize, ToSchema)]
pub struct TournamentPage {
    /// Newest first.
    pub items: Vec<TournamentLine>,
    /// How many tournaments there are.
    pub total: i64,
    /// Rows skipped.
    pub offset: i64,
    /// Rows per page.
    pub limit: i64,
}

/// Tournaments with their progress, newest first.
#[utoipa::path(get, path = "/api/tournaments", tag = "tournaments",
    params(TournamentListQuery),
    responses((status = 200, body = TournamentPage), (status = 400, body = ErrorBody)))]
async fn list_tournaments(
    State(state): State<AppState>,
    caller: Caller,
    AppQuery(q): AppQuery<TournamentListQuery>,
) -> ApiResult<axum::Json<TournamentPage>> {
    let page = super::lists::page(q.offset, q.limit)?;
    let (rows, total) = state
        .storage
        .list_tournaments(page, !caller.is_admin())
        .await?;
    Ok(axum::Json(TournamentPage {
        items: rows
            .into_iter()
            .map(|t| TournamentLine {
                tournament_id: t.tournament_id,
                name: t.name,
                repeats: t.repeats,
                done: t.done,
                total: t.total,
                created_at: t.created_at,
            })
            .collect(),
        total,
        offset: page.offset,
        limit: page.limit,
    }))
}
