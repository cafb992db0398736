//! The web face in a real browser: the server's pages over a real tournament, the match
//! page's replay viewer, and the offline HTML file of `mazearena replay`. Screenshots
//! go to `target/browser-artifacts/`.

use std::time::{Duration, Instant};

use serde_json::{Value, json};

use super::browser::Browser;
use super::support::{ADMIN, TestServer, mazearena, register, root, simple_bot_files};

/// Steps the viewer forward `n` times from where it is, then checks that the robot
/// drawn is at the trace's position and heading after step `k` (the step shown).
async fn check_robot(b: &Browser, trace: &[Value], k: usize, what: &str) {
    assert_eq!(
        b.attr("#viewer", "data-step").await.as_deref(),
        Some(k.to_string().as_str()),
        "{what}: the viewer shows step {k}"
    );
    let (x, y, heading) = if k == 0 {
        (0, 0, "up".to_string())
    } else {
        let s = &trace[k - 1];
        (
            s["position"]["x"].as_i64().unwrap(),
            s["position"]["y"].as_i64().unwrap(),
            s["heading"].as_str().unwrap().to_string(),
        )
    };
    assert_eq!(
        b.attr("#robot", "data-x").await,
        Some(x.to_string()),
        "{what}: x at step {k}"
    );
    assert_eq!(
        b.attr("#robot", "data-y").await,
        Some(y.to_string()),
        "{what}: y at step {k}"
    );
    assert_eq!(
        b.attr("#robot", "data-heading").await,
        Some(heading),
        "{what}: heading at step {k}"
    );
}

