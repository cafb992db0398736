//! The participant's pages: `/login`, `/logout`, `/register`, `/me` (with its practice
//! button) and `/competitions/{name}/submit`. Each form goes through the operation the
//! API's route of the same purpose calls, with the same checks, quotas and messages.

use axum::extract::{Query, Request, State};
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Response};
use serde::Deserialize;

use super::super::AppState;
use super::super::auth::{Caller, hash_token};
use super::super::error::AppQuery;
use super::super::limits;
use super::super::session::{self, Visitor};
use super::forms::{
    PageError, PageResult, client_of, local_next, login_first, no_store, read_form,
    read_token_form, see_other,
};
use crate::storage::bots::build_status;
use crate::storage::matches::lists::{MatchFilter, Page};
use crate::web::pages::account;

/// How many of the visitor's latest matches "me" lists.
const MY_MATCHES: i64 = 20;

/// Query of `/login`.
#[derive(Debug, Deserialize)]
pub(super) struct NextQuery {
    next: Option<String>,
}

pub(super) async fn login_page(visitor: Visitor, Query(q): Query<NextQuery>) -> Response {
    let next = local_next(q.next.as_deref());
    if visitor.signed_in() {
        return see_other(&next, None);
    }
    Html(account::login(None, &next)).into_response()
}

/// A form that deals in keys: the sender's address (for the budget of wrong guesses),
/// whether the session cookie must be `Secure`, and the form.
async fn key_form<T: serde::de::DeserializeOwned>(
    state: &AppState,
    request: Request,
) -> PageResult<(Option<std::net::IpAddr>, bool, T)> {
    let client = client_of(&request);
    let secure = session::secure(state, request.headers());
    Ok((client, secure, read_form(state, request).await?))
}

/// A new session for the key `key_hash`: a session the browser had before (planted or
/// not) ends here. Returns its cookie.
async fn new_session(
    state: &AppState,
    visitor: &Visitor,
    key_hash: &str,
    secure: bool,
) -> PageResult<cookie::Cookie<'static>> {
    if let Some(old) = &visitor.session {
        state.storage.end_session(&old.hash).await?;
    }
    Ok(session::open(state, key_hash, secure).await?)
}

/// The login form.
#[derive(Debug, Deserialize)]
struct LoginForm {
    key: String,
    next: Option<String>,
}

pub(super) async fn login(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let (client, secure, form): (_, _, LoginForm) = key_form(&state, request).await?;
    let next = local_next(form.next.as_deref());
    let again = |message: &str| account::login(Some(message), &next);
    // A right key always logs in; a key nobody holds spends its address's budget of
    // guesses (api::limits), and past it is refused with 429 rather than 401.
    let key = form.key.trim();
    let key_hash = hash_token(key);
    if key.is_empty() || !session::known_key(&state, &key_hash).await? {
        if !key.is_empty() {
            limits::spend(&state, limits::Spend::WrongKey, client)
                .await
                .map_err(|e| PageError::from(e).with_page(again))?;
        }
        return Err(PageError::new(
            StatusCode::UNAUTHORIZED,
            "this key is not known on this server: check that you pasted all of it",
        )
        .with_page(again));
    }
    // A new session every time: a session the browser had before (planted or not)
    // ends here.
    let cookie = new_session(&state, &visitor, &key_hash, secure).await?;
    Ok(see_other(&next, Some(cookie)))
}

pub(super) async fn logout(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let secure = session::secure(&state, request.headers());
    read_token_form(&state, &visitor, request).await?;
    if let Some(s) = &visitor.session {
        state.storage.end_session(&s.hash).await?;
    }
    let gone = session::cookie(String::new(), secure, std::time::Duration::ZERO);
    Ok(see_other("/", Some(gone)))
}

/// The registration page's data, with the invite code `invite` a link carried: a
/// competition's (whose title the page shows), the server's, or a wrong one, which
/// spends the address's budget of guesses when `guess` (the page would otherwise tell
/// right codes from wrong ones for free).
async fn register_page_data(
    state: &AppState,
    invite: Option<&str>,
    guess: Option<Option<std::net::IpAddr>>,
) -> PageResult<account::RegisterPage> {
    let mode = state.storage.registration().await?;
    let mut p = account::RegisterPage {
        mode: super::super::entrants::registration_name(&mode).into(),
        ..Default::default()
    };
    let Some(code) = invite
        .map(str::trim)
        .filter(|c| !c.is_empty() && c.len() <= 128)
    else {
        return Ok(p);
    };
    p.invite = Some(code.to_string());
    let hash = hash_token(code);
    match state.storage.competition_by_invite(&hash).await? {
        Some(c)
            if crate::registry::competitions::phase(&c, crate::storage::now_ms()).is_closed() =>
        {
            p.invite_error = Some(format!(
                "{} has closed: its invite code registers no one now",
                c.title
            ));
        }
        Some(c) => p.competition = Some(c.title),
        None if matches!(&mode, crate::storage::entrants::Registration::Invite(h) if *h == hash) => {
        }
        None => {
            if let Some(client) = guess {
                limits::spend(state, limits::Spend::WrongInviteCode, client).await?;
            }
            p.invite_error = Some(
                "this invite code is not known on this server: check the link with your organiser"
                    .into(),
            );
        }
    }
    Ok(p)
}

