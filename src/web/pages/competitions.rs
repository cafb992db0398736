//! The competitions' pages: the list, and one competition with its timeline, texts,
//! practice mazes, boards, results and "my submissions" (fetched by a script with the
//! key an entrant pastes; the key stays in the page).

use maud::{Markup, PreEscaped, html};

use super::super::layout::page;
use super::ranks;
use crate::registry::competitions::{Board, BoardLine};
use crate::storage::competitions::ResultRow;

/// A competition as its pages show it.
#[derive(Debug, Clone)]
pub struct CompetitionSummary {
    /// Short name (in addresses).
    pub name: String,
    /// Title.
    pub title: String,
    /// `upcoming`, `open`, `frozen` or `closed`.
    pub phase: String,
    /// `final_run`, `final` or none.
    pub state: Option<String>,
    /// `default` or `competition`.
    pub kind: String,
    /// Opening, freeze and close, as UTC text.
    pub opens_at: Option<String>,
    /// The freeze.
    pub freezes_at: Option<String>,
    /// The close.
    pub closes_at: Option<String>,
    /// Entrants.
    pub entrants: usize,
}

/// Everything the page of one competition shows.
#[derive(Debug, Clone)]
pub struct CompetitionPage {
    /// The competition.
    pub summary: CompetitionSummary,
    /// Description (shown as text).
    pub description: String,
    /// Rules (shown as text).
    pub rules: String,
    /// Settings in words: repeats, quotas, selection, limits.
    pub settings: Vec<(String, String)>,
    /// Practice mazes: id and name.
    pub practice: Vec<(i64, String)>,
    /// Ranking mazes by set: names only (ids too once revealed).
    pub ranking: Vec<(String, String, Option<i64>)>,
    /// The public board.
    pub public: Board,
    /// The private board (the final run's, after the close).
    pub private: Option<Board>,
    /// The final results, once written.
    pub results: Option<Vec<ResultRow>>,
    /// The invite code the visitor's link carried, passed on to the registration.
    pub invite: Option<String>,
}

/// The list of competitions.
pub fn competitions(rows: &[CompetitionSummary]) -> String {
    page(
        "Competitions",
        html! {
            h1 { "Competitions" }
            table.data.competitions {
                thead { tr { th { "competition" } th { "phase" } th { "opens" } th { "closes" } th.num { "entrants" } } }
                tbody {
                    @for c in rows {
                        tr {
                            td { a href={ "/competitions/" (c.name) } { (c.title) } " " span.muted { "(" (c.name) ")" } }
                            td { (phase_badge(c)) }
                            td { (c.opens_at.as_deref().unwrap_or("-")) }
                            td { (c.closes_at.as_deref().unwrap_or("-")) }
                            td.num { @if c.kind == "default" { "-" } @else { (c.entrants) } }
                        }
                    }
                }
            }
        },
    )
}

fn phase_badge(c: &CompetitionSummary) -> Markup {
    let word = match c.state.as_deref() {
        Some("final") => "final",
        Some("final_run") => "final run",
        Some("held") => "results held",
        _ => c.phase.as_str(),
    };
    let class = match word {
        "open" => "ready",
        "frozen" | "final run" | "results held" => "building",
        "final" => "finished",
        _ => "queued",
    };
    html! { span class={ "status " (class) } { (word) } }
}

pub(super) fn board_table(lines: &[BoardLine]) -> Markup {
    html! {
        @if lines.is_empty() { p.muted { "No entrant has a version with all its matches played yet." } } @else {
            table.data.board {
                thead { tr { th.num { "rank" } th { "entrant" } th { "bot" } th.num.wide { "version" } th.num { "mean score" } (ranks::header_cells()) th.num.wide { "finished" } } }
                tbody {
                    @for l in lines {
                        tr {
                            (ranks::rank_cell(l.rank, &l.uncertainty))
                            td { (l.entrant) }
                            td { a href={ "/bots/" (l.bot_id) } { (l.bot_name) } }
                            td.num.wide { (l.version) }
                            td.num { (format!("{:.3}", l.mean_score)) }
                            (ranks::interval_cell(&l.uncertainty))
                            (ranks::tie_cell(&l.uncertainty))
                            td.num.wide { (l.finished) "/" (l.played) }
                        }
                    }
                }
            }
            (ranks::ranking_note(lines.iter().map(|l| &l.uncertainty)))
        }
    }
}

