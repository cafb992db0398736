//! The replay viewer: one piece of markup, script and styles (`assets/viewer.*`) used
//! both as a self-contained HTML file (`mazearena replay`, `mazearena run --html`) and
//! inside the server's match page.
//!
//! The viewer reads one JSON document, [`ViewerData`], from a
//! `<script type="application/json" id="replay-data">` element.

use maud::{Markup, PreEscaped, html};
use serde::Serialize;

use crate::engine::{Maze, Position, mazefile, solver};
use crate::runner::MatchRecord;

/// The viewer's markup (an HTML fragment whose root is `#viewer`).
pub const VIEWER_HTML: &str = include_str!("assets/viewer.html");
/// The viewer's script (no network access, no libraries).
pub const VIEWER_JS: &str = concat!(
    include_str!("assets/maze.js"),
    include_str!("assets/viewer.js")
);
/// The viewer's styles, scoped under `#viewer`.
pub const VIEWER_CSS: &str = include_str!("assets/viewer.css");

/// The maze part of [`ViewerData`].
#[derive(Debug, Clone, Serialize)]
pub struct ViewerMaze {
    /// The side.
    pub dim: u32,
    /// The canonical numeric text; `None` draws an empty grid ("maze hidden").
    pub layout: Option<String>,
}

/// The solver's optimal run 1, drawn as an overlay.
#[derive(Debug, Clone, Serialize)]
pub struct ViewerOptimal {
    /// Its number of steps.
    pub steps: u32,
    /// The cells after each step, the start first.
    pub path: Vec<Position>,
}

/// Everything the viewer shows.
#[derive(Debug, Clone, Serialize)]
pub struct ViewerData<'a> {
    /// A heading, e.g. "simple-python on test_maze_01 (seed 0)".
    pub title: String,
    /// The maze.
    pub maze: ViewerMaze,
    /// The optimal route, when the maze is shown and its goal room reachable.
    pub optimal: Option<ViewerOptimal>,
    /// The match record with its trace.
    pub record: &'a MatchRecord,
    /// The file name of "download replay".
    pub download_name: String,
    /// True when the record's stderr was left out (it is the bot owner's): the viewer
    /// says so, and shows it when the page hands it the owner's copy.
    pub stderr_hidden: bool,
}

impl<'a> ViewerData<'a> {
    /// The data for `record` played on `maze` (`None`: the layout is not shown).
    pub fn new(
        title: String,
        record: &'a MatchRecord,
        maze: Option<&Maze>,
        download_name: String,
    ) -> ViewerData<'a> {
        ViewerData {
            title,
            maze: ViewerMaze {
                dim: maze.map_or(record.maze_dim, Maze::dim),
                layout: maze.map(mazefile::numeric::write),
            },
            optimal: maze.and_then(solver::solve).map(|s| ViewerOptimal {
                steps: s.steps,
                path: s.path,
            }),
            record,
            download_name,
            stderr_hidden: false,
        }
    }
}

/// JSON for a `<script type="application/json">` element: `<`, `>` and `&` escaped
/// (so no `</script>` in a bot's text can end the element), and U+2028/2029 too.
pub fn script_json<T: Serialize>(value: &T) -> String {
    // Plain data with string keys always serializes.
    let text = serde_json::to_string(value).expect("viewer data serializes");
    let mut out = String::with_capacity(text.len() + 64);
    for c in text.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// The viewer inside a page: its styles, markup, data and script.
pub fn embed(data: &ViewerData<'_>) -> Markup {
    html! {
        style { (PreEscaped(VIEWER_CSS)) }
        (PreEscaped(VIEWER_HTML))
        script type="application/json" id="replay-data" { (PreEscaped(script_json(data))) }
        script { (PreEscaped(VIEWER_JS)) }
    }
}

/// A whole self-contained HTML file showing one match: opens from disk, loads nothing.
pub fn standalone(data: &ViewerData<'_>) -> String {
    super::layout::offline_document(
        &format!("{} · mazearena replay", data.title),
        Some("margin:0;font-family:system-ui,sans-serif;background:#f6f7f9"),
        embed(data),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_json_cannot_end_its_element() {
        let text =
            script_json(&serde_json::json!({"t": "</script><script>alert(1)</script>&\u{2028}"}));
        assert!(!text.contains('<') && !text.contains('>') && !text.contains('&'));
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back["t"], "</script><script>alert(1)</script>&\u{2028}");
    }
}
