//! What an organiser and the admin do for the people of a class: a competition's own
//! invite code (set, rotated, removed), and new keys for those who lost theirs (an
//! entrant's: the admin, or the organiser of the competitions it takes part in; an
//! organiser's: the admin).

use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::{Caller, hash_token, new_token};
use super::entrants::NewKey;
use super::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use crate::registry::invites;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(set_invite, remove_invite))
        .routes(routes!(rotate_organiser_key))
}

/// A competition's own invite code to set: the code, or none for a fresh random one.
#[derive(Debug, Default, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct InviteRequest {
    /// 8 to 64 letters, digits, `-`, `_` or `.` (left out: a fresh random code).
    #[serde(default)]
    pub invite_code: Option<String>,
}

/// A competition's own invite code and the link that carries it.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct InviteView {
    /// The code: registering with it makes an entrant whatever the server's mode, and
    /// leads to the competition.
    pub invite_code: String,
    /// The competition's page with the code (a path on this server): its "How to take
    /// part" registers with the code filled in. Give it to the class.
    pub link: String,
}

/// Sets competition `name`'s own invite code for `caller` (its organiser or the
/// admin): the API's and the manage page's one way.
///
/// # Errors
/// Not its organiser; a bad or taken code.
pub(crate) async fn set(
    state: &AppState,
    caller: &Caller,
    name: &str,
    code: Option<&str>,
) -> ApiResult<InviteView> {
    let c = super::competitions::find(state, name).await?;
    caller.require_organiser_of(&c)?;
    if c.kind == "default" {
        return Err(ApiError::Conflict(
            "the default competition takes no invite code: set the server's registration".into(),
        ));
    }
    let code = invites::set(&state.storage, &c, code).await?;
    Ok(InviteView {
        link: invites::link(&c, &code),
        invite_code: code,
    })
}

/// Removes competition `name`'s own invite code for `caller` (its organiser or the
/// admin).
///
/// # Errors
/// Not its organiser.
pub(crate) async fn remove(state: &AppState, caller: &Caller, name: &str) -> ApiResult<()> {
    let c = super::competitions::find(state, name).await?;
    caller.require_organiser_of(&c)?;
    Ok(invites::remove(&state.storage, &c).await?)
}

/// Set or rotate a competition's own invite code (its organiser or the admin): a chosen
/// code, or a fresh random one; the old code stops working at once.
#[utoipa::path(put, path = "/api/competitions/{name}/invite", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = InviteRequest, security(("bearer" = [])),
    responses((status = 200, body = InviteView), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
async fn set_invite(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(body): AppJson<InviteRequest>,
) -> ApiResult<axum::Json<InviteView>> {
    Ok(axum::Json(
        set(&state, &caller, &name, body.invite_code.as_deref()).await?,
    ))
}

/// Remove a competition's own invite code (its organiser or the admin).
#[utoipa::path(delete, path = "/api/competitions/{name}/invite", tag = "competitions",
    params(("name" = String, Path, description = "competition name")), security(("bearer" = [])),
    responses((status = 204), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn remove_invite(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<StatusCode> {
    remove(&state, &caller, &name).await?;
    Ok(StatusCode::NO_CONTENT)
}

/// Replaces organiser `id`'s key for `caller` (the admin): the API's and the admin
/// page's one way. The old key and its sessions stop working at once.
///
/// # Errors
/// Not the admin; no such organiser.
pub(crate) async fn new_organiser_key(
    state: &AppState,
    caller: &Caller,
    id: i64,
) -> ApiResult<NewKey> {
    caller.require_admin()?;
    let key = new_token()?;
    if !state
        .storage
        .rotate_organiser_key(id, &hash_token(&key))
        .await?
    {
        return Err(ApiError::NotFound(format!("no organiser {id}")));
    }
    Ok(NewKey { key })
}

/// Replace an organiser's key (the admin only): the old key stops working at once.
#[utoipa::path(post, path = "/api/organisers/{id}/key", tag = "competitions",
    params(("id" = i64, Path, description = "organiser id")), security(("bearer" = [])),
    responses((status = 200, body = NewKey), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn rotate_organiser_key(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<NewKey>> {
    Ok(axum::Json(new_organiser_key(&state, &caller, id).await?))
}
