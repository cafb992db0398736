//! The real server binary over HTTP: bots, mazes, matches, tournaments, leaderboards,
//! authorization, bad requests, restart recovery.

use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant};

use reqwest::Method;
use serde_json::{Value, json};

use crate::support::{
    ADMIN, TestServer, adapter_bot_files, assert_standings_equal_recount, mazearena, register,
    root, shared_maze, simple_bot_files, wait_match,
};

async fn upload_maze(server: &TestServer, name: &str, path: &std::path::Path, hidden: bool) -> i64 {
    let layout = std::fs::read_to_string(path).unwrap();
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": name, "layout": layout, "hidden": hidden}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    v["maze_id"].as_i64().unwrap()
}

async fn wait_tournament(server: &TestServer, id: i64, timeout: Duration) -> Value {
    let deadline = Instant::now() + timeout;
    loop {
        let (s, v) = server.get(&format!("/api/tournaments/{id}"), None).await;
        assert_eq!(s, 200, "{v}");
        if v["done"] == v["total"] {
            return v;
        }
        assert!(
            Instant::now() < deadline,
            "tournament {id} did not end: {v}"
        );
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

fn assert_error(status: u16, body: &Value, want: u16) {
    assert_eq!(status, want, "{body}");
    assert!(
        body["error"]["code"].is_string(),
        "JSON error body expected: {body}"
    );
    assert!(!body["error"]["message"].as_str().unwrap().is_empty());
}

#[tokio::test]
async fn a_match_over_http_scores_like_mazearena_run() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (bot, token) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let maze = upload_maze(
        &server,
        "classic-02",
        &shared_maze("classic/test_maze_02.txt"),
        false,
    )
    .await;
    let (s, queued) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": maze, "seed": 11}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 202, "{queued}");
    let done = wait_match(&server, queued["match_id"].as_i64().unwrap()).await;

    let local = mazearena(&[
        "run",
        "--maze",
        shared_maze("classic/test_maze_02.txt").to_str().unwrap(),
        "--bot",
        "python3 bots/python/simple_bot.py",
        "--seed",
        "11",
        "--json",
    ]);
    let local: Value = serde_json::from_slice(&local.stdout).unwrap();
    assert_eq!(done["status"], "finished");
    for key in [
        "status",
        "score",
        "run0_steps",
        "run1_steps",
        "total_steps",
        "seed",
        "maze_hash",
    ] {
        assert_eq!(done[key], local[key], "{key}: server {done} vs run {local}");
    }
    assert_eq!(done["bot_version"], 1);
    assert!(done["timings"]["wall_ms"].is_u64());
    assert_eq!(done["limits"]["move_timeout_ms"], 1000);

    // The replay has every step; the log is the owner's.
    let id = done["match_id"].as_i64().unwrap();
    let (s, replay) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_eq!(s, 200);
    assert_eq!(
        replay["trace"].as_array().unwrap().len() as u64,
        done["total_steps"].as_u64().unwrap()
    );
    assert_eq!(replay["maze_dim"], 14);
    let (s, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(&token))
        .await;
    assert_eq!(s, 200, "{log}");
    assert!(log["error"].is_null());
}

#[tokio::test]
async fn a_tournament_records_every_match_and_ranks_by_mean_score() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (a, _) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let (b, _) = register(
        &server,
        "adapter",
        "python3 udacity_adapter.py robot.py",
        adapter_bot_files(),
    )
    .await;
    let mut mazes = Vec::new();
    for n in 1..=3 {
        let path = shared_maze(&format!("classic/test_maze_0{n}.txt"));
        mazes.push(upload_maze(&server, &format!("classic-0{n}"), &path, true).await);
    }
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "cup", "bot_ids": [a, b], "maze_ids": mazes, "repeats": 2}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    assert_eq!(t["total"], 12);
    let id = t["tournament_id"].as_i64().unwrap();
    let done = wait_tournament(&server, id, Duration::from_secs(120)).await;
    assert_eq!(done["done"], 12);

    // Exactly 12 records, one per (bot, maze, repeat), read from the database itself.
    let storage = mazearena::storage::Storage::open(&server.database)
        .await
        .unwrap();
    let rows = storage.tournament_matches(id).await.unwrap();
    assert_eq!(rows.len(), 12);
    assert_standings_equal_recount(&server.database, &[id]).await;
    let keys: BTreeSet<(i64, i64, i64)> = rows
        .iter()
        .map(|r| (r.bot_id, r.maze_id, r.repeat.unwrap()))
        .collect();
    assert_eq!(keys.len(), 12);
    // The leaderboard's order follows the mean scores computed from the records.
    let mut sums: BTreeMap<i64, (f64, f64)> = BTreeMap::new();
    for r in &rows {
        let score = if r.status == "finished" {
            r.score.unwrap()
        } else {
            1000.0
        };
        let e = sums.entry(r.bot_id).or_default();
        e.0 += score;
        e.1 += 1.0;
    }
    let mut expected: Vec<(f64, i64)> = sums.iter().map(|(bot, (s, n))| (s / n, *bot)).collect();
    expected.sort_by(|x, y| x.0.partial_cmp(&y.0).unwrap());
    let (s, board) = server
        .get(&format!("/api/leaderboard?tournament={id}"), Some(ADMIN))
        .await;
    assert_eq!(s, 200);
    let board = board.as_array().unwrap();
    assert_eq!(board.len(), 2);
    for (i, (mean, bot)) in expected.iter().enumerate() {
        assert_eq!(board[i]["bot_id"], *bot);
        assert_eq!(board[i]["rank"], i as i64 + 1);
        // Shown rounded to 3 decimals.
        assert_eq!(
            board[i]["mean_score"].as_f64().unwrap(),
            (mean * 1000.0).round() / 1000.0
        );
        assert_eq!(board[i]["played"], 6);
        assert!(board[i]["mean_ratio"].as_f64().unwrap() > 1.0);
    }
    // The mazes are hidden: for anyone else the ratio to their optimum is left out.
    let (_, public) = server
        .get(&format!("/api/leaderboard?tournament={id}"), None)
        .await;
    assert!(public[0]["mean_ratio"].is_null(), "{public}");
    assert_eq!(public[0]["mean_score"], board[0]["mean_score"]);
    assert_eq!(done["standings"].as_array().unwrap().len(), 2);
    // Hidden mazes are the ranking set: the default board counts these matches too.
    let (_, ranking) = server.get("/api/leaderboard", None).await;
    assert_eq!(ranking.as_array().unwrap().len(), 2);
}

