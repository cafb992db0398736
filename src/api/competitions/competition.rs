//! A competition as a resource: listed, read as each caller may see it, created from
//! its file and edited.

use crate::api::AppState;
use crate::api::auth::Caller;
use crate::api::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use crate::competition::{Limits, MazeText, Phase, Spec, Timestamp};
use crate::registry::competitions::{self as ops, Patch};
use crate::storage::competitions::CompetitionRow;
use crate::storage::now_ms;
use axum::extract::State;
use axum::http::StatusCode;
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

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
pub(crate) async fn view(
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
pub(super) async fn list_competitions(
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
pub(super) async fn create_competition(
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
pub(super) async fn get_competition(
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
pub(super) async fn edit_competition(
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

/// Its routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(list_competitions, create_competition))
        .routes(routes!(get_competition, edit_competition))
}
