//! Organisers, registered by the admin.

use crate::api::AppState;
use crate::api::auth::{Caller, hash_token, new_token};
use crate::api::error::{ApiError, ApiResult, AppJson, ErrorBody};
use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// A new organiser.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct OrganiserRequest {
    /// Unique name (1 to 64 characters).
    pub name: String,
}

/// A new organiser and its key (shown once).
#[derive(Debug, Serialize, ToSchema)]
pub struct OrganiserCreated {
    /// Id.
    pub organiser_id: i64,
    /// Name.
    pub name: String,
    /// The organiser's key: manages competitions and sees what they seal (`Authorization:
    /// Bearer KEY`). Shown once.
    pub key: String,
}

/// Register an organiser (admin only): manages competitions, reads no other secret.
#[utoipa::path(post, path = "/api/organisers", tag = "competitions",
    request_body = OrganiserRequest, security(("bearer" = [])),
    responses((status = 201, body = OrganiserCreated), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub(super) async fn create_organiser(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(body): AppJson<OrganiserRequest>,
) -> ApiResult<(StatusCode, axum::Json<OrganiserCreated>)> {
    let created = register_organiser(&state, &caller, body).await?;
    Ok((StatusCode::CREATED, axum::Json(created)))
}

/// Registers an organiser (the admin only): the API's and the admin page's one way.
///
/// # Errors
/// Not the admin; a bad or taken name.
pub(crate) async fn register_organiser(
    state: &AppState,
    caller: &Caller,
    body: OrganiserRequest,
) -> ApiResult<OrganiserCreated> {
    caller.require_admin()?;
    let name = body.name.trim();
    if name.is_empty() || name.chars().count() > 64 {
        return Err(ApiError::BadRequest(
            "an organiser's name is 1 to 64 characters".into(),
        ));
    }
    let key = new_token()?;
    let organiser_id = state
        .storage
        .create_organiser(name, &hash_token(&key))
        .await?;
    Ok(OrganiserCreated {
        organiser_id,
        name: name.to_string(),
        key,
    })
}

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(create_organiser))
}
