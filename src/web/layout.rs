//! The frame of every server page: head, navigation, styles (embedded, no network).

use maud::{DOCTYPE, Markup, PreEscaped, html};

/// The site's styles.
pub const SITE_CSS: &str = r#"
:root { --fg:#1d2330; --muted:#5b6577; --line:#dde2ea; --accent:#2563eb; --bg:#f6f7f9; }
* { box-sizing: border-box; }
body { margin:0; font-family: system-ui, -apple-system, "Segoe UI", sans-serif; color:var(--fg); background:var(--bg); }
header.site { background:#1d2330; color:#fff; padding:0 24px; display:flex; gap:24px; align-items:center; height:52px; }
header.site a { color:#dbe4ff; text-decoration:none; font-weight:500; }
header.site a.brand { color:#fff; font-weight:700; font-size:1.1em; letter-spacing:.02em; }
main { max-width:1180px; margin:0 auto; padding:20px 24px 60px; }
h1 { font-size:1.6em; margin:.4em 0 .2em; } h2 { font-size:1.2em; margin:1.6em 0 .5em; }
p.lead { color:var(--muted); margin-top:0; }
a { color:var(--accent); }
table.data { border-collapse:collapse; width:100%; background:#fff; border:1px solid var(--line); border-radius:6px; overflow:hidden; }
table.data th, table.data td { padding:7px 10px; border-bottom:1px solid var(--line); text-align:left; font-variant-numeric:tabular-nums; }
table.data th { background:#eef1f6; font-weight:600; font-size:.9em; white-space:nowrap; }
table.data th a { color:inherit; text-decoration:none; }
table.data td.num, table.data th.num { text-align:right; }
table.data tr:last-child td { border-bottom:none; }
.status { display:inline-block; padding:1px 8px; border-radius:10px; font-size:.85em; background:#e5e7eb; }
.status.finished, .status.ready { background:#dcfce7; color:#166534; }
.status.queued, .status.running, .status.building { background:#e0e7ff; color:#3730a3; }
.status.step_limit { background:#fef9c3; color:#854d0e; }
.status.timeout, .status.crashed, .status.protocol_error, .status.memory_limit, .status.process_limit,
.status.scratch_limit, .status.aborted, .status.build_failed, .status.paused { background:#fee2e2; color:#991b1b; }
.tabs { display:flex; gap:8px; margin:8px 0 14px; flex-wrap:wrap; }
.tabs a { padding:5px 12px; border-radius:16px; border:1px solid var(--line); background:#fff; text-decoration:none; color:var(--fg); }
.tabs a.active { background:var(--accent); color:#fff; border-color:var(--accent); }
.muted { color:var(--muted); }
.progress { height:14px; background:#e5e7eb; border-radius:7px; overflow:hidden; max-width:520px; }
.progress > div { height:100%; background:var(--accent); }
.cards { display:flex; gap:14px; flex-wrap:wrap; }
.card { background:#fff; border:1px solid var(--line); border-radius:8px; padding:12px 16px; min-width:150px; }
.card b { display:block; font-size:1.3em; }
pre.log { background:#0f172a; color:#e2e8f0; padding:12px; border-radius:6px; overflow:auto; max-height:420px; font-size:.85em; white-space:pre-wrap; }
.pager { margin:10px 0; display:flex; gap:12px; }
form.inline { display:flex; gap:8px; align-items:center; margin:10px 0; }
form.inline input { padding:5px 8px; border:1px solid var(--line); border-radius:4px; min-width:320px; }
.maze-svg svg { max-width:560px; height:auto; background:#fff; border:1px solid var(--line); border-radius:6px; }
"#;

/// A whole page: `title` in the head and as the heading's text is given by `body`.
pub fn page(title: &str, body: Markup) -> String {
    html! {
        (DOCTYPE)
        html lang="en" {
            head {
                meta charset="utf-8";
                meta name="viewport" content="width=device-width, initial-scale=1";
                title { (title) " · mazearena" }
                style { (PreEscaped(SITE_CSS)) }
            }
            body {
                header.site {
                    a.brand href="/" { "mazearena" }
                    a href="/" { "Leaderboard" }
                    a href="/tournaments" { "Tournaments" }
                    a href="/matches" { "Matches" }
                    a href="/bots" { "Bots" }
                    a href="/mazes" { "Mazes" }
                    a href="/api/openapi.json" { "API" }
                }
                main { (body) }
            }
        }
    }
    .into_string()
}

/// A status as a coloured badge.
pub fn status(s: &str) -> Markup {
    html! { span class={ "status " (s) } { (s) } }
}

/// A score with three decimals, or "DNF".
pub fn score(s: Option<f64>) -> Markup {
    html! {
        @match s {
            Some(v) => (format!("{v:.3}")),
            None => span.muted { "DNF" },
        }
    }
}

/// Unix milliseconds as a UTC date and time (`2026-11-23 12:34`).
pub fn time(ms: i64) -> String {
    let secs = ms.div_euclid(1000);
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    // Civil-from-days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}",
        rem / 3600,
        (rem % 3600) / 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_utc_dates() {
        assert_eq!(time(0), "1970-01-01 00:00");
        assert_eq!(time(1_795_437_296_000), "2026-11-23 12:34");
    }

    #[test]
    fn values_are_escaped() {
        let html = page("<script>x</script>", html! { p { ("<b>bold</b>") } });
        assert!(!html.contains("<script>x"));
        assert!(html.contains("&lt;b&gt;bold&lt;/b&gt;"));
    }
}
