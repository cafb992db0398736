//! The leaderboard: rank, mean score (a did-not-finish counts as 1000), finish rate, mean
//! ratio of score to the maze's optimum, matches played.

use axum::extract::State;
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
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

/// One bot's line.
#[derive(Debug, Serialize, ToSchema)]
pub struct StandingView {
    /// 1 is best.
    pub rank: i64,
    /// Bot id.
    pub bot_id: i64,
    /// Bot name.
    pub name: String,
    /// The version counted.
    pub version: i64,
    /// Matches played.
    pub played: i64,
    /// Matches finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000.
    pub mean_score: f64,
    /// Finished / played.
    pub finish_rate: f64,
    /// Mean of score / the maze's optimum.
    pub mean_ratio: Option<f64>,
}

impl From<Standing> for StandingView {
    fn from(s: Standing) -> Self {
        StandingView {
            rank: s.rank,
            bot_id: s.bot_id,
            name: s.name,
            version: s.version,
            played: s.played,
            finished: s.finished,
            mean_score: s.mean_score,
            finish_rate: s.finish_rate,
            mean_ratio: s.mean_ratio,
        }
    }
}

/// The standings, best mean score first.
#[utoipa::path(get, path = "/api/leaderboard", tag = "leaderboard",
    params(LeaderboardQuery),
    responses((status = 200, body = [StandingView]), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
async fn get_leaderboard(
    State(state): State<AppState>,
    AppQuery(q): AppQuery<LeaderboardQuery>,
) -> ApiResult<axum::Json<Vec<StandingView>>> {
    let scope = match (q.tournament, q.scope.as_deref()) {
        (Some(id), None) => {
            if state.storage.get_tournament(id).await?.is_none() {
                return Err(ApiError::NotFound(format!("no tournament {id}")));
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
    Ok(axum::Json(rows.into_iter().map(Into::into).collect()))
}
