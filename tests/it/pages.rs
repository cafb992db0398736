//! The server's pages and list routes against a real server: bad ids and query strings
//! get JSON 4xx errors (never a 500), lists filter and page, hidden mazes' layouts
//! never reach a page, and uploaded sources are built once before they play.

use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::support::{ADMIN, TestServer, register, root, simple_bot_files, wait_built, wait_match};

#[tokio::test]
async fn pages_and_lists_answer_bad_input_with_json_4xx() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let cases = [
        ("/bots/abc", 400),
        ("/bots/999", 404),
        ("/bots/99999999999999999999999", 400),
        ("/mazes/999", 404),
        ("/mazes/-1", 404),
        ("/matches/0", 404),
        ("/matches/x", 400),
        ("/tournaments/7", 404),
        ("/tournaments/1.5", 400),
        ("/matches?status=bogus", 400),
        ("/matches?limit=0", 400),
        ("/matches?limit=201", 400),
        ("/matches?offset=-1", 400),
        ("/matches?bot_id=x", 400),
        ("/matches?unknown=1", 400),
        ("/tournaments?limit=x", 400),
        ("/?sort=bogus", 400),
        ("/?scope=weird", 400),
        ("/?tournament=42", 404),
        ("/?tournament=1&scope=all", 400),
        ("/api/matches?status=nope", 400),
        ("/api/matches?tournament_id=%00", 400),
        ("/api/matches?limit=100000", 400),
        ("/api/tournaments?offset=-5", 400),
        ("/api/tournaments?page=2", 400),
        ("/no/such/page", 404),
    ];
    for (path, want) in cases {
        let (status, body, headers) = server.call(reqwest::Method::GET, path, None, None).await;
        assert_eq!(status, want, "{path}: {body}");
        assert!(
            headers["content-type"]
                .to_str()
                .unwrap()
                .starts_with("application/json"),
            "{path}"
        );
        assert!(
            body["error"]["message"]
                .as_str()
                .is_some_and(|m| !m.is_empty()),
            "{path}: {body}"
        );
    }
    // And the good ones answer, even on an empty server.
    for path in [
        "/",
        "/bots",
        "/mazes",
        "/mazes/1",
        "/matches",
        "/tournaments",
        "/workers",
    ] {
        let resp = server
            .client()
            .get(format!("{}{path}", server.base))
            .send()
            .await
            .unwrap();
        assert_eq!(resp.status(), 200, "{path}");
        assert!(
            resp.headers()["content-type"]
                .to_str()
                .unwrap()
                .starts_with("text/html")
        );
    }
    let (s, doc) = server.get("/api/openapi.json", None).await;
    assert_eq!(s, 200);
    assert!(
        doc["paths"]["/api/matches"]["get"].is_object(),
        "the list routes are documented"
    );
    assert!(doc["paths"]["/api/tournaments"]["get"].is_object());
}

#[tokio::test]
async fn the_server_reports_its_workers_in_health_metrics_and_pages() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1"]);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    let worker = loop {
        let (s, health) = server.get("/healthz", Some(ADMIN)).await;
        assert_eq!(s, 200, "{health}");
        if let Some(w) = health["workers"].as_array().and_then(|a| a.first()) {
            break w.clone();
        }
        assert!(std::time::Instant::now() < deadline, "{health}");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    };
    assert_eq!(worker["role"], "serve");
    assert_eq!(worker["jobs"], 1);
    assert_eq!(worker["pid"], server.pid());
    let id = worker["worker_id"].as_str().unwrap();
    let html = page(&server, "/workers").await;
    assert!(html.contains(id), "{html}");
    // No count that moves with hidden matches: the queue's length, matches played.
    assert!(
        !html.contains("matches queued") && !html.contains("<th class=\"num\">matches</th>"),
        "{html}"
    );
    let (_, metrics, _) = server.get_raw("/metrics", Some(ADMIN)).await;
    assert!(
        metrics
            .lines()
            .any(|l| l.starts_with("mazearena_worker_jobs{")
                && l.contains(id)
                && l.ends_with(" 1")),
        "{metrics}"
    );
}

