//! Every page as its visitors see it, checked by axe-core (npm, run in Chromium) for
//! accessibility violations, and the replay viewer's and the tables' layout on a
//! 1280x900 screen and a 390 px phone. axe-core is installed by `.ci/run` in
//! `target/axe` (`npm install --prefix target/axe axe-core@4`); outside CI a missing
//! axe-core skips the test with a printed reason, with `CI=true` it fails.

use std::path::PathBuf;
use std::time::Duration;

use serde_json::json;

use super::browser::Browser;
use super::class_day::{browser_login, entrant, open_competition, wait_ranked};
use super::support::{ADMIN, TestServer, root, simple_bot_files};

/// axe-core's script, or `None` (with the reason printed) when it is not installed,
/// outside CI.
pub(crate) fn axe_source(test: &str) -> Option<String> {
    let path = std::env::var_os("MAZEARENA_AXE")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/axe/node_modules/axe-core/axe.min.js"));
    match std::fs::read_to_string(&path) {
        Ok(text) => Some(text),
        Err(e) => {
            let why = format!(
                "axe-core is not at {} ({e}): npm install --prefix target/axe axe-core@4",
                path.display()
            );
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "{test}: {why}; in CI the accessibility test must run"
            );
            eprintln!("SKIPPED {test}: {why}");
            None
        }
    }
}

/// axe-core's violations on the page the browser shows: rule, impact and the first
/// elements, one line each.
pub(crate) async fn violations(b: &Browser, axe: &str, page: &str) -> Vec<String> {
    b.client
        .execute(&format!("{axe}\n;return true;"), vec![])
        .await
        .unwrap();
    let found = b
        .client
        .execute_async(
            "const done = arguments[arguments.length - 1];
             axe.run(document, {resultTypes: ['violations']}).then(r => done(r.violations.map(v =>
                 ({id: v.id, impact: v.impact, nodes: v.nodes.slice(0, 3).map(n => n.target.join(' '))}))));",
            vec![],
        )
        .await
        .unwrap();
    found
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{page}: {} ({}) at {}", v["id"], v["impact"], v["nodes"]))
        .collect()
}

/// Opens `path` and waits for `css`, then runs axe-core on it.
async fn check(b: &Browser, axe: &str, base: &str, path: &str, css: &str, found: &mut Vec<String>) {
    b.open(&format!("{base}{path}"), css).await;
    found.extend(violations(b, axe, path).await);
}

/// The page's box of element `css`: left, top, right, bottom in CSS pixels.
async fn rect(b: &Browser, css: &str) -> [f64; 4] {
    let r = b
        .client
        .execute(
            "const r = document.querySelector(arguments[0]).getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom];",
            vec![json!(css)],
        )
        .await
        .unwrap();
    let v: Vec<f64> = r
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    [v[0], v[1], v[2], v[3]]
}