#[tokio::test]
async fn owner_and_admin_endpoints_refuse_others() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (bot, token) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let (_, other) = register(
        &server,
        "other",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let hidden = upload_maze(
        &server,
        "secret",
        &shared_maze("classic/test_maze_01.txt"),
        true,
    )
    .await;
    let maze_text = std::fs::read_to_string(shared_maze("classic/test_maze_03.txt")).unwrap();
    let upload = json!({"command": "python3 simple_bot.py", "files": simple_bot_files()});

    // Admin only: uploading mazes, tournaments.
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "m", "layout": maze_text}),
            None,
        )
        .await;
    assert_error(s, &v, 401);
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "m", "layout": maze_text}),
            Some(&token),
        )
        .await;
    assert_error(s, &v, 403);
    let t = json!({"name": "t", "bot_ids": [bot], "maze_ids": [1], "repeats": 1});
    let (s, v) = server
        .post("/api/tournaments", t.clone(), Some(&token))
        .await;
    assert_error(s, &v, 403);
    // Owner only: new versions, matches, logs.
    let (s, v) = server
        .post(&format!("/api/bots/{bot}/versions"), upload.clone(), None)
        .await;
    assert_error(s, &v, 401);
    let (s, v) = server
        .post(
            &format!("/api/bots/{bot}/versions"),
            upload.clone(),
            Some(&other),
        )
        .await;
    assert_error(s, &v, 403);
    let (s, v) = server
        .post(
            &format!("/api/bots/{bot}/versions"),
            upload.clone(),
            Some(&token),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    assert_eq!(v["version"], 2);
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1}),
            Some(&other),
        )
        .await;
    assert_error(s, &v, 403);
    let (s, v) = server
        .post("/api/matches", json!({"bot_id": bot, "maze_id": 1}), None)
        .await;
    assert_error(s, &v, 401);
    // Hidden mazes: no layout, no picture, no owner matches.
    let (s, v) = server.get(&format!("/api/mazes/{hidden}"), None).await;
    assert_eq!(s, 200);
    assert!(v.get("layout").is_none(), "{v}");
    let (s, v) = server
        .get(&format!("/api/mazes/{hidden}"), Some(ADMIN))
        .await;
    assert_eq!(s, 200);
    assert!(v["layout"].is_string());
    let (s, v) = server
        .get(&format!("/api/mazes/{hidden}/svg"), Some(&token))
        .await;
    assert_error(s, &v, 403);
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": hidden}),
            Some(&token),
        )
        .await;
    assert_error(s, &v, 403);
    // The admin may run it; its replay is the admin's only.
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": hidden, "seed": 1}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    let id = wait_match(&server, q["match_id"].as_i64().unwrap()).await["match_id"]
        .as_i64()
        .unwrap();
    let (s, v) = server
        .get(&format!("/api/matches/{id}/replay"), Some(&token))
        .await;
    assert_error(s, &v, 403);
    assert_eq!(
        server
            .get(&format!("/api/matches/{id}/replay"), Some(ADMIN))
            .await
            .0,
        200
    );
    let (s, v) = server
        .get(&format!("/api/matches/{id}/replay"), Some(&other))
        .await;
    assert_error(s, &v, 403);
    let (s, v) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_error(s, &v, 401);
    let (s, v) = server
        .get(&format!("/api/matches/{id}/log"), Some(&other))
        .await;
    assert_error(s, &v, 403);
    assert_eq!(
        server
            .get(&format!("/api/matches/{id}/log"), Some(ADMIN))
            .await
            .0,
        200
    );
    // A public maze's picture is for everyone.
    let resp = server
        .client()
        .get(format!("{}/api/mazes/1/svg", server.base))
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 200);
    assert!(resp.text().await.unwrap().contains("<svg"));
    // A malformed Authorization header.
    let resp = server
        .client()
        .post(format!("{}/api/matches", server.base))
        .header("Authorization", "Basic abc")
        .json(&json!({"bot_id": bot, "maze_id": 1}))
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 401);
}

#[tokio::test]
async fn bad_requests_get_a_4xx_json_error() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let url = |p: &str| format!("{}{p}", server.base);
    let c = server.client();
    let body = |r: reqwest::Response| async move {
        let status = r.status().as_u16();
        (
            status,
            serde_json::from_str::<Value>(&r.text().await.unwrap()).unwrap_or(Value::Null),
        )
    };
    // Malformed JSON, wrong types, unknown fields, missing content type.
    let r = c
        .post(url("/api/matches"))
        .header("content-type", "application/json")
        .body("{\"bot_id\": ")
        .send()
        .await
        .unwrap();
    let (s, v) = body(r).await;
    assert_error(s, &v, 400);
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": "x", "maze_id": 1}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 422);
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": 1, "maze_id": 1, "color": 1}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 422);
    let r = c
        .post(url("/api/mazes"))
        .bearer_auth(ADMIN)
        .body("{}")
        .send()
        .await
        .unwrap();
    let (s, v) = body(r).await;
    assert_error(s, &v, 415);
    // Unknown ids and routes, bad path parameters, wrong methods.
    for path in [
        "/api/bots/999",
        "/api/mazes/999",
        "/api/matches/999",
        "/api/tournaments/999",
        "/api/nothing",
    ] {
        let (s, v) = server.get(path, None).await;
        assert_error(s, &v, 404);
    }
    let (s, v) = server.get("/api/leaderboard?tournament=999", None).await;
    assert_error(s, &v, 404);
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": 999, "maze_id": 1}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 404);
    let (s, v) = server.get("/api/bots/abc", None).await;
    assert_error(s, &v, 400);
    let (s, v) = server.get("/api/leaderboard?scope=weird", None).await;
    assert_error(s, &v, 400);
    let (s, v, _) = server.call(Method::DELETE, "/api/bots", None, None).await;
    assert_error(s, &v, 405);
    // Oversized bodies.
    // A server that refuses while the body is still being sent may close the connection
    // before the client reads the 413; such a send is tried again (at most 5 times).
    let big = json!({"name": "big", "layout": "x".repeat(3 * 1024 * 1024)});
    let mut answer = None;
    for _ in 0..5 {
        // A client of its own: the server closes a connection whose body it refused,
        // and the shared client must not pick that connection for the next request.
        let sent = reqwest::Client::new()
            .post(format!("{}/api/mazes", server.base))
            .bearer_auth(ADMIN)
            .json(&big)
            .send()
            .await;
        if let Ok(resp) = sent {
            let status = resp.status().as_u16();
            answer = Some((status, resp.json::<Value>().await.unwrap_or(Value::Null)));
            break;
        }
    }
    let (s, v) = answer.expect("the server answered an oversized maze");
    assert_error(s, &v, 413);
    // A 40 MiB upload is refused from its Content-Length, before the body is read.
    let (s, v) = raw_post_headers(&server.base, "/api/bots", 40 * 1024 * 1024).await;
    assert_error(s, &v, 413);
    // A bad maze names its line.
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "bad", "layout": "4\n1,5,7,5\n3,5,14\n"}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 422);
    assert!(
        v["error"]["message"].as_str().unwrap().contains("line 3"),
        "{v}"
    );
    // A duplicate maze names the first.
    let layout = std::fs::read_to_string(root().join("mazes/gen-12-s1.txt")).unwrap();
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "again", "layout": layout}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 409);
    assert!(
        v["error"]["message"].as_str().unwrap().contains("maze 1"),
        "{v}"
    );
    // Archives that leave the bot's folder, bad base64, no files, bad names, taken names.
    let archive = tar_gz(&[("../x", b"boom")]);
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "evil", "command": "python3 x", "archive_base64": archive}),
            None,
        )
        .await;
    assert_error(s, &v, 422);
    assert!(
        v["error"]["message"].as_str().unwrap().contains("../x"),
        "{v}"
    );
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "b64", "command": "x", "archive_base64": "%%%"}),
            None,
        )
        .await;
    assert_error(s, &v, 422);
    let (s, v) = server
        .post("/api/bots", json!({"name": "none", "command": "x"}), None)
        .await;
    assert_error(s, &v, 422);
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "a b", "command": "x", "files": {"a": "1"}}),
            None,
        )
        .await;
    assert_error(s, &v, 422);
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "q", "command": "python3 'x", "files": {"a": "1"}}),
            None,
        )
        .await;
    assert_error(s, &v, 422);
    register(&server, "taken", "python3 a.py", json!({"a.py": "1"})).await;
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "taken", "command": "x", "files": {"a": "1"}}),
            None,
        )
        .await;
    assert_error(s, &v, 409);
    // Nothing bad was stored, and the server still answers.
    let (_, bots) = server.get("/api/bots", None).await;
    assert_eq!(bots.as_array().unwrap().len(), 1);
    assert_eq!(server.get("/healthz", None).await.0, 200);
}