#[tokio::test]
async fn match_lists_filter_and_page() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let (a, ta) = register(&server, "a", "python3 simple_bot.py", simple_bot_files()).await;
    let (b, tb) = register(&server, "b", "python3 simple_bot.py", simple_bot_files()).await;
    let mut ids = Vec::new();
    for (bot, token, maze) in [(a, &ta, 1), (a, &ta, 2), (a, &ta, 3), (b, &tb, 1)] {
        let (s, v) = server
            .post(
                "/api/matches",
                json!({"bot_id": bot, "maze_id": maze, "seed": 1}),
                Some(token),
            )
            .await;
        assert_eq!(s, 202, "{v}");
        ids.push(v["match_id"].as_i64().unwrap());
    }
    for id in &ids {
        wait_match(&server, *id).await;
    }
    let (_, page) = server
        .get(&format!("/api/matches?bot_id={a}&limit=2"), None)
        .await;
    assert_eq!(page["total"], 3);
    let got: Vec<i64> = page["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["match_id"].as_i64().unwrap())
        .collect();
    assert_eq!(got, [ids[2], ids[1]], "newest first");
    assert_eq!(
        (&page["total_exact"], &page["next_before"]),
        (&json!(true), &json!(ids[1]))
    );
    // The next page starts before the last match shown (or at an offset).
    for next in [format!("before={}", ids[1]), "offset=2".to_string()] {
        let (_, page2) = server
            .get(&format!("/api/matches?bot_id={a}&limit=2&{next}"), None)
            .await;
        assert_eq!(page2["items"][0]["match_id"], ids[0], "{next}");
        assert_eq!(page2["total"], 3);
        assert!(page2["next_before"].is_null(), "{page2}");
    }
    let (_, on1) = server
        .get("/api/matches?maze_id=1&status=finished", None)
        .await;
    assert_eq!(on1["total"], 2);
    let (_, none) = server.get("/api/matches?status=timeout", None).await;
    assert_eq!(none["total"], 0);
    // The list page shows the same, with a link to the next page.
    let html = server
        .client()
        .get(format!("{}/matches?bot_id={a}&limit=2", server.base))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(
        html.contains(&format!("/matches/{}", ids[2]))
            && !html.contains(&format!("href=\"/matches/{}\"", ids[0]))
    );
    assert!(
        html.contains(&format!(
            "/matches?bot_id={a}&amp;before={}&amp;limit=2",
            ids[1]
        )) && html.contains("3 matches"),
        "{html}"
    );
    // Each match says when it was queued; names do not wrap.
    assert!(
        html.contains("<th>queued</th>") && html.contains("<td class=\"time\">"),
        "{html}"
    );
    let (_, ts) = server.get("/api/tournaments", None).await;
    assert_eq!(ts["total"], 0);
}

async fn page(server: &TestServer, path: &str) -> String {
    let resp = server
        .client()
        .get(format!("{}{path}", server.base))
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 200, "{path}");
    resp.text().await.unwrap()
}

