//! The organiser's pages (create a competition from its file and mazes, manage one:
//! entrants, versions, queue, times, close, final run, downloads, rejudges) and the
//! admin's page (registration mode, invite code, organisers). Plain forms; every one
//! carries the session's anti-forgery token.

use maud::{Markup, html};

use super::super::layout::{page, status, time};
use super::account::csrf_field;

/// A competition in the organiser's list.
#[derive(Debug, Clone)]
pub struct OrganisedLine {
    /// Short name.
    pub name: String,
    /// Title.
    pub title: String,
    /// Phase.
    pub phase: String,
}

/// The "organise" page: the caller's competitions and the form that creates one.
pub fn organise(csrf: &str, mine: &[OrganisedLine], error: Option<&str>) -> String {
    page(
        "Organise",
        html! {
            h1 { "Organise" }
            h2 { "Your competitions" }
            @if mine.is_empty() { p.muted { "None yet." } } @else {
                ul.organised { @for c in mine {
                    li { a href={ "/competitions/" (c.name) "/manage" } { (c.title) } " " span.muted { "(" (c.name) ", " (c.phase) ")" } }
                } }
            }
            h2 { "Create a competition" }
            p.muted { "Upload its competition file (" code { "competition.toml" } ") and the maze files it names, or a folder exported from a server as an archive (.tar.gz or .zip). Mazes are found by the path the file gives, or by their file name." }
            @if let Some(e) = error { p.error role="alert" { (e) } }
            form.stacked.create-competition method="post" enctype="multipart/form-data" action="/organise" {
                (csrf_field(csrf))
                label { "Competition file " input type="file" name="competition" accept=".toml"; }
                label { "Maze files " input type="file" name="mazes" multiple; }
                p.muted { "or" }
                label { "An exported folder as an archive " input type="file" name="archive" accept=".tar.gz,.tgz,.zip,.tar"; }
                button type="submit" { "Create" }
            }
        },
    )
}

/// One entrant on the manage page.
#[derive(Debug, Clone)]
pub struct EntrantLine {
    /// Its id.
    pub entrant_id: i64,
    /// Entrant.
    pub entrant: String,
    /// Bot id and name.
    pub bot: (i64, String),
    /// Versions: id, number, build status.
    pub versions: Vec<(i64, i64, String)>,
    /// The quotas in words.
    pub quotas: String,
}

/// Everything the manage page shows.
#[derive(Debug, Clone)]
pub struct ManagePage {
    /// Short name.
    pub name: String,
    /// Title.
    pub title: String,
    /// Phase and state in words.
    pub phase: String,
    /// Whether it is closed.
    pub closed: bool,
    /// Whether its results are written.
    pub final_results: bool,
    /// `held` (written, the organisers' only), `final` (published) or empty (none yet).
    pub results_state: String,
    /// Whether the results wait for the organisers to publish them.
    pub hold_results: bool,
    /// Times as RFC 3339 (for the form) and in words.
    pub opens_at: String,
    /// The close.
    pub closes_at: String,
    /// Freeze hours before the close (empty: none).
    pub freeze_hours: String,
    /// Quotas.
    pub versions_per_day: i64,
    /// Practice per day.
    pub practice_per_day: i64,
    /// The entrants.
    pub entrants: Vec<EntrantLine>,
    /// Entrants registered with its invite code that have no bot in it yet: id, name.
    pub registered: Vec<(i64, String)>,
    /// Its own invite code and the link that carries it (a path), if it has one.
    pub invite: Option<(String, String)>,
    /// How new versions are checked: `start`, `match` or `off`.
    pub validation: String,
    /// Matches and builds still to do for it.
    pub work_left: i64,
    /// The final run: played of total.
    pub final_run: Option<(i64, i64)>,
    /// Its mazes: id, set, name.
    pub mazes: Vec<(i64, String, String)>,
    /// Its rejudges, newest first.
    pub rejudges: Vec<crate::storage::rejudges::RejudgeRow>,
    /// The anti-forgery token.
    pub csrf: String,
    /// A notice or an error of the last action.
    pub notice: Option<String>,
}

/// A "new key" button for `whom` (inside a disclosure, so that one click does not end
/// someone's sessions), posting to `action`.
fn new_key_form(action: &str, csrf: &str, whom: &str) -> Markup {
    html! {
        details.new-key {
            summary { "New key…" }
            form.inline method="post" action=(action) {
                (csrf_field(csrf))
                button.danger type="submit" { "Replace the key of " (whom) " now" }
            }
        }
    }
}