#[tokio::test]
async fn a_bot_uploaded_as_a_multipart_archive_plays() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let files = simple_bot_files();
    let entries: Vec<(&str, &[u8])> = files
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str().unwrap().as_bytes()))
        .collect();
    let bytes = tar_gz_bytes(&entries);
    let form = reqwest::multipart::Form::new()
        .text("name", "packed")
        .text("command", "python3 simple_bot.py")
        .part(
            "archive",
            reqwest::multipart::Part::bytes(bytes).file_name("bot.tar.gz"),
        );
    let resp = server
        .client()
        .post(format!("{}/api/bots", server.base))
        .multipart(form)
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 201);
    let v: Value = resp.json().await.unwrap();
    let token = v["owner_token"].as_str().unwrap();
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": v["bot_id"], "maze_id": 1}),
            Some(token),
        )
        .await;
    assert_eq!(s, 202);
    let done = wait_match(&server, q["match_id"].as_i64().unwrap()).await;
    assert_eq!(done["status"], "finished", "{done}");
}

#[tokio::test]
async fn hostile_bots_are_recorded_and_the_server_keeps_serving() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let fixtures = root().join("tests/fixtures/bots");
    let mut ids = Vec::new();
    for (name, status) in [
        ("not_json", "protocol_error"),
        ("exits_early", "crashed"),
        ("killed_by_signal", "crashed"),
    ] {
        let code = std::fs::read_to_string(fixtures.join(format!("{name}.py"))).unwrap();
        let (bot, token) = register(&server, name, "python3 bot.py", json!({"bot.py": code})).await;
        let (_, q) = server
            .post(
                "/api/matches",
                json!({"bot_id": bot, "maze_id": 1}),
                Some(&token),
            )
            .await;
        ids.push((q["match_id"].as_i64().unwrap(), status, token));
    }
    for (id, status, token) in ids {
        let done = wait_match(&server, id).await;
        assert_eq!(done["status"], status, "{done}");
        assert!(done["score"].is_null());
        let (_, log) = server
            .get(&format!("/api/matches/{id}/log"), Some(&token))
            .await;
        assert!(
            !log["error"]["reason"].as_str().unwrap().is_empty(),
            "{log}"
        );
    }
    assert_eq!(server.get("/healthz", None).await.0, 200);
    let (_, metrics, _) = server.get_raw("/metrics", Some(ADMIN)).await;
    assert!(
        metrics.contains("mazearena_matches{status=\"crashed\"} 2"),
        "{metrics}"
    );
    assert!(metrics.contains("mazearena_queue_depth 0"));
    assert!(metrics.contains("mazearena_match_duration_seconds_count 3"));
    assert_standings_equal_recount(&server.database, &[]).await;
}

#[tokio::test]
async fn a_full_queue_answers_429_with_retry_after() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--max-queue", "0"]);
    let (bot, token) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let (s, v, headers) = server
        .call(
            Method::POST,
            "/api/matches",
            Some(json!({"bot_id": bot, "maze_id": 1})),
            Some(&token),
        )
        .await;
    assert_error(s, &v, 429);
    assert!(headers.get("retry-after").is_some());
    let t = json!({"name": "t", "bot_ids": [bot], "maze_ids": [1, 2], "repeats": 1});
    let (s, v) = server.post("/api/tournaments", t, Some(ADMIN)).await;
    assert_error(s, &v, 429);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flooding_owner_neither_delays_another_owner_nor_the_ranking() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1", "--max-queued-per-owner", "30"]);
    // The flooder's bot takes a while each match (3 s to start), so its flood waits.
    let slow = "import sys, time\ntime.sleep(0.3)\nsys.stdin.readline()\nfor line in sys.stdin:\n    \
                print('{\"rotation\":0,\"movement\":0}', flush=True)\n";
    let (flooder, flood_token) = register(
        &server,
        "flooder",
        "python3 bot.py",
        json!({"bot.py": slow}),
    )
    .await;
    let (honest, honest_token) = register(
        &server,
        "honest",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let queue = |bot: i64, token: String, seed: i64| {
        let server = &server;
        async move {
            server
                .call(
                    Method::POST,
                    "/api/matches",
                    Some(json!({"bot_id": bot, "maze_id": 1, "seed": seed})),
                    Some(&token),
                )
                .await
        }
    };
    // Forty sent at once: queued up to the limit, 30 waiting (one or two more may have
    // started meanwhile), the rest refused. (Each request passes the early check
    // before any is queued; the limit holds because it is counted again where the
    // match is queued.)
    let burst = futures_util::future::join_all(
        (0..40).map(|seed| queue(flooder, flood_token.clone(), seed)),
    )
    .await;
    let accepted = burst.iter().filter(|(s, ..)| *s == 202).count();
    assert!(
        (30..=32).contains(&accepted),
        "{accepted} of 40 sent at once were queued: the owner's limit did not hold"
    );
    let (s, v, headers) = burst.into_iter().find(|(s, ..)| *s != 202).unwrap();
    assert_error(s, &v, 429);
    // Past its share: 429 naming whose limit, how many wait, and when to retry.
    let msg = v["error"]["message"].as_str().unwrap();
    assert!(
        msg.contains(&format!("owner of bot {flooder}")) && msg.contains("(30)"),
        "{msg}"
    );
    assert!(headers.get("retry-after").is_some());
    // The admin's tournament and the honest owner's match, queued behind the flood.
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "ranking", "bot_ids": [honest], "maze_ids": [1, 2], "repeats": 2}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let (s, mine, _) = queue(honest, honest_token.clone(), 7).await;
    assert_eq!(s, 202, "{mine}");
    let mine = mine["match_id"].as_i64().unwrap();
    let done = wait_match(&server, mine).await;
    assert_eq!(done["status"], "finished", "{done}");
    // The flooder's matches started after the honest one was queued and before it
    // started: at most one (its lane's turn).
    let (_, all) = server.get("/api/matches?limit=200", Some(ADMIN)).await;
    let (queued_at, started) = (
        done["created_at"].as_i64().unwrap(),
        done["started_at"].as_i64().unwrap(),
    );
    let flood_before = all["items"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["bot_id"] == flooder)
        .filter(|m| {
            m["started_at"]
                .as_i64()
                .is_some_and(|s| s >= queued_at && s < started)
        })
        .count();
    assert!(
        flood_before <= 1,
        "{flood_before} of the flooder's matches started between the honest one's queueing and start"
    );
    // The tournament finishes while the flood still waits.
    let tid = t["tournament_id"].as_i64().unwrap();
    let tv = wait_tournament(&server, tid, Duration::from_secs(120)).await;
    assert_eq!(tv["done"], tv["total"], "{tv}");
    let (_, queued) = server
        .get(
            &format!("/api/matches?bot_id={flooder}&status=queued"),
            None,
        )
        .await;
    assert!(
        queued["total"].as_i64() > Some(0),
        "the flood was played before the tournament ended: the test proves nothing"
    );
}

