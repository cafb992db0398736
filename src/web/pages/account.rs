//! The pages of a signed-in visitor: logging in, registering (the key shown once),
//! "me" (bots, versions, builds and validation, quotas, ranks, practice, matches) and
//! the submission form. Plain forms that work without JavaScript; every form that
//! changes something carries the session's anti-forgery token.

use maud::{Markup, html};

use super::super::layout::{page, status, time};
use super::lists::{MatchLine, match_table};
use super::ranks;
use crate::competition::Quota;
use crate::registry::competitions::BoardLine;

/// The hidden anti-forgery field of a form.
pub fn csrf_field(token: &str) -> Markup {
    html! { input type="hidden" name="csrf" value=(token); }
}

/// A short page with a heading and one paragraph (errors and notices of the forms).
pub fn message(title: &str, text: &str) -> String {
    page(
        title,
        html! {
            h1 { (title) }
            p.message { (text) }
            p { a href="/" { "The site" } " · " a href="/me" { "My page" } " · " a href="/login" { "Log in" } }
        },
    )
}

/// An error or a notice above a form.
fn notice(error: Option<&str>) -> Markup {
    html! {
        @if let Some(e) = error { p.error role="alert" { (e) } }
    }
}

/// The login page.
pub fn login(error: Option<&str>, next: &str) -> String {
    page(
        "Log in",
        html! {
            h1 { "Log in" }
            p.lead { "Paste your key: the one you were shown when you registered (an entrant's key), an organiser's key, a bot's owner token, or the admin token. It is sent once; your browser then keeps a session cookie." }
            (notice(error))
            form.stacked method="post" action="/login" {
                input type="hidden" name="next" value=(next);
                label { "Key " input type="password" name="key" autocomplete="current-password" required; }
                button type="submit" { "Log in" }
            }
            p { "No key yet? " a href="/register" { "Register" } "." }
        },
    )
}

/// What the registration page knows of the server.
#[derive(Debug, Clone)]
pub struct RegisterPage {
    /// `open`, `invite` or `closed`.
    pub mode: String,
}

/// The registration form.
pub fn register(p: &RegisterPage, error: Option<&str>, name: &str, members: &str) -> String {
    page(
        "Register",
        html! {
            h1 { "Register" }
            @match p.mode.as_str() {
                "closed" => {
                    p.lead { "Registration is closed on this server: the admin registers entrants. Ask your organiser for your key, then " a href="/login" { "log in" } "." }
                }
                _ => {
                    p.lead { "Register yourself or your team as an entrant. You get a key: it signs you in here and acts for your bots from the command line or the API." }
                    (notice(error))
                    form.stacked method="post" action="/register" {
                        label { "Name (letters, digits, - _ .) " input type="text" name="name" value=(name) required maxlength="64" pattern="[A-Za-z0-9._-]+"; }
                        label { "Members (one per line, optional) " textarea name="members" rows="3" { (members) } }
                        @if p.mode == "invite" {
                            label { "Invite code " input type="text" name="invite_code" required autocomplete="off"; }
                        }
                        button type="submit" { "Register" }
                    }
                }
            }
        },
    )
}

/// The page after a registration: the key, shown once.
pub fn registered(name: &str, key: &str) -> String {
    key_page("Registered", &format!("Welcome, {name}"), name, key)
}

/// The page after a key was replaced: the new key, shown once.
pub fn replaced(name: &str, key: &str) -> String {
    key_page("New key", "Your new key", name, key)
}

fn key_page(title: &str, heading: &str, name: &str, key: &str) -> String {
    page(
        title,
        html! {
            h1 { (heading) }
            p.warning { strong { "Save your key now: it is shown only this once." } " It signs you in on any browser and acts for your bots from the command line (" code { "mazearena login" } ") or the API (" code { "Authorization: Bearer KEY" } "). If you lose it, the admin can give you a new one." }
            pre.key id="new-key" { (key) }
            p { a.button download={ "mazearena-key-" (name) ".txt" } href={ "data:text/plain;charset=utf-8," (key) } { "Download the key as a file" } }
            p { "You are signed in. Next: " a href="/competitions" { "choose a competition" } " and upload your bot, or go to " a href="/me" { "your page" } "." }
        },
    )
}

/// One version on the "me" page.
#[derive(Debug, Clone)]
pub struct MyVersion {
    /// Number.
    pub version: i64,
    /// Uploaded at (unix ms).
    pub created_at: i64,
    /// Command.
    pub command: String,
    /// `building`, `ready`, `build_failed` or `invalid`.
    pub build_status: String,
    /// Its build and validation log (the owner's), if any yet.
    pub log: Option<String>,
}

/// One bot on the "me" page.
#[derive(Debug, Clone)]
pub struct MyBot {
    /// Id.
    pub bot_id: i64,
    /// Name.
    pub name: String,
    /// Versions, newest first.
    pub versions: Vec<MyVersion>,
}

