//! The server's pages: leaderboard, bots, mazes, matches, tournaments. Each function
//! takes what the page shows (already filtered for what an anonymous visitor may see:
//! `api::pages` applies the hidden-maze rules) and returns the whole page.
//!
//! Lists are plain HTML tables with links (sorting and paging are links too), so they
//! work without JavaScript; scripts only add live progress and the owner's logs.

use maud::{Markup, PreEscaped, html};

use super::layout::{page, score, status, time};
use super::viewer::{ViewerData, embed};
use crate::storage::bots::{BotRow, BotVersionRow};
use crate::storage::leaderboard::Standing;
use crate::storage::matches::MatchRow;
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
    /// Recent tournaments.
    pub tournaments: Vec<TournamentRow>,
    /// Every maze (hidden ones by name only).
    pub mazes: Vec<MazeRow>,
}

fn standings_table(s: &StandingsSection) -> Markup {
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
                    th.num { (link(SortKey::FinishRate, "finish rate")) }
                    th.num title="mean of score / the maze's optimal run-1 steps (1.0 is perfect)" {
                        (link(SortKey::Efficiency, "score / optimum"))
                    }
                    th.num { (link(SortKey::Played, "played")) }
                } }
                tbody {
                    @for r in &s.rows {
                        tr {
                            td.num { (r.rank) }
                            td { a href={ "/bots/" (r.bot_id) } { (r.name) } span.muted { " v" (r.version) } }
                            td.num { (format!("{:.3}", r.mean_score)) }
                            td.num { (format!("{:.0}%", r.finish_rate * 100.0)) }
                            td.num { @match r.mean_ratio { Some(x) => (format!("{x:.3}")), None => span.muted { "-" } } }
                            td.num { (r.played) }
                        }
                    }
                }
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
    };
    page("Leaderboard", body)
}

