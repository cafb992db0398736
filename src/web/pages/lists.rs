//! The list pages: tournaments, mazes, bots, matches (paged by links).

use maud::{Markup, html};

use super::super::layout::{page, score, status, time};
use super::board::{maze_table, tournament_table};
use crate::storage::bots::BotRow;
use crate::storage::matches::MatchRow;
use crate::storage::matches::lists::MatchCount;
use crate::storage::mazes::MazeRow;
use crate::storage::tournaments::TournamentRow;
use crate::storage::workers::WorkerRow;

/// A list page of tournaments.
pub fn tournaments(rows: &[TournamentRow], pager: &Pager) -> String {
    page(
        "Tournaments",
        html! { h1 { "Tournaments" } (tournament_table(rows)) (pager.links()) },
    )
}

/// A list page of mazes.
pub fn mazes(rows: &[MazeRow]) -> String {
    page("Mazes", html! { h1 { "Mazes" } (maze_table(rows)) })
}

/// A list page of bots.
pub fn bots(rows: &[BotRow]) -> String {
    page(
        "Bots",
        html! {
            h1 { "Bots" }
            @if rows.is_empty() { p.muted { "No bot yet." } } @else {
                table.data.bots {
                    thead { tr { th.num { "id" } th { "name" } th.num { "version" } th { "state" } th { "registered" } } }
                    tbody {
                        @for b in rows {
                            tr {
                                td.num { (b.bot_id) }
                                td { a href={ "/bots/" (b.bot_id) } { (b.name) } }
                                td.num { (b.version) }
                                td { @if b.is_paused() { (status("paused")) } @else { (status(&b.build_status)) } }
                                td { (time(b.created_at)) }
                            }
                        }
                    }
                }
            }
        },
    )
}

/// The page of the processes playing matches, as they last reported themselves: without
/// the queue's length or the matches each has played (they move with matches on hidden
/// mazes: the admin reads them in `/healthz` and `/metrics`).
pub fn workers(rows: &[WorkerRow]) -> String {
    page(
        "Workers",
        html! {
            h1 { "Workers" }
            p.muted { "Workers that reported in the last 30 seconds:" }
            @if rows.is_empty() { p.muted { "No worker is playing matches." } } @else {
                table.data.workers {
                    thead { tr {
                        th { "worker" } th { "role" } th { "host" } th.num { "pid" }
                        th.num { "jobs" } th { "sandbox" }
                        th { "started" } th { "last seen" }
                    } }
                    tbody {
                        @for w in rows {
                            tr {
                                td { code { (w.worker_id) } }
                                td { (w.role) }
                                td { (w.host) }
                                td.num { (w.pid) }
                                td.num { (w.jobs) }
                                td { (status(&w.sandbox)) }
                                td { (time(w.started_at)) }
                                td { (time(w.last_seen)) }
                            }
                        }
                    }
                }
            }
        },
    )
}

/// Links to the previous and next page of a list.
#[derive(Debug, Clone)]
pub struct Pager {
    /// The list's path and query without `offset`, e.g. `/matches?bot_id=2`.
    pub base: String,
    /// This page's offset.
    pub offset: i64,
    /// Rows per page.
    pub limit: i64,
    /// Rows in all.
    pub total: i64,
}

impl Pager {
    fn href(&self, offset: i64) -> String {
        let sep = if self.base.contains('?') { '&' } else { '?' };
        format!("{}{sep}offset={offset}&limit={}", self.base, self.limit)
    }

    /// Which rows are shown, counted from 1: "1–50 of 120", "3 of 3", "none".
    fn shown(&self, shown_to: i64) -> String {
        let from = self.offset + 1;
        match self.total {
            0 => "none".into(),
            total if from >= shown_to => format!("{} of {total}", shown_to.max(from.min(total))),
            total => format!("{from}–{shown_to} of {total}"),
        }
    }

    /// The links.
    pub fn links(&self) -> Markup {
        let shown_to = (self.offset + self.limit).min(self.total);
        html! {
            div.pager {
                span.muted { (self.shown(shown_to)) }
                @if self.offset > 0 {
                    a rel="prev" href=(self.href((self.offset - self.limit).max(0))) { "← newer" }
                }
                @if shown_to < self.total {
                    a rel="next" href=(self.href(shown_to)) { "older →" }
                }
            }
        }
    }
}

/// Links through a list of matches a page at a time, older by `before` the last match
/// shown (the same cost however deep), and how many there are.
#[derive(Debug, Clone)]
pub struct MatchPager {
    /// The list's path and query without `before`, `offset` and `limit`.
    pub base: String,
    /// Rows per page.
    pub limit: i64,
    /// How many matches pass the list's filters.
    pub count: MatchCount,
    /// Whether this is the list's first (newest) page.
    pub first_page: bool,
    /// The last match shown, when the page is full (an older page may follow).
    pub next_before: Option<i64>,
}

impl MatchPager {
    /// The links.
    pub fn links(&self) -> Markup {
        let sep = if self.base.contains('?') { '&' } else { '?' };
        html! {
            div.pager {
                span.muted { (count_text(self.count)) }
                @if !self.first_page {
                    a rel="first" href={ (self.base) (sep) "limit=" (self.limit) } { "← newest" }
                }
                @if let Some(before) = self.next_before {
                    a rel="next" href={ (self.base) (sep) "before=" (before) "&limit=" (self.limit) } { "older →" }
                }
            }
        }
    }
}