#[tokio::test]
async fn anonymous_registrations_are_limited_per_address_but_not_keys_or_the_admin() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--registrations-per-hour", "3"]);
    for i in 0..3 {
        register(
            &server,
            &format!("b{i}"),
            "python3 simple_bot.py",
            simple_bot_files(),
        )
        .await;
    }
    let body =
        json!({"name": "b3", "command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (s, v, headers) = server
        .call(Method::POST, "/api/bots", Some(body.clone()), None)
        .await;
    assert_error(s, &v, 429);
    let message = v["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("your network") && message.contains("entrant's key"),
        "{v}"
    );
    assert!(!message.contains("127.0.0.1"), "{v}");
    let wait: u64 = headers["retry-after"].to_str().unwrap().parse().unwrap();
    assert!((1..=1200).contains(&wait), "{wait}");
    // An anonymous entrant's registration spends the same budget.
    let (s, v, _) = server
        .call(
            Method::POST,
            "/api/entrants",
            Some(json!({"name": "anon"})),
            None,
        )
        .await;
    assert_error(s, &v, 429);
    // The admin has no limit; an entrant it registers registers bots with its key,
    // which spends nothing of the address's budget.
    let (s, v, _) = server
        .call(Method::POST, "/api/bots", Some(body), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{v}");
    let (s, e, _) = server
        .call(
            Method::POST,
            "/api/entrants",
            Some(json!({"name": "team"})),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{e}");
    let key = e["key"].as_str().unwrap();
    for i in 0..4 {
        let body = json!({"name": format!("team-{i}"), "command": "python3 simple_bot.py",
                          "files": simple_bot_files()});
        let (s, v, _) = server
            .call(Method::POST, "/api/bots", Some(body), Some(key))
            .await;
        assert_eq!(s, 201, "{v}");
    }
}

#[tokio::test]
async fn the_openapi_document_lists_every_route() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (s, doc) = server.get("/api/openapi.json", None).await;
    assert_eq!(s, 200);
    let paths = doc["paths"].as_object().unwrap();
    let expected = [
        ("/api/bots", vec!["get", "post"]),
        ("/api/bots/{id}", vec!["get"]),
        ("/api/bots/{id}/versions", vec!["post"]),
        ("/api/bots/{id}/resume", vec!["post"]),
        ("/api/bots/{id}/versions/{version}/build-log", vec!["get"]),
        ("/api/mazes", vec!["get", "post"]),
        ("/api/mazes/{id}", vec!["get"]),
        ("/api/mazes/{id}/svg", vec!["get"]),
        ("/api/matches", vec!["get", "post"]),
        ("/api/matches/{id}", vec!["get"]),
        ("/api/matches/{id}/replay", vec!["get"]),
        ("/api/matches/{id}/replay.html", vec!["get"]),
        ("/api/matches/{id}/log", vec!["get"]),
        ("/api/tournaments", vec!["get", "post"]),
        ("/api/tournaments/{id}", vec!["get"]),
        ("/api/leaderboard", vec!["get"]),
        ("/api/entrants", vec!["get", "post"]),
        ("/api/entrants/{id}", vec!["get"]),
        ("/api/entrants/{id}/key", vec!["post"]),
        ("/api/registration", vec!["get", "put"]),
        ("/api/me", vec!["get"]),
        ("/api/organisers", vec!["post"]),
        ("/api/organisers/{id}/key", vec!["post"]),
        ("/api/competitions/{name}/invite", vec!["put", "delete"]),
        ("/api/competitions/{name}/practice", vec!["post"]),
        (
            "/api/competitions/{name}/practice/{maze_id}",
            vec!["delete"],
        ),
        ("/api/competitions", vec!["get", "post"]),
        ("/api/competitions/{name}", vec!["get", "patch"]),
        ("/api/competitions/{name}/entries", vec!["post"]),
        ("/api/competitions/{name}/leaderboard", vec!["get"]),
        ("/api/competitions/{name}/submissions", vec!["get"]),
        ("/api/competitions/{name}/selection", vec!["put"]),
        ("/api/competitions/{name}/results", vec!["get"]),
        ("/api/competitions/{name}/results.csv", vec!["get"]),
        ("/api/competitions/{name}/rejudges", vec!["get", "post"]),
        ("/api/competitions/{name}/export", vec!["get"]),
        ("/api/competitions/{name}/publish", vec!["post"]),
        ("/api/competitions/{name}/reveal", vec!["get"]),
        ("/api/competitions/{name}/races", vec!["get"]),
        ("/api/competitions/{name}/race/{maze}/{repeat}", vec!["get"]),
        ("/api/tournaments/{id}/race/{maze_id}/{repeat}", vec!["get"]),
        ("/api/runtimes", vec!["get"]),
        ("/healthz", vec!["get"]),
        ("/metrics", vec!["get"]),
        ("/api/openapi.json", vec!["get"]),
    ];
    assert_eq!(
        paths.len(),
        expected.len(),
        "{:?}",
        paths.keys().collect::<Vec<_>>()
    );
    for (path, methods) in expected {
        let item = paths.get(path).unwrap_or_else(|| panic!("{path} missing"));
        for m in methods {
            assert!(item.get(m).is_some(), "{m} {path} missing");
            // Each documented route really answers (not with the 404 fallback).
            let concrete = path.replace("{id}", "1");
            let method = Method::from_bytes(m.to_uppercase().as_bytes()).unwrap();
            let (s, v, _) = server.call(method, &concrete, None, None).await;
            assert!(
                !(s == 404
                    && v["error"]["message"]
                        .as_str()
                        .unwrap_or("")
                        .contains("no such route")),
                "{m} {path}"
            );
        }
    }
}

#[tokio::test]
async fn a_server_killed_mid_tournament_completes_it_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--jobs", "2", "--lease-secs", "2"];
    let mut server = TestServer::start(dir.path(), &args);
    // A slow bot: the optimal script of maze 01 (17 steps), 30 ms per answer.
    let solution = mazearena::engine::solver::solve(&crate::support::classic(1)).unwrap();
    let mut script: Vec<String> = solution
        .actions
        .iter()
        .map(|a| match a {
            mazearena::engine::Action::Move { rotation, movement } => {
                format!("{rotation},{movement}")
            }
            mazearena::engine::Action::Reset { .. } => "reset".into(),
        })
        .collect();
    let run1 = script.clone();
    script.push("reset".into());
    script.extend(run1);
    let code = std::fs::read_to_string(root().join("tests/fixtures/bots/scripted.py")).unwrap();
    let command = format!("python3 scripted.py --delay-ms 30 {}", script.join(" "));
    let (a, _) = register(&server, "slow-a", &command, json!({"scripted.py": code})).await;
    let (b, _) = register(&server, "slow-b", &command, json!({"scripted.py": code})).await;
    let maze = upload_maze(
        &server,
        "classic-01",
        &shared_maze("classic/test_maze_01.txt"),
        false,
    )
    .await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "crash", "bot_ids": [a, b], "maze_ids": [maze], "repeats": 5}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let id = t["tournament_id"].as_i64().unwrap();
    // Kill the server once some, but not all, matches are recorded.
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let (_, v) = server.get(&format!("/api/tournaments/{id}"), None).await;
        let done = v["done"].as_i64().unwrap();
        if done >= 2 {
            assert!(done < 10, "the tournament ended before the kill: {v}");
            break;
        }
        assert!(Instant::now() < deadline);
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    server.kill();
    let server = TestServer::start(dir.path(), &args);
    let v = wait_tournament(&server, id, Duration::from_secs(120)).await;
    assert_eq!(v["total"], 10);
    assert_eq!(v["done"], 10);
    let storage = mazearena::storage::Storage::open(&server.database)
        .await
        .unwrap();
    let rows = storage.tournament_matches(id).await.unwrap();
    assert_eq!(rows.len(), 10, "no duplicates, none lost");
    assert_standings_equal_recount(&server.database, &[id]).await;
    let keys: BTreeSet<(i64, i64)> = rows.iter().map(|r| (r.bot_id, r.repeat.unwrap())).collect();
    assert_eq!(keys.len(), 10);
    for r in &rows {
        assert_eq!(r.status, "finished", "{r:?}");
        assert_eq!(r.score, Some(17.6));
    }
    assert!(
        rows.iter().any(|r| r.attempts > 1),
        "some match was re-run after the kill"
    );
}

#[tokio::test]
async fn sigterm_stops_the_server_without_losing_a_match() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--jobs", "1", "--shutdown-grace-secs", "0"];
    let mut server = TestServer::start(dir.path(), &args);
    let code = std::fs::read_to_string(root().join("tests/fixtures/bots/scripted.py")).unwrap();
    // Never finishes quickly: 1000 idle answers at 20 ms each.
    let (bot, token) = register(
        &server,
        "idle",
        "python3 scripted.py --delay-ms 20",
        json!({"scripted.py": code}),
    )
    .await;
    let (_, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": 1}),
            Some(&token),
        )
        .await;
    let id = q["match_id"].as_i64().unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    while server.get(&format!("/api/matches/{id}"), None).await.1["status"] != "running" {
        assert!(Instant::now() < deadline);
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let status = server.terminate();
    assert!(status.success(), "{status:?}");
    let storage = mazearena::storage::Storage::open(&server.database)
        .await
        .unwrap();
    let row = storage.get_match(id).await.unwrap().unwrap();
    assert_eq!(
        row.status, "queued",
        "the interrupted match is back in the queue"
    );
}