fn tournament_table(rows: &[TournamentRow]) -> Markup {
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

fn maze_table(rows: &[MazeRow]) -> Markup {
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

    /// The links.
    pub fn links(&self) -> Markup {
        let shown_to = (self.offset + self.limit).min(self.total);
        html! {
            div.pager {
                span.muted { (self.offset.min(self.total)) "–" (shown_to) " of " (self.total) }
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

/// A match in a list, with the names to show and what may be said of its failure.
#[derive(Debug, Clone)]
pub struct MatchLine {
    /// The stored match.
    pub row: MatchRow,
    /// Its bot's name.
    pub bot: String,
    /// Its maze's name.
    pub maze: String,
    /// The failure's reason as the visitor may see it (hidden mazes: the step only).
    pub reason: Option<String>,
}

/// A table of matches.
pub fn match_table(lines: &[MatchLine]) -> Markup {
    html! {
        @if lines.is_empty() { p.muted { "No match." } } @else {
            table.data.matches {
                thead { tr {
                    th.num { "match" } th { "bot" } th { "maze" } th.num { "seed" } th { "status" }
                    th.num { "score" } th.num { "run 0" } th.num { "run 1" } th { "reason" }
                } }
                tbody {
                    @for l in lines {
                        tr {
                            td.num { a href={ "/matches/" (l.row.match_id) } { (l.row.match_id) } }
                            td { a href={ "/bots/" (l.row.bot_id) } { (l.bot) } span.muted { " v" (l.row.version) } }
                            td { a href={ "/mazes/" (l.row.maze_id) } { (l.maze) } }
                            td.num { (l.row.seed) }
                            td { (status(&l.row.status)) }
                            td.num { @if l.row.status == "finished" { (score(l.row.score)) } @else { span.muted { "-" } } }
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

fn opt(v: Option<i64>) -> Markup {
    html! { @match v { Some(v) => (v), None => span.muted { "-" } } }
}

/// The list of matches, with its filters.
pub fn matches(lines: &[MatchLine], filters: &str, pager: &Pager) -> String {
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
    pub total_matches: i64,
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
        p { a href={ "/matches?bot_id=" (b.bot_id) } { "All " (p.total_matches) " matches" } }
        h2 { "Owner's logs" }
        p.muted { "The bot's owner can see each failed match's stderr and the build logs: paste the owner token (it stays in this page and is sent only to this server's API)." }
        form.inline #owner-form {
            input #owner-token type="password" placeholder="owner token" autocomplete="off";
            button type="submit" { "Show logs" }
        }
        div #owner-logs {}
        script { (PreEscaped(OWNER_LOGS_JS.replace("BOT_ID", &b.bot_id.to_string()))) }
    };
    page(&b.name, body)
}

/// The bot page's script: fetches the logs of the listed failed matches and the build
/// logs with the owner's token; shows them as text.
const OWNER_LOGS_JS: &str = r#"
(function () {
  var form = document.getElementById('owner-form');
  var out = document.getElementById('owner-logs');
  function token() { return document.getElementById('owner-token').value.trim(); }
  function block(title, text) {
    var h = document.createElement('h3'); h.textContent = title; out.appendChild(h);
    var pre = document.createElement('pre'); pre.className = 'log'; pre.textContent = text; out.appendChild(pre);
  }
  function get(url) {
    return fetch(url, { headers: { authorization: 'Bearer ' + token() } }).then(function (r) {
      return r.json().then(function (j) { if (!r.ok) { throw new Error(j.error ? j.error.message : r.status); } return j; });
    });
  }
  form.addEventListener('submit', function (e) {
    e.preventDefault();
    out.textContent = '';
    var rows = document.querySelectorAll('table.matches tbody tr');
    var failed = [];
    rows.forEach(function (tr) {
      var st = tr.querySelector('.status');
      if (st && ['finished', 'queued', 'running', 'step_limit'].indexOf(st.textContent) < 0) {
        failed.push(tr.querySelector('td a').textContent);
      }
    });
    if (failed.length === 0) { block('Logs', 'No failed match in the recent list.'); }
    failed.forEach(function (id) {
      get('/api/matches/' + id + '/log').then(function (j) {
        var text = j.redacted ? 'hidden maze: status ' + j.status + (j.step ? ' at step ' + j.step : '')
          : (j.error ? (j.error.reason || '') + (j.error.line ? '\noffending line: ' + j.error.line : '') + '\n\n' : '') + (j.stderr_tail || '');
        block('match ' + id + ' (' + j.status + ')', text);
      }).catch(function (err) { block('match ' + id, 'error: ' + err.message); });
    });
  });
  document.querySelectorAll('a.build-log').forEach(function (a) {
    a.addEventListener('click', function (e) {
      e.preventDefault();
      get('/api/bots/BOT_ID/versions/' + a.dataset.version + '/build-log').then(function (j) {
        block('build of version ' + j.version + ' (' + j.build_status + ')', j.build_log || '(no output yet)');
      }).catch(function (err) { block('build of version ' + a.dataset.version, 'error: ' + err.message + ' (paste the owner token above)'); });
    });
  });
})();
"#;

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
}

/// A match's page: its result, and the replay viewer.
pub fn match_page(p: &MatchPage<'_>) -> String {
    let r = &p.line.row;
    let title = format!("Match {}", r.match_id);
    let body = html! {
        h1 { (title) ": " (p.line.bot) " on " (p.line.maze) }
        div.cards {
            div.card { "status" b { (status(&r.status)) } }
            div.card { "score" b { @if r.status == "finished" { (score(r.score)) } @else { "-" } } }
            div.card { "run 0 / run 1 steps" b { (opt(r.run0_steps)) " / " (opt(r.run1_steps)) } }
            div.card { "seed" b { (r.seed) } }
            @if let Some(t) = r.tournament_id {
                div.card { "tournament" b { a href={ "/tournaments/" (t) } { (t) } } }
            }
        }
        @if let Some(reason) = &p.line.reason { p { strong { "Reason: " } (reason) } }
        p {
            a href={ "/bots/" (r.bot_id) } { "bot " (p.line.bot) } " · "
            a href={ "/mazes/" (r.maze_id) } { "maze " (p.line.maze) } " · "
            a href={ "/api/matches/" (r.match_id) } { "JSON" }
        }
        @match &p.viewer {
            Some(data) => (embed(data)),
            None => {
                @if r.maze_hidden {
                    p.muted { "Played on a hidden ranking maze: its replay is not shown." }
                } @else {
                    p.muted { "Not played yet." }
                }
            }
        }
    };
    page(&title, body)
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
}

/// One bot x maze cell of a tournament.
#[derive(Debug, Clone, Default)]
pub struct Cell {
    /// Matches played (final).
    pub played: i64,
    /// Matches finished.
    pub finished: i64,
    /// Sum of finished scores.
    pub score_sum: f64,
    /// A match to link to (the first failed one if any, else the first).
    pub link: Option<i64>,
    /// Matches in all.
    pub total: i64,
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
            div.progress { div #progress-bar style={ "width:" (pct) "%" } {} }
            p #progress-text { (t.done) " of " (t.total) " matches played" }
        }
        h2 { "Standings" }
        (standings_table(&p.standings))
        h2 { "Bot x maze" }
        p.muted { "Mean score of the finished matches, and how many finished; a cell links to one of its matches (a failed one first)." }
        table.data.grid {
            thead { tr { th { "bot" } @for (id, name) in &p.mazes { th { a href={ "/mazes/" (id) } { (name) } } } } }
            tbody {
                @for (bot_id, bot) in &p.bots {
                    tr {
                        td { a href={ "/bots/" (bot_id) } { (bot) } }
                        @for (maze_id, _) in &p.mazes {
                            @let c = p.cells.get(&(*bot_id, *maze_id)).cloned().unwrap_or_default();
                            td.num {
                                @if c.finished > 0 { (format!("{:.3}", c.score_sum / c.finished as f64)) } @else if c.played > 0 { "DNF" } @else { span.muted { "…" } }
                                br;
                                span.muted { (c.finished) "/" (c.total) }
                                @if let Some(id) = c.link { " " a href={ "/matches/" (id) } { "#" (id) } }
                            }
                        }
                    }
                }
            }
        }
        p { a href={ "/matches?tournament_id=" (t.tournament_id) } { "Every match" } }
        script { (PreEscaped(PROGRESS_JS)) }
    };
    page(&t.name, body)
}

/// Live progress: polls the tournament's JSON every two seconds until it is complete,
/// then reloads once to show the final tables.
const PROGRESS_JS: &str = r#"
(function () {
  var box = document.getElementById('progress');
  var id = box.dataset.tournament, total = +box.dataset.total, done = +box.dataset.done;
  if (done >= total) { return; }
  var timer = setInterval(function () {
    fetch('/api/tournaments/' + id).then(function (r) { return r.json(); }).then(function (t) {
      box.dataset.done = t.done;
      document.getElementById('progress-bar').style.width = (t.total ? Math.floor(t.done * 100 / t.total) : 100) + '%';
      document.getElementById('progress-text').textContent = t.done + ' of ' + t.total + ' matches played';
      if (t.done >= t.total) { clearInterval(timer); location.reload(); }
    }).catch(function () {});
  }, 2000);
})();
"#;

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
            finish_rate: 1.0 / rank as f64,
            mean_ratio: ratio,
            hidden_played: 0,
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

    #[test]
    fn pager_links_move_by_pages() {
        let p = Pager {
            base: "/matches?bot_id=2".into(),
            offset: 50,
            limit: 50,
            total: 120,
        };
        let html = p.links().into_string();
        assert!(html.contains("/matches?bot_id=2&amp;offset=0&amp;limit=50"));
        assert!(html.contains("/matches?bot_id=2&amp;offset=100&amp;limit=50"));
    }
}
