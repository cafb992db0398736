//! The leaderboard page at `/`: the ranking on hidden mazes once they have been played
//! on, else the standings over all mazes, with the latest tournament beside it.

use axum::extract::State;
use axum::response::{Html, IntoResponse, Redirect, Response};
use serde::Deserialize;

use super::super::AppState;
use super::super::auth::Caller;
use super::super::error::{ApiError, ApiResult, AppQuery};
use super::super::leaderboard::settled_for_caller;
use super::RECENT;
use crate::storage::leaderboard::{Scope, Standing};
use crate::storage::matches::lists::Page;
use crate::web::pages::{self as web, SortKey, StandingsSection};

/// Query of `/`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoardQuery {
    scope: Option<String>,
    tournament: Option<i64>,
    sort: Option<String>,
}

pub(super) async fn leaderboard_page(
    State(state): State<AppState>,
    AppQuery(q): AppQuery<BoardQuery>,
) -> ApiResult<Response> {
    let sort = match q.sort.as_deref() {
        None => SortKey::Rank,
        Some(s) => SortKey::parse(s).ok_or_else(|| {
            ApiError::BadRequest(format!(
                "unknown sort {s:?}: use rank, name, finish_rate, efficiency or played"
            ))
        })?,
    };
    let mazes = state.storage.list_mazes().await?;
    let hidden = mazes.iter().filter(|m| m.hidden).count();
    let (tournaments, _) = state
        .storage
        .list_tournaments(
            Page {
                offset: 0,
                limit: RECENT,
            },
            true,
        )
        .await?;
    let storage = &state.storage;
    let state = &state;
    let board = |scope| async move {
        settled_for_caller(
            state,
            scope,
            storage.leaderboard(scope).await?,
            &Caller::Anonymous,
        )
        .await
    };
    let (scope, rows) = match (q.tournament, q.scope.as_deref()) {
        (Some(_), Some(_)) => {
            return Err(ApiError::BadRequest(
                "give either `tournament` or `scope`, not both".into(),
            ));
        }
        (Some(id), None) => {
            let t = super::super::auth::Caller::Anonymous
                .tournament(state, id)
                .await?;
            // A competition's tournament: its standings are the competition's boards.
            if let Some(c) = t.competition_id {
                return match state.storage.get_competition_by_id(c).await? {
                    Some(c) => {
                        Ok(Redirect::to(&format!("/competitions/{}", c.name)).into_response())
                    }
                    None => Err(super::super::leaderboard::competition_standings_elsewhere(
                        state, id, c,
                    )
                    .await?),
                };
            }
            (Scope::Tournament(id), board(Scope::Tournament(id)).await?)
        }
        (None, Some("ranking")) => (Scope::Ranking, board(Scope::Ranking).await?),
        (None, Some("all")) => (Scope::All, board(Scope::All).await?),
        (None, Some(other)) => {
            return Err(ApiError::BadRequest(format!(
                "unknown scope {other:?}: use `ranking` or `all`"
            )));
        }
        // The default: the ranking once hidden mazes have been played on, else every maze.
        (None, None) => {
            let ranking = if hidden > 0 {
                board(Scope::Ranking).await?
            } else {
                Vec::new()
            };
            if ranking.is_empty() {
                (Scope::All, board(Scope::All).await?)
            } else {
                (Scope::Ranking, ranking)
            }
        }
    };
    let (heading, note, query) = match scope {
        Scope::Ranking => (
            "Ranking".to_string(),
            format!(
                "Each bot's latest version on the {hidden} hidden ranking maze(s). Mean score: run-1 steps + run-0 steps / 30, a match that did not finish counts as 1000; lower is better."
            ),
            "scope=ranking".to_string(),
        ),
        Scope::All => (
            "Standings over all mazes".to_string(),
            if hidden == 0 {
                "No hidden ranking maze yet: each bot's latest version over every maze. Mean score: run-1 steps + run-0 steps / 30, a match that did not finish counts as 1000; lower is better.".to_string()
            } else {
                "Each bot's latest version over every maze, public and hidden. Lower is better."
                    .to_string()
            },
            "scope=all".to_string(),
        ),
        Scope::Tournament(id) => {
            let name = tournaments
                .iter()
                .find(|t| t.tournament_id == id)
                .map_or_else(|| format!("tournament {id}"), |t| t.name.clone());
            (
                format!("Tournament: {name}"),
                "Every bot version in the tournament over its mazes. Lower is better.".into(),
                format!("tournament={id}"),
            )
        }
    };
    // The latest tournament outside the competitions (theirs are on their own pages).
    let latest = match (
        scope,
        tournaments.iter().find(|t| t.competition_id.is_none()),
    ) {
        (Scope::Tournament(_), _) | (_, None) => None,
        (_, Some(t)) => Some((
            t.clone(),
            section(
                String::new(),
                String::new(),
                board(Scope::Tournament(t.tournament_id)).await?,
                format!("tournament={}", t.tournament_id),
                SortKey::Rank,
            ),
        )),
    };
    let mut tabs = vec![
        (
            "Ranking (hidden mazes)".to_string(),
            "/?scope=ranking".to_string(),
            scope == Scope::Ranking,
        ),
        (
            "All mazes".to_string(),
            "/?scope=all".to_string(),
            scope == Scope::All,
        ),
    ];
    // Competitions have their own pages: a chip and their public board (as anyone sees
    // it there), not their tournaments' standings.
    let now = crate::storage::now_ms();
    let mut competitions = Vec::new();
    for c in state.storage.list_competitions().await? {
        if c.kind == "default" {
            continue;
        }
        let board = crate::registry::competitions::board(
            &state.storage,
            &c,
            crate::registry::competitions::BoardKind::Public,
            false,
            now,
        )
        .await?;
        tabs.push((c.title.clone(), format!("/competitions/{}", c.name), false));
        let phase = crate::registry::competitions::phase(&c, now);
        competitions.push(web::CompetitionBoard {
            name: c.name,
            title: c.title,
            phase: phase.as_str().to_string(),
            lines: board
                .standings
                .into_iter()
                .take(COMPETITION_LINES)
                .collect(),
        });
    }
    for t in tournaments
        .iter()
        .filter(|t| t.competition_id.is_none())
        .take(5)
    {
        tabs.push((
            t.name.clone(),
            format!("/?tournament={}", t.tournament_id),
            scope == Scope::Tournament(t.tournament_id),
        ));
    }
    Ok(Html(web::leaderboard(&web::LeaderboardPage {
        main: section(heading, note, rows, query, sort),
        latest,
        tabs,
        competitions,
        tournaments,
        mazes,
        runtimes: state.runtimes.as_ref().clone(),
    }))
    .into_response())
}

/// How many lines of each competition's public board the home page shows.
const COMPETITION_LINES: usize = 10;

pub(super) fn section(
    heading: String,
    note: String,
    mut rows: Vec<Standing>,
    query: String,
    sort: SortKey,
) -> StandingsSection {
    sort.sort(&mut rows);
    StandingsSection {
        heading,
        note,
        rows,
        query,
        sort,
    }
}
