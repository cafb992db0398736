//! The pages of one thing: a bot, a maze, a match (with the replay viewer), a
//! tournament.

use maud::{PreEscaped, html};

use super::super::layout::{page, score, status, time};
use super::super::viewer::{ViewerData, embed};
use super::board::{StandingsSection, standings_table};
use super::lists::{MatchLine, count_text, match_table, opt};
use crate::storage::bots::{BotRow, BotVersionRow};
use crate::storage::matches::lists::MatchCount;
use crate::storage::mazes::MazeRow;
use crate::storage::tournaments::TournamentRow;

/// A bot's page.
#[derive(Debug, Clone)]
pub struct BotPage {
    /// The bot.
    pub bot: BotRow,
    /// Its versions, newest first.
    pub versions: Vec<BotVersionRow>,
    /// Its recent matches.
    pub recent: Vec<MatchLine>,
    /// How many matches it has in all.
    pub total_matches: MatchCount,
    /// True when the visitor's session owns the bot: its build logs are in the page.
    pub owner: bool,
}

/// A bot's page: versions, recent matches; the owner can paste their token to see the
/// logs (fetched from the API by the page's script, never put in the page).
pub fn bot(p: &BotPage) -> String {
    let b = &p.bot;
    let body = html! {
        h1 { (b.name) }
        p.lead {
            "Bot " (b.bot_id) ", registered " (time(b.created_at)) ". Latest version " (b.version) ": "
            code { (b.command) } " "
            @if b.is_paused() { (status("paused")) } @else { (status(&b.build_status)) }
        }
        @if let Some(reason) = &b.paused_reason {
            p { strong { "Paused: " } (reason) }
        }
        h2 { "Versions" }
        table.data.versions {
            thead { tr { th.num { "version" } th { "command" } th { "build" } th.num { "files" } th { "uploaded" } th { "build log" } } }
            tbody {
                @for v in &p.versions {
                    tr {
                        td.num { (v.version) }
                        td { code { (v.command) } }
                        td {
                            (status(&v.build_status))
                            @if let Some(cmd) = &v.build_command { " " code.muted { (cmd) } }
                        }
                        td.num { (v.file_count) }
                        td { (time(v.created_at)) }
                        td {
                            @if v.build_command.is_some() {
                                a.build-log href="#" data-version=(v.version) { "show (owner)" }
                            }
                        }
                    }
                }
            }
        }
        h2 { "Recent matches" }
        (match_table(&p.recent))
        p { a href={ "/matches?bot_id=" (b.bot_id) } { "All " (count_text(p.total_matches)) } }
        @if p.owner {
            h2 { "Build and validation logs" }
            p.muted { "You own this bot: its logs are shown to you. Open a match to see its stderr." }
            @for v in &p.versions {
                @if let Some(log) = &v.build_log {
                    h3 { "version " (v.version) " " (status(&v.build_status)) }
                    pre.log.owner-build-log { (log) }
                }
            }
        } @else {
            h2 { "Owner's logs" }
            p.muted { a href="/login" { "Log in" } " to see your bot's logs here, or paste the owner token (it stays in this page and is sent only to this server's API)." }
            form.inline #owner-form data-bot=(b.bot_id) {
                input #owner-token type="password" placeholder="owner token" autocomplete="off";
                button type="submit" { "Show logs" }
            }
            div #owner-logs {}
            script { (PreEscaped(OWNER_LOGS_JS)) }
        }
    };
    page(&b.name, body)
}

/// The match page's script: the bot's stderr, fetched with the pasted owner token and
/// handed to the viewer.
pub const MATCH_STDERR_JS: &str = include_str!("../assets/match_stderr.js");

/// The bot page's script: the owner's logs, fetched with the pasted token.
pub const OWNER_LOGS_JS: &str = include_str!("../assets/owner_logs.js");

/// A maze's page: public mazes drawn with their optimal route; hidden ones named only.
pub fn maze(m: &MazeRow, svg: Option<&str>, recent: &[MatchLine]) -> String {
    let body = html! {
        h1 { (m.name) }
        @if m.hidden {
            p.lead { "A hidden ranking maze: its layout, side and optimum are not shown." }
        } @else {
            p.lead {
                "Public maze, " (m.dim) "x" (m.dim) ". Optimal run 1: "
                @match m.optimum { Some(o) => { (o) " steps." }, None => "the goal room cannot be reached." }
            }
            @if let Some(svg) = svg { div.maze-svg { (PreEscaped(svg)) } }
            p { a href={ "/api/mazes/" (m.maze_id) } { "Layout (JSON)" } }
        }
        h2 { "Recent matches" }
        (match_table(recent))
    };
    page(&m.name, body)
}