/// A version of the entered bot in a competition, as its entrant sees it.
#[derive(Debug, Clone)]
pub struct MySubmission {
    /// Number.
    pub version: i64,
    /// Build status.
    pub build_status: String,
    /// `waiting`, `playing`, `ranked`, `not_counted`.
    pub status: String,
    /// Its public numbers once ranked.
    pub public: Option<BoardLine>,
}

/// A competition on the "me" page.
#[derive(Debug, Clone)]
pub struct MyCompetition {
    /// Short name.
    pub name: String,
    /// Title.
    pub title: String,
    /// Phase in words.
    pub phase: String,
    /// Whether new versions are taken (open, or frozen).
    pub taking_part: bool,
    /// The entered bot.
    pub bot_id: Option<i64>,
    /// Its versions, newest first.
    pub versions: Vec<MySubmission>,
    /// The version quota.
    pub versions_quota: Quota,
    /// The practice quota.
    pub practice_quota: Quota,
    /// The practice mazes: id and name.
    pub practice_mazes: Vec<(i64, String)>,
    /// The final result once written.
    pub final_result: Option<BoardLine>,
}

/// Everything the "me" page shows.
#[derive(Debug, Clone)]
pub struct MePage {
    /// Who is signed in, in words.
    pub who: String,
    /// `admin`, `organiser`, `entrant` or `owner`.
    pub kind: String,
    /// The forms' anti-forgery token.
    pub csrf: String,
    /// A notice from the last action.
    pub notice: Option<String>,
    /// The competitions (entrants).
    pub competitions: Vec<MyCompetition>,
    /// The bots.
    pub bots: Vec<MyBot>,
    /// Their latest matches.
    pub matches: Vec<MatchLine>,
    /// Something is building or playing: the page reloads itself.
    pub live: bool,
    /// What the visitor has used of the server's quotas on uploads, in words.
    pub uploads_quota: Option<String>,
}

/// The "me" page.
pub fn me(p: &MePage) -> String {
    let body = html! {
        h1 { "My page" }
        p.lead { "Signed in as " strong.who { (p.who) } "." }
        form.inline method="post" action="/logout" {
            (csrf_field(&p.csrf))
            button type="submit" { "Log out" }
        }
        @if p.kind == "entrant" {
            details.rotate {
                summary { "Replace my key" }
                p.muted { "If your key was seen by someone else: a new key replaces it at once. The old key, your bots' owner tokens and every session opened with them stop working (log in again on your other browsers and with " code { "mazearena login" } ")." }
                form.inline.rotate method="post" action="/me/key" {
                    (csrf_field(&p.csrf))
                    button.danger type="submit" { "Replace my key now" }
                }
            }
        }
        @if let Some(n) = &p.notice { p.notice role="status" { (n) } }
        @if p.live { p.muted.live { "Something is building or playing: this page reloads every 5 seconds." } }
        @if let Some(q) = &p.uploads_quota { p.quota.uploads { (q) } }
        @if p.kind == "admin" || p.kind == "organiser" {
            h2 { "Organising" }
            ul {
                li { a href="/organise" { "Create a competition" } " or manage yours" }
                @if p.kind == "admin" { li { a href="/admin" { "Server administration" } ": registration, invite code, organisers" } }
            }
        }
        @for c in &p.competitions {
            section.my-competition id={ "competition-" (c.name) } {
                h2 { a href={ "/competitions/" (c.name) } { (c.title) } " " span.muted { "(" (c.phase) ")" } }
                @if let Some(f) = &c.final_result {
                    p.final-result { strong { "Final rank " (f.rank) } " with version " (f.version) ": mean score " (format!("{:.3}", f.mean_score)) " over " (f.played) " private matches (" (f.finished) " finished)." }
                }
                p.quota { (c.versions_quota.message) }
                p.quota { (c.practice_quota.message) }
                @match c.bot_id {
                    None => {
                        @if c.taking_part { p { a.button href={ "/competitions/" (c.name) "/submit" } { "Take part: upload your bot" } } }
                        @else { p.muted { "You have no bot in this competition." } }
                    }
                    Some(bot) => {
                        @if c.taking_part { p { a.button href={ "/competitions/" (c.name) "/submit" } { "Upload a new version" } } }
                        table.data.submissions {
                            thead { tr { th.num { "version" } th { "build" } th { "status" } th.num { "public rank" } th.num { "mean" } (ranks::header_cells()) th.num { "finished" } } }
                            tbody {
                                @for v in &c.versions {
                                    tr {
                                        td.num { (v.version) }
                                        td { (status(&v.build_status)) }
                                        td { (v.status) }
                                        @match &v.public {
                                            Some(l) => {
                                                (ranks::rank_cell(l.rank, &l.uncertainty))
                                                td.num { (format!("{:.3}", l.mean_score)) }
                                                (ranks::interval_cell(&l.uncertainty))
                                                (ranks::tie_cell(&l.uncertainty))
                                                td.num { (l.finished) "/" (l.played) }
                                            }
                                            None => { td.num { "-" } td.num { "-" } td.num { "-" } td {} td.num { "-" } }
                                        }
                                    }
                                }
                            }
                        }
                        @if !c.practice_mazes.is_empty() {
                            form.inline.practice method="post" action="/me/practice" {
                                (csrf_field(&p.csrf))
                                input type="hidden" name="bot_id" value=(bot);
                                label { "Practice maze " select name="maze_id" {
                                    @for (id, name) in &c.practice_mazes { option value=(id) { (name) " (maze " (id) ")" } }
                                } }
                                button type="submit" { "Practice" }
                            }
                        }
                    }
                }
            }
        }
        @if p.kind == "entrant" && p.competitions.is_empty() {
            p { "No competition is running. " a href="/competitions" { "See the competitions" } "." }
        }
        @if !p.bots.is_empty() {
            h2 { "My bots" }
            @for b in &p.bots {
                section.my-bot {
                    h3 { a href={ "/bots/" (b.bot_id) } { (b.name) } " " span.muted { "(bot " (b.bot_id) ")" } }
                    @for (i, v) in b.versions.iter().enumerate() {
                        details.version open[i == 0 || v.build_status != "ready"] {
                            summary { "version " (v.version) " " (status(&v.build_status)) " " span.muted { (time(v.created_at)) " · " code { (v.command) } } }
                            @match &v.log {
                                Some(log) => { pre.log.build-log { (log) } }
                                None => { p.muted { "No build or validation output yet." } }
                            }
                        }
                    }
                }
            }
        }
        @if !p.matches.is_empty() {
            h2 { "My latest matches" }
            p.muted { "Open a match to replay it with your bot's stderr at each step." }
            (match_table(&p.matches))
        }
    };
    let html = page("My page", body);
    if p.live {
        html.replacen(
            "<meta charset=\"utf-8\">",
            "<meta charset=\"utf-8\"><meta http-equiv=\"refresh\" content=\"5\">",
            1,
        )
    } else {
        html
    }
}

