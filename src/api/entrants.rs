//! Entrants: a person or a team with an API key (shown once, stored hashed, rotatable)
//! that acts for every bot registered with it; and the server's registration mode
//! (open, closed, or by invite code), set by the admin.

use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::{Caller, hash_token, new_token};
use super::error::{ApiError, ApiResult, AppJson, AppPath, AppQuery, ErrorBody};
use crate::registry::entrants::EntrantList;
use crate::storage::entrants::Registration;

/// The most members an entrant lists, and the longest member name.
const MAX_MEMBERS: usize = 20;
const MAX_MEMBER_CHARS: usize = 100;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_entrant, list_entrants))
        .routes(routes!(get_entrant))
        .routes(routes!(rotate_key))
        .routes(routes!(get_registration, set_registration))
        .routes(routes!(get_me))
}

/// A new entrant.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct EntrantRequest {
    /// Unique name: 1 to 64 letters, digits, `-`, `_`, `.`.
    pub name: String,
    /// The members' names (at most 20).
    #[serde(default)]
    pub members: Vec<String>,
    /// The invite code: the server's, when registration is by invite, or a
    /// competition's own (which registers whatever the server's mode and leads to that
    /// competition).
    pub invite_code: Option<String>,
}

/// A registered entrant and its key (shown once).
#[derive(Debug, Serialize, ToSchema)]
pub struct EntrantCreated {
    /// Id.
    pub entrant_id: i64,
    /// Name.
    pub name: String,
    /// The entrant's key: acts for every bot registered with it (`Authorization: Bearer
    /// KEY`). Shown once; keep it.
    pub key: String,
    /// The competition whose invite code it registered with (its short name), if any:
    /// where to submit a bot next.
    pub competition: Option<String>,
}

/// An entrant as anyone sees it.
#[derive(Debug, Serialize, ToSchema)]
pub struct EntrantView {
    /// Id.
    pub entrant_id: i64,
    /// Name.
    pub name: String,
    /// The members' names.
    pub members: Vec<String>,
    /// When it registered (unix ms).
    pub created_at: i64,
    /// Its bots: id and name.
    pub bots: Vec<EntrantBot>,
}

/// A bot of an entrant.
#[derive(Debug, Serialize, ToSchema)]
pub struct EntrantBot {
    /// Id.
    pub bot_id: i64,
    /// Name.
    pub name: String,
}

/// Who a key is and what it acts for.
#[derive(Debug, Serialize, ToSchema)]
pub struct MeView {
    /// `admin`, `organiser`, `entrant` (an entrant's key) or `owner` (a bot's owner
    /// token).
    pub kind: String,
    /// The entrant, for an entrant's key.
    pub entrant_id: Option<i64>,
    /// The entrant's name.
    pub entrant: Option<String>,
    /// The bots the key acts for.
    pub bots: Vec<EntrantBot>,
}

/// Who the caller's key is: the admin, an organiser, an entrant (with its bots) or a
/// bot's owner (its bot). A key the server does not know: 401.
#[utoipa::path(get, path = "/api/me", tag = "entrants", security(("bearer" = [])),
    responses((status = 200, body = MeView), (status = 401, body = ErrorBody)))]
async fn get_me(State(state): State<AppState>, caller: Caller) -> ApiResult<axum::Json<MeView>> {
    let me = |kind: &str| MeView {
        kind: kind.into(),
        entrant_id: None,
        entrant: None,
        bots: Vec::new(),
    };
    let bots = |list: Vec<(i64, String)>| {
        list.into_iter()
            .map(|(bot_id, name)| EntrantBot { bot_id, name })
            .collect::<Vec<_>>()
    };
    Ok(axum::Json(match &caller {
        Caller::Anonymous => {
            return Err(ApiError::Unauthorized(
                "no key given (Authorization: Bearer KEY)".into(),
            ));
        }
        Caller::Admin => me("admin"),
        Caller::Organiser(_) => me("organiser"),
        Caller::Token(hash) => {
            if let Some(e) = state.storage.entrant_by_key(hash).await? {
                MeView {
                    kind: "entrant".into(),
                    entrant_id: Some(e.entrant_id),
                    entrant: Some(e.name),
                    bots: bots(state.storage.bots_owned_by(hash).await?),
                }
            } else {
                let owned = state.storage.bots_owned_by(hash).await?;
                if owned.is_empty() {
                    return Err(ApiError::Unauthorized(
                        "this key is not known on this server".into(),
                    ));
                }
                MeView {
                    bots: bots(owned),
                    ..me("owner")
                }
            }
        }
    }))
}

