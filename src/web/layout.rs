//! The frame of every server page: head, navigation, styles (embedded, no network).

use maud::{DOCTYPE, Markup, PreEscaped, html};

/// The site's styles.
pub const SITE_CSS: &str = include_str!("assets/site.css");

/// The `pattern` of a name field (entrant, bot): letters, digits, `.`, `_`
/// and `-`. Browsers compile patterns with the `v` flag, where a `-` in a class must
/// be escaped (unescaped, the pattern is invalid and the field is not checked at all).
pub const NAME_PATTERN: &str = r"[A-Za-z0-9._\-]+";

/// The start of every document's head: its characters, a reload every 5 seconds when
/// `live`, the viewport, `title`.
fn head_start(title: &str, live: bool) -> Markup {
    html! {
        meta charset="utf-8";
        @if live { meta http-equiv="refresh" content="5"; }
        meta name="viewport" content="width=device-width, initial-scale=1";
        title { (title) }
    }
}

/// A whole self-contained document that opens from disk and loads nothing (the offline
/// replay and the final night's files): `title`, `body` with its inline style if any.
pub fn offline_document(title: &str, body_style: Option<&str>, body: Markup) -> String {
    html! {
        (DOCTYPE)
        html lang="en" {
            head { (head_start(title, false)) }
            body style=[body_style] { (body) }
        }
    }
    .into_string()
}

/// A whole page, as [`page`], that reloads itself every 5 seconds while `live` (a
/// match or a build that is still going): the site's header, `body` in `main`.
pub fn live_page(title: &str, body: Markup, live: bool) -> String {
    html! {
        (DOCTYPE)
        html lang="en" {
            head {
                (head_start(&format!("{title} · mazearena"), live))
                link rel="icon" type="image/svg+xml" href="/favicon.svg";
                style { (PreEscaped(SITE_CSS)) }
            }
            body {
                a.skip href="#main" { "Skip to the content" }
                header.site {
                    a.brand href="/" { "mazearena" }
                    a href="/" { "Leaderboard" }
                    a href="/competitions" { "Competitions" }
                    a href="/tournaments" { "Tournaments" }
                    a href="/matches" { "Matches" }
                    a href="/bots" { "Bots" }
                    a href="/mazes" { "Mazes" }
                    a href="/workers" { "Workers" }
                    a href="/api" { "API" }
                    a.me href="/me" { "My page" }
                }
                main #main tabindex="-1" { (body) }
            }
        }
    }
    .into_string()
}

/// A whole page: `title` in the head and as the heading's text is given by `body`.
pub fn page(title: &str, body: Markup) -> String {
    live_page(title, body, false)
}

/// A status as a coloured badge.
pub fn status(s: &str) -> Markup {
    html! { span class={ "status " (s) } { (s) } }
}

/// A match's score with three decimals: "hidden" for a finished match whose score the
/// caller may not see (a hidden maze's), "DNF" for one that did not finish, "-" while
/// it has not ended.
pub fn score(status: &str, s: Option<f64>) -> Markup {
    html! {
        @match (status, s) {
            (_, Some(v)) => (format!("{v:.3}")),
            ("finished", None) => span.muted title="the maze is hidden: its scores are not shown" { "hidden" },
            ("queued" | "running", None) => span.muted { "-" },
            (_, None) => span.muted { "DNF" },
        }
    }
}

/// Unix milliseconds as a UTC date and time (`2026-11-23 12:34 UTC`).
pub fn time(ms: i64) -> String {
    crate::competition::Timestamp(ms).words()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_utc_dates() {
        assert_eq!(time(0), "1970-01-01 00:00 UTC");
        assert_eq!(time(1_795_437_296_000), "2026-11-23 12:34 UTC");
    }

    #[test]
    fn values_are_escaped() {
        let html = page("<script>x</script>", html! { p { ("<b>bold</b>") } });
        assert!(!html.contains("<script>x"));
        assert!(html.contains("&lt;b&gt;bold&lt;/b&gt;"));
    }

    #[test]
    fn a_live_page_reloads_itself_and_a_finished_one_does_not() {
        let refresh = "<meta http-equiv=\"refresh\" content=\"5\">";
        let live = live_page("t", html! { p { "x" } }, true);
        let head = &live[..live.find("</head>").unwrap()];
        assert_eq!(head.matches(refresh).count(), 1, "{live}");
        assert!(!live_page("t", html! {}, false).contains("http-equiv"));
        assert!(!page("t", html! {}).contains("http-equiv"));
    }
}
