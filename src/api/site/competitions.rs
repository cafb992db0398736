//! The competitions' pages, as an anonymous visitor sees them (the private board sealed
//! until the close, ranking mazes by name only until revealed).

use axum::extract::State;
use axum::response::Html;

use super::super::AppState;
use super::super::auth::Caller;
use super::super::competitions::{CompetitionView, view};
use super::super::error::{ApiError, ApiResult, AppPath, AppQuery};
use crate::registry::competitions::{self as ops, BoardKind};
use crate::web::pages::{self as web, CompetitionSummary};
use serde::Deserialize;

fn summary(v: &CompetitionView) -> CompetitionSummary {
    let when = |t: Option<crate::competition::Timestamp>| t.map(|t| t.words());
    CompetitionSummary {
        name: v.name.clone(),
        title: v.title.clone(),
        phase: v.phase.as_str().to_string(),
        state: v.state.clone(),
        kind: v.kind.clone(),
        opens_at: when(v.opens_at),
        freezes_at: when(v.freezes_at),
        closes_at: when(v.closes_at),
        entrants: v.entrants,
    }
}

pub(super) async fn competitions_page(State(state): State<AppState>) -> ApiResult<Html<String>> {
    let mut rows = Vec::new();
    for c in state.storage.list_competitions().await? {
        rows.push(summary(&view(&state, &c, &Caller::Anonymous).await?));
    }
    Ok(Html(web::competitions(&rows)))
}

/// A competition page's query: the invite code its organiser's link carries.
#[derive(Debug, Deserialize)]
pub(super) struct InviteQuery {
    invite: Option<String>,
}

pub(super) async fn competition_page(
    State(state): State<AppState>,
    AppPath(name): AppPath<String>,
    AppQuery(q): AppQuery<InviteQuery>,
) -> ApiResult<Html<String>> {
    // Carried on to the registration as it is (never checked here: the registration
    // page checks it, and spends a guess on a wrong one); only a code a link can carry.
    let invite = q
        .invite
        .filter(|code| crate::registry::invites::valid(code));
    let c = state
        .storage
        .get_competition(&name)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no competition {name:?}")))?;
    let v = view(&state, &c, &Caller::Anonymous).await?;
    let now = crate::storage::now_ms();
    let (public, private) = if c.kind == "default" {
        let board = super::super::competitions::default_board(
            &state,
            &Caller::Anonymous,
            BoardKind::Public,
        )
        .await?;
        (board, None)
    } else {
        (
            ops::board(&state.storage, &c, BoardKind::Public, false, now).await?,
            Some(ops::board(&state.storage, &c, BoardKind::Private, false, now).await?),
        )
    };
    let results = if c.state.as_deref() == Some("final") {
        Some(crate::registry::competitions::results(&state.storage, &c).await?)
    } else {
        None
    };
    let limits = v.limits;
    // The limits matches are played under: the competition's, else the server's.
    let effective = limits.apply(crate::runner::Limits::default());
    let effective_ms = |d: Option<std::time::Duration>| {
        d.map_or("no limit".to_string(), |d| format!("{} ms", d.as_millis()))
    };
    let settings = if c.kind == "default" {
        Vec::new()
    } else {
        vec![
            (
                "matches per version per ranking maze".into(),
                v.repeats.to_string(),
            ),
            ("final run".into(), {
                let repeats = if v.final_repeats > 0 {
                    v.final_repeats
                } else {
                    v.repeats
                };
                let mut text = format!(
                    "after the close: {repeats} matches per selected version per private maze (the private set's only run)"
                );
                if let Some(p) = v.final_run {
                    text.push_str(&format!("; {} of {} played", p.played, p.total));
                }
                text
            }),
            (
                "versions per entrant per 24 hours".into(),
                v.versions_per_day.to_string(),
            ),
            (
                "practice matches per entrant per 24 hours".into(),
                v.practice_per_day.to_string(),
            ),
            (
                "what counts at the end".into(),
                match v.selection.as_str() {
                    "best_public" => "the version with the best public score".to_string(),
                    "choice" => format!(
                        "the entrant's choice of up to {} versions (else the latest)",
                        v.max_selected
                    ),
                    _ => "the latest version".to_string(),
                },
            ),
            (
                "CPU time per move (move_timeout_ms)".into(),
                effective_ms(effective.move_timeout),
            ),
            (
                "CPU time to start (startup_timeout_ms)".into(),
                effective_ms(effective.startup_timeout),
            ),
            (
                "time bank: CPU time the moves may use beyond their limit, all together (time_bank_ms)".into(),
                format!("{} ms", effective.time_bank.as_millis()),
            ),
            (
                "wall-clock backstop".into(),
                format!(
                    "an answer is given up on after {} x (its limit + the CPU time it used): the limits count CPU time, the same on a busy server",
                    crate::runner::WALL_BACKSTOP_FACTOR
                ),
            ),
            (
                "the longest a match may last (wall-clock time)".into(),
                match effective.match_wall_clock() {
                    Some(c) => format!(
                        "{}: {} x the CPU time these limits allow ({}) + {} s; a bot that waits past it ends as a timeout, one that thinks is not stopped while it gets half a core",
                        duration_words(c),
                        crate::runner::MATCH_WALL_FACTOR,
                        duration_words(effective.most_cpu_time().unwrap_or_default()),
                        crate::runner::MATCH_WALL_SLACK.as_secs()
                    ),
                    None => "no limit".into(),
                },
            ),
            (
                "memory, all the bot's processes (memory_limit_mb)".into(),
                effective
                    .memory_limit_mb
                    .map_or("no limit".into(), |m| format!("{m} MiB")),
            ),
        ]
    };
    let practice = v
        .mazes
        .iter()
        .filter(|m| m.set == "practice")
        .filter_map(|m| Some((m.maze_id?, m.name.clone())))
        .collect();
    let ranking = v
        .mazes
        .iter()
        .filter(|m| m.set != "practice")
        .map(|m| (m.set.clone(), m.name.clone(), m.maze_id))
        .collect();
    Ok(Html(web::competition(&web::CompetitionPage {
        summary: summary(&v),
        description: v.description.clone(),
        rules: v.rules.clone(),
        settings,
        practice,
        ranking,
        public,
        private,
        results,
        invite,
    })))
}

/// "17 min 20 s", "45 s": a duration in words.
fn duration_words(d: std::time::Duration) -> String {
    let secs = d.as_secs_f64().ceil() as u64;
    match (secs / 60, secs % 60) {
        (0, s) => format!("{s} s"),
        (m, 0) => format!("{m} min"),
        (m, s) => format!("{m} min {s} s"),
    }
}