/// What the submission form offers.
#[derive(Debug, Clone)]
pub struct SubmitPage {
    /// The competition's name.
    pub competition: String,
    /// Its title.
    pub title: String,
    /// The anti-forgery token.
    pub csrf: String,
    /// The entered bot (a new version of it), or none (a new bot, entered).
    pub bot: Option<(i64, String)>,
    /// The runtimes the server offers: name and what it is.
    pub runtimes: Vec<(String, String)>,
    /// The version quota in words.
    pub quota: String,
    /// The error of the last try.
    pub error: Option<String>,
}

/// The submission form.
pub fn submit(p: &SubmitPage) -> String {
    page(
        "Submit",
        html! {
            h1 { "Submit to " (p.title) }
            p.lead {
                @match &p.bot {
                    Some((id, name)) => { "A new version of your bot " a href={ "/bots/" (id) } { (name) } ". " }
                    None => { "Your bot, entered in this competition. " }
                }
                (p.quota)
            }
            (notice(p.error.as_deref()))
            form.stacked.submit method="post" enctype="multipart/form-data" action={ "/competitions/" (p.competition) "/submit" } {
                (csrf_field(&p.csrf))
                @if p.bot.is_none() {
                    label { "Bot name (letters, digits, - _ .) " input type="text" name="name" required maxlength="64" pattern="[A-Za-z0-9._-]+"; }
                }
                fieldset {
                    legend { "Your files" }
                    label { "Files (one or several text files) " input type="file" name="files" multiple; }
                    p.muted { "or" }
                    label { "A folder as an archive (.zip, .tar.gz) " input type="file" name="archive" accept=".zip,.tar.gz,.tgz,.tar"; }
                }
                fieldset {
                    legend { "How it runs" }
                    label.check { input type="checkbox" name="original_task" value="true"; " A " code { "robot.py" } " of the original task (class Robot with next_move): the server adds the adapter, so upload only your own files" }
                    label { "Command (leave empty for a robot.py of the original task) " input type="text" name="command" placeholder="python3 bot.py"; }
                    label { "Build command (optional, run once without network) " input type="text" name="build" placeholder="make"; }
                    label { "Protocol " select name="protocol" {
                        option value="v1" { "v1: JSON lines (the kits, an original-task robot.py)" }
                        option value="mms" { "mms: a mouse written for the mms simulator, unchanged" }
                    } }
                    label { "Runtime " select name="runtime" {
                        option value="" { "the system's (python3, gcc, node, java, go...)" }
                        @for (name, what) in &p.runtimes { option value=(name) { (name) " — " (what) } }
                    } }
                }
                button type="submit" { "Upload" }
            }
            p.muted { "After the upload the server builds your version (if it has a build command) and plays a short validation match; " a href="/me" { "your page" } " shows both as they happen." }
        },
    )
}
