//! Mazes: upload or generate (admin), list, show, draw. Hidden mazes are for ranking:
//! their layout, and anything that would identify it (hash, side, optimum), is only
//! ever served to the admin; a generated hidden maze's seed is random and never kept.

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
use crate::engine::generator;
use crate::engine::mazefile::numeric;
use crate::engine::render;
use crate::registry;
use crate::storage::mazes::MazeRow;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_maze, list_mazes))
        .routes(routes!(get_maze))
        .routes(routes!(get_maze_svg))
}

/// A maze to upload (`layout`) or to generate (`generate`): exactly one of the two.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MazeUpload {
    /// A display name. Everyone sees it, hidden mazes' too: it should not describe the
    /// maze (e.g. its seed).
    pub name: String,
    /// The maze file's text, numeric or ASCII format.
    #[serde(default)]
    pub layout: Option<String>,
    /// Make the maze with the generator of `mazearena maze generate` instead.
    #[serde(default)]
    pub generate: Option<GenerateRequest>,
    /// Hidden (ranking) maze: its layout, hash, side and optimum are never shown to
    /// non-admins. Default: public.
    #[serde(default)]
    pub hidden: bool,
}

/// A maze to generate (the generator of `mazearena maze generate`).
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct GenerateRequest {
    /// The side: an even number from 4 to 32 (task mazes: 12, 14 or 16).
    pub dim: u32,
    /// The seed, for public mazes only (random if omitted). A hidden maze always gets
    /// a secret random seed that is not stored anywhere: anyone who knew it could
    /// rebuild the maze with `mazearena maze generate`.
    #[serde(default)]
    pub seed: Option<u64>,
}

/// A maze. For a hidden maze, `hash`, `dim` and `optimum` are null unless the caller
/// is the admin; `layout` (canonical numeric text) only when the caller may see it.
#[derive(Debug, Serialize, ToSchema)]
pub struct MazeView {
    /// Id.
    pub maze_id: i64,
    /// Name.
    pub name: String,
    /// Side (null: hidden maze, caller not the admin).
    pub dim: Option<i64>,
    /// Hidden (ranking) maze.
    pub hidden: bool,
    /// Fewest run-1 steps with full knowledge (null if the goal is unreachable, or a
    /// hidden maze and the caller is not the admin).
    pub optimum: Option<i64>,
    /// SHA-256 of the canonical numeric text (null: hidden maze, caller not the admin).
    pub hash: Option<String>,
    /// Uploaded at (unix ms).
    pub created_at: i64,
    /// The canonical numeric text.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<String>,
    /// The generator seed: only in the answer to generating a public maze.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

impl MazeView {
    /// The maze as `caller` may see it; the layout only if `with_layout` too.
    fn new(row: MazeRow, caller: &Caller, with_layout: bool) -> MazeView {
        let reveal = !row.hidden || caller.is_admin();
        MazeView {
            maze_id: row.maze_id,
            name: row.name,
            dim: reveal.then_some(row.dim),
            hidden: row.hidden,
            optimum: row.optimum.filter(|_| reveal),
            hash: reveal.then_some(row.hash),
            created_at: row.created_at,
            layout: (reveal && with_layout).then_some(row.layout),
            seed: None,
        }
    }
}

/// Upload a maze, or generate one (admin token).
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
    let (text, public_seed) = match (body.layout, body.generate) {
        (Some(layout), None) => (layout, None),
        (None, Some(generate)) => {
            let seed = generator_seed(generate.seed, body.hidden)?;
            let maze = generator::generate(generate.dim, seed)
                .map_err(|e| ApiError::Unprocessable(e.to_string()))?;
            (numeric::write(&maze), (!body.hidden).then_some(seed))
        }
        _ => {
            return Err(ApiError::Unprocessable(
                "send either `layout` (a maze file's text) or `generate` ({\"dim\": 16}), not both"
                    .into(),
            ));
        }
    };
    let row =
        registry::mazes::admit(&state.storage, &body.name, text.as_bytes(), body.hidden).await?;
    let mut view = MazeView::new(row, &caller, true);
    view.seed = public_seed;
    Ok((StatusCode::CREATED, axum::Json(view)))
}

/// The seed to generate a maze with: a public maze may be given one (else a random
/// one, small enough for any JSON reader); a hidden maze always gets 64 secret random
/// bits, which the caller drops once the maze is made.
fn generator_seed(given: Option<u64>, hidden: bool) -> ApiResult<u64> {
    let random = |bytes: &mut [u8]| {
        getrandom::fill(bytes).map_err(|e| ApiError::Internal(format!("no randomness: {e}")))
    };
    match (given, hidden) {
        (Some(_), true) => Err(ApiError::Unprocessable(
            "a hidden maze's seed is chosen at random by the server and never shown: leave `seed` out"
                .into(),
        )),
        (Some(seed), false) => Ok(seed),
        (None, false) => {
            let mut b = [0u8; 4];
            random(&mut b)?;
            Ok(u64::from(u32::from_le_bytes(b)))
        }
        (None, true) => {
            let mut b = [0u8; 8];
            random(&mut b)?;
            Ok(u64::from_le_bytes(b))
        }
    }
}

/// List the mazes (without layouts; a hidden maze's hash, side and optimum are null
/// unless the caller is the admin).
#[utoipa::path(get, path = "/api/mazes", tag = "mazes",
    responses((status = 200, body = [MazeView])))]
async fn list_mazes(
    State(state): State<AppState>,
    caller: Caller,
) -> ApiResult<axum::Json<Vec<MazeView>>> {
    let rows = state.storage.list_mazes().await?;
    Ok(axum::Json(
        rows.into_iter()
            .map(|r| MazeView::new(r, &caller, false))
            .collect(),
    ))
}

/// One maze; the layout is included for public mazes, and for the admin (a hidden
/// maze's hash, side and optimum are null for anyone else).
#[utoipa::path(get, path = "/api/mazes/{id}", tag = "mazes",
    params(("id" = i64, Path, description = "maze id")),
    responses((status = 200, body = MazeView), (status = 404, body = ErrorBody)))]
async fn get_maze(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<MazeView>> {
    let row = find_maze(&state, id).await?;
    Ok(axum::Json(MazeView::new(row, &caller, true)))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hidden_maze_gets_a_fresh_secret_seed_and_refuses_a_given_one() {
        assert!(matches!(
            generator_seed(Some(7), true),
            Err(ApiError::Unprocessable(_))
        ));
        let a = generator_seed(None, true).unwrap();
        let b = generator_seed(None, true).unwrap();
        assert_ne!(a, b, "two hidden mazes got the same seed");
        assert_eq!(generator_seed(Some(7), false).unwrap(), 7);
        assert!(generator_seed(None, false).unwrap() <= u64::from(u32::MAX));
    }
}