/// The page of one competition.
pub fn competition(p: &CompetitionPage) -> String {
    let c = &p.summary;
    let body = html! {
        h1 { (c.title) }
        p.lead { (phase_badge(c)) " " (c.name) }
        @if c.kind != "default" {
            table.data.timeline {
                tbody {
                    tr { th { "opens" } td { (c.opens_at.as_deref().unwrap_or("-")) } }
                    @if let Some(f) = &c.freezes_at { tr { th { "public board freezes" } td { (f) } } }
                    tr { th { "closes" } td { (c.closes_at.as_deref().unwrap_or("-")) } }
                }
            }
        }
        @if !p.description.is_empty() { pre.text.description { (p.description) } }
        @if c.kind != "default" && c.phase != "closed" && c.phase != "final" {
            section.take-part #take-part {
                h2 { "How to take part" }
                ol {
                    li { strong { "In the browser: " }
                        @match &p.invite {
                            Some(code) => { a.button.register href={ "/register?invite=" (code) } { "register with your class's invite code" } }
                            None => { a.register href="/register" { "register" } }
                        }
                        " (or " a href="/login" { "log in" } " with your key), then "
                        a.button href={ "/competitions/" (c.name) "/submit" } { "upload your bot" }
                        ". Upload your files or a .zip; for a robot of the original task tick \"A robot of the original task\" and upload only your own files (the form finds the file that defines " code { "class Robot" } "). "
                        a href="/me" { "Your page" } " shows the build, the validation match, your practice matches with your stderr, your rank and your quotas." }
                    li { strong { "From a terminal: " } code { "mazearena login URL --key KEY" } ", then " code { "mazearena submit ./my-bot --competition " (c.name) } " (see the README's \"Take part\")." }
                    li { strong { "With curl: " } code { "POST /api/entrants" } ", " code { "POST /api/bots" } " with your key, then " code { "POST /api/competitions/" (c.name) "/entries" } " (the " a href="/api/openapi.json" { "API document" } ")." }
                }
            }
        }
        @if !p.rules.is_empty() { h2 { "Rules" } pre.text.rules { (p.rules) } }
        @if !p.settings.is_empty() {
            table.data.settings { tbody { @for (k, v) in &p.settings { tr { th { (k) } td { (v) } } } } }
        }
        @if !p.practice.is_empty() {
            h2 { "Practice mazes" }
            ul { @for (id, name) in &p.practice { li { a href={ "/mazes/" (id) } { (name) } } } }
        }
        @if !p.ranking.is_empty() {
            h2 { "Ranking mazes" }
            p.muted { "Their layouts are hidden; only their names are shown." }
            ul {
                @for (set, name, id) in &p.ranking {
                    li { (set) ": " @if let Some(id) = id { a href={ "/mazes/" (id) } { (name) } } @else { (name) } }
                }
            }
        }
        @if let Some(rows) = &p.results {
            h2 { "Final results" }
            p { a.reveal-link href={ "/competitions/" (c.name) "/reveal" } { "The reveal" } " (from the last place to the first) · "
                a.races-link href={ "/competitions/" (c.name) "/race" } { "The races" } " (every robot on one maze) · "
                a href={ "/api/competitions/" (c.name) "/results.csv" } { "CSV" } " · "
                a href={ "/api/competitions/" (c.name) "/results" } { "JSON with manifests" } }
            table.data.results {
                thead { tr { th.num { "rank" } th { "entrant" } th { "bot" } th.num { "version" } th.num { "mean score" } (ranks::header_cells()) th.num { "finished" } } }
                tbody {
                    @for r in rows {
                        tr {
                            (ranks::rank_cell(r.rank, &r.uncertainty)) td { (r.entrant_name) }
                            td { a href={ "/bots/" (r.bot_id) } { (r.bot_name) } }
                            td.num { (r.version) } td.num { (format!("{:.3}", r.mean_score)) }
                            (ranks::interval_cell(&r.uncertainty))
                            (ranks::tie_cell(&r.uncertainty))
                            td.num { (r.finished) "/" (r.played) }
                        }
                    }
                }
            }
            (ranks::ranking_note(rows.iter().map(|r| &r.uncertainty)))
        }
        h2 { "Public leaderboard" }
        @if let Some(f) = &p.public.frozen_at { p.muted { "Frozen since " (f.words()) ": versions uploaded later show after the close." } }
        (board_table(&p.public.standings))
        @if let Some(private) = &p.private {
            h2 { "Private leaderboard" }
            @if private.sealed {
                @if private.final_run_playing {
                    p.muted.sealed #final-run {
                        "The final run is playing"
                        @if let Some(run) = private.final_run { ": " (run.played) " of " (run.total) " matches played" }
                        ". The private board comes with the results."
                    }
                } @else {
                    p.muted.sealed { "No bot plays a private maze before the close: the private set's only run is the final run, after the close." }
                }
            } @else { (board_table(&private.standings)) }
        }
        @if c.kind != "default" {
            h2 { "My submissions" }
            p { a href="/me" { "Log in and see your page" } " for everything about your entry." }
            p.muted { "Or paste your entrant key to see your versions, their status, your own public-set scores and your quotas (the key stays in this page and is sent only to this server's API)." }
            form.inline #mine-form data-competition=(c.name) {
                input #mine-key type="password" placeholder="entrant key" autocomplete="off";
                button type="submit" { "Show" }
            }
            div #mine {}
            script { (PreEscaped(MY_SUBMISSIONS_JS)) }
        }
    };
    page(&c.title, body)
}

/// The competition page's script: the entrant's submissions and quotas, fetched with
/// the pasted key.
pub const MY_SUBMISSIONS_JS: &str = include_str!("../assets/my_submissions.js");