/// An admin-generated hidden 12x12 maze; its id.
async fn generate_hidden(server: &TestServer, name: &str) -> i64 {
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": name, "hidden": true, "generate": {"dim": 12}}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    assert!(
        v.get("seed").is_none(),
        "a hidden maze's seed is shown: {v}"
    );
    v["maze_id"].as_i64().unwrap()
}

/// Asserts that a non-admin's view of hidden maze `id` names no hash, side or optimum.
fn assert_maze_redacted(v: &Value, id: i64) {
    assert_eq!(v["maze_id"], id, "{v}");
    assert_eq!(v["hidden"], true, "{v}");
    for key in ["hash", "dim", "optimum"] {
        assert!(v[key].is_null(), "{key} of hidden maze {id} shown: {v}");
    }
    assert!(v.get("layout").is_none(), "{v}");
}

#[tokio::test]
async fn non_admins_see_no_hash_dim_or_optimum_of_a_hidden_maze() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (bot, token) = register(
        &server,
        "simple",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let hidden = generate_hidden(&server, "ranking-1").await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "cup", "bot_ids": [bot], "maze_ids": [hidden]}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tid = t["tournament_id"].as_i64().unwrap();
    wait_tournament(&server, tid, Duration::from_secs(60)).await;
    let storage = mazearena::storage::Storage::open(&server.database)
        .await
        .unwrap();
    let mid = storage.tournament_matches(tid).await.unwrap()[0].match_id;
    // The admin sees everything.
    let (_, maze) = server
        .get(&format!("/api/mazes/{hidden}"), Some(ADMIN))
        .await;
    let hash = maze["hash"].as_str().unwrap().to_string();
    assert_eq!(maze["dim"], 12);
    assert!(maze["optimum"].is_u64(), "{maze}");
    let (_, m) = server
        .get(&format!("/api/matches/{mid}"), Some(ADMIN))
        .await;
    assert_eq!(
        (m["maze_hash"].as_str(), &m["maze_dim"]),
        (Some(&*hash), &json!(12))
    );
    assert!(m["timings"]["wall_ms"].is_u64(), "{m}");
    let boards = [
        "/api/leaderboard".to_string(),
        "/api/leaderboard?scope=all".to_string(),
        format!("/api/leaderboard?tournament={tid}"),
    ];
    for path in &boards {
        let (_, b) = server.get(path, Some(ADMIN)).await;
        assert!(b[0]["mean_ratio"].is_f64(), "{path}: {b}");
    }
    // Anonymous callers and a bot's owner see no hash, side or optimum, anywhere.
    for caller in [None, Some(token.as_str())] {
        let mut bodies = Vec::new();
        let (_, list) = server.get("/api/mazes", caller).await;
        let listed = list.as_array().unwrap();
        assert_maze_redacted(
            listed.iter().find(|m| m["maze_id"] == hidden).unwrap(),
            hidden,
        );
        assert!(
            listed
                .iter()
                .any(|m| m["hidden"] == false && m["hash"].is_string())
        );
        let (_, one) = server.get(&format!("/api/mazes/{hidden}"), caller).await;
        assert_maze_redacted(&one, hidden);
        let (s, m) = server.get(&format!("/api/matches/{mid}"), caller).await;
        assert_eq!(s, 200, "{m}");
        for key in ["maze_hash", "maze_dim", "warnings", "timings"] {
            assert!(m[key].is_null(), "{key} shown: {m}");
        }
        assert_eq!(
            (&m["status"], m["maze_hidden"].as_bool()),
            (&json!("finished"), Some(true))
        );
        // Whether it finished, nothing more: each number could carry bits of the maze.
        for key in [
            "score",
            "run0_steps",
            "run1_steps",
            "total_steps",
            "started_at",
            "finished_at",
        ] {
            assert!(m[key].is_null(), "{key} shown: {m}");
        }
        let (_, tv) = server.get(&format!("/api/tournaments/{tid}"), caller).await;
        assert_eq!(tv["standings"][0]["played"], 1, "{tv}");
        assert!(tv["standings"][0]["mean_ratio"].is_null(), "{tv}");
        for path in &boards {
            let (_, b) = server.get(path, caller).await;
            assert!(b[0]["mean_score"].is_f64(), "{path}: {b}");
            assert!(b[0]["mean_ratio"].is_null(), "{path}: {b}");
            bodies.push(b);
        }
        let (s, svg) = server
            .get(&format!("/api/mazes/{hidden}/svg"), caller)
            .await;
        assert!(s == 401 || s == 403, "{s} {svg}");
        bodies.extend([
            list,
            one,
            m,
            tv,
            server.get(&format!("/api/bots/{bot}"), caller).await.1,
        ]);
        for b in bodies {
            assert!(!b.to_string().contains(&hash), "the hash leaks: {b}");
        }
    }
}

#[tokio::test]
async fn an_owner_gets_no_replay_or_stderr_of_a_hidden_maze_match() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    // A bot that prints what it senses to stderr, then quits at its third step.
    let leaky = "import sys\nn = 0\nfor line in sys.stdin:\n    if '\"sense\"' in line:\n        \
                 n += 1\n        sys.stderr.write('LEAK ' + line)\n        sys.stderr.flush()\n        \
                 if n == 3:\n            sys.exit(0)\n        print('{\"rotation\":0,\"movement\":1}', flush=True)\n";
    let (bot, token) = register(&server, "leaky", "python3 bot.py", json!({"bot.py": leaky})).await;
    let hidden = generate_hidden(&server, "ranking-1").await;
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": hidden, "seed": 5}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    let id = q["match_id"].as_i64().unwrap();
    let done = wait_match(&server, id).await;
    assert_eq!(done["status"], "crashed", "{done}");
    // The owner: the status (the kind of failure) only, in the view and the log; no
    // replay.
    let (_, m) = server
        .get(&format!("/api/matches/{id}"), Some(&token))
        .await;
    assert_eq!(m["status"], "crashed", "{m}");
    for key in [
        "score",
        "total_steps",
        "run0_steps",
        "started_at",
        "finished_at",
    ] {
        assert!(m[key].is_null(), "{key} shown: {m}");
    }
    let (_, admin) = server.get(&format!("/api/matches/{id}"), Some(ADMIN)).await;
    assert!(
        admin["total_steps"].is_u64(),
        "the admin sees it all: {admin}"
    );
    let (s, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(&token))
        .await;
    assert_eq!(s, 200, "{log}");
    assert_eq!(
        (&log["status"], &log["redacted"]),
        (&json!("crashed"), &json!(true))
    );
    assert!(
        log["step"].is_null(),
        "the failure step is not shown: {log}"
    );
    assert!(
        log.get("error").is_none() && log.get("stderr_tail").is_none(),
        "{log}"
    );
    assert!(!log.to_string().contains("LEAK"));
    let (s, v) = server
        .get(&format!("/api/matches/{id}/replay"), Some(&token))
        .await;
    assert_error(s, &v, 403);
    assert!(
        v["error"]["message"].as_str().unwrap().contains("hidden"),
        "{v}"
    );
    // Nor as one HTML file, for anyone but the admin.
    for (caller, status) in [(Some(token.as_str()), 403), (None, 401), (Some(ADMIN), 200)] {
        let (s, body, _) = server
            .get_raw(&format!("/api/matches/{id}/replay.html"), caller)
            .await;
        assert_eq!(s, status, "{body}");
    }
    // Anonymous callers: the match view, nothing else.
    let (s, v) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_error(s, &v, 401);
    let (s, v) = server.get(&format!("/api/matches/{id}/log"), None).await;
    assert_error(s, &v, 401);
    // The admin sees the stderr, the failure and the replay.
    let (_, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(ADMIN))
        .await;
    assert_eq!(log["redacted"], false);
    assert!(
        log["stderr_tail"].as_str().unwrap().contains("LEAK"),
        "{log}"
    );
    assert!(
        !log["error"]["reason"].as_str().unwrap().is_empty(),
        "{log}"
    );
    let (s, replay) = server
        .get(&format!("/api/matches/{id}/replay"), Some(ADMIN))
        .await;
    assert_eq!(s, 200, "{replay}");
    assert!(replay["maze_layout"].is_string() && replay["trace"].is_array());
}