/// A replaced key.
#[derive(Debug, Serialize, ToSchema)]
pub struct NewKey {
    /// The new key (the old one no longer works). Shown once.
    pub key: String,
}

/// The registration mode.
#[derive(Debug, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RegistrationMode {
    /// `open` (anyone registers), `closed` (only the admin registers entrants; bots only
    /// with an entrant's key), or `invite` (an entrant gives the invite code).
    pub mode: String,
    /// With `invite`, when set by the admin: the code (kept only as its hash).
    #[serde(default, skip_serializing)]
    pub invite_code: Option<String>,
}

pub(crate) fn registration_name(r: &Registration) -> &'static str {
    match r {
        Registration::Open => "open",
        Registration::Closed => "closed",
        Registration::Invite(_) => "invite",
    }
}

/// Register an entrant: answers its id and key (shown once). Open registration: anyone;
/// by invite: with the code; closed: the admin only.
#[utoipa::path(post, path = "/api/entrants", tag = "entrants",
    request_body = EntrantRequest,
    responses(
        (status = 201, body = EntrantCreated),
        (status = 400, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 409, body = ErrorBody), (status = 422, body = ErrorBody),
        (status = 429, body = ErrorBody, description = "a budget is used up: registrations without a key from this address, wrong invite codes from it, the invite code's own, or the entrant's quotas (the message says whose); see Retry-After"),
    ))]
async fn create_entrant(
    State(state): State<AppState>,
    caller: Caller,
    client: Option<axum::Extension<super::client_address::ClientAddress>>,
    AppJson(body): AppJson<EntrantRequest>,
) -> ApiResult<(StatusCode, axum::Json<EntrantCreated>)> {
    let created = register(&state, &caller, client.map(|c| c.0.0), body).await?;
    Ok((StatusCode::CREATED, axum::Json(created)))
}

/// Registers an entrant for `caller` from address `client` (the API's and the
/// registration page's one way).
///
/// # Errors
/// The registration limit, a bad name or member, the registration mode, a taken name.
pub(crate) async fn register(
    state: &AppState,
    caller: &Caller,
    client: Option<std::net::IpAddr>,
    body: EntrantRequest,
) -> ApiResult<EntrantCreated> {
    crate::registry::bots::check_name(&body.name)
        .map_err(|e| ApiError::Unprocessable(e.to_string().replace("bot name", "entrant name")))?;
    if body.members.len() > MAX_MEMBERS
        || body.members.iter().any(|m| {
            m.trim().is_empty()
                || m.chars().count() > MAX_MEMBER_CHARS
                || m.chars().any(char::is_control)
        })
    {
        return Err(ApiError::Unprocessable(format!(
            "members: at most {MAX_MEMBERS} names of 1 to {MAX_MEMBER_CHARS} characters, no control characters"
        )));
    }
    // A competition's own invite code registers whatever the server's mode, and leads
    // to that competition (while it takes part: not after its close).
    let given = body
        .invite_code
        .as_deref()
        .map(str::trim)
        .filter(|c| !c.is_empty());
    let through = match given {
        Some(code) => {
            state
                .storage
                .competition_by_invite(&hash_token(code))
                .await?
        }
        None => None,
    };
    if let Some(c) = &through {
        let now = crate::storage::now_ms();
        if crate::registry::competitions::phase(c, now).is_closed() {
            return Err(ApiError::Forbidden(format!(
                "competition {} has closed: its invite code registers no one now",
                c.name
            )));
        }
    }
    // The admin has no limit; the right invite code spends the code's budget, a wrong
    // one its address's budget of guesses, an open registration its address's budget
    // of anonymous registrations (`api::limits`).
    if !caller.is_admin() {
        use super::limits::{Spend, spend};
        let mode = state.storage.registration().await?;
        match (given.map(hash_token), through.is_some(), mode) {
            // A competition's own code, whatever the mode, or the server's: the code's
            // budget.
            (Some(hash), true, _) => {
                spend(state, Spend::InviteRegistration(&hash), client).await?;
            }
            (Some(hash), false, Registration::Invite(server)) if hash == server => {
                spend(state, Spend::InviteRegistration(&hash), client).await?;
            }
            // Any other code is a wrong one, whatever the mode (a student who followed a
            // mistyped link should hear so): the address's budget of guesses.
            (Some(_), false, _) => {
                spend(state, Spend::WrongInviteCode, client).await?;
                return Err(ApiError::Forbidden(
                    "this invite code is not known on this server: check it, or the link, with \
                     your organiser (`invite_code`)"
                        .into(),
                ));
            }
            (None, _, Registration::Open) => {
                if !caller.can_organise() {
                    spend(state, Spend::AnonymousRegistration, client).await?;
                }
            }
            (None, _, Registration::Closed) => {
                return Err(ApiError::Forbidden(
                    "registration is closed: the admin registers entrants".into(),
                ));
            }
            (None, _, Registration::Invite(_)) => {
                return Err(ApiError::Forbidden(
                    "registration is by invite: give the invite code (`invite_code`)".into(),
                ));
            }
        }
    }
    let key = new_token()?;
    let members = serde_json::to_string(&body.members)
        .map_err(|e| ApiError::Internal(format!("members: {e}")))?;
    let row = state
        .storage
        .create_entrant(
            &body.name,
            &members,
            &hash_token(&key),
            through.as_ref().map(|c| c.competition_id),
        )
        .await?;
    Ok(EntrantCreated {
        entrant_id: row.entrant_id,
        name: row.name,
        key,
        competition: through.map(|c| c.name),
    })
}