#[tokio::test]
async fn every_page_passes_axe_and_the_viewer_and_tables_fit_a_laptop_and_a_phone() {
    let test = "every_page_passes_axe_and_the_viewer_and_tables_fit_a_laptop_and_a_phone";
    let Some(axe) = axe_source(test) else {
        return;
    };
    let Some(b) = Browser::start(test).await else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let base = server.base.clone();
    let organiser = open_competition(&server, "access-cup").await;
    // An entrant with a ranked bot and a practice match with a replay.
    let key = entrant(&server, "ada").await;
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "ada-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    let bot_id = bot["bot_id"].as_i64().unwrap();
    let (s, v) = server
        .post(
            "/api/competitions/access-cup/entries",
            json!({"bot_id": bot_id}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    wait_ranked(&server, "access-cup", "ada-bot", 120).await;
    // A match on a shipped 16x16 maze (the tallest), and a tournament.
    let (_, mazes) = server.get("/api/mazes", None).await;
    let big = mazes
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["dim"] == 16)
        .expect("a shipped 16x16 maze")["maze_id"]
        .as_i64()
        .unwrap();
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot_id, "maze_id": big, "seed": 3}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    let match_id = q["match_id"].as_i64().unwrap();
    super::support::wait_match(&server, match_id).await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "access", "bot_ids": [bot_id], "maze_ids": [big], "repeats": 1}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tournament = t["tournament_id"].as_i64().unwrap();

    let mut found = Vec::new();
    // Anyone's pages.
    for (path, css) in [
        ("/".to_string(), "main"),
        ("/bots".into(), "main"),
        (format!("/bots/{bot_id}"), "main"),
        ("/mazes".into(), "main"),
        (format!("/mazes/{big}"), "main"),
        ("/matches".into(), "main"),
        (format!("/matches/{match_id}"), "#viewer"),
        ("/competitions".into(), "main"),
        ("/competitions/access-cup".into(), "#take-part"),
        ("/tournaments".into(), "main"),
        (format!("/tournaments/{tournament}"), "main"),
        ("/workers".into(), "main"),
        ("/api".into(), "main"),
        ("/login".into(), "input[name=key]"),
        ("/register".into(), "input[name=name]"),
    ] {
        check(&b, &axe, &base, &path, css, &mut found).await;
    }
    // The entrant's.
    browser_login(&b, &base, &key).await;
    for (path, css) in [
        ("/me".to_string(), ".who"),
        ("/competitions/access-cup/submit".into(), "form.submit"),
        (format!("/matches/{match_id}"), "#viewer"),
    ] {
        check(&b, &axe, &base, &path, css, &mut found).await;
    }
    // The organiser's and the admin's.
    browser_login(&b, &base, &organiser).await;
    for (path, css) in [
        ("/organise", "main"),
        ("/competitions/access-cup/manage", "table.entrants"),
    ] {
        check(&b, &axe, &base, path, css, &mut found).await;
    }
    browser_login(&b, &base, ADMIN).await;
    check(&b, &axe, &base, "/admin", "form.registration", &mut found).await;
    assert!(found.is_empty(), "axe-core found:\n{}", found.join("\n"));

    // The viewer on a laptop and a phone: the whole maze in the window, nothing over it.
    browser_login(&b, &base, &key).await;
    for (width, height) in [(1280, 900), (390, 844)] {
        b.window(width, height).await;
        b.open(&format!("{base}/matches/{match_id}"), "#viewer svg")
            .await;
        tokio::time::sleep(Duration::from_millis(300)).await;
        let inner: Vec<f64> = b
            .client
            .execute("return [window.innerWidth, window.innerHeight];", vec![])
            .await
            .unwrap()
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        b.client
            .execute(
                "document.querySelector('#viewer svg').scrollIntoView({block: 'start'});",
                vec![],
            )
            .await
            .unwrap();
        tokio::time::sleep(Duration::from_millis(200)).await;
        let maze = rect(&b, "#viewer .mv-maze-box svg").await;
        let dock = rect(&b, "#viewer .mv-dock").await;
        b.screenshot(&format!("viewer-{width}")).await;
        assert!(
            maze[3] - maze[1] <= inner[1] && maze[2] - maze[0] <= inner[0] + 0.5,
            "{width}x{height}: the maze ({maze:?}) does not fit the window ({inner:?})"
        );
        let overlap =
            maze[1] < dock[3] && dock[1] < maze[3] && maze[0] < dock[2] && dock[0] < maze[2];
        assert!(
            !overlap,
            "{width}x{height}: the controls ({dock:?}) cover the maze ({maze:?})"
        );
        assert!(
            b.overflow_x().await <= 0,
            "{width}: the page scrolls sideways"
        );
    }
    // The boards and "me" on the phone: each table's rank and mean are in view.
    b.window(390, 844).await;
    for (path, table) in [
        ("/competitions/access-cup", "table.board"),
        ("/me", "table.submissions"),
        ("/", "table.data"),
    ] {
        b.open(&format!("{base}{path}"), "main").await;
        let cut = b
            .client
            .execute(
                "const out = [];
                 for (const t of document.querySelectorAll(arguments[0])) {
                   const heads = [...t.querySelectorAll('th')];
                   for (const h of heads) {
                     const text = h.textContent.trim().toLowerCase();
                     if (/rank$/.test(text) || text.startsWith('mean')) {
                       const r = h.getBoundingClientRect();
                       if (r.right > window.innerWidth + 0.5 || r.width < 1) out.push(text + ' at ' + r.left + '-' + r.right);
                     }
                   }
                 }
                 return out;",
                vec![json!(table)],
            )
            .await
            .unwrap();
        b.screenshot(&format!("phone-{}", path.replace('/', "_")))
            .await;
        assert_eq!(cut, json!([]), "{path} at 390 px: columns cut off");
    }
    b.quit().await;
}