/// "12 matches", or "more than 10000 matches" past what lists count.
pub fn count_text(count: MatchCount) -> String {
    match (count.total, count.exact) {
        (1, true) => "1 match".into(),
        (n, true) => format!("{n} matches"),
        (n, false) => format!("more than {n} matches"),
    }
}

/// A match in a list, with the names to show and what may be said of its failure.
#[derive(Debug, Clone)]
pub struct MatchLine {
    /// The stored match (with its bot's and maze's names).
    pub row: MatchRow,
    /// The failure's reason as the visitor may see it (hidden mazes: the step only).
    pub reason: Option<String>,
}

/// A table of matches.
pub fn match_table(lines: &[MatchLine]) -> Markup {
    html! {
        @if lines.is_empty() { p.muted { "No match." } } @else {
            table.data.matches {
                thead { tr {
                    th.num { "match" } th { "queued" } th { "bot" } th { "maze" } th.num { "seed" } th { "status" }
                    th.num { "score" } th.num { "run 0" } th.num { "run 1" } th { "reason" }
                } }
                tbody {
                    @for l in lines {
                        tr {
                            td.num { a href={ "/matches/" (l.row.match_id) } { (l.row.match_id) } }
                            td.time { (time(l.row.created_at)) }
                            td.name { a href={ "/bots/" (l.row.bot_id) } { (l.row.bot_name) } span.muted { " v" (l.row.version) } }
                            td.name { a href={ "/mazes/" (l.row.maze_id) } { (l.row.maze_name) } }
                            td.num { @if l.row.maze_hidden { span.muted { "-" } } @else { (l.row.seed) } }
                            td { (status(l.row.status.as_str())) }
                            td.num { (score(&l.row.status.to_string(), l.row.score)) }
                            td.num { (opt(l.row.run0_steps)) }
                            td.num { (opt(l.row.run1_steps)) }
                            td.reason { @if let Some(r) = &l.reason { (r) } }
                        }
                    }
                }
            }
        }
    }
}

pub(super) fn opt(v: Option<i64>) -> Markup {
    html! { @match v { Some(v) => (v), None => span.muted { "-" } } }
}

/// The list of matches, with its filters.
pub fn matches(lines: &[MatchLine], filters: &str, pager: &MatchPager) -> String {
    page(
        "Matches",
        html! {
            h1 { "Matches" }
            @if !filters.is_empty() { p.lead { (filters) } }
            (match_table(lines))
            (pager.links())
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pager_links_move_by_pages() {
        let p = Pager {
            base: "/matches?bot_id=2".into(),
            offset: 50,
            limit: 50,
            total: 120,
        };
        let html = p.links().into_string();
        assert!(html.contains("51–100 of 120"), "{html}");
        assert!(html.contains("/matches?bot_id=2&amp;offset=0&amp;limit=50"));
        assert!(html.contains("/matches?bot_id=2&amp;offset=100&amp;limit=50"));
        // Counted from 1: one row is "1 of 1", not "0-1 of 1"; none is "none".
        let one = Pager {
            base: "/bots".into(),
            offset: 0,
            limit: 50,
            total: 1,
        };
        assert!(one.links().into_string().contains(">1 of 1<"));
        let none = Pager { total: 0, ..one };
        assert!(none.links().into_string().contains(">none<"));
    }

    #[test]
    fn match_pages_go_older_by_the_last_match_shown() {
        let mut p = MatchPager {
            base: "/matches?bot_id=2".into(),
            limit: 50,
            count: MatchCount {
                total: 10_000,
                exact: false,
            },
            first_page: true,
            next_before: Some(700),
        };
        let html = p.links().into_string();
        assert!(
            html.contains("/matches?bot_id=2&amp;before=700&amp;limit=50"),
            "{html}"
        );
        assert!(html.contains("more than 10000 matches") && !html.contains("newest"));
        p.first_page = false;
        p.next_before = None;
        p.count.exact = true;
        let html = p.links().into_string();
        assert!(html.contains("10000 matches") && html.contains("newest"));
        assert!(!html.contains("older") && !html.contains("more than"));
    }
}

/// A route of the API, for its page.
#[derive(Debug, Clone)]
pub struct ApiRoute {
    /// `GET`, `POST`, ...
    pub method: &'static str,
    /// Its path.
    pub path: String,
    /// What it does.
    pub text: String,
    /// Whether it takes a key.
    pub auth: bool,
}

/// The API's page: every route, and where the machine-readable document is.
pub fn api_routes(routes: &[ApiRoute]) -> String {
    page(
        "API",
        html! {
            h1 { "API" }
            p.lead { "JSON over HTTP. Routes marked with a key take " code { "Authorization: Bearer KEY" } " (an entrant's key, a bot's owner token, an organiser's key or the admin token). Errors are " code { "{\"error\":{\"code\":..,\"message\":..}}" } ". The machine-readable description: " a href="/api/openapi.json" { "/api/openapi.json" } " (OpenAPI 3.1)." }
            table.data.api-routes {
                thead { tr { th { "method" } th { "path" } th { "key" } th { "what it does" } } }
                tbody { @for r in routes {
                    tr { td { code { (r.method) } } td { code { (r.path) } } td { @if r.auth { "key" } } td { (r.text) } }
                } }
            }
        },
    )
}
