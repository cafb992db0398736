//! The final night through the API: publishing held results, the reveal, the races
//! (who may see what is [`crate::registry::finale`]'s, once; the pages call the same
//! functions).

use std::sync::Arc;

use axum::extract::State;
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::competitions::{CompetitionView, find, view};
use super::error::{ApiError, ApiResult, AppPath, ErrorBody};
use crate::registry::competitions as ops;
use crate::registry::finale::{self, Race, RaceLink, Reveal};
use crate::storage::competitions::CompetitionRow;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(publish_results))
        .routes(routes!(get_reveal))
        .routes(routes!(list_races))
        .routes(routes!(get_race))
        .routes(routes!(get_tournament_race))
}

/// Publishes competition `name`'s held results for `caller` (its organiser or the
/// admin): the API's and the organiser page's one way.
///
/// # Errors
/// Not its organiser; nothing held.
pub(crate) async fn publish(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<CompetitionRow> {
    let c = find(state, name).await?;
    caller.require_organiser_of(&c)?;
    ops::publish(&state.storage, &c).await?;
    find(state, name).await
}

/// Publish a competition's held results (its organiser or the admin): from now on
/// everyone sees them, the reveal and the races.
#[utoipa::path(post, path = "/api/competitions/{name}/publish", tag = "competitions",
    params(("name" = String, Path, description = "competition name")), security(("bearer" = [])),
    responses((status = 200, body = CompetitionView), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
async fn publish_results(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<CompetitionView>> {
    let c = publish(&state, &caller, &name).await?;
    Ok(axum::Json(view(&state, &c, &caller).await?))
}

/// The reveal of competition `name` as `caller` may see it.
///
/// # Errors
/// No such competition; its results not open to the caller.
pub(crate) async fn reveal(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<Arc<Reveal>> {
    let c = find(state, name).await?;
    Ok(state
        .shows
        .reveal(&state.storage, &c, caller.organises(&c))
        .await?)
}

/// The final results for a reveal, last place to first: each entrant's final rank (ties
/// share one), private mean, public rank and how far it moved, best and worst private
/// match (each as a race of one). Held results are the organisers' only; a private
/// maze the competition keeps hidden is drawn for them only.
#[utoipa::path(get, path = "/api/competitions/{name}/reveal", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, body = Reveal), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
async fn get_reveal(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<Reveal>> {
    Ok(axum::Json(Reveal::clone(
        &*reveal(&state, &caller, &name).await?,
    )))
}

/// The races of a competition a caller may watch.
#[derive(Debug, Serialize, ToSchema)]
pub struct RacesView {
    /// The competition.
    pub competition: String,
    /// One per maze and repeat.
    pub races: Vec<RaceLink>,
}

/// The races of competition `name` as `caller` may see them.
///
/// # Errors
/// No such competition; its results not open to the caller.
pub(crate) async fn races(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<(CompetitionRow, Vec<RaceLink>)> {
    let c = find(state, name).await?;
    let races = finale::races(&state.storage, &c, caller.organises(&c)).await?;
    Ok((c, races))
}

/// The races of a competition after its results: one per private maze of the final
/// run (drawn for the caller) and per public maze, and per repeat.
#[utoipa::path(get, path = "/api/competitions/{name}/races", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, body = RacesView), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
async fn list_races(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<RacesView>> {
    let (c, races) = races(&state, &caller, &name).await?;
    Ok(axum::Json(RacesView {
        competition: c.name,
        races,
    }))
}

/// Competition `name`'s race on its maze `maze`, repeat `repeat`, as `caller` may see it.
///
/// # Errors
/// No such competition, maze or repeat; not open to the caller.
pub(crate) async fn race(
    state: &AppState,
    caller: &Caller,
    name: &str,
    maze: &str,
    repeat: i64,
) -> ApiResult<Arc<Race>> {
    let c = find(state, name).await?;
    Ok(state
        .shows
        .race(&state.storage, &c, caller.organises(&c), maze, repeat)
        .await?)
}

/// Every entrant's match on one maze and seed of a competition (the version that
/// counted for each), with each robot's cells run by run, to be played together.
#[utoipa::path(get, path = "/api/competitions/{name}/race/{maze}/{repeat}", tag = "competitions",
    params(("name" = String, Path, description = "competition name"),
        ("maze" = String, Path, description = "the maze's name in the competition"),
        ("repeat" = i64, Path, description = "the repeat index (one seed), from 0")),
    responses((status = 200, body = Race), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
async fn get_race(
    State(state): State<AppState>,
    caller: Caller,
    AppPath((name, maze, repeat)): AppPath<(String, String, i64)>,
) -> ApiResult<axum::Json<Race>> {
    Ok(axum::Json(Race::clone(
        &*race(&state, &caller, &name, &maze, repeat).await?,
    )))
}

/// Tournament `id`'s race on maze `maze_id`, repeat `repeat`, as `caller` may see it: a
/// sealed tournament's or a hidden maze's for the admin and its competition's organisers
/// only.
///
/// # Errors
/// No such tournament or match; not open to the caller.
pub(crate) async fn tournament_race(
    state: &AppState,
    caller: &Caller,
    id: i64,
    maze_id: i64,
    repeat: i64,
) -> ApiResult<Arc<Race>> {
    let t = caller.tournament(state, id).await?;
    // A competition's tournament races by the competition's rules (its results first,
    // the versions that counted, its hidden mazes its organisers' only).
    if let Some(c) = t.competition_id {
        let c = state
            .storage
            .get_competition_by_id(c)
            .await?
            .ok_or_else(|| ApiError::NotFound(format!("no tournament {id}")))?;
        let name = state
            .storage
            .competition_mazes(c.competition_id)
            .await?
            .into_iter()
            .find(|m| m.maze_id == maze_id)
            .map(|m| m.name)
            .ok_or_else(|| ApiError::NotFound(format!("tournament {id} has no maze {maze_id}")))?;
        return Ok(state
            .shows
            .race(&state.storage, &c, caller.organises(&c), &name, repeat)
            .await?);
    }
    let hidden = state
        .storage
        .get_maze(maze_id)
        .await?
        .is_none_or(|m| m.hidden);
    if hidden
        && !caller
            .organises_competition_of(state, t.competition_id)
            .await?
    {
        return Err(ApiError::Forbidden(format!(
            "maze {maze_id} is hidden: its races are its competition's organisers' only"
        )));
    }
    Ok(state
        .shows
        .tournament_race(&state.storage, id, maze_id, repeat)
        .await?)
}

/// Every bot's match of a tournament on one maze and seed, to be played together.
#[utoipa::path(get, path = "/api/tournaments/{id}/race/{maze_id}/{repeat}", tag = "tournaments",
    params(("id" = i64, Path, description = "tournament id"), ("maze_id" = i64, Path, description = "maze id"),
        ("repeat" = i64, Path, description = "the repeat index, from 0")),
    responses((status = 200, body = Race), (status = 403, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn get_tournament_race(
    State(state): State<AppState>,
    caller: Caller,
    AppPath((id, maze_id, repeat)): AppPath<(i64, i64, i64)>,
) -> ApiResult<axum::Json<Race>> {
    Ok(axum::Json(Race::clone(
        &*tournament_race(&state, &caller, id, maze_id, repeat).await?,
    )))
}
