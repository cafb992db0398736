//! The class's forms on the organiser's and the admin's pages: a competition's own
//! invite code, its practice mazes, and new keys for those who lost theirs (an
//! entrant's, by the organiser of its competitions or the admin; an organiser's, by the
//! admin). Each goes through the operation the API's route of the same purpose calls;
//! a key is shown once, on a page no cache keeps.

use std::path::Path;

use axum::Router;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::StatusCode;
use axum::routing::post;
use serde::Deserialize;

use super::super::AppState;
use super::super::error::{ApiError, AppPath};
use super::super::session::Visitor;
use super::forms::{PageError, PageResult, no_store, read_form, read_token_form};
use super::organise::manage_after;
use crate::competition::MazeText;
use crate::web::pages::account;

/// Their routes.
pub(super) fn router() -> Router<AppState> {
    Router::new()
        .route("/competitions/{name}/invite", post(invite))
        .route(
            "/competitions/{name}/practice",
            post(practice).layer(DefaultBodyLimit::max(MAX_MAZE_FORM_BYTES)),
        )
        .route("/competitions/{name}/entrants/{id}/key", post(entrant_key))
        .route("/admin/entrants/{id}/key", post(admin_entrant_key))
        .route("/admin/organisers/{id}/key", post(admin_organiser_key))
}

/// The invite code's forms: `action` is `set` (with `invite_code`, or empty for a
/// random code) or `remove`.
#[derive(Debug, Deserialize)]
struct InviteForm {
    csrf: Option<String>,
    action: String,
    #[serde(default)]
    invite_code: String,
}

async fn invite(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: InviteForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let caller = &visitor.caller;
    let result = match form.action.as_str() {
        "set" => {
            let code = Some(form.invite_code.as_str()).filter(|c| !c.trim().is_empty());
            super::super::invites::set(&state, caller, &name, code)
                .await
                .map(|_| "invite".to_string())
                .map_err(PageError::from)
        }
        "remove" => super::super::invites::remove(&state, caller, &name)
            .await
            .map(|()| "invite_removed".to_string())
            .map_err(PageError::from),
        other => Err(PageError::new(
            StatusCode::BAD_REQUEST,
            format!("unknown action {other:?}: set or remove"),
        )),
    };
    manage_after(&state, &visitor, &name, result).await
}

/// The practice mazes' forms: a `remove` field (a maze id), or a `maze` file to add
/// (multipart, after the form's token).
async fn practice(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let caller = visitor.caller.clone();
    let is_multipart = request
        .headers()
        .get(axum::http::header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.to_ascii_lowercase().starts_with("multipart/form-data"));
    let result = if is_multipart {
        let mut form = super::forms::multipart_after_token(&state, &visitor, request).await?;
        let mut maze = None;
        while let Some(field) = form.next_field().await.map_err(ApiError::from)? {
            if field.name() != Some("maze") {
                return Err(PageError::new(
                    StatusCode::BAD_REQUEST,
                    "the form has an unknown field: expected csrf and maze",
                ));
            }
            let file_name = field.file_name().unwrap_or("practice").to_string();
            let bytes = field.bytes().await.map_err(ApiError::from)?;
            let layout = String::from_utf8(bytes.to_vec()).map_err(|_| {
                PageError::new(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    format!("{file_name} is not a maze file (not text)"),
                )
            })?;
            let stem = Path::new(&file_name)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "practice".into());
            maze = Some(MazeText { name: stem, layout });
        }
        match maze {
            Some(m) => super::super::practice::add(&state, &caller, &name, &m)
                .await
                .map(|_| "practice_added".to_string())
                .map_err(PageError::from),
            None => Err(PageError::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                "choose a maze file to add",
            )),
        }
    } else {
        let form: PracticeRemoveForm = read_form(&state, request).await?;
        visitor.check_csrf(form.csrf.as_deref())?;
        super::super::practice::remove(&state, &caller, &name, form.remove)
            .await
            .map(|()| "practice_removed".to_string())
            .map_err(PageError::from)
    };
    manage_after(&state, &visitor, &name, result).await
}

/// The largest practice maze form: a maze file and the form's token, with room for
/// the multipart framing.
const MAX_MAZE_FORM_BYTES: usize = crate::engine::mazefile::MAX_FILE_BYTES + 16 * 1024;

/// The practice maze's remove form.
#[derive(Debug, Deserialize)]
struct PracticeRemoveForm {
    csrf: Option<String>,
    remove: i64,
}

/// The organiser's (or the admin's) "new key" for an entrant of the competition: the
/// key is shown once, to be handed over.
async fn entrant_key(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath((name, id)): AppPath<(String, i64)>,
    request: Request,
) -> PageResult {
    read_token_form(&state, &visitor, request).await?;
    let c = super::super::competitions::find(&state, &name).await?;
    visitor.caller.require_organiser_of(&c)?;
    let back = format!("/competitions/{name}/manage");
    new_entrant_key(&state, &visitor, id, &back).await
}

/// A new key for entrant `id` by `visitor` (the API's rule: the admin, or the
/// organiser of the competitions it takes part in), shown once.
async fn new_entrant_key(state: &AppState, visitor: &Visitor, id: i64, back: &str) -> PageResult {
    let e = state
        .storage
        .get_entrant(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no entrant {id}")))?;
    let new = super::super::entrants::rotate(state, &visitor.caller, id).await?;
    Ok(no_store(account::handed_over(
        &format!("entrant {}", e.name),
        &e.name,
        &new.key,
        back,
    )))
}

/// The admin's "new key" for any entrant.
async fn admin_entrant_key(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(id): AppPath<i64>,
    request: Request,
) -> PageResult {
    read_token_form(&state, &visitor, request).await?;
    visitor.caller.require_admin()?;
    new_entrant_key(&state, &visitor, id, "/admin#entrants").await
}

/// The admin's "new key" for an organiser.
async fn admin_organiser_key(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(id): AppPath<i64>,
    request: Request,
) -> PageResult {
    read_token_form(&state, &visitor, request).await?;
    let name = state
        .storage
        .organiser_name(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no organiser {id}")))?;
    let new = super::super::invites::new_organiser_key(&state, &visitor.caller, id).await?;
    Ok(no_store(account::handed_over(
        &format!("organiser {name}"),
        &name,
        &new.key,
        "/admin",
    )))
}