/// The manage page of a competition.
pub fn manage(p: &ManagePage) -> String {
    let action = |what: &str| format!("/competitions/{}/{what}", p.name);
    let body = html! {
        h1 { "Manage " (p.title) }
        p.lead { span.phase { (p.phase) } " · " a href={ "/competitions/" (p.name) } { "its public page" } }
        @if let Some(n) = &p.notice { p.notice role="status" { (n) } }
        div.cards {
            div.card { "entrants" b.entrants { (p.entrants.len()) } }
            div.card { "matches and builds to do" b.work-left { (p.work_left) } }
            @if let Some((played, total)) = p.final_run {
                div.card { "final run" b.final-run { (played) " of " (total) } }
            }
        }
        h2 { "Downloads" }
        ul.downloads {
            @if p.final_results || p.results_state == "held" {
                li { a.results-csv href={ "/api/competitions/" (p.name) "/results.csv" } { "results.csv" } " (the final results)" }
            } @else { li.muted { "results.csv comes with the results, after the close and the final run" } }
            li { a.export href={ "/competitions/" (p.name) "/export.tar.gz" } { "the competition as a folder (.tar.gz)" } ": its file and every maze, private ones included" }
        }
        h2 { "The final night" }
        @match p.results_state.as_str() {
            "held" => {
                p.results-held { "The results are written and held: only you see them. Rehearse the reveal on the projector, then publish them; the class learns them from the reveal." }
                ul.finale-links {
                    li { a.reveal-link href=(action("reveal")) { "The reveal" } " (from the last place to the first)" }
                    li { a.races-link href=(action("race")) { "The races" } " (every robot on one maze)" }
                }
                form.stacked.publish method="post" action=(action("publish")) {
                    (csrf_field(&p.csrf))
                    label.check { input type="checkbox" name="confirm" value="yes" required; " I understand: everyone sees the results, the reveal and the races from now on." }
                    button.danger type="submit" { "Publish the results" }
                }
            }
            "final" => {
                p { "The results are published." }
                ul.finale-links {
                    li { a.reveal-link href=(action("reveal")) { "The reveal" } }
                    li { a.races-link href=(action("race")) { "The races" } }
                }
            }
            _ => {
                p.muted { "After the final run: the reveal (from the last place to the first) and the races of every robot on one maze. Hold the results to reveal them to the class yourself." }
                form.inline.hold method="post" action=(action("hold")) {
                    (csrf_field(&p.csrf))
                    label { "When the results are written " select name="hold_results" {
                        option value="no" selected[!p.hold_results] { "publish them at once" }
                        option value="yes" selected[p.hold_results] { "hold them until I publish them" }
                    } }
                    button type="submit" { "Save" }
                }
            }
        }
        h2 { "Invite code" }
        @if !p.closed {
            @match &p.invite {
                Some((code, link)) => {
                    p { "Its code: " code.invite-code { (code) } ". Give the class this link: it opens the competition's page, whose \"How to take part\" registers with the code filled in and then leads to the upload." }
                    p { a.invite-link href=(link) { (link) } " (on this server)" }
                }
                None => p.muted { "None: students register as the server allows (" a href="/register" { "its registration" } "). A code of the competition's own registers them whatever the server's mode and leads them here." },
            }
            form.inline.invite-set method="post" action=(action("invite")) {
                (csrf_field(&p.csrf))
                input type="hidden" name="action" value="set";
                label { "Code (8 to 64 letters, digits, - _ .; empty: a random one) " input type="text" name="invite_code" maxlength="64" pattern=(crate::web::layout::NAME_PATTERN) autocomplete="off"; }
                button type="submit" { @if p.invite.is_some() { "Replace the code" } @else { "Set a code" } }
            }
            @if p.invite.is_some() {
                form.inline.invite-remove method="post" action=(action("invite")) {
                    (csrf_field(&p.csrf))
                    input type="hidden" name="action" value="remove";
                    button type="submit" { "Remove the code" }
                }
            }
        } @else { p.muted { "Closed: its invite code registers no one now." } }
        h2 { "Entrants" }
        @if p.entrants.is_empty() { p.muted { "No entrant yet." } } @else {
            table.data.entrants {
                thead { tr { th { "entrant" } th { "bot" } th { "versions" } th { "quotas" } th { "key" } } }
                tbody { @for e in &p.entrants {
                    tr {
                        td { (e.entrant) }
                        td { a href={ "/bots/" (e.bot.0) } { (e.bot.1) } }
                        td { @for (id, n, s) in &e.versions { span.version title={ "version id " (id) } { "v" (n) " " (status(s)) " " } } }
                        td.muted { (e.quotas) }
                        td { (new_key_form(&action(&format!("entrants/{}/key", e.entrant_id)), &p.csrf, &e.entrant)) }
                    }
                } }
            }
        }
        @if !p.registered.is_empty() {
            h3 { "Registered with the invite code, no bot yet" }
            table.data.registered {
                thead { tr { th { "entrant" } th { "key" } } }
                tbody { @for (id, name) in &p.registered {
                    tr { td { (name) } td { (new_key_form(&action(&format!("entrants/{id}/key")), &p.csrf, name)) } }
                } }
            }
        }
        h2 { "Times and quotas" }
        @if p.closed { p.muted { "Closed: only its texts change now." } } @else {
            form.stacked.edit method="post" action=(action("edit")) {
                (csrf_field(&p.csrf))
                label { "Opens (RFC 3339, e.g. 2026-12-01T09:00:00Z) " input type="text" name="opens_at" value=(p.opens_at); }
                label { "Closes " input type="text" name="closes_at" value=(p.closes_at); }
                label { "Freeze the public board this many hours before the close (empty: no freeze) " input type="text" name="freeze_hours" value=(p.freeze_hours); }
                label { "Versions per entrant per 24 hours " input type="number" min="1" name="versions_per_day" value=(p.versions_per_day); }
                label { "Practice matches per entrant per 24 hours " input type="number" min="0" name="practice_per_day" value=(p.practice_per_day); }
                label { "Validation of each new version " select name="validation" {
                    option value="start" selected[p.validation == "start"] { "start: invalid only if it fails before its first move on every maze tried (it does not start); a failure on one maze is a warning" }
                    option value="match" selected[p.validation == "match"] { "match: invalid for any failure in its validation match on the first practice maze" }
                    option value="off" selected[p.validation == "off"] { "off: no validation match" }
                } }
                button type="submit" { "Save" }
            }
            h2 { "Practice mazes" }
            p.muted { "The mazes entrants practise on (public), and on which each new version plays its validation match, in this order." }
            @let practice: Vec<&(i64, String, String)> = p.mazes.iter().filter(|(_, set, _)| set == "practice").collect();
            @if practice.is_empty() { p.muted { "None: validation matches play a generated maze." } } @else {
                table.data.practice {
                    thead { tr { th { "maze" } th { "remove" } } }
                    tbody { @for (id, _, name) in &practice { tr {
                        td { a href={ "/mazes/" (id) } { (name) } }
                        td { form.inline.practice-remove method="post" action=(action("practice")) {
                            (csrf_field(&p.csrf))
                            input type="hidden" name="remove" value=(id);
                            button type="submit" { "Remove " (name) }
                        } }
                    } } }
                }
            }
            form.stacked.practice-add method="post" enctype="multipart/form-data" action=(action("practice")) {
                (csrf_field(&p.csrf))
                label { "Add a maze file (numeric or ASCII; its file name names it) " input type="file" name="maze" required; }
                button type="submit" { "Add the practice maze" }
            }
            h2 { "Close now" }
            form.stacked.close method="post" action=(action("close")) {
                (csrf_field(&p.csrf))
                label.check { input type="checkbox" name="confirm" value="yes" required; " I understand: no new versions are taken, the final selection is made and the final run starts. This cannot be undone." }
                button.danger type="submit" { "Close the competition now" }
            }
        }
        h2 { "Rejudge" }
        p.muted { "Play again every ranking match of a version or on a maze (after an infrastructure failure or a referee fix). The earlier records are kept and marked superseded; the boards and results are counted again as the matches are played." }
        form.inline.rejudge-version method="post" action=(action("rejudge")) {
            (csrf_field(&p.csrf))
            label { "Version " select name="bot_version_id" {
                @for e in &p.entrants { @for (id, n, _) in &e.versions { option value=(id) { (e.entrant) " v" (n) } } }
            } }
            input type="text" name="reason" placeholder="why" required maxlength="500";
            button type="submit" { "Rejudge the version" }
        }
        form.inline.rejudge-maze method="post" action=(action("rejudge")) {
            (csrf_field(&p.csrf))
            label { "Maze " select name="maze_id" {
                @for (id, set, name) in &p.mazes { @if set != "practice" { option value=(id) { (set) ": " (name) } } }
            } }
            input type="text" name="reason" placeholder="why" required maxlength="500";
            button type="submit" { "Rejudge the maze" }
        }
        @if !p.rejudges.is_empty() {
            table.data.rejudges {
                thead { tr { th.num { "rejudge" } th { "what" } th.num { "matches" } th { "why" } th { "by" } th { "when" } } }
                tbody { @for r in &p.rejudges {
                    tr {
                        td.num { (r.rejudge_id) }
                        td { @if let Some(v) = r.bot_version_id { "version id " (v) } @if let Some(m) = r.maze_id { "maze " (m) } }
                        td.num { (r.matches) }
                        td { (r.reason) }
                        td { (r.requested_by) }
                        td { (time(r.created_at)) }
                    }
                } }
            }
        }
    };
    page(&format!("Manage {}", p.name), body)
}

