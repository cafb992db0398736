//! The leaderboard page and the tables it shares with the list pages.

use maud::{Markup, html};

use super::super::layout::{page, status, time};
use super::ranks;
use crate::storage::leaderboard::Standing;
use crate::storage::mazes::MazeRow;
use crate::storage::tournaments::TournamentRow;

/// How the leaderboard's rows are ordered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SortKey {
    /// By rank (mean score).
    Rank,
    /// By name.
    Name,
    /// By finish rate, best first.
    FinishRate,
    /// By mean score / optimum, best first.
    Efficiency,
    /// By matches played, most first.
    Played,
}

impl SortKey {
    /// The query value.
    pub fn as_str(self) -> &'static str {
        match self {
            SortKey::Rank => "rank",
            SortKey::Name => "name",
            SortKey::FinishRate => "finish_rate",
            SortKey::Efficiency => "efficiency",
            SortKey::Played => "played",
        }
    }

    /// Parses a query value.
    pub fn parse(s: &str) -> Option<SortKey> {
        [
            SortKey::Rank,
            SortKey::Name,
            SortKey::FinishRate,
            SortKey::Efficiency,
            SortKey::Played,
        ]
        .into_iter()
        .find(|k| k.as_str() == s)
    }

    /// Orders `rows` by this key (ties keep the rank order).
    pub fn sort(self, rows: &mut [Standing]) {
        let key = |r: &Standing| -> (f64, String) {
            match self {
                SortKey::Rank => (r.rank as f64, String::new()),
                SortKey::Name => (0.0, r.name.to_lowercase()),
                SortKey::FinishRate => (-r.finish_rate, String::new()),
                SortKey::Efficiency => (r.mean_ratio.unwrap_or(f64::INFINITY), String::new()),
                SortKey::Played => (-(r.played as f64), String::new()),
            }
        };
        rows.sort_by(|a, b| {
            let (ka, kb) = (key(a), key(b));
            ka.0.total_cmp(&kb.0)
                .then(ka.1.cmp(&kb.1))
                .then(a.rank.cmp(&b.rank))
        });
    }
}

/// One standings table with its heading.
#[derive(Debug, Clone)]
pub struct StandingsSection {
    /// The heading.
    pub heading: String,
    /// A line under it.
    pub note: String,
    /// The rows, in display order.
    pub rows: Vec<Standing>,
    /// The query (without `sort`) the sort links keep, e.g. `scope=all`.
    pub query: String,
    /// The active order.
    pub sort: SortKey,
}

/// The leaderboard at `/`.
#[derive(Debug, Clone)]
pub struct LeaderboardPage {
    /// The main table.
    pub main: StandingsSection,
    /// The latest tournament's table, when the main one is not a tournament's.
    pub latest: Option<(TournamentRow, StandingsSection)>,
    /// Scope tabs: label, link, active.
    pub tabs: Vec<(String, String, bool)>,
    /// The competitions' public boards (their first lines), as their pages show them.
    pub competitions: Vec<CompetitionBoard>,
    /// Recent tournaments.
    pub tournaments: Vec<TournamentRow>,
    /// Every maze (hidden ones by name only).
    pub mazes: Vec<MazeRow>,
    /// The runtimes bots may use here.
    pub runtimes: Vec<crate::runner::runtimes::RuntimeInfo>,
}

/// A competition's public board on the home page.
#[derive(Debug, Clone)]
pub struct CompetitionBoard {
    /// Its name (its page's address).
    pub name: String,
    /// Its title.
    pub title: String,
    /// Its phase.
    pub phase: String,
    /// The first lines of its public board.
    pub lines: Vec<crate::registry::competitions::BoardLine>,
}

pub(super) fn standings_table(s: &StandingsSection) -> Markup {
    let link = |key: SortKey, label: &str| {
        let sep = if s.query.is_empty() { "" } else { "&" };
        let href = format!("/?{}{sep}sort={}", s.query, key.as_str());
        html! {
            a href=(href) {
                (label) @if s.sort == key { " ▾" }
            }
        }
    };
    html! {
        @if s.rows.is_empty() {
            p.muted { "No match counted yet." }
        } @else {
            table.data.standings {
                thead { tr {
                    th.num { (link(SortKey::Rank, "rank")) }
                    th { (link(SortKey::Name, "bot")) }
                    th.num { (link(SortKey::Rank, "mean score")) }
                    (ranks::header_cells())
                    th.num.wide { (link(SortKey::FinishRate, "finish rate")) }
                    th.num.wide title="mean of score / the maze's optimal run-1 steps (1.0 is perfect)" {
                        (link(SortKey::Efficiency, "score / optimum"))
                    }
                    th.num.wide { (link(SortKey::Played, "played")) }
                } }
                tbody {
                    @for r in &s.rows {
                        tr {
                            (ranks::rank_cell(r.rank, &r.uncertainty))
                            td { a href={ "/bots/" (r.bot_id) } { (r.name) } span.muted { " v" (r.version) } }
                            td.num { (format!("{:.3}", r.mean_score)) }
                            (ranks::interval_cell(&r.uncertainty))
                            (ranks::tie_cell(&r.uncertainty))
                            td.num.wide { (format!("{:.0}%", r.finish_rate * 100.0)) }
                            td.num.wide { @match r.mean_ratio { Some(x) => (format!("{x:.3}")), None => span.muted { "-" } } }
                            td.num.wide { (r.played) }
                        }
                    }
                }
            }
            (ranks::ranking_note(s.rows.iter().map(|r| &r.uncertainty)))
            @if s.rows.iter().any(|r| r.mean_ratio.is_none()) {
                p.muted.ratio-note { "score / optimum: \"-\" where hidden mazes are counted (over a hidden maze the ratio would give its optimum away)." }
            }
        }
    }
}

