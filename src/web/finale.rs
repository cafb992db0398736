//! The final night's pages: the reveal of a competition's results and the race of every
//! robot on one maze, on the server (inside the site's frame) and as single offline
//! HTML files that play without it. One script and one style sheet
//! (`assets/finale.*`) serve both; the data is one JSON element.

use maud::{Markup, PreEscaped, html};
use serde::Serialize;

use super::viewer::script_json;
use crate::registry::finale::{Race, RaceLink, Reveal};

/// The script of the reveal and the race (no network access, no libraries).
pub const FINALE_JS: &str = concat!(
    include_str!("assets/maze.js"),
    include_str!("assets/finale.js")
);
/// Their styles, scoped under `#finale`.
pub const FINALE_CSS: &str = include_str!("assets/finale.css");

/// The JSON the script reads.
#[derive(Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum FinaleData<'a> {
    Reveal { reveal: &'a Reveal },
    Race { race: &'a Race },
}

/// Links a page on the server shows above the reveal or the race.
#[derive(Debug, Clone, Default)]
pub struct Online {
    /// The competition's page (or the tournament's).
    pub back: (String, String),
    /// The path that downloads this page as one offline file.
    pub download: String,
    /// The competition's races page, if any.
    pub races: Option<String>,
}

fn body(data: &FinaleData<'_>, online: Option<&Online>) -> Markup {
    html! {
        style { (PreEscaped(FINALE_CSS)) }
        div #finale data-online=(if online.is_some() { "true" } else { "false" }) {
            @if let Some(o) = online {
                nav.fn-top aria-label="This page" {
                    a href=(o.back.0) { "\u{2190} " (o.back.1) }
                    @if let Some(r) = &o.races { a href=(r) { "All races" } }
                    a href=(o.download) download { "Download as one offline file" }
                }
            }
            noscript { p { "This page plays with JavaScript; the results are also on the competition's page." } }
        }
        script type="application/json" id="finale-data" { (PreEscaped(script_json(data))) }
        script { (PreEscaped(FINALE_JS)) }
    }
}

fn document(title: &str, data: &FinaleData<'_>) -> String {
    super::layout::offline_document(&format!("{title} · mazearena"), None, body(data, None))
}

/// The reveal as a page of the server.
pub fn reveal_page(reveal: &Reveal, online: &Online) -> String {
    super::layout::page(
        &format!("{}: the reveal", reveal.title),
        body(&FinaleData::Reveal { reveal }, Some(online)),
    )
}

/// The reveal as one offline HTML file (its matches inside).
pub fn reveal_file(reveal: &Reveal) -> String {
    document(
        &format!("{}: the reveal", reveal.title),
        &FinaleData::Reveal { reveal },
    )
}

/// A race as a page of the server.
pub fn race_page(race: &Race, online: &Online) -> String {
    super::layout::page(
        &format!("Race: {}", race.title),
        body(&FinaleData::Race { race }, Some(online)),
    )
}

/// A race as one offline HTML file.
pub fn race_file(race: &Race) -> String {
    document(&format!("Race: {}", race.title), &FinaleData::Race { race })
}

/// The list of a competition's races a caller may watch.
pub fn races_page(competition: &str, title: &str, races: &[RaceLink]) -> String {
    super::layout::page(
        &format!("{title}: races"),
        html! {
            h1 { (title) ": races" }
            p { "Every robot's match on one maze and seed, played together. "
                a href={ "/competitions/" (competition) } { "Back to the competition" } "." }
            @if races.is_empty() {
                p { "No race to watch." }
            } @else {
                @for set in ["private", "public"] {
                    @let of_set: Vec<&RaceLink> = races.iter().filter(|r| r.set == set).collect();
                    @if !of_set.is_empty() {
                        h2 { @if set == "private" { "The final run (private mazes)" } @else { "The public mazes" } }
                        ul {
                            @for r in of_set {
                                li { a href=(r.path) { (r.maze) ", seed " (r.repeat + 1) } }
                            }
                        }
                    }
                }
            }
        },
    )
}