/// The registration page's query: the invite code a link carries.
#[derive(Debug, Deserialize)]
pub(super) struct RegisterQuery {
    invite: Option<String>,
}

pub(super) async fn register_page(
    State(state): State<AppState>,
    AppQuery(q): AppQuery<RegisterQuery>,
    request: Request,
) -> PageResult<Html<String>> {
    let client = client_of(&request);
    let p = register_page_data(&state, q.invite.as_deref(), Some(client)).await?;
    Ok(Html(account::register(&p, None, "", "")))
}

/// The registration form: the fields of `POST /api/entrants` (members one per line).
#[derive(Debug, Deserialize)]
struct RegisterForm {
    name: String,
    #[serde(default)]
    members: String,
    invite_code: Option<String>,
}

pub(super) async fn register(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let (client, secure, form): (_, _, RegisterForm) = key_form(&state, request).await?;
    let p = register_page_data(&state, form.invite_code.as_deref(), None).await?;
    let body = super::super::entrants::EntrantRequest {
        name: form.name.trim().to_string(),
        members: form
            .members
            .lines()
            .map(str::trim)
            .filter(|m| !m.is_empty())
            .map(str::to_string)
            .collect(),
        invite_code: form.invite_code.filter(|c| !c.trim().is_empty()),
    };
    let created = super::super::entrants::register(&state, &Caller::Anonymous, client, body)
        .await
        .map_err(|e| {
            PageError::from(e)
                .with_page(|m| account::register(&p, Some(m), &form.name, &form.members))
        })?;
    let cookie = new_session(&state, &visitor, &hash_token(&created.key), secure).await?;
    Ok(key_page(
        account::registered(&created.name, &created.key, created.competition.as_deref()),
        cookie,
    ))
}

/// A page that shows a new key, with the new session's cookie; no cache keeps it.
fn key_page(html: String, cookie: cookie::Cookie<'static>) -> Response {
    let mut response = no_store(html);
    if let Ok(v) = axum::http::HeaderValue::from_str(&cookie.to_string()) {
        response
            .headers_mut()
            .append(axum::http::header::SET_COOKIE, v);
    }
    response
}

/// Who the caller is, in words, and its kind.
async fn who(state: &AppState, caller: &Caller) -> PageResult<(String, &'static str)> {
    Ok(match caller {
        Caller::Admin => ("the admin".into(), "admin"),
        Caller::Organiser(id) => (
            format!(
                "organiser {}",
                state
                    .storage
                    .organiser_name(*id)
                    .await?
                    .unwrap_or_else(|| id.to_string())
            ),
            "organiser",
        ),
        Caller::Token(hash) => match state.storage.entrant_by_key(hash).await? {
            Some(e) => (format!("entrant {}", e.name), "entrant"),
            None => ("a bot's owner".into(), "owner"),
        },
        Caller::Anonymous => ("nobody".into(), "anonymous"),
    })
}

pub(super) async fn me_page(State(state): State<AppState>, visitor: Visitor) -> PageResult {
    if let Some(r) = login_first(&visitor, "/me") {
        return Ok(r);
    }
    let page = me_data(&state, &visitor).await?;
    Ok(Html(account::me(&page)).into_response())
}