/// Drives the viewer on the page that is open: forward, back, keyboard, the debug
/// layer, jump to run 1.
async fn drive_viewer(b: &Browser, trace: &[Value], what: &str) {
    assert!(
        trace.len() > 12,
        "{what}: a trace long enough to step through"
    );
    check_robot(b, trace, 0, what).await;
    for _ in 0..9 {
        b.click("#btn-forward").await;
    }
    check_robot(b, trace, 9, what).await;
    b.click("#btn-back").await;
    b.click("#btn-back").await;
    check_robot(b, trace, 7, what).await;
    // The keyboard: the right arrow steps forward.
    b.client
        .find(fantoccini::Locator::Css("body"))
        .await
        .unwrap()
        .send_keys("\u{E014}")
        .await
        .unwrap();
    check_robot(b, trace, 8, what).await;
    // The debug layer: drawn (the bot sends debug objects), hidden, shown again.
    let drawn = || async {
        b.client
            .execute(
                "return document.querySelector('#debug-layer').childElementCount",
                vec![],
            )
            .await
            .unwrap()
            .as_i64()
            .unwrap()
    };
    assert!(
        drawn().await > 0,
        "{what}: the bot's debug drawing is shown"
    );
    assert_ne!(
        b.attr("#debug-layer", "display").await.as_deref(),
        Some("none")
    );
    assert!(
        !b.text("#debug-text").await.is_empty(),
        "{what}: the debug text"
    );
    b.screenshot(&format!("{what}-step8-debug")).await;
    // Not every layer at once: the visits heat map and the optimal route start hidden
    // (one click shows each), the trail, run-1 path, sensors and debug drawing shown.
    for hidden in ["#heat-layer", "#optimal-layer"] {
        assert_eq!(
            b.attr(hidden, "display").await.as_deref(),
            Some("none"),
            "{what}: {hidden} starts hidden"
        );
    }
    assert_ne!(
        b.attr("#trail-layer", "display").await.as_deref(),
        Some("none")
    );
    b.click("#layer-heat").await;
    assert_ne!(
        b.attr("#heat-layer", "display").await.as_deref(),
        Some("none")
    );
    b.click("#layer-heat").await;
    b.click("#layer-debug").await;
    assert_eq!(
        b.attr("#debug-layer", "display").await.as_deref(),
        Some("none"),
        "{what}: the debug layer hides"
    );
    b.screenshot(&format!("{what}-step8-no-debug")).await;
    b.click("#layer-debug").await;
    assert_ne!(
        b.attr("#debug-layer", "display").await.as_deref(),
        Some("none")
    );
    // Jump to run 1: the first step of run 1.
    let first_run1 = trace.iter().position(|s| s["run"] == 1).unwrap() + 1;
    b.click("#btn-run1").await;
    check_robot(b, trace, first_run1, what).await;
    b.screenshot(&format!("{what}-run1")).await;
    // The whole maze fits a short window: with the maze's top at the window's top, its
    // bottom is in the window, and the controls and the layers' legend follow below it,
    // covering none of it.
    b.client.set_window_size(1000, 520).await.unwrap();
    let seen = b
        .client
        .execute(
            "const box = document.querySelector('#mv-maze-box');\
             window.scrollTo(0, box.getBoundingClientRect().top + window.scrollY);\
             const m = box.getBoundingClientRect();\
             const r = document.querySelector('.mv-layers').getBoundingClientRect();\
             return [m.bottom <= window.innerHeight + 0.5, r.top >= m.bottom - 0.5];",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(
        seen,
        serde_json::json!([true, true]),
        "{what}: [the maze fits the window, the legend is below it]"
    );
    b.screenshot(&format!("{what}-legend-in-view")).await;
    b.client.set_window_size(1300, 1100).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn pages_and_the_match_viewer_in_a_real_browser() {
    let Some(b) = Browser::start("pages_and_the_match_viewer_in_a_real_browser").await else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2", "--no-validation"]);
    let (simple, token) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let crasher =
        std::fs::read_to_string(root().join("tests/fixtures/bots/exits_early.py")).unwrap();
    let (broken, broken_token) = register(
        &server,
        "broken",
        "python3 bot.py",
        json!({"bot.py": crasher}),
    )
    .await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "autumn cup", "bot_ids": [simple, broken], "maze_ids": [1, 2], "repeats": 1}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tid = t["tournament_id"].as_i64().unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let (_, v) = server.get(&format!("/api/tournaments/{tid}"), None).await;
        if v["done"] == v["total"] {
            break;
        }
        assert!(Instant::now() < deadline, "the tournament did not end: {v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }

    // The leaderboard: no hidden maze yet, so the standings over all mazes and the
    // latest tournament.
    b.open(&format!("{}/", server.base), "table.standings")
        .await;
    let html = b.source().await;
    assert!(html.contains("Standings over all mazes"), "{html}");
    assert!(html.contains("autumn cup") && html.contains("simple") && html.contains("broken"));
    b.screenshot("leaderboard").await;
    // Sorting is a link: by name puts "broken" first.
    b.open(
        &format!("{}/?scope=all&sort=name", server.base),
        "table.standings",
    )
    .await;
    let first = b
        .text("table.standings tbody tr:first-child td:nth-child(2)")
        .await;
    assert!(first.starts_with("broken"), "{first}");

    // A bot page: versions and recent matches with their reasons.
    b.open(&format!("{}/bots/{broken}", server.base), "table.versions")
        .await;
    let html = b.source().await;
    assert!(html.contains("crashed"), "the failed matches are listed");
    assert!(html.contains("before answering step"), "with their reason");
    assert!(
        !html.contains("giving up at the first sense"),
        "stderr is the owner's"
    );
    // The owner pastes the token: the failed matches' stderr appears.
    b.client
        .find(fantoccini::Locator::Css("#owner-token"))
        .await
        .unwrap()
        .send_keys(&broken_token)
        .await
        .unwrap();
    b.click("#owner-form button").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    while !b
        .text("#owner-logs")
        .await
        .contains("giving up at the first sense")
    {
        assert!(Instant::now() < deadline, "the owner's logs did not appear");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    b.screenshot("bot-page").await;

    // The tournament page: progress and the bot x maze table.
    b.open(&format!("{}/tournaments/{tid}", server.base), "table.grid")
        .await;
    assert_eq!(b.attr("#progress", "data-done").await, Some("4".into()));
    // The page's own script ran under its Content-Security-Policy: it drew the bar.
    let width = b
        .client
        .execute(
            "return document.getElementById('progress-bar').style.width",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(
        width.as_str(),
        Some("100%"),
        "the progress script did not run"
    );
    let grid = b.text("table.grid").await;
    assert!(grid.contains("simple") && grid.contains("broken"), "{grid}");
    b.screenshot("tournament-page").await;

    // A match page with the viewer, checked against the API's replay.
    let (_, list) = server
        .get(
            &format!("/api/matches?bot_id={simple}&tournament_id={tid}&status=finished"),
            None,
        )
        .await;
    assert_eq!(list["total"], 2, "{list}");
    let m = list["items"][0]["match_id"].as_i64().unwrap();
    let (_, replay) = server.get(&format!("/api/matches/{m}/replay"), None).await;
    let trace = replay["trace"].as_array().unwrap().clone();
    b.open(&format!("{}/matches/{m}", server.base), "#robot")
        .await;
    b.screenshot("match-page").await;
    // The page's heading and cards say what the match is; the viewer's own header, the
    // same again, is not shown (the offline file shows it: it has nothing else).
    let header = b
        .client
        .find(fantoccini::Locator::Css("#viewer .mv-header"))
        .await
        .unwrap();
    assert!(
        !header.is_displayed().await.unwrap(),
        "the header is shown twice"
    );
    drive_viewer(&b, &trace, "match-page").await;

    // A bot's stderr is its owner's, on a public maze too: the page and the anonymous
    // replay carry none of it; the owner's token shows it in the viewer.
    let chatty = std::fs::read_to_string(root().join("tests/fixtures/bots/chatty.py")).unwrap();
    let (talker, talker_token) = register(
        &server,
        "talker",
        "python3 bot.py",
        json!({"bot.py": chatty}),
    )
    .await;
    let tm = crate::support::queue(&server, talker, 1, 1, &talker_token).await;
    crate::support::wait_match(&server, tm).await;
    let (_, anon) = server.get(&format!("/api/matches/{tm}/replay"), None).await;
    assert_eq!(anon["stderr_shown"], false);
    assert!(!anon.to_string().contains("thinking about step"), "{anon}");
    let (_, own) = server
        .get(&format!("/api/matches/{tm}/replay"), Some(&talker_token))
        .await;
    assert_eq!(own["stderr_shown"], true);
    assert!(own.to_string().contains("thinking about step 2"));
    // The replay as one HTML file: the same, sent as a download under the pages' policy.
    let (s, html, headers) = server
        .get_raw(&format!("/api/matches/{tm}/replay.html"), None)
        .await;
    assert_eq!(s, 200);
    assert!(html.contains("id=\"replay-data\"") && !html.contains("thinking about step"));
    assert!(
        headers["content-disposition"]
            .to_str()
            .unwrap()
            .starts_with("attachment"),
        "{headers:?}"
    );
    assert!(
        headers.contains_key("content-security-policy"),
        "{headers:?}"
    );
    let (_, html, _) = server
        .get_raw(
            &format!("/api/matches/{tm}/replay.html"),
            Some(&talker_token),
        )
        .await;
    assert!(html.contains("thinking about step 2"));
    b.open(&format!("{}/matches/{tm}#step=2", server.base), "#robot")
        .await;
    assert!(!b.source().await.contains("thinking about step"));
    assert!(b.text("#step-stderr").await.contains("shown to its owner"));
    b.client
        .find(fantoccini::Locator::Css("#match-owner-token"))
        .await
        .unwrap()
        .send_keys(&talker_token)
        .await
        .unwrap();
    b.click("#match-owner-form button").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    while !b
        .text("#step-stderr")
        .await
        .contains("thinking about step 2")
    {
        assert!(
            Instant::now() < deadline,
            "the owner's stderr did not appear: {}",
            b.text("#match-owner-status").await
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    b.screenshot("match-page-owner-stderr").await;

    // At a phone's width no page scrolls sideways (wide tables scroll in their own box),
    // and every page names its icon, which the server has.
    b.window(375, 800).await;
    for path in [
        "/".to_string(),
        "/bots".into(),
        format!("/bots/{broken}"),
        "/mazes".into(),
        "/matches".into(),
        format!("/matches/{tm}"),
        "/tournaments".into(),
        "/competitions".into(),
        "/workers".into(),
    ] {
        b.open(&format!("{}{path}", server.base), "header.site")
            .await;
        let over = b.overflow_x().await;
        if over > 0 {
            b.screenshot(&format!("phone{}", path.replace('/', "-")))
                .await;
        }
        assert!(over <= 0, "{path} scrolls sideways by {over} px at 375 px");
        assert!(b.source().await.contains("rel=\"icon\""), "{path}");
    }
    let (s, _, headers) = server.get_raw("/favicon.ico", None).await;
    assert_eq!(s, 200);
    assert_eq!(headers["content-type"], "image/svg+xml");

    let _ = token;
    b.quit().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn the_offline_replay_file_shows_the_same() {
    let Some(b) = Browser::start("the_offline_replay_file_shows_the_same").await else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let replay = dir.path().join("m.json");
    let html = dir.path().join("m.html");
    let out = mazearena(&[
        "run",
        "--maze",
        "mazes/gen-12-s1.txt",
        "--bot",
        "python3 simple_bot.py",
        "--bot-dir",
        "bots/python",
        "--replay",
        replay.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let out = mazearena(&[
        "replay",
        replay.to_str().unwrap(),
        "-o",
        html.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let page = std::fs::read_to_string(&html).unwrap();
    // Self-contained: nothing is loaded from anywhere.
    for remote in ["<script src", "<link", "fetch(", "@import", "url(http"] {
        assert!(
            !page.contains(remote),
            "the offline file loads nothing ({remote})"
        );
    }
    let record: Value = serde_json::from_str(&std::fs::read_to_string(&replay).unwrap()).unwrap();
    assert!(
        record["maze_layout"].as_str().unwrap().starts_with("12\n"),
        "the replay carries its maze"
    );
    let trace = record["trace"].as_array().unwrap().clone();
    b.open(&format!("file://{}", html.display()), "#robot")
        .await;
    b.screenshot("offline").await;
    let header = b
        .client
        .find(fantoccini::Locator::Css("#viewer .mv-header"))
        .await
        .unwrap();
    assert!(
        header.is_displayed().await.unwrap(),
        "the offline file has its header"
    );
    drive_viewer(&b, &trace, "offline").await;
    b.quit().await;
}

#[tokio::test]
async fn a_competition_page_shows_an_entrants_submissions_in_a_real_browser() {
    let Some(b) =
        Browser::start("a_competition_page_shows_an_entrants_submissions_in_a_real_browser").await
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let (_, o) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    let organiser = o["key"].as_str().unwrap().to_string();
    let maze = |name: &str, seed: u64| {
        json!({"name": name, "layout": mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, seed).unwrap())})
    };
    let now = mazearena::storage::now_ms();
    let at = |ms: i64| mazearena::competition::Timestamp(ms).rfc3339();
    let (s, c) = server
        .post(
            "/api/competitions",
            json!({"name": "spring", "title": "Spring <b>cup</b>", "rules": "Be <i>kind</i>.",
                   "opens_at": at(now - 60_000), "closes_at": at(now + 3_600_000),
                   "mazes": {"practice": [maze("warm-up", 8001)], "public": [maze("p", 8002)],
                             "private": [maze("q", 8003)]}}),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 201, "{c}");
    let (_, e) = server
        .post("/api/entrants", json!({"name": "team-b"}), None)
        .await;
    let key = e["key"].as_str().unwrap().to_string();
    let body =
        json!({"name": "b-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (_, bot) = server.post("/api/bots", body, Some(&key)).await;
    let (s, v) = server
        .post(
            "/api/competitions/spring/entries",
            json!({"bot_id": bot["bot_id"]}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let (_, board) = server
            .get("/api/competitions/spring/leaderboard", None)
            .await;
        if board["standings"].as_array().is_some_and(|r| r.len() == 1) {
            break;
        }
        assert!(Instant::now() < deadline, "never ranked: {board}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    b.open(
        &format!("{}/competitions", server.base),
        "table.competitions",
    )
    .await;
    b.click("table.competitions a[href='/competitions/spring']")
        .await;
    b.open(
        &format!("{}/competitions/spring", server.base),
        "table.board",
    )
    .await;
    let html = b.source().await;
    // Texts are text (no markup of the organiser's runs), the private board is sealed.
    assert!(
        html.contains("Spring &lt;b&gt;cup&lt;/b&gt;")
            && html.contains("Be &lt;i&gt;kind&lt;/i&gt;."),
        "{html}"
    );
    assert!(
        b.text("p.sealed")
            .await
            .contains("No bot plays a private maze before the close")
    );
    assert!(b.text("table.board").await.contains("team-b"));
    b.client
        .find(fantoccini::Locator::Css("#mine-key"))
        .await
        .unwrap()
        .send_keys(&key)
        .await
        .unwrap();
    b.click("#mine-form button").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    while !b
        .text("#mine")
        .await
        .contains("1 of 5 versions used in the last 24 hours")
    {
        assert!(
            Instant::now() < deadline,
            "my submissions did not appear: {}",
            b.text("#mine").await
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let row = b.text("table.submissions tbody tr").await;
    assert!(row.contains("ranked") && row.contains("1/1"), "{row}");
    // The version's public rank is a real one (1 of 1 here), not 0.
    let cells: Vec<String> = row.split_whitespace().map(str::to_string).collect();
    assert!(!cells.iter().any(|c| c == "0"), "{row}");
    b.screenshot("competition-page").await;
    // At a phone's width the competition's page does not scroll sideways.
    b.window(375, 800).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let over = b.overflow_x().await;
    if over > 0 {
        b.screenshot("phone-competition").await;
    }
    assert!(
        over <= 0,
        "the competition page scrolls sideways by {over} px"
    );
    b.quit().await;
}