/// The leaderboard page.
pub fn leaderboard(p: &LeaderboardPage) -> String {
    let body = html! {
        h1 { (p.main.heading) }
        p.lead { (p.main.note) }
        div.tabs {
            @for (label, href, active) in &p.tabs {
                a href=(href) class=[active.then_some("active")] { (label) }
            }
        }
        (standings_table(&p.main))
        @for c in &p.competitions {
            h2 { "Competition: " a href={ "/competitions/" (c.name) } { (c.title) } " " span.muted { "(" (c.phase) ")" } }
            p.muted { "Its public board, as on " a href={ "/competitions/" (c.name) } { "its page" } " (the first lines)." }
            (super::competitions::board_table(&c.lines))
        }
        @if let Some((t, section)) = &p.latest {
            h2 { "Latest tournament: " a href={ "/tournaments/" (t.tournament_id) } { (t.name) } }
            p.muted { (t.done) " of " (t.total) " matches played" }
            (standings_table(section))
        }
        h2 { "Tournaments" }
        (tournament_table(&p.tournaments))
        p { a href="/tournaments" { "All tournaments" } }
        h2 { "Mazes" }
        (maze_table(&p.mazes))
        h2 #runtimes { "Runtimes for bots" }
        (runtime_table(&p.runtimes))
    };
    page("Leaderboard", body)
}

/// How many package names a runtime's row shows before "and N more".
const PACKAGES_SHOWN: usize = 12;

/// The runtimes: name, languages, programs with versions, packages.
fn runtime_table(rows: &[crate::runner::runtimes::RuntimeInfo]) -> Markup {
    html! {
        p.muted { "A bot names one as " code { "runtime" } " in its bot.toml or upload to have it first on its PATH; "
            "the system's is always there. The whole list: " a href="/api/runtimes" { "/api/runtimes" } "." }
        table.data.runtimes {
            thead { tr { th { "runtime" } th { "languages" } th { "programs" } th { "packages" } } }
            tbody {
                @for r in rows {
                    tr {
                        td { code { (r.name) } }
                        td { (r.languages.join(", ")) }
                        td {
                            @for (i, p) in r.programs.iter().enumerate() {
                                @if i > 0 { br; }
                                code { (p.program) } span.muted { " " (p.version) }
                            }
                        }
                        td {
                            @let names: Vec<String> = r.packages.iter().take(PACKAGES_SHOWN)
                                .map(|p| format!("{} {}", p.name, p.version)).collect();
                            (names.join(", "))
                            @if r.packages.len() > PACKAGES_SHOWN {
                                span.muted { " and " (r.packages.len() - PACKAGES_SHOWN) " more" }
                            }
                        }
                    }
                }
            }
        }
    }
}

pub(super) fn tournament_table(rows: &[TournamentRow]) -> Markup {
    html! {
        @if rows.is_empty() {
            p.muted { "No tournament yet." }
        } @else {
            table.data.tournaments {
                thead { tr { th.num { "id" } th { "name" } th { "progress" } th.num { "repeats" } th { "created" } } }
                tbody {
                    @for t in rows {
                        tr {
                            td.num { (t.tournament_id) }
                            td { a href={ "/tournaments/" (t.tournament_id) } { (t.name) } }
                            td { (t.done) " / " (t.total) @if t.done < t.total { " " (status("running")) } }
                            td.num { (t.repeats) }
                            td { (time(t.created_at)) }
                        }
                    }
                }
            }
        }
    }
}

pub(super) fn maze_table(rows: &[MazeRow]) -> Markup {
    html! {
        @if rows.is_empty() {
            p.muted { "No maze yet." }
        } @else {
            table.data.mazes {
                thead { tr { th.num { "id" } th { "name" } th { "kind" } th.num { "side" } th.num { "optimum" } } }
                tbody {
                    @for m in rows {
                        tr {
                            td.num { (m.maze_id) }
                            td { a href={ "/mazes/" (m.maze_id) } { (m.name) } }
                            @if m.hidden {
                                td { "hidden (ranking)" } td.num { "-" } td.num { "-" }
                            } @else {
                                td { "public" }
                                td.num { (m.dim) "x" (m.dim) }
                                td.num { @match m.optimum { Some(o) => (o), None => "-" } }
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn standing(rank: i64, name: &str, ratio: Option<f64>, played: i64) -> Standing {
        Standing {
            rank,
            bot_id: rank,
            name: name.into(),
            version: 1,
            played,
            finished: played,
            mean_score: rank as f64,
            score_sum30: rank * 30 * played,
            finish_rate: 1.0 / rank as f64,
            mean_ratio: ratio,
            hidden_played: 0,
            uncertainty: Default::default(),
        }
    }

    #[test]
    fn standings_sort_by_each_key() {
        let mut rows = vec![
            standing(1, "zeta", Some(1.5), 3),
            standing(2, "Alpha", None, 9),
            standing(3, "mid", Some(1.1), 5),
        ];
        SortKey::Name.sort(&mut rows);
        assert_eq!(rows[0].name, "Alpha");
        SortKey::Efficiency.sort(&mut rows);
        assert_eq!(
            rows.iter().map(|r| r.rank).collect::<Vec<_>>(),
            [3, 1, 2],
            "no ratio sorts last"
        );
        SortKey::Played.sort(&mut rows);
        assert_eq!(rows[0].name, "Alpha");
        SortKey::Rank.sort(&mut rows);
        assert_eq!(rows[0].rank, 1);
        assert_eq!(SortKey::parse("finish_rate"), Some(SortKey::FinishRate));
        assert_eq!(SortKey::parse("bogus"), None);
    }
}
