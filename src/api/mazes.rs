//! Mazes: upload (admin), list, show, draw. Hidden mazes are for ranking: their layout
//! is only ever served to the admin.

use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use crate::engine::mazefile::{self, numeric};
use crate::engine::{render, solver};
use crate::storage::mazes::{MazeRow, NewMaze};
use crate::storage::{Storage, StorageError};

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_maze, list_mazes))
        .routes(routes!(get_maze))
        .routes(routes!(get_maze_svg))
}

/// A maze to upload.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MazeUpload {
    /// A display name.
    pub name: String,
    /// The maze file's text, numeric or ASCII format.
    pub layout: String,
    /// Hidden (ranking) maze: its layout is never shown to non-admins. Default: public.
    #[serde(default)]
    pub hidden: bool,
}

/// A maze; `layout` (canonical numeric text) only when the caller may see it.
#[derive(Debug, Serialize, ToSchema)]
pub struct MazeView {
    /// Id.
    pub maze_id: i64,
    /// Name.
    pub name: String,
    /// Side.
    pub dim: i64,
    /// Hidden (ranking) maze.
    pub hidden: bool,
    /// Fewest run-1 steps with full knowledge (null if the goal is unreachable).
    pub optimum: Option<i64>,
    /// SHA-256 of the canonical numeric text.
    pub hash: String,
    /// Uploaded at (unix ms).
    pub created_at: i64,
    /// The canonical numeric text.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<String>,
}

impl MazeView {
    fn new(row: MazeRow, with_layout: bool) -> MazeView {
        MazeView {
            maze_id: row.maze_id,
            name: row.name,
            dim: row.dim,
            hidden: row.hidden,
            optimum: row.optimum,
            hash: row.hash,
            created_at: row.created_at,
            layout: with_layout.then_some(row.layout),
        }
    }
}

/// Parses, validates and stores a maze; the optimum is computed here.
///
/// # Errors
/// [`ApiError::Unprocessable`] for an invalid maze (with line and column),
/// [`ApiError::Conflict`] for a layout stored already.
pub async fn store_maze(
    storage: &Storage,
    name: &str,
    text: &[u8],
    hidden: bool,
) -> ApiResult<MazeRow> {
    if name.trim().is_empty() || name.chars().count() > 200 {
        return Err(ApiError::Unprocessable(
            "a maze needs a name of 1 to 200 characters".into(),
        ));
    }
    let text = text.to_vec();
    let (maze, optimum) = tokio::task::spawn_blocking(move || {
        mazefile::parse(&text).map(|m| {
            let optimum = solver::solve(&m).map(|s| s.steps as i64);
            (m, optimum)
        })
    })
    .await
    .map_err(|e| ApiError::Internal(format!("maze task failed: {e}")))?
    .map_err(|e| ApiError::Unprocessable(format!("invalid maze: {e}")))?;
    let layout = numeric::write(&maze);
    let row = storage
        .insert_maze(&NewMaze {
            name,
            hash: &maze.hash(),
            dim: maze.dim() as i64,
            layout: &layout,
            hidden,
            optimum,
        })
        .await
        .map_err(|e| match e {
            StorageError::Conflict(msg) => ApiError::Conflict(msg),
            other => other.into(),
        })?;
    Ok(row)
}

/// Upload a maze (admin token).
#[utoipa::path(post, path = "/api/mazes", tag = "mazes",
    request_body = MazeUpload,
    security(("bearer" = [])),
    responses(
        (status = 201, body = MazeView),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 422, body = ErrorBody),
    ))]
async fn create_maze(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(body): AppJson<MazeUpload>,
) -> ApiResult<(StatusCode, axum::Json<MazeView>)> {
    caller.require_admin()?;
    let row = store_maze(
        &state.storage,
        &body.name,
        body.layout.as_bytes(),
        body.hidden,
    )
    .await?;
    Ok((StatusCode::CREATED, axum::Json(MazeView::new(row, true))))
}

/// List the mazes (layouts are not included; hidden ones are listed without it).
#[utoipa::path(get, path = "/api/mazes", tag = "mazes",
    responses((status = 200, body = [MazeView])))]
async fn list_mazes(State(state): State<AppState>) -> ApiResult<axum::Json<Vec<MazeView>>> {
    let rows = state.storage.list_mazes().await?;
    Ok(axum::Json(
        rows.into_iter().map(|r| MazeView::new(r, false)).collect(),
    ))
}

/// One maze; the layout is included for public mazes, and for the admin.
#[utoipa::path(get, path = "/api/mazes/{id}", tag = "mazes",
    params(("id" = i64, Path, description = "maze id")),
    responses((status = 200, body = MazeView), (status = 404, body = ErrorBody)))]
async fn get_maze(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<MazeView>> {
    let row = find_maze(&state, id).await?;
    let visible = !row.hidden || caller.is_admin();
    Ok(axum::Json(MazeView::new(row, visible)))
}

/// A picture of the maze (SVG): public mazes, or the admin.
#[utoipa::path(get, path = "/api/mazes/{id}/svg", tag = "mazes",
    params(("id" = i64, Path, description = "maze id")),
    responses(
        (status = 200, description = "SVG picture", content_type = "image/svg+xml"),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
    ))]
async fn get_maze_svg(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Response> {
    let row = find_maze(&state, id).await?;
    if row.hidden && !caller.is_admin() {
        return Err(hidden_error(id, &caller));
    }
    let maze = numeric::parse(row.layout.as_bytes())
        .map_err(|e| ApiError::Internal(format!("stored maze {id} does not parse: {e}")))?;
    Ok((
        [(header::CONTENT_TYPE, "image/svg+xml")],
        render::svg(&maze, None),
    )
        .into_response())
}

pub(super) async fn find_maze(state: &AppState, id: i64) -> ApiResult<MazeRow> {
    state
        .storage
        .get_maze(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no maze {id}")))
}

pub(super) fn hidden_error(id: i64, caller: &Caller) -> ApiError {
    let msg = format!("maze {id} is hidden (a ranking maze): only the admin may see it");
    match caller {
        Caller::Anonymous => ApiError::Unauthorized(msg),
        _ => ApiError::Forbidden(msg),
    }
}
