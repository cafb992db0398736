//! Entering a bot, an entrant's versions as it sees them, and its choice for the
//! final.

use super::competition::find;
use crate::api::AppState;
use crate::api::auth::Caller;
use crate::api::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use crate::competition::{Phase, Quota, Rule, Timestamp};
use crate::registry::competitions::{self as ops, BoardKind, BoardLine};
use crate::storage::entrants::EntrantRow;
use crate::storage::now_ms;
use axum::extract::State;
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// The entrant whose key the caller gave.
pub(crate) async fn entrant(state: &AppState, caller: &Caller) -> ApiResult<EntrantRow> {
    let none = || {
        ApiError::Unauthorized(
            "this needs an entrant's key (Authorization: Bearer KEY; POST /api/entrants gives one)"
                .into(),
        )
    };
    match caller {
        Caller::Token(hash) => state.storage.entrant_by_key(hash).await?.ok_or_else(none),
        Caller::Anonymous => Err(none()),
        _ => Err(ApiError::Forbidden("this needs an entrant's key".into())),
    }
}

/// A bot to enter.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct EntryRequest {
    /// One of the entrant's bots (registered with its key).
    pub bot_id: i64,
}

/// An entry.
#[derive(Debug, Serialize, ToSchema)]
pub struct EntryView {
    /// The competition.
    pub competition: String,
    /// The bot entered.
    pub bot_id: i64,
    /// The entrant.
    pub entrant: String,
}