/// Everything the admin's page shows.
#[derive(Debug, Clone)]
pub struct AdminPage {
    /// `open`, `invite` or `closed`.
    pub mode: String,
    /// Organisers: id, name, registered at.
    pub organisers: Vec<(i64, String, i64)>,
    /// The anti-forgery token.
    pub csrf: String,
    /// A notice or an error of the last action.
    pub notice: Option<String>,
    /// A new organiser's name and key, shown once.
    pub new_key: Option<(String, String)>,
    /// The entrants' search: the text searched for.
    pub search: String,
    /// The entrants found: id, name, members, registered at, key replaced at.
    pub entrants: Vec<crate::registry::entrants::EntrantLine>,
    /// How many entrants match the search in all.
    pub entrants_total: i64,
}

fn mode_option(current: &str, value: &str, label: &str) -> Markup {
    html! { option value=(value) selected[current == value] { (label) } }
}

/// The admin's page.
pub fn admin(p: &AdminPage) -> String {
    page(
        "Administration",
        html! {
            h1 { "Administration" }
            @if let Some(n) = &p.notice { p.notice role="status" { (n) } }
            @if let Some((name, key)) = &p.new_key {
                p.warning { strong { "The key of organiser " (name) ", shown once: " } }
                pre.key id="new-key" { (key) }
            }
            h2 { "Registration" }
            p { "Now: " strong.mode { (p.mode) } "." }
            form.stacked.registration method="post" action="/admin/registration" {
                (csrf_field(&p.csrf))
                label { "Mode " select name="mode" {
                    (mode_option(&p.mode, "open", "open: anyone registers"))
                    (mode_option(&p.mode, "invite", "invite: with the invite code"))
                    (mode_option(&p.mode, "closed", "closed: only the admin registers entrants"))
                } }
                label { "Invite code (with invite; at least 8 characters; only its hash is kept) " input type="text" name="invite_code" autocomplete="off"; }
                button type="submit" { "Set" }
            }
            h2 { "Organisers" }
            @if p.organisers.is_empty() { p.muted { "None yet." } } @else {
                table.data.organisers {
                    thead { tr { th.num { "id" } th { "name" } th { "since" } th { "key" } } }
                    tbody { @for (id, name, at) in &p.organisers { tr {
                        td.num { (id) } td { (name) } td { (time(*at)) }
                        td { (new_key_form(&format!("/admin/organisers/{id}/key"), &p.csrf, &format!("organiser {name}"))) }
                    } } }
                }
            }
            form.inline.organiser method="post" action="/admin/organisers" {
                (csrf_field(&p.csrf))
                label { "Name " input type="text" name="name" placeholder="organiser's name" required maxlength="64"; }
                button type="submit" { "Add an organiser" }
            }
            h2 #entrants { "Entrants" }
            form.inline.search method="get" action="/admin#entrants" role="search" {
                label { "Name or member " input type="search" name="search" value=(p.search) maxlength="100"; }
                button type="submit" { "Search" }
            }
            p.muted.found { (p.entrants_total) " entrants"
                @if !p.search.is_empty() { " match " q { (p.search) } }
                @if (p.entrants.len() as i64) < p.entrants_total { "; the first " (p.entrants.len()) " by name are shown" }
                "." }
            @if !p.entrants.is_empty() {
                table.data.entrants {
                    thead { tr { th.num { "id" } th { "name" } th { "members" } th { "since" } th { "key replaced" } th { "key" } } }
                    tbody { @for e in &p.entrants { tr {
                        td.num { (e.entrant_id) } td.name { (e.name) } td { (e.members.join(", ")) } td { (time(e.created_at)) }
                        td { (e.key_rotated_at.map(time).unwrap_or_default()) }
                        td { (new_key_form(&format!("/admin/entrants/{}/key", e.entrant_id), &p.csrf, &format!("entrant {}", e.name))) }
                    } } }
                }
            }
        },
    )
}