#[tokio::test]
async fn hidden_generated_mazes_get_secret_random_seeds() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let a = generate_hidden(&server, "h1").await;
    let b = generate_hidden(&server, "h2").await;
    let (_, ma) = server.get(&format!("/api/mazes/{a}"), Some(ADMIN)).await;
    let (_, mb) = server.get(&format!("/api/mazes/{b}"), Some(ADMIN)).await;
    assert_ne!(ma["hash"], mb["hash"]);
    assert_ne!(ma["layout"], mb["layout"]);
    for v in [&ma, &mb] {
        assert!(v.get("seed").is_none(), "{v}");
    }
    let (_, list) = server.get("/api/mazes", Some(ADMIN)).await;
    assert!(
        list.as_array()
            .unwrap()
            .iter()
            .all(|m| m.get("seed").is_none()),
        "{list}"
    );
    // A hidden maze cannot be given a seed; a public one can, and shows it.
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "h3", "hidden": true, "generate": {"dim": 12, "seed": 7}}),
            Some(ADMIN),
        )
        .await;
    assert_error(s, &v, 422);
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "p", "generate": {"dim": 12, "seed": 4242}}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    assert_eq!(v["seed"], 4242);
    let expected = mazearena::engine::generator::generate(12, 4242).unwrap();
    assert_eq!(v["hash"].as_str().unwrap(), expected.hash());
    // Not both a layout and a generator; the generator's sides only; admin only.
    let both = json!({"name": "x", "layout": "2\n3,6\n9,12\n", "generate": {"dim": 12}});
    let (s, v) = server.post("/api/mazes", both, Some(ADMIN)).await;
    assert_error(s, &v, 422);
    let odd = json!({"name": "x", "generate": {"dim": 13}});
    let (s, v) = server.post("/api/mazes", odd.clone(), Some(ADMIN)).await;
    assert_error(s, &v, 422);
    let (s, v) = server.post("/api/mazes", odd, None).await;
    assert_error(s, &v, 401);
}

#[tokio::test]
async fn a_match_running_each_time_the_server_dies_is_aborted_and_its_bot_paused() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--jobs", "2", "--lease-secs", "1"];
    let mut server = TestServer::start(dir.path(), &args);
    let code = std::fs::read_to_string(root().join("tests/fixtures/bots/scripted.py")).unwrap();
    // Slow: 1000 idle answers at 50 ms each; both matches run at once.
    let command = "python3 scripted.py --delay-ms 50";
    let (bot, token) = register(&server, "pill", command, json!({"scripted.py": code})).await;
    let mut ids = Vec::new();
    for seed in [1, 2] {
        let body = json!({"bot_id": bot, "maze_id": 1, "seed": seed});
        let (s, q) = server.post("/api/matches", body, Some(&token)).await;
        assert_eq!(s, 202, "{q}");
        ids.push(q["match_id"].as_i64().unwrap());
    }
    // Kill the server while both run, three times.
    for attempt in 1..=3 {
        let deadline = Instant::now() + Duration::from_secs(30);
        for &id in &ids {
            loop {
                let (_, v) = server.get(&format!("/api/matches/{id}"), None).await;
                if v["status"] == "running" && v["attempts"] == attempt {
                    break;
                }
                assert!(Instant::now() < deadline, "attempt {attempt}: {v}");
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        }
        server.kill();
        server = TestServer::start(dir.path(), &args);
    }
    // Their leases expire once more: the third expiry aborts them; the bot is paused.
    for &id in &ids {
        let v = wait_match(&server, id).await;
        assert_eq!(
            (&v["status"], &v["attempts"]),
            (&json!("aborted"), &json!(3)),
            "{v}"
        );
        let (_, log) = server
            .get(&format!("/api/matches/{id}/log"), Some(&token))
            .await;
        assert_eq!(
            log["error"]["reason"],
            "the match was running each time the server stopped (3 attempts); it is not retried"
        );
    }
    let (_, b) = server.get(&format!("/api/bots/{bot}"), None).await;
    assert_eq!(b["paused"], true, "{b}");
    assert!(
        b["paused_reason"].as_str().unwrap().contains("aborted"),
        "{b}"
    );
    let again = json!({"bot_id": bot, "maze_id": 1});
    let (s, v) = server
        .post("/api/matches", again.clone(), Some(&token))
        .await;
    assert_error(s, &v, 409);
    assert!(
        v["error"]["message"].as_str().unwrap().contains("paused"),
        "{v}"
    );
    // Only the admin resumes it.
    let resume = format!("/api/bots/{bot}/resume");
    let (s, v) = server.post(&resume, json!({}), Some(&token)).await;
    assert_error(s, &v, 403);
    let (s, v) = server.post(&resume, json!({}), Some(ADMIN)).await;
    assert_eq!(
        (s, &v["paused"], &v["paused_reason"]),
        (200, &json!(false), &Value::Null),
        "{v}"
    );
    assert_eq!(
        server.post("/api/matches", again, Some(&token)).await.0,
        202
    );
    let (_, metrics, _) = server.get_raw("/metrics", Some(ADMIN)).await;
    assert!(
        metrics.contains("mazearena_matches{status=\"aborted\"} 2"),
        "{metrics}"
    );
}

/// A base64 `.tar.gz` with the given entries (names written raw, even unsafe ones).
fn tar_gz(entries: &[(&str, &[u8])]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(tar_gz_bytes(entries))
}

fn tar_gz_bytes(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut builder = tar::Builder::new(gz);
    for (name, data) in entries {
        let mut header = tar::Header::new_gnu();
        // Write the name bytes directly so unsafe names are kept as they are.
        let bytes = name.as_bytes();
        header.as_old_mut().name[..bytes.len()].copy_from_slice(bytes);
        header.set_size(data.len() as u64);
        header.set_mode(0o644);
        header.set_entry_type(tar::EntryType::Regular);
        header.set_cksum();
        builder.append(&header, *data).unwrap();
    }
    builder.into_inner().unwrap().finish().unwrap()
}