/// A match's page.
#[derive(Debug, Clone)]
pub struct MatchPage<'a> {
    /// The match, names and reason.
    pub line: MatchLine,
    /// The viewer's data, when the visitor may see the replay (not on hidden mazes).
    pub viewer: Option<ViewerData<'a>>,
    /// True when its trace was removed (an old practice match, pruned).
    pub pruned: bool,
    /// True when the visitor's session owns the bot: its stderr is in the viewer.
    pub owner: bool,
    /// The end of the bot's stderr, for its owner (any status; none on a hidden maze or
    /// for anyone else).
    pub stderr_tail: Option<String>,
    /// Earlier outcomes that rejudges superseded: status, score, when it had ended.
    pub superseded: Vec<crate::storage::rejudges::SupersededRow>,
}

/// A match's page: its result, and the replay viewer.
pub fn match_page(p: &MatchPage<'_>) -> String {
    let r = &p.line.row;
    let title = format!("Match {}", r.match_id);
    let body = html! {
        h1 { (title) ": " (p.line.row.bot_name) " on " (p.line.row.maze_name) }
        div.cards {
            div.card { "status" b { (status(r.status.as_str())) } }
            div.card { "score" b { (score(&r.status.to_string(), r.score)) } }
            div.card { "run 0 / run 1 steps" b { (opt(r.run0_steps)) " / " (opt(r.run1_steps)) } }
            div.card { "seed" b { @if r.maze_hidden { "-" } @else { (r.seed) } } }
            @if let Some(t) = r.tournament_id {
                div.card { "tournament" b { a href={ "/tournaments/" (t) } { (t) } } }
            }
        }
        @if let Some(reason) = &p.line.reason { p.reason { strong { "Reason: " } (reason) } }
        @if let Some(tail) = &p.stderr_tail {
            h2 { "The end of its stderr" }
            @if tail.is_empty() {
                p.muted.stderr-tail { "Its bot wrote nothing on stderr." }
            } @else {
                pre.stderr-tail tabindex="0" { (tail) }
            }
        }
        p {
            a href={ "/bots/" (r.bot_id) } { "bot " (p.line.row.bot_name) } " · "
            a href={ "/mazes/" (r.maze_id) } { "maze " (p.line.row.maze_name) } " · "
            a href={ "/api/matches/" (r.match_id) } { "JSON" }
        }
        @match &p.viewer {
            Some(data) if p.owner => {
                (embed(data))
                p.muted.owner-note { "You own this bot: its stderr is shown in the viewer, step by step and at the end." }
            },
            Some(data) => {
                (embed(data))
                h2 { "Owner's stderr" }
                p.muted { "The bot's stderr is its owner's: paste the owner token to see it in the viewer (the token stays in this page and is sent only to this server's API)." }
                form.inline #match-owner-form data-match=(r.match_id) {
                    input #match-owner-token type="password" placeholder="owner token" autocomplete="off";
                    button type="submit" { "Show stderr" }
                }
                p #match-owner-status.muted {}
                script { (PreEscaped(MATCH_STDERR_JS)) }
            },
            None => {
                @if r.maze_hidden {
                    p.muted { "Played on a hidden ranking maze: its replay is not shown." }
                } @else if p.pruned {
                    p.muted { "Its replay was removed to save space (an old practice match); its result stays." }
                } @else if !matches!(r.status.as_str(), "queued" | "running") {
                    p.muted { "No replay: the match ended before its bot's first move." }
                } @else {
                    p.muted { "Not played yet: this page reloads every 5 seconds until it is." }
                }
            }
        }
        @if !p.superseded.is_empty() {
            h2 { "Earlier outcomes" }
            p.muted { "This match was played again by a rejudge; its earlier outcomes are kept here and no longer count." }
            table.data.superseded {
                thead { tr { th.num { "rejudge" } th { "status" } th.num { "score" } th.num { "steps" } th { "ended" } } }
                tbody { @for s in &p.superseded {
                    tr.superseded {
                        td.num { (s.rejudge_id) }
                        td { (status(&s.status)) " " span.muted { "superseded" } }
                        td.num { @if r.maze_hidden { "hidden" } @else { (score(&s.status, s.score)) } }
                        td.num { (opt(s.total_steps)) }
                        td { (s.finished_at.map(super::super::layout::time).unwrap_or_default()) }
                    }
                } }
            }
        }
    };
    super::super::layout::live_page(
        &title,
        body,
        matches!(r.status.to_string().as_str(), "queued" | "running"),
    )
}

