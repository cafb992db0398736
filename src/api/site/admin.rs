//! The admin's page (`/admin`): who may register, the organisers, the entrants; each
//! form goes through the operation the API's route of the same purpose calls.

use axum::Router;
use axum::extract::{Request, State};
use axum::response::{Html, IntoResponse};
use axum::routing::{get, post};
use serde::Deserialize;

use super::super::AppState;
use super::super::error::AppQuery;
use super::super::session::Visitor;
use super::forms::{PageError, PageResult, csrf, login_first, no_store, read_form, see_other};
use crate::web::pages::organise as web;

/// Their routes.
pub(super) fn router() -> Router<AppState> {
    Router::new()
        .route("/admin", get(admin_page))
        .route("/admin/registration", post(set_registration))
        .route("/admin/organisers", post(add_organiser))
}

/// How many entrants the admin page lists.
const ADMIN_ENTRANTS: i64 = 100;

async fn admin_data(
    state: &AppState,
    visitor: &Visitor,
    notice: Option<String>,
    new_key: Option<(String, String)>,
) -> PageResult<web::AdminPage> {
    admin_data_found(state, visitor, notice, new_key, "").await
}

async fn admin_data_found(
    state: &AppState,
    visitor: &Visitor,
    notice: Option<String>,
    new_key: Option<(String, String)>,
    search: &str,
) -> PageResult<web::AdminPage> {
    visitor.caller.require_admin()?;
    let mode = state.storage.registration().await?;
    let found =
        super::super::entrants::find_entrants(state, &visitor.caller, search, ADMIN_ENTRANTS)
            .await?;
    Ok(web::AdminPage {
        mode: super::super::entrants::registration_name(&mode).into(),
        organisers: state.storage.list_organisers().await?,
        csrf: csrf(visitor),
        notice,
        new_key,
        search: search.to_string(),
        entrants: found.items,
        entrants_total: found.total,
    })
}

/// The admin page's query: what the last form did.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AdminQuery {
    /// `registration`: the registration mode was set.
    done: Option<AdminDone>,
    /// The entrants' search.
    search: Option<String>,
}

/// What a form of the admin page did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum AdminDone {
    /// The registration mode was set.
    Registration,
}

async fn admin_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppQuery(q): AppQuery<AdminQuery>,
) -> PageResult {
    if let Some(r) = login_first(&visitor, "/admin") {
        return Ok(r);
    }
    let notice = match q.done {
        Some(AdminDone::Registration) => {
            let mode = state.storage.registration().await?;
            Some(format!(
                "Registration is now {}.",
                super::super::entrants::registration_name(&mode)
            ))
        }
        None => None,
    };
    let p = admin_data_found(
        &state,
        &visitor,
        notice,
        None,
        q.search.as_deref().unwrap_or("").trim(),
    )
    .await?;
    Ok(Html(web::admin(&p)).into_response())
}

/// The registration form: the fields of `PUT /api/registration`.
#[derive(Debug, Deserialize)]
struct RegistrationForm {
    csrf: Option<String>,
    mode: String,
    invite_code: Option<String>,
}

async fn set_registration(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let form: RegistrationForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let body = super::super::entrants::RegistrationMode {
        mode: form.mode,
        invite_code: form.invite_code.filter(|c| !c.trim().is_empty()),
    };
    match super::super::entrants::set_mode(&state, &visitor.caller, body).await {
        Ok(_) => Ok(see_other("/admin?done=registration", None)),
        Err(e) => {
            let e = PageError::from(e);
            let p = admin_data(&state, &visitor, Some(e.message().to_string()), None).await?;
            Err(e.with_page(|_| web::admin(&p)))
        }
    }
}

/// The new organiser form: the fields of `POST /api/organisers`.
#[derive(Debug, Deserialize)]
struct OrganiserForm {
    csrf: Option<String>,
    name: String,
}

async fn add_organiser(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let form: OrganiserForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let body = super::super::competitions::OrganiserRequest { name: form.name };
    match super::super::competitions::register_organiser(&state, &visitor.caller, body).await {
        Ok(o) => {
            let p = admin_data(&state, &visitor, None, Some((o.name, o.key))).await?;
            Ok(no_store(web::admin(&p)))
        }
        Err(e) => {
            let e = PageError::from(e);
            let p = admin_data(&state, &visitor, Some(e.message().to_string()), None).await?;
            Err(e.with_page(|_| web::admin(&p)))
        }
    }
}