/// Sends only the request line and headers of a POST claiming `length` bytes of JSON,
/// and reads the answer (a server must refuse an oversized body without reading it).
async fn raw_post_headers(base: &str, path: &str, length: usize) -> (u16, Value) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let addr = base.trim_start_matches("http://");
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let head = format!(
        "POST {path} HTTP/1.1\r\nHost: {addr}\r\nContent-Type: application/json\r\nContent-Length: {length}\r\nConnection: close\r\n\r\n"
    );
    stream.write_all(head.as_bytes()).await.unwrap();
    let mut answer = Vec::new();
    let _ = tokio::time::timeout(Duration::from_secs(10), stream.read_to_end(&mut answer)).await;
    let text = String::from_utf8_lossy(&answer);
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let body = text.split("\r\n\r\n").nth(1).unwrap_or("");
    // The body may be chunked: take the JSON object inside it.
    let json = body
        .find('{')
        .and_then(|i| body.rfind('}').map(|j| &body[i..=j]))
        .unwrap_or("");
    (status, serde_json::from_str(json).unwrap_or(Value::Null))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bot_encoding_a_hidden_maze_in_its_step_count_leaks_nothing_per_match() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2", "--no-validation"]);
    // The attack: map what it can, then crash at a step that encodes it (here: the
    // readings of its first steps and its seed, so every match ends at another step).
    let encoder = std::fs::read_to_string(
        crate::support::root().join("tests/fixtures/bots/hostile/encode_steps.py"),
    )
    .unwrap();
    let (bot, token) = register(
        &server,
        "encoder",
        "python3 bot.py",
        json!({"bot.py": encoder}),
    )
    .await;
    let hidden = generate_hidden(&server, "ranking-secret").await;
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "ranking", "bot_ids": [bot], "maze_ids": [hidden], "repeats": 8}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let tid = t["tournament_id"].as_i64().unwrap();
    // While it runs: standings sealed for everyone but the admin.
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let (_, v) = server.get(&format!("/api/tournaments/{tid}"), None).await;
        if v["done"] == v["total"] {
            break;
        }
        if v["done"].as_i64() > Some(0) {
            assert_eq!(v["standings_sealed"], true, "{v}");
            assert_eq!(v["standings"], json!([]), "{v}");
            // Nor does the leaderboard count the bot while its hidden matches run.
            for board in [
                "/api/leaderboard".to_string(),
                "/api/leaderboard?scope=all".into(),
                format!("/api/leaderboard?tournament={tid}"),
            ] {
                let (_, rows) = server.get(&board, Some(&token)).await;
                let (_, now) = server.get(&format!("/api/tournaments/{tid}"), None).await;
                if now["done"] != now["total"] {
                    assert!(
                        rows.as_array().unwrap().iter().all(|r| r["bot_id"] != bot),
                        "{board} counts a bot whose hidden matches are still running: {rows}"
                    );
                }
            }
        }
        assert!(Instant::now() < deadline, "the tournament did not end: {v}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // Played: the standings show the mean, and over the hidden maze nothing the mean
    // does not say (an interval over its runs would be made of single matches); the
    // admin gets the interval.
    let (_, t) = server.get(&format!("/api/tournaments/{tid}"), None).await;
    let line = &t["standings"][0];
    assert_eq!(line["uncertainty"]["withheld"], true, "{t}");
    assert_eq!(line["uncertainty"]["low"], line["mean_score"], "{t}");
    assert_eq!(line["uncertainty"]["high"], line["mean_score"], "{t}");
    assert_eq!(line["uncertainty"]["runs_per_maze"], 0, "{t}");
    let (_, t) = server
        .get(&format!("/api/tournaments/{tid}"), Some(ADMIN))
        .await;
    assert_eq!(t["standings"][0]["uncertainty"]["withheld"], false, "{t}");
    assert_eq!(t["standings"][0]["uncertainty"]["runs_per_maze"], 8, "{t}");
    // The admin sees that the matches did end at different steps: the attack was real.
    let (_, all) = server
        .get(&format!("/api/matches?tournament_id={tid}"), Some(ADMIN))
        .await;
    let steps: std::collections::BTreeSet<String> = all["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["total_steps"].to_string())
        .collect();
    assert!(
        steps.len() > 1,
        "the fixture must vary its step count: {all}"
    );
    // Anyone else, the owner included, reads the same thing of every match: its status.
    for caller in [None, Some(token.as_str())] {
        let (_, list) = server
            .get(&format!("/api/matches?tournament_id={tid}"), caller)
            .await;
        let mut seen = std::collections::BTreeSet::new();
        for item in list["items"].as_array().unwrap() {
            let id = item["match_id"].as_i64().unwrap();
            let (_, one) = server.get(&format!("/api/matches/{id}"), caller).await;
            let (_, log) = server.get(&format!("/api/matches/{id}/log"), caller).await;
            for mut v in [item.clone(), one, log] {
                if let Some(o) = v.as_object_mut() {
                    for k in ["match_id", "seed", "repeat", "created_at", "attempts"] {
                        o.remove(k);
                    }
                }
                seen.insert(v.to_string());
            }
        }
        // One view per endpoint (list item, match, log), equal for all 8 matches.
        assert!(seen.len() <= 3, "a match differs from another: {seen:#?}");
        for page in [
            format!("/tournaments/{tid}"),
            format!("/bots/{bot}"),
            format!("/matches?tournament_id={tid}"),
        ] {
            let (s, html) = server.get_text(&page).await;
            assert_eq!(s, 200);
            // (Numbers under 10 stand on a page for other reasons: repeats, counts.)
            for n in steps
                .iter()
                .filter(|n| n.parse::<u64>().is_ok_and(|n| n >= 10))
            {
                assert!(
                    !html.contains(&format!(">{n}<")) && !html.contains(&format!(" {n} ")),
                    "{page} shows a step count {n}"
                );
            }
        }
    }
}

#[tokio::test]
async fn entrants_register_by_invite_and_their_key_acts_for_their_bots_until_rotated() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "0"]);
    let put = |body: Value| {
        let server = &server;
        async move {
            server
                .call(Method::PUT, "/api/registration", Some(body), Some(ADMIN))
                .await
        }
    };
    let (s, v, _) = put(json!({"mode": "invite", "invite_code": "short"})).await;
    assert_error(s, &v, 422);
    let (s, v, _) = put(json!({"mode": "invite", "invite_code": "class-of-2026"})).await;
    assert_eq!((s, v["mode"].as_str()), (200, Some("invite")), "{v}");
    let (_, v) = server.get("/api/registration", None).await;
    assert_eq!(v, json!({"mode": "invite"}), "the code is never shown");
    // Without the code: refused; with it: an entrant and its key.
    let team = json!({"name": "team-a", "members": ["Ada", "Alan"]});
    let (s, v) = server.post("/api/entrants", team.clone(), None).await;
    assert_error(s, &v, 403);
    let mut with_code = team.clone();
    with_code["invite_code"] = json!("class-of-2026");
    let (s, e) = server.post("/api/entrants", with_code.clone(), None).await;
    assert_eq!(s, 201, "{e}");
    let (s, v) = server.post("/api/entrants", with_code, None).await;
    assert_error(s, &v, 409);
    let (entrant, key) = (
        e["entrant_id"].as_i64().unwrap(),
        e["key"].as_str().unwrap().to_string(),
    );
    // Bots: not anonymously on a server that is not open; with the key, the entrant's.
    let bot_body =
        json!({"name": "a-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (s, v, _) = server
        .call(Method::POST, "/api/bots", Some(bot_body.clone()), None)
        .await;
    assert_error(s, &v, 403);
    let (s, b, _) = server
        .call(Method::POST, "/api/bots", Some(bot_body), Some(&key))
        .await;
    assert_eq!(s, 201, "{b}");
    let bot = b["bot_id"].as_i64().unwrap();
    let (_, view) = server.get(&format!("/api/entrants/{entrant}"), None).await;
    assert_eq!(view["members"], json!(["Ada", "Alan"]));
    assert_eq!(view["bots"][0]["bot_id"], bot, "{view}");
    assert!(!view.to_string().contains(&key));
    // The key acts for the bot (as does the bot's own token).
    let queue_with = |token: String| {
        let server = &server;
        async move {
            server
                .call(
                    Method::POST,
                    "/api/matches",
                    Some(json!({"bot_id": bot, "maze_id": 1})),
                    Some(&token),
                )
                .await
        }
    };
    assert_eq!(queue_with(key.clone()).await.0, 202);
    assert_eq!(
        queue_with(b["owner_token"].as_str().unwrap().to_string())
            .await
            .0,
        202
    );
    // Rotated: the old key stops at once, the new one works; nobody else may rotate it.
    let (s, v, _) = server
        .call(
            Method::POST,
            &format!("/api/entrants/{entrant}/key"),
            None,
            None,
        )
        .await;
    assert_error(s, &v, 401);
    let (s, fresh, _) = server
        .call(
            Method::POST,
            &format!("/api/entrants/{entrant}/key"),
            None,
            Some(&key),
        )
        .await;
    assert_eq!(s, 200, "{fresh}");
    let fresh = fresh["key"].as_str().unwrap().to_string();
    assert_eq!(queue_with(key).await.0, 403);
    assert_eq!(queue_with(fresh.clone()).await.0, 202);
    // The bot's owner token, given when it was registered with the old key, is revoked
    // with it: it queues no match and uploads no version.
    let owner = b["owner_token"].as_str().unwrap().to_string();
    assert_eq!(queue_with(owner.clone()).await.0, 403);
    let upload = json!({"command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (s, v, _) = server
        .call(
            Method::POST,
            &format!("/api/bots/{bot}/versions"),
            Some(upload.clone()),
            Some(&owner),
        )
        .await;
    assert_error(s, &v, 403);
    let (s, v, _) = server
        .call(
            Method::POST,
            &format!("/api/bots/{bot}/versions"),
            Some(upload),
            Some(&fresh),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    // Closed: nobody registers but through the admin.
    put(json!({"mode": "closed"})).await;
    let (s, v) = server
        .post("/api/entrants", json!({"name": "team-b"}), None)
        .await;
    assert_error(s, &v, 403);
    let (s, v) = server
        .post("/api/entrants", json!({"name": "team-b"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{v}");
}

#[tokio::test]
async fn an_entrants_key_acts_for_no_other_entrant_and_sets_nothing_of_the_server() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "0"]);
    let mut keys = Vec::new();
    for name in ["team-a", "team-b"] {
        let (s, e) = server
            .post("/api/entrants", json!({"name": name}), None)
            .await;
        assert_eq!(s, 201, "{e}");
        keys.push((
            e["entrant_id"].as_i64().unwrap(),
            e["key"].as_str().unwrap().to_string(),
        ));
    }
    let (b_id, b_key) = keys[1].clone();
    let a_key = keys[0].1.clone();
    let body =
        json!({"name": "b-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (s, bot, _) = server
        .call(Method::POST, "/api/bots", Some(body), Some(&b_key))
        .await;
    assert_eq!(s, 201, "{bot}");
    let bot = bot["bot_id"].as_i64().unwrap();
    // A's key: not B's bot, not B's key, not the registration mode.
    let (s, v, _) = server
        .call(
            Method::POST,
            "/api/matches",
            Some(json!({"bot_id": bot, "maze_id": 1})),
            Some(&a_key),
        )
        .await;
    assert_error(s, &v, 403);
    let (s, v, _) = server
        .call(
            Method::POST,
            &format!("/api/entrants/{b_id}/key"),
            None,
            Some(&a_key),
        )
        .await;
    assert_error(s, &v, 403);
    let (s, v, _) = server
        .call(
            Method::PUT,
            "/api/registration",
            Some(json!({"mode": "open"})),
            Some(&a_key),
        )
        .await;
    assert_error(s, &v, 403);
    // B's key still works: nothing A did changed it.
    let (s, _, _) = server
        .call(
            Method::POST,
            "/api/matches",
            Some(json!({"bot_id": bot, "maze_id": 1})),
            Some(&b_key),
        )
        .await;
    assert_eq!(s, 202);
}

#[test]
fn a_short_admin_token_is_refused_and_a_generated_one_is_kept_for_the_next_start() {
    let dir = tempfile::tempdir().unwrap();
    let serve = |token: Option<&str>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"));
        cmd.args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--jobs",
            "0",
            "--database",
        ])
        .arg(format!(
            "sqlite://{}",
            dir.path().join("db.sqlite").display()
        ))
        .arg("--data-dir")
        .arg(dir.path().join("data"))
        .env("MAZEARENA_SANDBOX", "none")
        .env_remove("MAZEARENA_ADMIN_TOKEN")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
        if let Some(t) = token {
            cmd.env("MAZEARENA_ADMIN_TOKEN", t);
        }
        cmd.spawn().unwrap()
    };
    let out = serve(Some("change-me")).wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("the admin token is too short (9 characters)"),
        "{out:?}"
    );
    // Generated on the first start, printed, kept (owner-only) and reused.
    let token_line = |mut child: std::process::Child| {
        use std::io::BufRead;
        let mut reader = std::io::BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        while !line.contains("admin token") {
            line.clear();
            assert!(
                reader.read_line(&mut line).unwrap() > 0,
                "no admin token line"
            );
        }
        let _ = child.kill();
        let _ = child.wait();
        line
    };
    let said = token_line(serve(None));
    let kept = std::fs::read_to_string(dir.path().join("data/admin-token")).unwrap();
    assert!(
        said.contains("generated") && said.contains(kept.trim()),
        "{said}"
    );
    use std::os::unix::fs::PermissionsExt;
    let mode = std::fs::metadata(dir.path().join("data/admin-token"))
        .unwrap()
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o600);
    let said = token_line(serve(None));
    assert!(
        said.contains("the one kept in") && !said.contains(kept.trim()),
        "{said}"
    );
}

#[test]
fn a_servers_log_written_to_a_file_is_plain_text() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("server.log");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--jobs",
            "1",
            "--database",
        ])
        .arg(format!(
            "sqlite://{}",
            dir.path().join("db.sqlite").display()
        ))
        .arg("--data-dir")
        .arg(dir.path().join("data"))
        .env("MAZEARENA_SANDBOX", "none")
        .env("MAZEARENA_ADMIN_TOKEN", ADMIN)
        .env("RUST_LOG", "mazearena=info")
        .stdout(std::process::Stdio::piped())
        .stderr(std::fs::File::create(&log).unwrap())
        .spawn()
        .unwrap();
    use std::io::BufRead;
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(
        line.contains("(1 match worker, sandbox none, match limits by rlimit)"),
        "{line}"
    );
    // Once it answers, its signal handler is in place.
    let addr = line
        .split("http://")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .to_string();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    loop {
        use std::io::{Read, Write};
        let mut answer = String::new();
        if let Ok(mut s) = std::net::TcpStream::connect(&addr) {
            let _ = s.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
            let _ = s.read_to_string(&mut answer);
        }
        if answer.starts_with("HTTP/1.1 200") {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the server did not answer"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let killed = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait().unwrap();
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains("shutting down"), "{text}");
    assert!(!text.contains('\u{1b}'), "colour codes in a file: {text:?}");
}

