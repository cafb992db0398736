//! The site's handlers: the server's web pages (HTML) and forms, thin handlers that fetch what a page shows, apply the
//! hidden-maze rules (a hidden maze's layout, replay and failure text never appear in a
//! page), and call `web::pages`. Pages never take a token: a visitor is anonymous, or
//! signed in with a browser session ([`super::session`]), which acts as the key that
//! opened it. Bad ids and query strings of the reading pages get the API's JSON errors;
//! the forms (`account`, `organise`) answer every error as a page.

use std::collections::BTreeMap;

use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::{get, post};
use serde::Deserialize;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppPath, AppQuery};
use super::leaderboard::tournament_for_caller;
use super::lists::{MatchListQuery, page};
use crate::engine::{mazefile, render, solver};
use crate::runner::{MatchRecord, MatchState, MatchStatus};
use crate::storage::leaderboard::Scope;
use crate::storage::matches::MatchRow;
use crate::storage::matches::lists::{MatchCount, MatchFilter, Page};
use crate::web::pages::{self as web, MatchLine, MatchPager, Pager, SortKey};
use crate::web::viewer::ViewerData;

mod account;
mod admin;
mod board;
mod class;
mod competitions;
mod finale;
mod forms;
mod organise;
mod submit;

/// How many tournaments the leaderboard lists, and recent matches a bot or maze page.
const RECENT: i64 = 20;

/// The page routes.
pub(super) fn router() -> Router<AppState> {
    Router::new()
        .route("/", get(board::leaderboard_page))
        .route("/bots", get(bots_page))
        .route("/bots/{id}", get(bot_page))
        .route("/mazes", get(mazes_page))
        .route("/mazes/{id}", get(maze_page))
        .route("/matches", get(matches_page))
        .route("/matches/{id}", get(match_page))
        .route("/competitions", get(competitions::competitions_page))
        .route("/competitions/{name}", get(competitions::competition_page))
        .route("/tournaments", get(tournaments_page))
        .route("/tournaments/{id}", get(tournament_page))
        .route("/workers", get(workers_page))
        .route("/favicon.svg", get(favicon))
        .route("/favicon.ico", get(favicon))
        .route("/api", get(api_page))
        .route("/login", get(account::login_page).post(account::login))
        .route("/logout", post(account::logout))
        .route(
            "/register",
            get(account::register_page).post(account::register),
        )
        .route("/me", get(account::me_page))
        .route("/me/practice", post(account::practice))
        .route("/me/key", post(account::rotate_key))
        .route(
            "/competitions/{name}/submit",
            get(submit::submit_page).post(submit::submit).layer(
                axum::extract::DefaultBodyLimit::max(super::MAX_UPLOAD_BYTES),
            ),
        )
        .merge(organise::router())
        .merge(admin::router())
        .merge(finale::router())
        .merge(class::router())
        .layer(axum::middleware::from_fn(super::session::refuse_cross_site))
}

/// The API's routes as a page: each path and method with its summary, from the OpenAPI
/// document the handlers generate.
async fn api_page() -> Html<String> {
    let doc = super::openapi();
    let mut routes = Vec::new();
    for (path, item) in &doc.paths.paths {
        for (method, op) in [
            ("GET", &item.get),
            ("POST", &item.post),
            ("PUT", &item.put),
            ("PATCH", &item.patch),
            ("DELETE", &item.delete),
        ] {
            if let Some(op) = op {
                let text = op
                    .description
                    .clone()
                    .or_else(|| op.summary.clone())
                    .unwrap_or_default();
                let auth = op.security.as_ref().is_some_and(|s| !s.is_empty());
                routes.push(web::ApiRoute {
                    method,
                    path: path.clone(),
                    text,
                    auth,
                });
            }
        }
    }
    Html(web::api_routes(&routes))
}

/// The site's icon (an SVG, also for browsers that ask for `/favicon.ico`).
async fn favicon() -> impl axum::response::IntoResponse {
    (
        [
            (axum::http::header::CONTENT_TYPE, "image/svg+xml"),
            (axum::http::header::CACHE_CONTROL, "public, max-age=86400"),
        ],
        crate::web::FAVICON_SVG,
    )
}

async fn bots_page(State(state): State<AppState>) -> ApiResult<Html<String>> {
    Ok(Html(web::bots(&state.storage.list_bots().await?)))
}

async fn mazes_page(State(state): State<AppState>) -> ApiResult<Html<String>> {
    Ok(Html(web::mazes(&state.storage.list_mazes().await?)))
}

/// A match as a line of a page.
fn line(row: MatchRow) -> MatchLine {
    MatchLine {
        reason: public_reason(&row),
        row: row.redacted(),
    }
}

