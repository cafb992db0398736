//! Competitions: created and edited by organisers (and the admin), entered by entrants
//! (their key), ranked by the server's clock, with a public and a private leaderboard,
//! "my submissions" for an entrant, and the final results (JSON and CSV).
//!
//! What is sealed stays sealed for anyone but the admin and the organisers: the private
//! board before the close; the private set's and final run's tournaments and matches
//! (not found) until the close and the results; the seeds until the results.

use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::IntoResponse;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::{Caller, hash_token, new_token};
use super::error::{ApiError, ApiResult, AppJson, AppPath, AppQuery, ErrorBody};
use crate::competition::{Limits, MazeText, Phase, Quota, Rule, Spec, Timestamp};
use crate::registry::competitions::{self as ops, Board, BoardKind, BoardLine, Patch};
use crate::storage::competitions::{CompetitionRow, ResultRow};
use crate::storage::entrants::EntrantRow;
use crate::storage::leaderboard::Scope;
use crate::storage::now_ms;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_organiser))
        .routes(routes!(list_competitions, create_competition))
        .routes(routes!(get_competition, edit_competition))
        .routes(routes!(enter))
        .routes(routes!(leaderboard))
        .routes(routes!(submissions))
        .routes(routes!(choose))
        .routes(routes!(results))
        .routes(routes!(results_csv))
        .routes(routes!(create_rejudge, list_rejudges))
        .routes(routes!(export))
}

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
async fn create_rejudge(
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
async fn list_rejudges(
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
async fn export(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::response::Response> {
    export_archive(&state, &caller, &name).await
}

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
async fn create_organiser(
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

/// A competition's maze as anyone sees it: a practice maze by id (its layout is public);
/// a ranking maze by name only (organisers also see its id and hash).
#[derive(Debug, Serialize, ToSchema)]
pub struct MazeLine {
    /// `practice`, `public` or `private`.
    pub set: String,
    /// Its name.
    pub name: String,
    /// Its id (practice mazes; every maze for organisers, or once revealed).
    pub maze_id: Option<i64>,
    /// SHA-256 of its canonical text (the same).
    pub hash: Option<String>,
}

/// A competition as the caller may see it.
#[derive(Debug, Serialize, ToSchema)]
pub struct CompetitionView {
    /// Short unique name (in addresses).
    pub name: String,
    /// Title.
    pub title: String,
    /// Description (text).
    pub description: String,
    /// Rules (text).
    pub rules: String,
    /// `default` (the server's ranking) or `competition`.
    pub kind: String,
    /// Where it stands now.
    pub phase: Phase,
    /// `final` once the results are written; `final_run` while the final run plays.
    pub state: Option<String>,
    /// Opening.
    pub opens_at: Option<Timestamp>,
    /// When the public board freezes.
    pub freezes_at: Option<Timestamp>,
    /// Close.
    pub closes_at: Option<Timestamp>,
    /// Matches per version per ranking maze.
    pub repeats: i64,
    /// The final run's matches per selected version per private maze (0: as many as
    /// `repeats`).
    pub final_repeats: i64,
    /// Versions per entrant per 24 hours.
    pub versions_per_day: i64,
    /// Practice matches per entrant per 24 hours.
    pub practice_per_day: i64,
    /// The final selection rule.
    pub selection: String,
    /// With `choice`: the most versions an entrant may choose.
    pub max_selected: i64,
    /// Whether the private mazes are shown with the results.
    pub reveal_private_mazes: bool,
    /// Whether the results wait for an organiser to publish them (`state` is `held`
    /// from when they are written until then).
    pub hold_results: bool,
    /// How each new version is checked before it plays: `start` (invalid only for a
    /// failure that no maze causes), `match` (invalid for any failure in its validation
    /// match) or `off`.
    pub validation: String,
    /// The match limits (those left out are the server's).
    pub limits: Limits,
    /// The longest one of its matches may last, in wall-clock ms (null without time
    /// limits): twice the CPU time its limits allow (startup, 999 moves and the time
    /// bank), and 10 s more. A bot that waits instead of thinking is stopped there
    /// (`timeout`, limit `match_wall_clock`); one that thinks is not while it gets half
    /// a core.
    pub match_wall_clock_ms: Option<u64>,
    /// Its mazes.
    pub mazes: Vec<MazeLine>,
    /// Entrants with a bot in it.
    pub entrants: usize,
    /// The secret seeds (organisers; everyone once the results are final).
    pub seeds: Option<Vec<i64>>,
    /// The public set's tournament (its matches show how each went, not the scores).
    pub public_tournament_id: Option<i64>,
    /// Its own invite code, for its organisers (none: it has none, or the caller is not
    /// one of them).
    pub invite_code: Option<String>,
    /// The competition's link that carries its invite code (a path on this server), for
    /// its organisers: give it to the class.
    pub invite_link: Option<String>,
    /// After the close: how far the final run (the private set's only run) has played,
    /// for the competition's organisers, and for everyone once the results are written
    /// (while it plays, `state` is `final_run`).
    pub final_run: Option<ops::RunProgress>,
}

/// Competition `c` as `caller` may see it.
pub(super) async fn view(
    state: &AppState,
    c: &CompetitionRow,
    caller: &Caller,
) -> ApiResult<CompetitionView> {
    let now = now_ms();
    let timeline = ops::timeline(c);
    let organiser = caller.organises(c);
    let revealed = c.state.as_deref() == Some("final") && c.reveal_private_mazes;
    let mazes = state
        .storage
        .competition_mazes(c.competition_id)
        .await?
        .into_iter()
        .map(|m| {
            let shown =
                organiser || m.maze_set == "practice" || (revealed && m.maze_set == "private");
            MazeLine {
                set: m.maze_set,
                name: m.name,
                maze_id: shown.then_some(m.maze_id),
                hash: shown.then_some(m.hash),
            }
        })
        .collect();
    let seeds = (organiser || c.state.as_deref() == Some("final")).then(|| c.seed_list());
    Ok(CompetitionView {
        name: c.name.clone(),
        title: c.title.clone(),
        description: c.description.clone(),
        rules: c.rules.clone(),
        kind: c.kind.clone(),
        phase: ops::phase(c, now),
        state: c.state.clone(),
        opens_at: c.opens_at.map(Timestamp),
        freezes_at: timeline.and_then(|t| t.frozen_from()).map(Timestamp),
        closes_at: c.closes_at.map(Timestamp),
        repeats: c.repeats,
        final_repeats: c.final_repeats,
        versions_per_day: c.versions_per_day,
        practice_per_day: c.practice_per_day,
        selection: c.selection.clone(),
        max_selected: c.max_selected,
        reveal_private_mazes: c.reveal_private_mazes,
        hold_results: c.hold_results,
        validation: c.validation.clone(),
        limits: c.limit_set(),
        match_wall_clock_ms: c
            .limit_set()
            .apply(crate::runner::Limits::default())
            .match_wall_clock()
            .map(|d| d.as_millis() as u64),
        mazes,
        entrants: state
            .storage
            .competition_entries(c.competition_id)
            .await?
            .len(),
        seeds,
        public_tournament_id: c.public_tournament_id,
        final_run: ops::progress_for(c, ops::final_progress(&state.storage, c).await?, organiser),
        invite_code: c.invite_code.clone().filter(|_| organiser),
        invite_link: c
            .invite_code
            .as_deref()
            .filter(|_| organiser)
            .map(|code| crate::registry::invites::link(c, code)),
    })
}

pub(crate) async fn find(state: &AppState, name: &str) -> ApiResult<CompetitionRow> {
    state
        .storage
        .get_competition(name)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no competition {name:?}")))
}

/// The competitions, the server's default ranking first.
#[utoipa::path(get, path = "/api/competitions", tag = "competitions",
    responses((status = 200, body = [CompetitionView])))]
async fn list_competitions(
    State(state): State<AppState>,
    caller: Caller,
) -> ApiResult<axum::Json<Vec<CompetitionView>>> {
    let mut out = Vec::new();
    for c in state.storage.list_competitions().await? {
        out.push(view(&state, &c, &caller).await?);
    }
    Ok(axum::Json(out))
}

/// Create a competition (organisers and the admin): its settings and its three maze
/// sets, each maze given by its text (numeric or ASCII format). It belongs to the
/// organiser who made it (the admin's, if the admin did).
#[utoipa::path(post, path = "/api/competitions", tag = "competitions",
    request_body = Spec<MazeText>, security(("bearer" = [])),
    responses((status = 201, body = CompetitionView), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
async fn create_competition(
    State(state): State<AppState>,
    caller: Caller,
    AppJson(spec): AppJson<Spec<MazeText>>,
) -> ApiResult<(StatusCode, axum::Json<CompetitionView>)> {
    let c = create(&state, &caller, spec).await?;
    Ok((
        StatusCode::CREATED,
        axum::Json(view(&state, &c, &caller).await?),
    ))
}

/// Creates a competition for `caller` (an organiser or the admin): the API's and the
/// organiser page's one way.
///
/// # Errors
/// Not an organiser; a bad competition or maze; a taken name.
pub(crate) async fn create(
    state: &AppState,
    caller: &Caller,
    spec: Spec<MazeText>,
) -> ApiResult<CompetitionRow> {
    caller.require_organiser()?;
    let owner = match caller {
        Caller::Organiser(id) => Some(*id),
        _ => None,
    };
    Ok(ops::create(&state.storage, spec, owner).await?)
}

/// A competition: timeline, phase, rules, mazes (ranking mazes by name only).
#[utoipa::path(get, path = "/api/competitions/{name}", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, body = CompetitionView), (status = 404, body = ErrorBody)))]
async fn get_competition(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<CompetitionView>> {
    let c = find(&state, &name).await?;
    Ok(axum::Json(view(&state, &c, &caller).await?))
}

/// Edit a competition (its organiser and the admin; `organiser`, which hands it to
/// another organiser, the admin only). Once open its opening stays; once closed only
/// its texts change. A close moved to now (or earlier) closes it now.
#[utoipa::path(patch, path = "/api/competitions/{name}", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    request_body = Patch, security(("bearer" = [])),
    responses((status = 200, body = CompetitionView), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody), (status = 422, body = ErrorBody)))]
async fn edit_competition(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppJson(patch): AppJson<Patch>,
) -> ApiResult<axum::Json<CompetitionView>> {
    let c = edit(&state, &caller, &name, patch).await?;
    Ok(axum::Json(view(&state, &c, &caller).await?))
}

/// Edits competition `name` for `caller` (its organiser or the admin): the API's and
/// the organiser page's one way.
///
/// # Errors
/// Not its organiser; a change too late or out of range.
pub(crate) async fn edit(
    state: &AppState,
    caller: &Caller,
    name: &str,
    patch: Patch,
) -> ApiResult<CompetitionRow> {
    let c = find(state, name).await?;
    caller.require_organiser_of(&c)?;
    if patch.organiser.is_some() {
        caller.require_admin()?;
    }
    let c = ops::edit(&state.storage, c, patch, now_ms()).await?;
    // A close moved to now is acted on at once by the competitions' clock.
    state.wake.notify_waiters();
    Ok(c)
}

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
async fn enter(
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

/// Which board.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct BoardQuery {
    /// `public` (default) or `private`.
    pub board: Option<BoardKind>,
}

/// A leaderboard of the competition: `public` (the public ranking set; frozen before
/// the close if the competition says so) or `private` (the final run's, played after
/// the close: sealed until the results, for its organisers until the final run has
/// played; `final_run` says how far it is). Each entrant's latest version that has played all its
/// matches there.
#[utoipa::path(get, path = "/api/competitions/{name}/leaderboard", tag = "competitions",
    params(("name" = String, Path, description = "competition name"), BoardQuery),
    responses((status = 200, body = Board), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn leaderboard(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
    AppQuery(q): AppQuery<BoardQuery>,
) -> ApiResult<axum::Json<Board>> {
    let c = find(&state, &name).await?;
    let kind = q.board.unwrap_or(BoardKind::Public);
    if c.kind == "default" {
        return Ok(axum::Json(default_board(&state, &caller, kind).await?));
    }
    Ok(axum::Json(
        ops::board(&state.storage, &c, kind, caller.organises(&c), now_ms()).await?,
    ))
}

/// The default competition's board: the server's ranking (no private set).
pub(super) async fn default_board(
    state: &AppState,
    caller: &Caller,
    kind: BoardKind,
) -> ApiResult<Board> {
    if kind == BoardKind::Private {
        return Err(ApiError::NotFound(
            "the default competition has no private set".into(),
        ));
    }
    let rows = state.storage.leaderboard(Scope::Ranking).await?;
    let rows = super::leaderboard::settled_for_caller(state, Scope::Ranking, rows, caller).await?;
    Ok(Board {
        board: kind,
        sealed: false,
        frozen_at: None,
        final_run: None,
        final_run_playing: false,
        standings: rows
            .into_iter()
            .map(|r| BoardLine {
                rank: r.rank,
                entrant: String::new(),
                bot_id: r.bot_id,
                bot_name: r.name,
                version: r.version,
                played: r.played,
                finished: r.finished,
                mean_score: r.mean_score,
                score_sum30: r.score_sum30,
                finish_rate: r.finish_rate,
                uncertainty: r.uncertainty,
            })
            .collect(),
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
async fn submissions(
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
async fn choose(
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

/// The final results.
#[derive(Debug, Serialize, ToSchema)]
pub struct ResultsView {
    /// The competition.
    pub competition: String,
    /// When they were written.
    pub finalized_at: Timestamp,
    /// The referee version that wrote them.
    pub referee: String,
    /// Whether every row equals a recount from the match records now.
    pub recount_equal: bool,
    /// One row per entrant, best first.
    pub results: Vec<ResultRow>,
}

async fn final_results(
    state: &AppState,
    caller: &Caller,
    name: &str,
) -> ApiResult<(CompetitionRow, Vec<ResultRow>)> {
    let c = find(state, name).await?;
    let held = c.state.as_deref() == Some("held");
    if held && !caller.organises(&c) {
        return Err(ApiError::Conflict(format!(
            "the results of competition {} are held by its organisers until the reveal",
            c.name
        )));
    }
    if c.state.as_deref() != Some("final") && !held {
        let progress = ops::final_progress(&state.storage, &c).await?;
        return Err(ApiError::Conflict(match (c.closes_at, progress) {
            (_, Some(_)) => format!(
                "the final run of competition {} is playing; the results come when it has played",
                c.name
            ),
            (Some(t), None) => format!(
                "the results of competition {} come after its close ({}) and its final run",
                c.name,
                Timestamp(t).words()
            ),
            (None, None) => "the default competition has no final results".into(),
        }));
    }
    let rows = ops::results(&state.storage, &c).await?;
    Ok((c, rows))
}

/// The final results (after the close and the final run): one row per entrant with its
/// manifest (bundle hash, referee version, maze hashes, seeds, limits, recount).
#[utoipa::path(get, path = "/api/competitions/{name}/results", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, body = ResultsView), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
async fn results(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<axum::Json<ResultsView>> {
    let (c, rows) = final_results(&state, &caller, &name).await?;
    let differ = ops::recount_differences(&state.storage, &c).await?;
    Ok(axum::Json(ResultsView {
        competition: c.name.clone(),
        finalized_at: Timestamp(c.finalized_at.unwrap_or(0)),
        referee: crate::runner::ENGINE_VERSION.to_string(),
        recount_equal: differ.is_empty(),
        results: rows,
    }))
}

/// The final results as CSV (one row per entrant).
#[utoipa::path(get, path = "/api/competitions/{name}/results.csv", tag = "competitions",
    params(("name" = String, Path, description = "competition name")),
    responses((status = 200, content_type = "text/csv", body = String), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody)))]
async fn results_csv(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(name): AppPath<String>,
) -> ApiResult<impl IntoResponse> {
    let (_, rows) = final_results(&state, &caller, &name).await?;
    Ok((
        [(header::CONTENT_TYPE, "text/csv; charset=utf-8")],
        ops::results_csv(&rows),
    ))
}
