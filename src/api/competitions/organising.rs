//! An organiser's work on a competition: rejudges and the export of its folder.

use super::competition::find;
use crate::api::AppState;
use crate::api::auth::Caller;
use crate::api::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use crate::registry::competitions::{self as ops};
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::IntoResponse;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// Who asks, as a rejudge records it.
pub(crate) fn requested_by(caller: &Caller) -> String {
    match caller {
        Caller::Organiser(id) => format!("organiser:{id}"),
        _ => "admin".into(),
    }
}

/// A rejudge of competition `name` for `caller` (its organiser or the admin): the API's,
/// the CLI's and the organiser page's one way.
///
/// # Errors
/// Not its organiser; a bad request.
pub(crate) async fn rejudge(
    state: &AppState,
    caller: &Caller,
    name: &str,
    request: &ops::RejudgeRequest,
) -> ApiResult<crate::storage::rejudges::RejudgeRow> {
    let c = find(state, name).await?;
    caller.require_organiser_of(&c)?;
    let row = ops::rejudge(&state.storage, &c, request, &requested_by(caller)).await?;
    state.wake.notify_waiters();
    Ok(row)
}

/// Play again a version's or a maze's ranking matches (a rejudge: after an
/// infrastructure failure or a referee fix; the competition's organiser or the admin).
/// Each match goes back to the queue under its own id, seed and repeat; its earlier
/// record is kept, marked superseded (`GET /api/matches/{id}` lists it); the boards and
/// results are counted again as the matches are played.
#[utoipa::path(post, path = "/api/competitions/{name}/rejudges", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = ops::RejudgeRequest, security(("bearer" = [])),
    responses((status = 201, body = crate::storage::rejudges::RejudgeRow), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub(super) async fn create_rejudge(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(body): AppJson<ops::RejudgeRequest>,
) -> ApiResult<(StatusCode, axum::Json<crate::storage::rejudges::RejudgeRow>)> {
    let row = rejudge(&state, &caller, &name, &body).await?;
    Ok((StatusCode::CREATED, axum::Json(row)))
}

/// The rejudges of a competition, newest first (its organiser or the admin).
#[utoipa::path(get, path = "/api/competitions/{name}/rejudges", tag = "competitions",
    params(("name" = String, Path, description = "competition name")), security(("bearer" = [])),
    responses((status = 200, body = [crate::storage::rejudges::RejudgeRow]), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub(super) async fn list_rejudges(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<Vec<crate::storage::rejudges::RejudgeRow>>> {
    let c = find(&state, &name).await?;
    caller.require_organiser_of(&c)?;
    Ok(axum::Json(state.storage.rejudges(c.competition_id).await?))
}

/// Competition `name` exported for `caller` (its organiser or the admin) as a
/// `.tar.gz` of its folder: the API's and the organiser page's one way.
///
/// # Errors
/// Not its organiser; the default competition.
pub(crate) async fn export_archive(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<axum::response::Response> {
    let c = find(state, name).await?;
    caller.require_organiser_of(&c)?;
    let files = ops::export_files(&state.storage, &c).await?;
    let bytes = ops::tar_gz(&c.name, &files)
        .map_err(|e| ApiError::Internal(format!("cannot pack the export: {e}")))?;
    Ok((
        [
            (header::CONTENT_TYPE, "application/gzip".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{}.tar.gz\"", c.name),
            ),
            (header::CACHE_CONTROL, "no-store".to_string()),
        ],
        bytes,
    )
        .into_response())
}

/// The competition as a `.tar.gz` of its folder (`competition.toml` and every maze,
/// private ones included): what `mazearena competition create` or the organiser's page
/// takes back (its organiser or the admin).
#[utoipa::path(get, path = "/api/competitions/{name}/export", tag = "competitions",
    params(("name" = String, Path, description = "competition name")), security(("bearer" = [])),
    responses((status = 200, content_type = "application/gzip", body = Vec<u8>), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub(super) async fn export(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::response::Response> {
    export_archive(&state, &caller, &name).await
}

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_rejudge, list_rejudges))
        .routes(routes!(export))
}