/// `/metrics` and `/healthz`'s counts move with matches on hidden mazes (a bot that
/// times its matches, a status counted): they are the operator's. `/metrics` answers the
/// metrics token and the admin token; `/healthz` says ok to anyone and counts for the
/// admin only.
#[tokio::test]
async fn metrics_and_healthz_counts_are_the_operators() {
    let dir = tempfile::tempdir().unwrap();
    let token = "metrics-scrape-token-0123456789";
    let server = TestServer::start(dir.path(), &["--jobs", "0", "--metrics-token", token]);
    let (_, owner) = crate::support::register(
        &server,
        "counted",
        "python3 simple_bot.py",
        crate::support::simple_bot_files(),
    )
    .await;
    for (t, status) in [(None, 401), (Some(owner.as_str()), 403)] {
        let (s, body, _) = server.get_raw("/metrics", t).await;
        assert_eq!(s, status, "{body}");
        assert!(!body.contains("mazearena_"), "{body}");
    }
    for t in [token, ADMIN] {
        let (s, body, _) = server.get_raw("/metrics", Some(t)).await;
        assert_eq!(s, 200, "{body}");
        assert!(body.contains("mazearena_queue_depth"), "{body}");
    }
    for t in [None, Some(owner.as_str())] {
        let (s, health) = server.get("/healthz", t).await;
        assert_eq!(
            (s, health["status"].as_str()),
            (200, Some("ok")),
            "{health}"
        );
        assert!(
            health.get("queued").is_none() && health.get("workers").is_none(),
            "{health}"
        );
    }
    let (_, health) = server.get("/healthz", Some(ADMIN)).await;
    assert_eq!(health["queued"], 0, "{health}");
    assert!(health["workers"].is_array(), "{health}");
}