#[tokio::test]
async fn hidden_mazes_layouts_never_appear_in_any_page() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let (bot, _) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let (s, m) = server
        .post(
            "/api/mazes",
            json!({"name": "secret-16", "hidden": true, "generate": {"dim": 16}}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{m}");
    let hidden = m["maze_id"].as_i64().unwrap();
    let (_, full) = server
        .get(&format!("/api/mazes/{hidden}"), Some(ADMIN))
        .await;
    let layout = full["layout"].as_str().unwrap().to_string();
    let hash = full["hash"].as_str().unwrap().to_string();
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "ranked", "bot_ids": [bot], "maze_ids": [hidden, 1], "repeats": 1}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tid = t["tournament_id"].as_i64().unwrap();
    let deadline = Instant::now() + Duration::from_secs(90);
    loop {
        let (_, v) = server.get(&format!("/api/tournaments/{tid}"), None).await;
        if v["done"] == v["total"] {
            break;
        }
        assert!(Instant::now() < deadline, "{v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    let (_, list) = server
        .get(&format!("/api/matches?maze_id={hidden}"), None)
        .await;
    let on_hidden = list["items"][0]["match_id"].as_i64().unwrap();
    let (_, list) = server.get("/api/matches?maze_id=1", None).await;
    let on_public = list["items"][0]["match_id"].as_i64().unwrap();
    let columns: Vec<&str> = layout.lines().skip(1).filter(|l| !l.is_empty()).collect();
    assert_eq!(columns.len(), 16);
    let paths = [
        "/".to_string(),
        "/?scope=ranking".into(),
        "/?scope=all".into(),
        format!("/?tournament={tid}"),
        "/mazes".into(),
        format!("/mazes/{hidden}"),
        "/matches".into(),
        format!("/matches?maze_id={hidden}"),
        format!("/matches/{on_hidden}"),
        format!("/bots/{bot}"),
        "/bots".into(),
        format!("/tournaments/{tid}"),
        "/tournaments".into(),
    ];
    for path in &paths {
        let html = page(&server, path).await;
        for col in &columns {
            assert!(
                !html.contains(col),
                "{path} shows a column of the hidden maze"
            );
        }
        assert!(!html.contains(&hash), "{path} shows the hidden maze's hash");
    }
    let hidden_page = page(&server, &format!("/matches/{on_hidden}")).await;
    assert!(
        !hidden_page.contains("replay-data"),
        "no viewer for a hidden maze's match"
    );
    assert!(hidden_page.contains("hidden ranking maze"));
    let maze_page = page(&server, &format!("/mazes/{hidden}")).await;
    assert!(maze_page.contains("secret-16") && !maze_page.contains("<svg"));
    // The public maze's match has its viewer with the maze.
    let public_page = page(&server, &format!("/matches/{on_public}")).await;
    assert!(public_page.contains("id=\"replay-data\"") && public_page.contains("maze_layout"));
    // The ranking appears at / once the hidden maze has been played on.
    let board = page(&server, "/").await;
    assert!(board.contains("<h1>Ranking</h1>"), "{board}");
}

#[tokio::test]
async fn uploaded_sources_are_built_once_in_the_sandbox_before_they_play() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let read = |f: &str| std::fs::read_to_string(root().join("bots/c").join(f)).unwrap();
    let files: serde_json::Map<String, Value> = [
        "Makefile",
        "mazebot.c",
        "mazebot.h",
        "mazemap.c",
        "mazemap.h",
        "minimal_bot.c",
    ]
    .iter()
    .map(|f| (f.to_string(), Value::String(read(f))))
    .collect();
    let (s, created) = server
        .post("/api/bots", json!({"name": "c-bot", "command": "./minimal_bot", "build": "make minimal_bot", "files": files}), None)
        .await;
    assert_eq!(s, 201, "{created}");
    assert_eq!(created["version"]["build_status"], "building");
    let (bot, token) = (
        created["bot_id"].as_i64().unwrap(),
        created["owner_token"].as_str().unwrap().to_string(),
    );
    // A match asked for while it builds waits for the build.
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1, "seed": 3}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    let v = wait_built(&server, bot).await;
    assert_eq!(v["build_status"], "ready", "{v}");
    let m = wait_match(&server, q["match_id"].as_i64().unwrap()).await;
    assert_eq!(m["status"], "finished", "{m}");
    let (s, log) = server
        .get(
            &format!("/api/bots/{bot}/versions/1/build-log"),
            Some(&token),
        )
        .await;
    assert_eq!(s, 200);
    assert!(
        log["build_log"].as_str().unwrap().contains("minimal_bot"),
        "{log}"
    );

    // A build that fails: never plays, its queued match is recorded with the reason, and
    // the log is the owner's.
    let (s, v2) = server
        .post(
            &format!("/api/bots/{bot}/versions"),
            json!({"command": "./bot", "build": "cc -o bot nosuch.c", "files": {"README": "x"}}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 201, "{v2}");
    let (s, q2) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 202, "{q2}");
    let v = wait_built(&server, bot).await;
    assert_eq!(v["build_status"], "build_failed", "{v}");
    assert!(v.get("build_log_tail").is_none(), "not for anyone");
    let (_, mine) = server.get(&format!("/api/bots/{bot}"), Some(&token)).await;
    let tail = mine["versions"][1]["build_log_tail"].as_str().unwrap();
    assert!(tail.contains("nosuch.c"), "{tail}");
    let m2 = wait_match(&server, q2["match_id"].as_i64().unwrap()).await;
    assert_eq!(m2["status"], "crashed");
    let (_, log) = server
        .get(
            &format!("/api/matches/{}/log", q2["match_id"]),
            Some(&token),
        )
        .await;
    assert!(
        log["error"]["reason"]
            .as_str()
            .unwrap()
            .contains("build failed"),
        "{log}"
    );
    let (s, e) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 409, "{e}");
    let (s, _) = server
        .get(&format!("/api/bots/{bot}/versions/2/build-log"), None)
        .await;
    assert_eq!(s, 401);
    let html = page(&server, &format!("/bots/{bot}")).await;
    assert!(html.contains("build_failed") && html.contains("ready"));
    // Bad build commands and environments are refused at upload.
    for (body, what) in [
        (
            json!({"name": "x1", "command": "./b", "build": "'unbalanced", "files": {"a": "b"}}),
            "build",
        ),
        (
            json!({"name": "x2", "command": "./b", "env": {"PATH": "/x"}, "files": {"a": "b"}}),
            "env",
        ),
        (
            json!({"name": "x3", "command": "./b", "env": {"A": 1}, "files": {"a": "b"}}),
            "env value",
        ),
    ] {
        let (s, e) = server.post("/api/bots", body, None).await;
        assert!(s == 422 || s == 400, "{what}: {s} {e}");
    }
}