/// The query of `GET /api/entrants`.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct EntrantSearch {
    /// Part of a name or a member's name, any case (left out: everyone).
    pub search: Option<String>,
    /// At most this many (1 to 500; default 100).
    pub limit: Option<i64>,
}

/// The entrants whose name or members hold `search`, for `caller` (the admin): the
/// API's and the admin page's one way.
///
/// # Errors
/// Not the admin; a limit out of range.
pub(crate) async fn find_entrants(
    state: &AppState,
    caller: &Caller,
    search: &str,
    limit: i64,
) -> ApiResult<EntrantList> {
    caller.require_admin()?;
    if !(1..=500).contains(&limit) {
        return Err(ApiError::BadRequest("limit: 1 to 500".into()));
    }
    if search.chars().count() > 100 || search.chars().any(char::is_control) {
        return Err(ApiError::BadRequest(
            "search: at most 100 characters, no control characters".into(),
        ));
    }
    Ok(crate::registry::entrants::find(&state.storage, search, limit).await?)
}

/// List and search the entrants (the admin only).
#[utoipa::path(get, path = "/api/entrants", tag = "entrants", params(EntrantSearch),
    security(("bearer" = [])),
    responses((status = 200, body = crate::registry::entrants::EntrantList), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody)))]
async fn list_entrants(
    State(state): State<AppState>,
    caller: Caller,
    AppQuery(q): AppQuery<EntrantSearch>,
) -> ApiResult<axum::Json<crate::registry::entrants::EntrantList>> {
    Ok(axum::Json(
        find_entrants(
            &state,
            &caller,
            q.search.as_deref().unwrap_or(""),
            q.limit.unwrap_or(100),
        )
        .await?,
    ))
}

/// An entrant: name, members and bots.
#[utoipa::path(get, path = "/api/entrants/{id}", tag = "entrants",
    params(("id" = i64, Path, description = "entrant id")),
    responses((status = 200, body = EntrantView), (status = 404, body = ErrorBody)))]
async fn get_entrant(
    State(state): State<AppState>,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<EntrantView>> {
    let row = state
        .storage
        .get_entrant(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no entrant {id}")))?;
    let bots = state
        .storage
        .bots_of_entrant(id)
        .await?
        .into_iter()
        .map(|(bot_id, name)| EntrantBot { bot_id, name })
        .collect();
    Ok(axum::Json(EntrantView {
        entrant_id: row.entrant_id,
        name: row.name,
        members: serde_json::from_str(&row.members).unwrap_or_default(),
        created_at: row.created_at,
        bots,
    }))
}

/// Replace an entrant's key (its current key or the admin token): the old key stops
/// working at once.
#[utoipa::path(post, path = "/api/entrants/{id}/key", tag = "entrants",
    params(("id" = i64, Path, description = "entrant id")),
    security(("bearer" = [])),
    responses(
        (status = 200, body = NewKey),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody),
    ))]
