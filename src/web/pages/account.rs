//! The pages of a signed-in visitor: logging in, registering (the key shown once),
//! "me" (bots, versions, builds and validation, quotas, ranks, practice, matches) and
//! the submission form. Plain forms that work without JavaScript; every form that
//! changes something carries the session's anti-forgery token.

use maud::{Markup, PreEscaped, html};

use super::super::layout::{NAME_PATTERN, page, status, time};
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
#[derive(Debug, Clone, Default)]
pub struct RegisterPage {
    /// `open`, `invite` or `closed`.
    pub mode: String,
    /// The invite code the visitor's link carried (filled in).
    pub invite: Option<String>,
    /// The competition whose code it is: its title (none: not a competition's code).
    pub competition: Option<String>,
    /// Why the carried code does not register (a wrong code; its competition closed).
    pub invite_error: Option<String>,
}

/// The registration form.
pub fn register(p: &RegisterPage, error: Option<&str>, name: &str, members: &str) -> String {
    page(
        "Register",
        html! {
            h1 { "Register" }
            @if let Some(title) = &p.competition {
                p.lead.competition { "You are registering for " strong { (title) } ": with its invite code, filled in below." }
            }
            @if let Some(e) = &p.invite_error { p.error role="alert" { (e) } }
            @match p.mode.as_str() {
                "closed" if p.competition.is_none() => {
                    p.lead { "Registration is closed on this server: the admin registers entrants. Ask your organiser for your key, then " a href="/login" { "log in" } "." }
                }
                _ => {
                    p.lead { "Register yourself or your team as an entrant. You get a key: it signs you in here and acts for your bots from the command line or the API." }
                    (notice(error))
                    form.stacked method="post" action="/register" {
                        label { "Name (letters, digits, - _ .) " input type="text" name="name" value=(name) required maxlength="64" pattern=(NAME_PATTERN); }
                        label { "Members (one per line, optional) " textarea name="members" rows="3" { (members) } }
                        @if p.mode == "invite" || p.invite.is_some() {
                            label { "Invite code " input type="text" name="invite_code" value=(p.invite.as_deref().unwrap_or("")) required[p.mode == "invite" && p.competition.is_none()] autocomplete="off"; }
                        }
                        button type="submit" { "Register" }
                    }
                }
            }
        },
    )
}

/// The page after a registration: the key, shown once; with the competition whose
/// invite code registered it (its short name), the way to its submit form.
pub fn registered(name: &str, key: &str, competition: Option<&str>) -> String {
    let next = html! {
        @match competition {
            Some(c) => p.next { "You are signed in. Next: " a.button href={ "/competitions/" (c) "/submit" } { "upload your robot to " (c) } " or go to " a href="/me" { "your page" } "." },
            None => p.next { "You are signed in. Next: " a href="/competitions" { "choose a competition" } " and upload your bot, or go to " a href="/me" { "your page" } "." },
        }
    };
    key_page("Registered", &format!("Welcome, {name}"), name, key, next)
}

/// The page after a key was replaced: the new key, shown once.
pub fn replaced(name: &str, key: &str) -> String {
    let next = html! { p { "You are signed in with it. Go to " a href="/me" { "your page" } "." } };
    key_page("New key", "Your new key", name, key, next)
}

/// The page after the admin or an organiser gave `whom` (an entrant or an organiser,
/// in words) a new key: shown once, to be handed over; `back` is the page to go on to.
pub fn handed_over(whom: &str, file_name: &str, key: &str, back: &str) -> String {
    page(
        "New key",
        html! {
            h1 { "A new key for " (whom) }
            p.warning { strong { "Give this key to " (whom) " now: it is shown only this once." } " The old key, and every session opened with it, no longer work." }
            pre.key id="new-key" { (key) }
            p { a.button download={ "mazearena-key-" (file_name) ".txt" } href={ "data:text/plain;charset=utf-8," (key) } { "Download the key as a file" } }
            p { a href=(back) { "Back" } }
        },
    )
}