/// Enter one of the entrant's bots (the entrant's key; one bot per entrant). Its latest
/// version and every later one are ranked automatically once the competition is open.
#[utoipa::path(post, path = "/api/competitions/{name}/entries", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = EntryRequest, security(("bearer" = [])),
    responses((status = 201, body = EntryView), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub(super) async fn enter(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(body): AppJson<EntryRequest>,
) -> ApiResult<(StatusCode, axum::Json<EntryView>)> {
    let entry = enter_bot(&state, &caller, &name, body.bot_id).await?;
    Ok((StatusCode::CREATED, axum::Json(entry)))
}

/// Enters bot `bot_id` of the caller's entrant in competition `name`: the API's and the
/// submission page's one way.
///
/// # Errors
/// No such competition or bot; not an entrant's key, or not its bot; closed.
pub(crate) async fn enter_bot(
    state: &AppState,
    caller: &Caller,
    name: &str,
    bot_id: i64,
) -> ApiResult<EntryView> {
    let c = find(state, name).await?;
    let e = entrant(state, caller).await?;
    if c.kind != "competition" {
        return Err(ApiError::Conflict(
            "the default competition needs no entry: every bot's latest version counts".into(),
        ));
    }
    if ops::phase(&c, now_ms()).is_closed() {
        return Err(ApiError::Conflict(format!(
            "competition {} closed at {}",
            c.name,
            Timestamp(c.closes_at.unwrap_or(0)).words()
        )));
    }
    let bot = state
        .storage
        .get_bot(bot_id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no bot {bot_id}")))?;
    if state.storage.entrant_of_bot(bot.bot_id).await? != Some(e.entrant_id) {
        return Err(ApiError::Forbidden(format!(
            "bot {} is not this entrant's (register it with the entrant's key)",
            bot.bot_id
        )));
    }
    state
        .storage
        .enter_competition(c.competition_id, bot.bot_id, e.entrant_id)
        .await?;
    Ok(EntryView {
        competition: c.name,
        bot_id: bot.bot_id,
        entrant: e.name,
    })
}

/// One of the entrant's versions.
#[derive(Debug, Serialize, ToSchema)]
pub struct SubmissionView {
    /// Its number.
    pub version: i64,
    /// Uploaded at.
    pub uploaded_at: Timestamp,
    /// `ready`, `building` or `build_failed`.
    pub build_status: String,
    /// `waiting` (not yet queued), `playing`, `ranked` (all its public matches
    /// played), `not_counted` (failed to build, or the server could not play it).
    pub status: String,
    /// Its public-ranking numbers, once all its public matches are played: its mean and
    /// the rank that mean has among the other entrants' lines of the public board as
    /// the entrant sees it (over hidden mazes: the means only, no interval).
    pub public: Option<BoardLine>,
    /// Chosen for the final (`choice` rule).
    pub chosen: bool,
    /// Taken by the final selection.
    pub selected: bool,
}

/// The entrant's submissions and quotas.
#[derive(Debug, Serialize, ToSchema)]
pub struct SubmissionsView {
    /// The competition.
    pub competition: String,
    /// The entrant.
    pub entrant: String,
    /// The bot entered (none yet: enter one).
    pub bot_id: Option<i64>,
    /// Versions, newest first.
    pub versions: Vec<SubmissionView>,
    /// The version quota now.
    pub versions_quota: Quota,
    /// The practice quota now.
    pub practice_quota: Quota,
    /// The competition's phase (`final` once the results are written).
    pub phase: Phase,
    /// The entrant's final result, once the results are written: its rank (shared by
    /// equal means), the version that counted and its numbers on the private set.
    pub final_result: Option<BoardLine>,
}

/// "My submissions": the entrant's versions (the entrant's key), their status, their own
/// public-ranking numbers once played, and the quotas ("2 of 5 versions used in the
/// last 24 hours; the next one at ...").
#[utoipa::path(get, path = "/api/competitions/{name}/submissions", tag = "competitions",
    params(("name" = String, Path, description = "competition name")), security(("bearer" = [])),
    responses((status = 200, body = SubmissionsView), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub(super) async fn submissions(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<SubmissionsView>> {
    Ok(axum::Json(my_submissions(&state, &caller, &name).await?))
}

/// The caller's entrant's submissions and quotas in competition `name`: the API's and
/// the "me" page's one way.
///
/// # Errors
/// No such competition; not an entrant's key.
pub(crate) async fn my_submissions(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<SubmissionsView> {
    let c = find(state, name).await?;
    let e = entrant(state, caller).await?;
    let now = now_ms();
    let entry = state
        .storage
        .competition_entries(c.competition_id)
        .await?
        .into_iter()
        .find(|x| x.entrant_id == e.entrant_id);
    let public = match c.public_tournament_id {
        Some(t) => state.storage.competition_board(t, false).await?,
        None => Vec::new(),
    };
    let pending_public = |id: i64| public.iter().any(|r| r.bot_version_id == id && r.pending);
    let shown = ops::board(&state.storage, &c, BoardKind::Public, false, now).await?;
    let ranked_line = |r: &crate::storage::competitions::BoardRow| {
        let mut line = BoardLine::from_row(r);
        let better = shown
            .standings
            .iter()
            .filter(|l| l.entrant != e.name && l.mean() < line.mean())
            .count() as i64;
        line.rank = better + 1;
        line.uncertainty = crate::ranking::withheld(&[(line.rank, line.mean())]).remove(0);
        line
    };
    let mut versions = Vec::new();
    for s in state.storage.submissions(&c, e.entrant_id).await? {
        let line = public
            .iter()
            .find(|r| r.bot_version_id == s.bot_version_id && !r.pending)
            .map(ranked_line);
        let status =
            if crate::storage::bots::build_status::never_plays(&s.build_status) || s.aborted {
                "not_counted"
            } else if line.is_some() {
                "ranked"
            } else if s.ranked || pending_public(s.bot_version_id) {
                "playing"
            } else {
                "waiting"
            };
        versions.push(SubmissionView {
            version: s.version,
            uploaded_at: Timestamp(s.created_at),
            build_status: s.build_status,
            status: status.to_string(),
            public: line,
            chosen: s.chosen,
            selected: s.selected,
        });
    }
    let final_result = if c.state.as_deref() == Some("final") {
        ops::results(&state.storage, &c)
            .await?
            .into_iter()
            .find(|r| r.entrant_id == e.entrant_id)
            .map(|r| BoardLine::from_result(&r))
    } else {
        None
    };
    Ok(SubmissionsView {
        competition: c.name.clone(),
        entrant: e.name.clone(),
        bot_id: entry.map(|x| x.bot_id),
        phase: ops::phase(&c, now),
        final_result,
        versions,
        versions_quota: ops::version_quota(&state.storage, &c, e.entrant_id, now).await?,
        practice_quota: ops::practice_quota(&state.storage, &c, e.entrant_id, now).await?,
    })
}

/// The versions an entrant chooses for the final.
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ChoiceRequest {
    /// Version numbers of the entered bot (at most the competition's `max_selected`).
    pub versions: Vec<i64>,
}

/// Choose the versions that count at the end (the entrant's key; competitions with the
/// `choice` rule; before the close).
#[utoipa::path(put, path = "/api/competitions/{name}/selection", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = ChoiceRequest, security(("bearer" = [])),
    responses((status = 204), (status = 400, body = ErrorBody), (status = 401, body = ErrorBody),
        (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub(super) async fn choose(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(body): AppJson<ChoiceRequest>,
) -> ApiResult<StatusCode> {
    let c = find(&state, &name).await?;
    let e = entrant(&state, &caller).await?;
    if Rule::parse(&c.selection) != Some(Rule::Choice) {
        return Err(ApiError::Conflict(format!(
            "competition {} selects by `{}`: there is nothing to choose",
            c.name, c.selection
        )));
    }
    if ops::phase(&c, now_ms()).is_closed() {
        return Err(ApiError::Conflict(format!(
            "competition {} is closed",
            c.name
        )));
    }
    if body.versions.len() > c.max_selected as usize {
        return Err(ApiError::BadRequest(format!(
            "at most {} versions may be chosen",
            c.max_selected
        )));
    }
    let mine = state.storage.submissions(&c, e.entrant_id).await?;
    let mut ids = Vec::new();
    for v in &body.versions {
        let s = mine
            .iter()
            .find(|s| s.version == *v && s.ranked)
            .ok_or_else(|| {
                ApiError::BadRequest(format!(
                    "version {v} is not one of this entrant's ranked versions"
                ))
            })?;
        ids.push(s.bot_version_id);
    }
    state
        .storage
        .choose_versions(&c, e.entrant_id, &ids)
        .await?;
    Ok(StatusCode::NO_CONTENT)
}

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(enter))
        .routes(routes!(submissions))
        .routes(routes!(choose))
}
