//! A class on the day: a crowd behind one address and one builder, shared fairly.
//! Budgets by identity rather than address, trusted proxies (a real nginx in front),
//! the fair builder and the owners' quotas, the limits a match plays under and its
//! wall-clock ceiling, and a deadline rush of 30 students through nginx.

use std::time::{Duration, Instant};

use mazearena::engine::generator::generate;
use mazearena::engine::mazefile::numeric;
use serde_json::{Value, json};

use crate::support::{ADMIN, TestServer, root};

/// RFC 3339 of unix ms.
fn at(ms: i64) -> String {
    mazearena::competition::Timestamp(ms).rfc3339()
}

/// A generated maze as the API takes it.
fn maze(name: &str, dim: u32, seed: u64) -> Value {
    json!({"name": name, "layout": numeric::write(&generate(dim, seed).unwrap())})
}

/// The files of the fixture bot `name` (tests/fixtures/bots) as an upload's `files`.
fn fixture_files(name: &str) -> Value {
    let text = std::fs::read_to_string(root().join("tests/fixtures/bots").join(name)).unwrap();
    json!({ name: text })
}

/// Makes an organiser and, with its key, competition `spec`; the organiser's key.
async fn competition(server: &TestServer, spec: Value) -> String {
    let (s, o) = server
        .post(
            "/api/organisers",
            json!({"name": format!("org-{}", spec["name"].as_str().unwrap())}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{o}");
    let key = o["key"].as_str().unwrap().to_string();
    let (s, c) = server.post("/api/competitions", spec, Some(&key)).await;
    assert_eq!(s, 201, "{c}");
    key
}

/// Registers entrant `name`; its key.
async fn entrant(server: &TestServer, name: &str) -> String {
    let (s, e) = server
        .post("/api/entrants", json!({"name": name}), None)
        .await;
    assert_eq!(s, 201, "{e}");
    e["key"].as_str().unwrap().to_string()
}

/// Registers a bot with `key` and enters it in competition `name`; the bot's id.
async fn enter(server: &TestServer, key: &str, name: &str, bot: Value) -> i64 {
    let (s, b) = server.post("/api/bots", bot, Some(key)).await;
    assert_eq!(s, 201, "{b}");
    let id = b["bot_id"].as_i64().unwrap();
    let (s, v) = server
        .post(
            &format!("/api/competitions/{name}/entries"),
            json!({"bot_id": id}),
            Some(key),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    id
}

/// Waits (at most `secs`) until bot `bot` has `count` matches that ended (as the admin
/// sees them); those matches.
async fn ended_matches(server: &TestServer, bot: i64, count: usize, secs: u64) -> Vec<Value> {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        let (_, list) = server
            .get(&format!("/api/matches?bot_id={bot}"), Some(ADMIN))
            .await;
        let items = list["items"].as_array().cloned().unwrap_or_default();
        let ended: Vec<Value> = items
            .into_iter()
            .filter(|m| !["queued", "running"].contains(&m["status"].as_str().unwrap_or("")))
            .collect();
        if ended.len() >= count {
            return ended;
        }
        assert!(
            Instant::now() < deadline,
            "bot {bot}'s matches did not end: {list}"
        );
        tokio::time::sleep(Duration::from_millis(250)).await;
    }
}

/// A competition's practice match plays under the competition's limits (recorded with
/// it), and every match has a wall-clock ceiling, published on the competition's page
/// and in its API view: a bot that waits a little on every move (inside each answer's
/// own backstop) is stopped there, in practice and in ranking, and holds its worker no
/// longer; a bot that thinks to its limits on every move is never stopped by it.
#[tokio::test]
async fn a_match_lasts_no_longer_than_its_published_ceiling() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let start = mazearena::storage::now_ms();
    // Ceiling: 2 x (1 s + 999 x 10 ms + 2 s) + 10 s = 35.98 s.
    let spec = json!({
        "name": "ceiling", "title": "Ceiling",
        "opens_at": at(start + 2_000), "closes_at": at(start + 3_600_000),
        "repeats": 1, "final_repeats": 1, "versions_per_day": 5, "practice_per_day": 5,
        "limits": {"move_timeout_ms": 10, "startup_timeout_ms": 1000, "time_bank_ms": 2000},
        "mazes": {
            "practice": [maze("ceiling-practice", 12, 4601)],
            "public": [maze("ceiling-public", 12, 4602)],
            "private": [maze("ceiling-private", 12, 4603)],
        },
    });
    competition(&server, spec).await;
    let (_, view) = server.get("/api/competitions/ceiling", None).await;
    let ceiling = view["match_wall_clock_ms"].as_u64().unwrap();
    assert_eq!(ceiling, 35_980, "{view}");
    let (_, page) = server.get_text("/competitions/ceiling").await;
    assert!(
        page.contains("the longest a match may last") && page.contains("36 s"),
        "the page does not publish the ceiling"
    );
    let practice = view["mazes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["set"] == "practice")
        .unwrap()["maze_id"]
        .as_i64()
        .unwrap();
    // 8 ms of CPU and 32 ms of sleep per move: 40 s for 1000 moves, each answer well
    // inside its own backstop of 4 x (10 + 8) ms.
    let waiter_key = entrant(&server, "waiter").await;
    let waiter = enter(
        &server,
        &waiter_key,
        "ceiling",
        json!({"name": "waiter", "command": "python3 think_and_wait.py 8 32",
               "files": fixture_files("think_and_wait.py")}),
    )
    .await;
    // 9 ms of CPU per move, no sleep: about 9 s of CPU time in all.
    let thinker_key = entrant(&server, "thinker").await;
    let thinker = enter(
        &server,
        &thinker_key,
        "ceiling",
        json!({"name": "thinker", "command": "python3 think_and_wait.py 9 0",
               "files": fixture_files("think_and_wait.py")}),
    )
    .await;
    for (bot, key) in [(waiter, &waiter_key), (thinker, &thinker_key)] {
        crate::support::wait_built(&server, bot).await;
        let (s, q) = server
            .post(
                "/api/matches",
                json!({"bot_id": bot, "maze_id": practice, "seed": 3}),
                Some(key),
            )
            .await;
        assert_eq!(s, 202, "{q}");
    }
    // Each plays one practice match and one ranking match.
    for bot in [waiter, thinker] {
        let ended = ended_matches(&server, bot, 2, 240).await;
        assert!(
            ended.iter().any(|m| m["tournament_id"].is_null())
                && ended.iter().any(|m| !m["tournament_id"].is_null()),
            "{ended:?}"
        );
        for m in ended {
            let id = m["match_id"].as_i64().unwrap();
            let (_, full) = server.get(&format!("/api/matches/{id}"), Some(ADMIN)).await;
            // Practice and ranking alike play under the competition's limits.
            assert_eq!(full["limits"]["move_timeout_ms"], 10, "{full}");
            assert_eq!(full["limits"]["startup_timeout_ms"], 1000, "{full}");
            assert_eq!(full["limits"]["time_bank_ms"], 2000, "{full}");
            assert_eq!(full["limits"]["match_wall_clock_ms"], ceiling, "{full}");
            let (_, log) = server
                .get(&format!("/api/matches/{id}/log"), Some(ADMIN))
                .await;
            if bot == thinker {
                assert_eq!(full["status"], "step_limit", "{full} {log}");
                continue;
            }
            assert_eq!(full["status"], "timeout", "{full} {log}");
            assert_eq!(log["error"]["limit"]["name"], "match_wall_clock", "{log}");
            assert_eq!(log["error"]["limit"]["value"], ceiling, "{log}");
            let wall = full["timings"]["wall_ms"].as_u64().unwrap();
            assert!(
                wall >= ceiling && wall <= ceiling + 3_000,
                "the waiting bot held its worker {wall} ms, its ceiling is {ceiling} ms"
            );
        }
    }
}

/// A class behind its school's one address (every client of these tests is 127.0.0.1),
/// with someone guessing among them: wrong invite codes and unknown keys spend the
/// address's budget and are refused past it, in words a student understands; every
/// request that proves who it is goes on: the right invite code (on the code's own
/// budget), the right keys at `/login`, the admin's key, bots registered with an
/// entrant's key.
#[tokio::test]
async fn a_class_behind_one_address_is_never_refused_for_proving_who_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &["--no-validation"],
        &[
            ("MAZEARENA_LOGINS_PER_HOUR", "5"),
            ("MAZEARENA_REGISTRATIONS_PER_HOUR", "3"),
            ("MAZEARENA_INVITE_REGISTRATIONS_PER_HOUR", "12"),
        ],
    );
    let (s, v, _) = server
        .call(
            reqwest::Method::PUT,
            "/api/registration",
            Some(json!({"mode": "invite", "invite_code": "maze-class-2026"})),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    let register = |name: String, code: &'static str| {
        let server = &server;
        async move {
            server
                .post(
                    "/api/entrants",
                    json!({"name": name, "invite_code": code}),
                    None,
                )
                .await
        }
    };
    // The guesser spends the address's budget of guesses on wrong codes.
    for i in 0..5 {
        let (s, v) = register(format!("guess-{i}"), "maze-class-2025").await;
        assert_eq!(s, 403, "{v}");
    }
    let (s, v) = register("guess-5".into(), "maze-class-2025").await;
    assert_eq!(s, 429, "{v}");
    let message = v["error"]["message"].as_str().unwrap();
    assert!(message.contains("your network"), "{message}");
    assert!(!message.contains("127.0.0.1"), "{message}");
    // The class registers with the right code, however many, up to the code's own budget.
    let mut keys = Vec::new();
    for i in 0..12 {
        let (s, v) = register(format!("student-{i}"), "maze-class-2026").await;
        assert_eq!(s, 201, "student {i}: {v}");
        keys.push(v["key"].as_str().unwrap().to_string());
    }
    let (s, v) = register("student-12".into(), "maze-class-2026").await;
    assert_eq!(s, 429, "{v}");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("invite code"),
        "{v}"
    );
    // Unknown keys at /login share the address's budget of guesses (used up above).
    let web = crate::sessions::Web::new(&server);
    let guess = web
        .post("/login", None, &[("key", "0123456789abcdef")])
        .await;
    assert_eq!(guess.status, 429, "{}", guess.body);
    // Every student logs in, twice, and so does the admin.
    for key in keys.iter().chain(keys.iter()) {
        web.login(key).await;
    }
    web.login(ADMIN).await;
    // Each registers a bot with its key: the address's budgets are not theirs.
    for (i, key) in keys.iter().enumerate() {
        let bot = json!({"name": format!("robot-{i}"), "command": "python3 simple_bot.py",
                         "files": crate::support::simple_bot_files()});
        let (s, v) = server.post("/api/bots", bot, Some(key)).await;
        assert_eq!(s, 201, "student {i}: {v}");
    }
}