fn key_page(title: &str, heading: &str, name: &str, key: &str, next: Markup) -> String {
    page(
        title,
        html! {
            h1 { (heading) }
            p.warning { strong { "Save your key now: it is shown only this once." } " It signs you in on any browser and acts for your bots from the command line (" code { "mazearena login" } ") or the API (" code { "Authorization: Bearer KEY" } "). If you lose it, your competition's organiser or the admin can give you a new one." }
            pre.key id="new-key" { (key) }
            p { a.button download={ "mazearena-key-" (name) ".txt" } href={ "data:text/plain;charset=utf-8," (key) } { "Download the key as a file" } }
            (next)
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
    /// Why the last "replace my key" was refused.
    pub key_error: Option<String>,
}

/// The submit form's script: offers the uploaded `.py` files as the robot's file.
pub const SUBMIT_FORM_JS: &str = include_str!("../assets/submit_form.js");

/// How many of a runtime's packages the submit form's list names (with versions).
const RUNTIME_PACKAGES_SHOWN: usize = 12;

/// What runtime `r` is, in the submit form's list: its programs and packages with their
/// versions (as the home page says them), so that two runtimes that differ only in a
/// package's version do not look the same.
pub fn runtime_words(r: &crate::runner::runtimes::RuntimeInfo) -> String {
    let programs: Vec<String> = r
        .programs
        .iter()
        .map(|p| format!("{} {}", p.program, p.version))
        .collect();
    let packages: Vec<String> = r
        .packages
        .iter()
        .take(RUNTIME_PACKAGES_SHOWN)
        .map(|p| format!("{} {}", p.name, p.version))
        .collect();
    let mut what = programs.join(", ");
    if !packages.is_empty() {
        what.push_str(&format!(" with {}", packages.join(", ")));
    }
    if r.packages.len() > RUNTIME_PACKAGES_SHOWN {
        what.push_str(&format!(
            " and {} more",
            r.packages.len() - RUNTIME_PACKAGES_SHOWN
        ));
    }
    what
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
            details.rotate open[p.key_error.is_some()] {
                summary { "Replace my key" }
                p.muted { "If your key was seen by someone else: a new key replaces it at once. The old key, your bots' owner tokens and every session opened with them stop working (log in again on your other browsers and with " code { "mazearena login" } ")." }
                @if let Some(e) = &p.key_error { p.error role="alert" { (e) } }
                form.inline.rotate method="post" action="/me/key" {
                    (csrf_field(&p.csrf))
                    label { "Your current key " input type="password" name="current_key" required autocomplete="current-password"; }
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
                            thead { tr { th.num { "version" } th.wide { "build" } th { "status" } th.num { "public rank" } th.num { "mean" } (ranks::header_cells()) th.num.wide { "finished" } } }
                            tbody {
                                @for v in &c.versions {
                                    tr {
                                        td.num { (v.version) }
                                        td.wide { (status(&v.build_status)) }
                                        td { (v.status) }
                                        @match &v.public {
                                            Some(l) => {
                                                (ranks::rank_cell(l.rank, &l.uncertainty))
                                                td.num { (format!("{:.3}", l.mean_score)) }
                                                (ranks::interval_cell(&l.uncertainty))
                                                (ranks::tie_cell(&l.uncertainty))
                                                td.num.wide { (l.finished) "/" (l.played) }
                                            }
                                            None => { td.num { "-" } td.num { "-" } td.num.wide { "-" } td.wide {} td.num.wide { "-" } }
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
                        @let warned = v.build_status == "ready" && v.log.as_deref().is_some_and(|l| l.contains("warning: "));
                        details.version open[i == 0 || v.build_status != "ready" || warned] {
                            summary { "version " (v.version) " " (status(&v.build_status)) @if warned { " " span.warned { "with a warning" } } " " span.muted { (time(v.created_at)) " · " code { (v.command) } } }
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
    super::super::layout::live_page("My page", body, p.live)
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
                    label { "Bot name (letters, digits, - _ .) " input type="text" name="name" required maxlength="64" pattern=(NAME_PATTERN); }
                }
                fieldset {
                    legend { "Your files" }
                    label { "Files (one or several text files) " input type="file" name="files" multiple; }
                    p.muted { "or" }
                    label { "A folder as an archive (.zip, .tar.gz) " input type="file" name="archive" accept=".zip,.tar.gz,.tgz,.tar"; }
                }
                fieldset {
                    legend { "How it runs" }
                    label.check { input type="checkbox" name="original_task" value="true"; " A robot of the original task (" code { "class Robot" } " with " code { "next_move" } "): the server adds the adapter, so upload only your own files" }
                    label { "The file that holds class Robot (original task) " select #robot-file name="robot_file" {
                        option value="" { "robot.py, or else the only .py file that defines class Robot" }
                    } }
                    label { "Command (leave empty for a robot of the original task) " input type="text" name="command" placeholder="python3 bot.py"; }
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
            script { (PreEscaped(SUBMIT_FORM_JS)) }
        },
    )
}

#[cfg(test)]
mod tests {
    use super::runtime_words;
    use crate::runner::runtimes::{Package, ProgramInfo, RuntimeInfo};

    fn runtime(name: &str, numpy: &str, pandas: &str) -> RuntimeInfo {
        RuntimeInfo {
            name: name.into(),
            kind: "operator".into(),
            languages: vec!["Python".into()],
            programs: vec![ProgramInfo {
                program: "python3".into(),
                version: "Python 3.11.2".into(),
            }],
            packages: vec![
                Package {
                    name: "numpy".into(),
                    version: numpy.into(),
                },
                Package {
                    name: "pandas".into(),
                    version: pandas.into(),
                },
            ],
        }
    }

    #[test]
    fn two_runtimes_that_differ_in_a_packages_version_are_told_apart() {
        let old = runtime_words(&runtime("np1", "1.26.4", "1.5.3"));
        let new = runtime_words(&runtime("np2", "2.1.0", "2.2.3"));
        assert_eq!(old, "python3 Python 3.11.2 with numpy 1.26.4, pandas 1.5.3");
        assert_ne!(old, new);
        let mut many = runtime("many", "1", "1");
        many.packages = (0..20)
            .map(|i| Package {
                name: format!("p{i:02}"),
                version: format!("0.{i}"),
            })
            .collect();
        let words = runtime_words(&many);
        assert!(
            words.contains("p11 0.11") && !words.contains("p12"),
            "{words}"
        );
        assert!(words.ends_with(" and 8 more"), "{words}");
    }
}
