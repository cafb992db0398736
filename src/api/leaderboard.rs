//! The leaderboard: rank, mean score (a did-not-finish, `aborted` included, counts as
//! 1000), finish rate, mean ratio of score to the maze's optimum, matches played. For
//! non-admins the ratio is null whenever a hidden maze is counted: over one hidden maze
//! it would give the maze's optimum away.

use axum::extract::State;
use serde::Deserialize;
use utoipa::IntoParams;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppQuery, ErrorBody};
use crate::storage::leaderboard::{Scope, Standing};

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(get_leaderboard))
}

/// Which matches to count.
#[derive(Debug, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
pub struct LeaderboardQuery {
    /// Only this tournament's matches (per bot version in it).
    pub tournament: Option<i64>,
    /// Without a tournament: `ranking` (default; hidden mazes) or `all` (every maze);
    /// each bot's latest version.
    pub scope: Option<String>,
}

/// The standings, best mean score first.
#[utoipa::path(get, path = "/api/leaderboard", tag = "leaderboard",
    params(LeaderboardQuery),
    responses((status = 200, body = [Standing]), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody, description = "the tournament ranks for a competition: see its leaderboard")))]
async fn get_leaderboard(
    State(state): State<AppState>,
    caller: Caller,
    AppQuery(q): AppQuery<LeaderboardQuery>,
) -> ApiResult<axum::Json<Vec<Standing>>> {
    let scope = match (q.tournament, q.scope.as_deref()) {
        (Some(id), None) => {
            let t = caller.tournament(&state, id).await?;
            let organises = caller
                .organises_competition_of(&state, t.competition_id)
                .await?;
            if let Some(c) = t.competition_id.filter(|_| !organises) {
                return Err(competition_standings_elsewhere(&state, id, c).await?);
            }
            Scope::Tournament(id)
        }
        (Some(_), Some(_)) => {
            return Err(ApiError::BadRequest(
                "give either `tournament` or `scope`, not both".into(),
            ));
        }
        (None, None | Some("ranking")) => Scope::Ranking,
        (None, Some("all")) => Scope::All,
        (None, Some(other)) => {
            return Err(ApiError::BadRequest(format!(
                "unknown scope {other:?}: use `ranking` or `all`"
            )));
        }
    };
    let rows = state.storage.leaderboard(scope).await?;
    Ok(axum::Json(
        settled_for_caller(&state, scope, rows, &caller).await?,
    ))
}

/// The 409 for the standings of tournament `id`, which ranks for competition
/// `competition_id`: anyone but the organisers reads them on the competition's boards,
/// which apply its rules (settled versions only, the freeze, the private set sealed).
///
/// # Errors
/// Database failures.
pub(super) async fn competition_standings_elsewhere(
    state: &AppState,
    id: i64,
    competition_id: i64,
) -> ApiResult<ApiError> {
    let name = state
        .storage
        .get_competition_by_id(competition_id)
        .await?
        .map_or_else(|| competition_id.to_string(), |c| c.name);
    Ok(ApiError::Conflict(format!(
        "tournament {id} ranks for competition {name}: its standings are on \
         GET /api/competitions/{name}/leaderboard"
    )))
}

/// The standings of `scope` as `caller` may see them ([`for_caller`]), and for anyone
/// but the admin without the bot versions that still have a match on a hidden maze
/// queued or running (their numbers would move with each such match, showing its
/// result); ranked with their uncertainty among the lines shown.
///
/// # Errors
/// Database failures.
pub(super) async fn settled_for_caller(
    state: &AppState,
    scope: Scope,
    rows: Vec<Standing>,
    caller: &Caller,
) -> ApiResult<Vec<Standing>> {
    if caller.is_admin() {
        return Ok(state.ranker.rank(&state.storage, scope, rows).await?);
    }
    let pending: std::collections::HashSet<(i64, i64)> = state
        .storage
        .versions_pending_on_hidden_mazes()
        .await?
        .into_iter()
        .collect();
    let kept: Vec<Standing> = rows
        .into_iter()
        .filter(|r| !pending.contains(&(r.bot_id, r.version)))
        .collect();
    // Ranked among the lines shown.
    let kept = state.ranker.rank(&state.storage, scope, kept).await?;
    Ok(for_caller(kept, caller))
}

/// A tournament's standings as `caller` may see them, and whether they are sealed:
/// while a tournament with hidden mazes is not complete, anyone but the admin gets no
/// standings (each match's result would show as the change in its bot's mean); a
/// competition's tournament (`in_competition`) shows its standings to the admin and
/// that competition's organiser (`organises`) only (everyone else reads them on the competition's boards, under its
/// rules: the freeze, the private set sealed).
pub(super) fn tournament_for_caller(
    rows: Vec<Standing>,
    caller: &Caller,
    complete: bool,
    in_competition: bool,
    organises: bool,
) -> (Vec<Standing>, bool) {
    let sealed = if in_competition {
        !organises
    } else {
        !caller.is_admin() && !complete && rows.iter().any(|r| r.hidden_played > 0)
    };
    if sealed {
        (Vec::new(), true)
    } else {
        (for_caller(rows, caller), false)
    }
}

/// The standings as `caller` may see them: without the score/optimum ratio of a bot
/// whose counted matches include a hidden maze, and with the uncertainty withheld
/// ([`crate::ranking::withheld`]) where any line counts a hidden maze, unless the
/// caller is the admin.
pub(super) fn for_caller(mut rows: Vec<Standing>, caller: &Caller) -> Vec<Standing> {
    if !caller.is_admin() {
        for row in rows.iter_mut().filter(|r| r.hidden_played > 0) {
            row.mean_ratio = None;
        }
        // Intervals, rank ranges and tie groups over hidden matches would tell single
        // matches (crate::ranking, "Hidden matches"): the means and ranks only.
        if rows.iter().any(|r| r.hidden_played > 0) {
            crate::registry::rankings::withhold_lines(
                &mut rows,
                |r| r.rank,
                Standing::mean,
                |r, u| r.uncertainty = u,
            );
        }
    }
    rows
}