/// A tournament's page.
#[derive(Debug, Clone)]
pub struct TournamentPage {
    /// The tournament.
    pub tournament: TournamentRow,
    /// Its standings.
    pub standings: StandingsSection,
    /// Bot names (columns of the table are mazes, rows bots).
    pub bots: Vec<(i64, String)>,
    /// Maze ids and names.
    pub mazes: Vec<(i64, String)>,
    /// Per (bot, maze): mean score over finished matches, played, finished, first
    /// match id.
    pub cells: std::collections::BTreeMap<(i64, i64), Cell>,
    /// True while the standings are withheld (hidden mazes, not complete).
    pub standings_sealed: bool,
    /// The competition it ranks for (name, title): its standings are that
    /// competition's boards.
    pub competition: Option<(String, String)>,
}

/// One bot x maze cell of a tournament.
#[derive(Debug, Clone, Default)]
pub struct Cell {
    /// Matches played (final).
    pub played: i64,
    /// Matches finished.
    pub finished: i64,
    /// Sum of finished scores, in thirtieths of a step.
    pub score_sum30: i64,
    /// A match to link to (the first failed one if any, else the first).
    pub link: Option<i64>,
    /// Matches in all.
    pub total: i64,
    /// On a hidden maze: nothing of it is shown.
    pub hidden: bool,
}

/// A tournament's page: progress (updated live by polling the API), standings, and
/// the bot x maze table.
pub fn tournament(p: &TournamentPage) -> String {
    let t = &p.tournament;
    let pct = if t.total > 0 {
        t.done * 100 / t.total
    } else {
        100
    };
    let body = html! {
        h1 { (t.name) }
        p.lead { "Tournament " (t.tournament_id) ", created " (time(t.created_at)) ", " (t.repeats) " repeat(s) of every bot on every maze." }
        div #progress data-tournament=(t.tournament_id) data-done=(t.done) data-total=(t.total) {
            div.progress { div #progress-bar data-pct=(pct) {} }
            p #progress-text { (t.done) " of " (t.total) " matches played" }
        }
        h2 { "Standings" }
        @if let Some((name, title)) = &p.competition {
            p.muted { "This tournament ranks for the competition " a href={ "/competitions/" (name) } { (title) } ": its standings are the competition's boards, on its page (each entrant's latest version whose matches are all played, under the competition's freeze)." }
        } @else if p.standings_sealed {
            p.muted { "The standings appear once every match is played: the tournament has hidden mazes, and standings that change with each match would show that match's result." }
        } @else {
            (standings_table(&p.standings))
        }
        h2 { "Bot x maze" }
        p.muted { "Mean score of the finished matches, and how many finished; a cell links to one of its matches (a failed one first)." }
        table.data.grid {
            thead { tr { th { "bot" } @for (id, name) in &p.mazes { th.num { a href={ "/mazes/" (id) } { (name) } } } } }
            tbody {
                @for (bot_id, bot) in &p.bots {
                    tr {
                        td { a href={ "/bots/" (bot_id) } { (bot) } }
                        @for (maze_id, _) in &p.mazes {
                            @let c = p.cells.get(&(*bot_id, *maze_id)).cloned().unwrap_or_default();
                            @if c.hidden {
                                td.num { span.muted { "hidden" } }
                            } @else {
                            td.num {
                                @if c.finished > 0 { (crate::ranking::Mean::new(c.score_sum30, c.finished)) } @else if c.played > 0 { "DNF" } @else { span.muted { "…" } }
                                br;
                                span.muted { (c.finished) "/" (c.total) }
                                @if let Some(id) = c.link { " " a href={ "/matches/" (id) } { "#" (id) } }
                            }
                            }
                        }
                    }
                }
            }
            @if t.done >= t.total && t.total > 0 {
                tfoot { tr {
                    th scope="row" { "every bot on one maze" }
                    @for (maze_id, name) in &p.mazes {
                        @let hidden = p.cells.iter().any(|((_, m), c)| m == maze_id && c.hidden);
                        td.num { @if !hidden { a.race-link href={ "/tournaments/" (t.tournament_id) "/race/" (maze_id) "/0" } aria-label={ "The race on " (name) } { "race" } } }
                    }
                } }
            }
        }
        p { a href={ "/matches?tournament_id=" (t.tournament_id) } { "Every match" } }
        script { (PreEscaped(PROGRESS_JS)) }
    };
    page(&t.name, body)
}

/// Live progress: polls the tournament's JSON until it is complete.
pub const PROGRESS_JS: &str = include_str!("../assets/progress.js");