async fn rotate_key(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<NewKey>> {
    Ok(axum::Json(rotate(&state, &caller, id).await?))
}

/// Replaces entrant `id`'s key for `caller` (that entrant, the organiser of the
/// competitions it takes part in, or the admin): the API's and the pages' one way. The old key, its bots' owner tokens and every browser
/// session opened with them stop working at once.
///
/// # Errors
/// No such entrant; not its key.
pub(crate) async fn rotate(state: &AppState, caller: &Caller, id: i64) -> ApiResult<NewKey> {
    if state.storage.get_entrant(id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no entrant {id}")));
    }
    let allowed = match caller {
        Caller::Admin => true,
        Caller::Anonymous => false,
        // An organiser, for an entrant of its competitions only: one that takes part
        // (or registered through the invite code) in its competitions and in no other
        // organiser's, whose entries a new key would hand to it.
        Caller::Organiser(o) => {
            let of = state.storage.organisers_of_entrant(id).await?;
            !of.is_empty() && of.iter().all(|x| *x == Some(*o))
        }
        Caller::Token(hash) => state
            .storage
            .entrant_by_key(hash)
            .await?
            .is_some_and(|e| e.entrant_id == id),
    };
    if !allowed {
        return Err(match caller {
            Caller::Anonymous => ApiError::Unauthorized(format!(
                "this needs entrant {id}'s key, the organiser of its competitions or the admin \
                 token (Authorization: Bearer KEY)"
            )),
            Caller::Organiser(_) => ApiError::Forbidden(format!(
                "entrant {id} does not take part only in your competitions: the admin gives it \
                 a new key"
            )),
            _ => ApiError::Forbidden(format!("this is not entrant {id}'s key")),
        });
    }
    let key = new_token()?;
    state
        .storage
        .rotate_entrant_key(id, &hash_token(&key))
        .await?;
    Ok(NewKey { key })
}

/// The registration mode: `open`, `closed` or `invite`.
#[utoipa::path(get, path = "/api/registration", tag = "entrants",
    responses((status = 200, body = RegistrationMode)))]
async fn get_registration(
    State(state): State<AppState>,
) -> ApiResult<axum::Json<RegistrationMode>> {
    let r = state.storage.registration().await?;
    Ok(axum::Json(RegistrationMode {
        mode: registration_name(&r).into(),
        invite_code: None,
    }))
}

/// Set the registration mode (admin token): `open`, `closed`, or `invite` with an
/// `invite_code` of at least 8 characters.
#[utoipa::path(put, path = "/api/registration", tag = "entrants",
    request_body = RegistrationMode,
    security(("bearer" = [])),
    responses(
        (status = 200, body = RegistrationMode),
        (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 422, body = ErrorBody),
    ))]
async fn set_registration(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(body): AppJson<RegistrationMode>,
) -> ApiResult<axum::Json<RegistrationMode>> {
    Ok(axum::Json(set_mode(&state, &caller, body).await?))
}

/// Sets the registration mode (the admin only): the API's and the admin page's one way.
///
/// # Errors
/// Not the admin; a bad mode or invite code.
pub(crate) async fn set_mode(
    state: &AppState,
    caller: &Caller,
    body: RegistrationMode,
) -> ApiResult<RegistrationMode> {
    caller.require_admin()?;
    let r = match (body.mode.as_str(), body.invite_code.as_deref()) {
        ("open", None) => Registration::Open,
        ("closed", None) => Registration::Closed,
        ("invite", Some(code)) if code.chars().count() >= 8 => {
            Registration::Invite(hash_token(code))
        }
        _ => {
            return Err(ApiError::Unprocessable(
                "mode: `open` or `closed` (no invite_code), or `invite` with an invite_code of \
                 at least 8 characters"
                    .into(),
            ));
        }
    };
    state.storage.set_registration(&r).await?;
    Ok(RegistrationMode {
        mode: registration_name(&r).into(),
        invite_code: None,
    })
}