/// The "me" page's data for a signed-in `visitor`.
async fn me_data(state: &AppState, visitor: &Visitor) -> PageResult<account::MePage> {
    let caller = &visitor.caller;
    let (who, kind) = who(state, caller).await?;
    let owned = match caller {
        Caller::Token(hash) => state.storage.bots_owned_by(hash).await?,
        _ => Vec::new(),
    };
    let mut live = false;
    let mut bots = Vec::new();
    for (bot_id, name) in &owned {
        let mut versions = Vec::new();
        for v in state.storage.bot_versions(*bot_id).await?.into_iter().rev() {
            live |= v.build_status == build_status::BUILDING;
            versions.push(account::MyVersion {
                version: v.version,
                created_at: v.created_at,
                command: v.command,
                build_status: v.build_status,
                log: v.build_log,
            });
        }
        bots.push(account::MyBot {
            bot_id: *bot_id,
            name: name.clone(),
            versions,
        });
    }
    let mut competitions = Vec::new();
    if kind == "entrant" {
        let now = crate::storage::now_ms();
        for c in state.storage.list_competitions().await? {
            if c.kind != "competition" {
                continue;
            }
            let phase = crate::registry::competitions::phase(&c, now);
            let mine = super::super::competitions::my_submissions(state, caller, &c.name).await?;
            if phase.is_closed() && mine.bot_id.is_none() {
                continue;
            }
            live |= mine
                .versions
                .iter()
                .any(|v| v.status == "playing" || v.build_status == build_status::BUILDING);
            let practice_mazes = state
                .storage
                .competition_mazes(c.competition_id)
                .await?
                .into_iter()
                .filter(|m| m.maze_set == "practice")
                .map(|m| (m.maze_id, m.name))
                .collect();
            competitions.push(account::MyCompetition {
                name: c.name.clone(),
                title: c.title.clone(),
                phase: phase.as_str().to_string(),
                taking_part: !phase.is_closed(),
                bot_id: mine.bot_id,
                versions: mine
                    .versions
                    .into_iter()
                    .map(|v| account::MySubmission {
                        version: v.version,
                        build_status: v.build_status,
                        status: v.status,
                        public: v.public,
                    })
                    .collect(),
                versions_quota: mine.versions_quota,
                practice_quota: mine.practice_quota,
                practice_mazes,
                final_result: mine.final_result,
            });
        }
    }
    let mut matches = Vec::new();
    for (bot_id, _) in &owned {
        let filter = MatchFilter {
            bot_id: Some(*bot_id),
            hide_sealed: true,
            ..MatchFilter::default()
        };
        let page = Page {
            offset: 0,
            limit: MY_MATCHES,
        };
        matches.extend(state.storage.list_matches(&filter, page).await?.0);
    }
    matches.sort_by_key(|m| std::cmp::Reverse(m.match_id));
    matches.truncate(MY_MATCHES as usize);
    // The server's quotas on the visitor's uploads (an entrant's, or a bot owner's).
    let owner = match caller {
        Caller::Token(hash) => match state.storage.entrant_by_key(hash).await? {
            Some(e) => Some(crate::storage::owners::Owner::Entrant(e.entrant_id)),
            None if !owned.is_empty() => Some(crate::storage::owners::Owner::Token(hash.clone())),
            None => None,
        },
        _ => None,
    };
    let uploads_quota = match owner {
        Some(o) => {
            let since = crate::storage::now_ms() - crate::competition::DAY_MS;
            let usage = state.storage.owner_usage(&o, since).await?;
            crate::registry::owners::summary(&state.settings.owner_quotas, &usage)
        }
        None => None,
    };
    live |= matches
        .iter()
        .any(|m| matches!(m.status.to_string().as_str(), "queued" | "running"));
    let page = account::MePage {
        who,
        kind: kind.into(),
        csrf: visitor
            .session
            .as_ref()
            .map(|s| s.csrf.clone())
            .unwrap_or_default(),
        notice: None,
        competitions,
        bots,
        matches: matches.into_iter().map(super::line).collect(),
        live,
        uploads_quota,
        key_error: None,
    };
    Ok(page)
}

/// The practice button's form: the fields of `POST /api/matches`.
#[derive(Debug, Deserialize)]
struct PracticeForm {
    csrf: Option<String>,
    bot_id: i64,
    maze_id: i64,
}

pub(super) async fn practice(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let form: PracticeForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let queued = super::super::matches::queue_match(
        &state,
        &visitor.caller,
        super::super::matches::MatchRequest {
            bot_id: form.bot_id,
            maze_id: form.maze_id,
            seed: None,
        },
    )
    .await?;
    Ok(see_other(&format!("/matches/{}", queued.match_id), None))
}

/// The "replace my key" form: the current key, which the session alone does not prove.
#[derive(Debug, Deserialize)]
struct RotateForm {
    csrf: Option<String>,
    current_key: Option<String>,
}

pub(super) async fn rotate_key(
    State(state): State<AppState>,
    visitor: Visitor,
    request: Request,
) -> PageResult {
    let (client, secure, form): (_, _, RotateForm) = key_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let e = super::super::competitions::entrant(&state, &visitor.caller).await?;
    // A copied session cookie must not become a key of its own: replacing the key
    // asks for the key itself. A wrong one spends the address's budget of guesses.
    let current = form.current_key.as_deref().unwrap_or("").trim();
    let right = matches!(&visitor.caller, Caller::Token(hash) if !current.is_empty()
        && bool::from(subtle::ConstantTimeEq::ct_eq(hash_token(current).as_bytes(), hash.as_bytes())));
    if !right {
        let data = me_data(&state, &visitor).await?;
        let again = move |m: &str| {
            account::me(&account::MePage {
                key_error: Some(m.to_string()),
                ..data.clone()
            })
        };
        if !current.is_empty() {
            limits::spend(&state, limits::Spend::WrongKey, client)
                .await
                .map_err(|e| PageError::from(e).with_page(&again))?;
        }
        return Err(PageError::new(
            StatusCode::FORBIDDEN,
            "that is not your current key: paste the key you log in with to replace it (a lost key is replaced by the admin or your competition's organiser)",
        )
        .with_page(&again));
    }
    let new = super::super::entrants::rotate(&state, &visitor.caller, e.entrant_id).await?;
    // This session ended with the old key: the visitor goes on with a new one.
    let cookie = session::open(&state, &hash_token(&new.key), secure).await?;
    Ok(key_page(account::replaced(&e.name, &new.key), cookie))
}