#[tokio::test]
async fn the_rust_kit_uploaded_as_source_builds_with_cargo_and_plays() {
    // As bots/rust/README.md shows: the sources, `cargo build --release --offline`.
    let dir = tempfile::tempdir().unwrap();
    // The toolchain is one of the server's runtimes, as bots/rust/README.md says.
    let toolchain = crate::support::rust_toolchain();
    let server = TestServer::start(dir.path(), &["--runtime", toolchain.to_str().unwrap()]);
    let kit = root().join("bots/rust");
    let mut files = serde_json::Map::new();
    for f in ["Cargo.toml", "Cargo.lock"] {
        let text = std::fs::read_to_string(kit.join(f)).unwrap();
        files.insert(f.to_string(), Value::String(text));
    }
    let mut stack = vec![kit.join("src")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let name = p.strip_prefix(&kit).unwrap().to_string_lossy().into_owned();
                files.insert(name, Value::String(std::fs::read_to_string(&p).unwrap()));
            }
        }
    }
    let (bot, token) = crate::support::upload(
        &server,
        json!({"name": "rust-bot", "command": "./target/release/champion",
               "build": "cargo build --release --offline", "files": files}),
    )
    .await;
    let v = wait_built(&server, bot).await;
    let log = crate::support::build_log(&server, bot, &token).await;
    assert_eq!(v["build_status"], "ready", "{log}");
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1, "seed": 1}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    let m = wait_match(&server, q["match_id"].as_i64().unwrap()).await;
    assert_eq!(m["status"], "finished", "{m}");
}

/// The texts of every inline `<tag>` element of `html` (a `<script>` of type
/// `application/json` is data, not a script, and is left out).
fn inline_texts(html: &str, tag: &str) -> Vec<String> {
    let mut out = Vec::new();
    let open = format!("<{tag}");
    let close = format!("</{tag}>");
    let mut rest = html;
    while let Some(start) = rest.find(&open) {
        let after = &rest[start..];
        let head_end = after.find('>').unwrap();
        let head = &after[..head_end];
        let body = &after[head_end + 1..];
        let end = body.find(&close).unwrap();
        if !head.contains("application/json") {
            out.push(body[..end].to_string());
        }
        rest = &body[end..];
    }
    out
}

#[tokio::test]
async fn every_page_runs_only_its_own_scripts_and_styles_and_cannot_be_framed() {
    use base64::Engine;
    use sha2::Digest;
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (bot, token) = register(
        &server,
        "policy-bot",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let id = crate::support::queue(&server, bot, 1, 1, &token).await;
    wait_match(&server, id).await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "cup", "bot_ids": [bot], "maze_ids": [1], "repeats": 1}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tournament = t["tournament_id"].as_i64().unwrap();
    let client = reqwest::Client::new();
    for path in [
        "/".to_string(),
        "/bots".into(),
        format!("/bots/{bot}"),
        "/mazes/1".into(),
        format!("/matches/{id}"),
        format!("/tournaments/{tournament}"),
        "/api/leaderboard".into(),
    ] {
        let resp = client
            .get(format!("{}{path}", server.base))
            .send()
            .await
            .unwrap();
        assert_eq!(resp.status(), 200, "{path}");
        let header = |name: &str| {
            resp.headers()
                .get(name)
                .map(|v| v.to_str().unwrap().to_string())
                .unwrap_or_else(|| panic!("{path} has no {name}"))
        };
        assert_eq!(header("x-content-type-options"), "nosniff");
        assert_eq!(header("x-frame-options"), "DENY");
        assert_eq!(header("referrer-policy"), "no-referrer");
        let csp = header("content-security-policy");
        assert!(csp.contains("frame-ancestors 'none'"), "{csp}");
        assert!(csp.contains("default-src 'none'"), "{csp}");
        assert!(!csp.contains("unsafe-inline"), "{csp}");
        let html = resp.text().await.unwrap();
        // Every inline script and style is allowed by its hash, and nothing else is
        // inline: no event handler, no style attribute.
        for tag in ["script", "style"] {
            for text in inline_texts(&html, tag) {
                let hash = base64::engine::general_purpose::STANDARD
                    .encode(sha2::Sha256::digest(text.as_bytes()));
                assert!(
                    csp.contains(&format!("'sha256-{hash}'")),
                    "{path}: an inline {tag} the policy does not allow: {}",
                    &text[..text.len().min(80)]
                );
            }
        }
        assert!(!html.contains(" style=\""), "{path} has a style attribute");
        for handler in [" onclick=", " onload=", " onerror=", " onsubmit="] {
            assert!(!html.contains(handler), "{path} has {handler}");
        }
    }
}