/// The latest [`RECENT`] matches that pass `filter`, as lines, and how many pass it.
async fn recent_matches(
    state: &AppState,
    mut filter: MatchFilter,
) -> ApiResult<(Vec<MatchLine>, MatchCount)> {
    filter.hide_sealed = true;
    let page = Page {
        offset: 0,
        limit: RECENT,
    };
    let (rows, count) = state.storage.list_matches(&filter, page).await?;
    Ok((rows.into_iter().map(line).collect(), count))
}

/// A failure's reason as anyone may see it: on a hidden maze nothing but that it failed
/// (the text, and even the step, could carry what the bot sensed).
fn public_reason(row: &MatchRow) -> Option<String> {
    let error = row.summary().error?;
    let step = error.step;
    if row.maze_hidden {
        return Some(
            "failed (hidden maze: its status is the kind of failure; details for the admin only)"
                .into(),
        );
    }
    let reason = error.reason.as_str();
    Some(match step {
        Some(s) if !reason.contains(&format!("step {s}")) => format!("step {s}: {reason}"),
        _ => reason.to_string(),
    })
}

async fn bot_page(
    State(state): State<AppState>,
    visitor: super::session::Visitor,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Html<String>> {
    let bot = state
        .storage
        .get_bot(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no bot {id}")))?;
    let mut versions = state.storage.bot_versions(id).await?;
    versions.reverse();
    let (recent, total_matches) = recent_matches(
        &state,
        MatchFilter {
            bot_id: Some(id),
            hide_sealed: true,
            ..MatchFilter::default()
        },
    )
    .await?;
    let owner = visitor.signed_in() && visitor.caller.owns(&state, id).await?;
    Ok(Html(web::bot(&web::BotPage {
        bot,
        versions,
        recent,
        total_matches,
        owner,
    })))
}

async fn maze_page(
    State(state): State<AppState>,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Html<String>> {
    let m = super::mazes::find_maze(&state, id).await?;
    let svg = if m.hidden {
        None
    } else {
        mazefile::parse(m.layout.as_bytes()).ok().map(|maze| {
            let path = solver::solve(&maze).map(|s| s.path);
            render::svg(&maze, path.as_deref())
        })
    };
    let (lines, _) = recent_matches(
        &state,
        MatchFilter {
            maze_id: Some(id),
            hide_sealed: true,
            ..MatchFilter::default()
        },
    )
    .await?;
    Ok(Html(web::maze(&m, svg.as_deref(), &lines)))
}

async fn matches_page(
    State(state): State<AppState>,
    AppQuery(q): AppQuery<MatchListQuery>,
) -> ApiResult<Html<String>> {
    let (filter, page) = q.parse()?;
    let (rows, count) = state.storage.list_matches(&filter, page).await?;
    let next_before = super::lists::next_before(&rows, page);
    let mut parts = Vec::new();
    let mut query = Vec::new();
    if let Some(b) = filter.bot_id {
        let name = state.storage.get_bot(b).await?.map(|bot| bot.name);
        parts.push(format!("bot {}", name.unwrap_or(b.to_string())));
        query.push(format!("bot_id={b}"));
    }
    if let Some(t) = filter.tournament_id {
        parts.push(format!("tournament {t}"));
        query.push(format!("tournament_id={t}"));
    }
    if let Some(m) = filter.maze_id {
        let name = state.storage.get_maze(m).await?.map(|maze| maze.name);
        parts.push(format!("maze {}", name.unwrap_or(m.to_string())));
        query.push(format!("maze_id={m}"));
    }
    if let Some(s) = &filter.status {
        parts.push(format!("status {s}"));
        query.push(format!("status={s}"));
    }
    let lines: Vec<MatchLine> = rows.into_iter().map(line).collect();
    let pager = MatchPager {
        base: if query.is_empty() {
            "/matches".into()
        } else {
            format!("/matches?{}", query.join("&"))
        },
        limit: page.limit,
        count,
        first_page: filter.before.is_none() && page.offset == 0,
        next_before,
    };
    let filters = if parts.is_empty() {
        String::new()
    } else {
        format!("Matches of {}.", parts.join(", "))
    };
    Ok(Html(web::matches(&lines, &filters, &pager)))
}

async fn match_page(
    State(state): State<AppState>,
    visitor: super::session::Visitor,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Html<String>> {
    let row = state
        .storage
        .get_match(id)
        .await?
        .filter(|m| !m.sealed)
        .ok_or_else(|| ApiError::NotFound(format!("no match {id}")))?;
    let hidden = row.maze_hidden;
    let mut record: Option<MatchRecord> = None;
    let mut maze = None;
    // A hidden maze's match shows no viewer; a record that cannot be read shows the
    // page without it.
    let stored = if hidden {
        None
    } else {
        state.storage.get_record(id).await.ok().flatten()
    };
    // The bot's stderr is its owner's: shown to a session that owns the bot (or the
    // admin's); for anyone else it is left out, and the page's owner form fetches it
    // from the API with a pasted token.
    let owner = visitor.signed_in() && visitor.caller.owns(&state, row.bot_id).await?;
    let pruned = !hidden && row.trace_removed();
    // The end of the bot's stderr, for its owner, whatever the match's status (a crash
    // at its first step has no replay to show it in).
    let stderr_tail = stored
        .as_ref()
        .filter(|_| owner)
        .map(|r| r.stderr_tail.clone());
    if let Some(mut r) = stored
        .filter(|r| !pruned && !r.trace.is_empty())
        .map(|r| if owner { r } else { r.without_stderr() })
    {
        let m = super::mazes::find_maze(&state, row.maze_id).await?;
        maze = mazefile::parse(m.layout.as_bytes()).ok();
        r.maze_layout = Some(m.layout);
        record = Some(r);
    }
    let line = line(row);
    let title = format!(
        "match {id}: {} on {} (seed {})",
        line.row.bot_name, line.row.maze_name, line.row.seed
    );
    let superseded = super::matches::superseded(&state, id, !hidden).await?;
    let viewer = record.as_ref().map(|r| ViewerData {
        stderr_hidden: !owner,
        ..ViewerData::new(title, r, maze.as_ref(), format!("match-{id}.json"))
    });
    Ok(Html(web::match_page(&web::MatchPage {
        line,
        viewer,
        pruned,
        owner,
        stderr_tail,
        superseded,
    })))
}

/// Query of `/tournaments`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ListQuery {
    offset: Option<i64>,
    limit: Option<i64>,
}

async fn workers_page(State(state): State<AppState>) -> ApiResult<Html<String>> {
    let rows = state
        .storage
        .live_workers(crate::metrics::LIVE_WINDOW.as_millis() as i64)
        .await?;
    Ok(Html(web::workers(&rows)))
}

async fn tournaments_page(
    State(state): State<AppState>,
    AppQuery(q): AppQuery<ListQuery>,
) -> ApiResult<Html<String>> {
    let page = page(q.offset, q.limit)?;
    let (rows, total) = state.storage.list_tournaments(page, true).await?;
    let pager = Pager {
        base: "/tournaments".into(),
        offset: page.offset,
        limit: page.limit,
        total,
    };
    Ok(Html(web::tournaments(&rows, &pager)))
}

async fn tournament_page(
    State(state): State<AppState>,
    AppPath(id): AppPath<i64>,
) -> ApiResult<Html<String>> {
    let t = super::auth::Caller::Anonymous
        .tournament(&state, id)
        .await?;
    let (standings, sealed) = tournament_for_caller(
        state
            .ranker
            .leaderboard(&state.storage, Scope::Tournament(id))
            .await?,
        &Caller::Anonymous,
        t.done >= t.total,
        t.competition_id.is_some(),
        false,
    );
    let competition = match t.competition_id {
        Some(c) => state
            .storage
            .get_competition_by_id(c)
            .await?
            .map(|c| (c.name, c.title)),
        None => None,
    };
    let mut bots: Vec<(i64, String)> = Vec::new();
    let mut mazes: Vec<(i64, String)> = Vec::new();
    let mut cells: BTreeMap<(i64, i64), web::Cell> = BTreeMap::new();
    let mut failed = std::collections::BTreeSet::new();
    for row in state.storage.tournament_matches(id).await? {
        if !bots.iter().any(|(b, _)| *b == row.bot_id) {
            bots.push((row.bot_id, row.bot_name.clone()));
        }
        if !mazes.iter().any(|(m, _)| *m == row.maze_id) {
            mazes.push((row.maze_id, row.maze_name.clone()));
        }
        let key = (row.bot_id, row.maze_id);
        let c = cells.entry(key).or_default();
        c.total += 1;
        // Nothing per hidden maze: not even how many finished.
        if row.maze_hidden {
            c.hidden = true;
            continue;
        }
        match row.status {
            MatchState::Queued | MatchState::Running => {}
            MatchState::Ended(MatchStatus::Finished) => {
                c.played += 1;
                c.finished += 1;
                c.score_sum30 += crate::ranking::mean::thirtieths(row.score.unwrap_or(0.0));
                c.link.get_or_insert(row.match_id);
            }
            _ => {
                c.played += 1;
                // A cell links to its first failed match, else to its first match.
                if failed.insert(key) {
                    c.link = Some(row.match_id);
                }
            }
        }
    }
    Ok(Html(web::tournament(&web::TournamentPage {
        standings: board::section(
            String::new(),
            String::new(),
            standings,
            format!("tournament={id}"),
            SortKey::Rank,
        ),
        tournament: t,
        bots,
        mazes,
        cells,
        standings_sealed: sealed,
        competition,
    })))
}
