//! A competition's practice mazes, added and removed by its organiser while it takes
//! part: the mazes its entrants practise on, and its validation matches are played on.

use axum::extract::State;
use axum::http::StatusCode;
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiResult, AppJson, AppPath, ErrorBody};
use crate::competition::MazeText;
use crate::registry::competitions as ops;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(add_practice))
        .routes(routes!(remove_practice))
}

/// A practice maze added.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct PracticeAdded {
    /// Its id (its layout is public: `GET /api/mazes/{id}`).
    pub maze_id: i64,
}

/// Adds maze `m` to competition `name`'s practice set for `caller` (its organiser or
/// the admin): the API's and the manage page's one way.
///
/// # Errors
/// Not its organiser; closed; a bad or hidden maze; a maze in it already.
pub(crate) async fn add(
    state: &AppState,
    caller: &Caller,
    name: &str,
    m: &MazeText,
) -> ApiResult<PracticeAdded> {
    let c = super::competitions::find(state, name).await?;
    caller.require_organiser_of(&c)?;
    let maze_id = ops::add_practice_maze(&state.storage, &c, m, crate::storage::now_ms()).await?;
    Ok(PracticeAdded { maze_id })
}

/// Removes practice maze `maze_id` from competition `name` for `caller` (its organiser
/// or the admin).
///
/// # Errors
/// Not its organiser; closed; not one of its practice mazes.
pub(crate) async fn remove(
    state: &AppState,
    caller: &Caller,
    name: &str,
    maze_id: i64,
) -> ApiResult<()> {
    let c = super::competitions::find(state, name).await?;
    caller.require_organiser_of(&c)?;
    Ok(ops::remove_practice_maze(&state.storage, &c, maze_id, crate::storage::now_ms()).await?)
}

/// Add a practice maze to a competition while it takes part (its organiser or the
/// admin): public on this server; validation matches play the practice mazes in order.
#[utoipa::path(post, path = "/api/competitions/{name}/practice", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = MazeText, security(("bearer" = [])),
    responses((status = 201, body = PracticeAdded), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
async fn add_practice(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(m): AppJson<MazeText>,
) -> ApiResult<(StatusCode, axum::Json<PracticeAdded>)> {
    Ok((
        StatusCode::CREATED,
        axum::Json(add(&state, &caller, &name, &m).await?),
    ))
}

/// Remove a practice maze from a competition while it takes part (its organiser or the
/// admin); its practice matches stay.
#[utoipa::path(delete, path = "/api/competitions/{name}/practice/{maze_id}", tag = "competitions",
    params(("name" = String, Path, description = "competition name"),
        ("maze_id" = i64, Path, description = "the practice maze's id")),
    security(("bearer" = [])),
    responses((status = 204), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody)))]
async fn remove_practice(
    State(state): State<AppState>,
    caller: Caller,
    AppPath((name, maze_id)): AppPath<(String, i64)>,
) -> ApiResult<StatusCode> {
    remove(&state, &caller, &name, maze_id).await?;
    Ok(StatusCode::NO_CONTENT)
}