/// The budgets are counted in the database: several API servers of one PostgreSQL
/// database spend the same ones.
#[tokio::test]
async fn the_budgets_are_shared_by_every_api_server_of_a_database() {
    let Some((url, _)) = crate::faults::postgres("the_budgets_are_shared") else {
        return;
    };
    let database = crate::faults::new_database(&url, "budgets").await;
    let env = [("MAZEARENA_LOGINS_PER_HOUR", "4")];
    let (dir_a, dir_b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = TestServer::start_on(dir_a.path(), Some(&database), &["--jobs", "0"], &env);
    let b = TestServer::start_on(dir_b.path(), Some(&database), &["--jobs", "0"], &env);
    let (web_a, web_b) = (crate::sessions::Web::new(&a), crate::sessions::Web::new(&b));
    for (i, web) in [&web_a, &web_a, &web_b, &web_b].into_iter().enumerate() {
        let r = web
            .post("/login", None, &[("key", &format!("guess-{i}"))])
            .await;
        assert_eq!(r.status, 401, "try {i}");
    }
    for web in [&web_a, &web_b] {
        let r = web.post("/login", None, &[("key", "guess-4")]).await;
        assert_eq!(r.status, 429, "{}", r.body);
    }
    // The right key logs in on either.
    web_a.login(ADMIN).await;
    web_b.login(ADMIN).await;
}
