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
    // Ceiling: 2 x (1 s + 999 x 20 ms + 2 s) + 10 s = 55.96 s.
    let spec = json!({
        "name": "ceiling", "title": "Ceiling",
        "opens_at": at(start + 2_000), "closes_at": at(start + 3_600_000),
        "repeats": 1, "final_repeats": 1, "versions_per_day": 5, "practice_per_day": 5,
        "limits": {"move_timeout_ms": 20, "startup_timeout_ms": 1000, "time_bank_ms": 2000},
        "mazes": {
            "practice": [maze("ceiling-practice", 12, 4601)],
            "public": [maze("ceiling-public", 12, 4602)],
            "private": [maze("ceiling-private", 12, 4603)],
        },
    });
    competition(&server, spec).await;
    let (_, view) = server.get("/api/competitions/ceiling", None).await;
    let ceiling = view["match_wall_clock_ms"].as_u64().unwrap();
    assert_eq!(ceiling, 55_960, "{view}");
    let (_, page) = server.get_text("/competitions/ceiling").await;
    assert!(
        page.contains("the longest a match may last") && page.contains("56 s"),
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
    // 16 ms of CPU and 44 ms of sleep per move: 60 s for 1000 moves, each answer well
    // inside its own backstop of 4 x (20 + 16) ms.
    let waiter_key = entrant(&server, "waiter").await;
    let waiter = enter(
        &server,
        &waiter_key,
        "ceiling",
        json!({"name": "waiter", "command": "python3 think_and_wait.py 16 44",
               "files": fixture_files("think_and_wait.py")}),
    )
    .await;
    // 18 ms of CPU per move, no sleep: about 18 s of CPU time in all.
    let thinker_key = entrant(&server, "thinker").await;
    let thinker = enter(
        &server,
        &thinker_key,
        "ceiling",
        json!({"name": "thinker", "command": "python3 think_and_wait.py 18 0",
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
            assert_eq!(full["limits"]["move_timeout_ms"], 20, "{full}");
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

/// The latest version of bot `bot` once its build and validation ended.
async fn built_version(server: &TestServer, bot: i64, secs: u64) -> Value {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        let (_, v) = server.get(&format!("/api/bots/{bot}"), None).await;
        let latest = v["versions"].as_array().unwrap().last().unwrap().clone();
        if latest["build_status"] != "building" {
            return latest;
        }
        assert!(
            Instant::now() < deadline,
            "bot {bot} is still building: {v}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// One entrant floods the builder with slow builds: it may have three waiting, the
/// fourth is refused naming them, and another entrant's new version waits behind one
/// of its builds at most, not all three.
#[tokio::test]
async fn one_entrant_flooding_the_builder_holds_another_up_for_one_build_at_most() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &[],
        &[("MAZEARENA_PENDING_BUILDS_PER_OWNER", "3")],
    );
    let flooder = entrant(&server, "flooder").await;
    let slow = |name: &str| {
        json!({"name": name, "command": "python3 simple_bot.py", "build": "sleep 4",
               "files": crate::support::simple_bot_files()})
    };
    let (s, b) = server
        .post("/api/bots", slow("flood"), Some(&flooder))
        .await;
    assert_eq!(s, 201, "{b}");
    let flood_bot = b["bot_id"].as_i64().unwrap();
    let path = format!("/api/bots/{flood_bot}/versions");
    for _ in 0..2 {
        let (s, v) = server.post(&path, slow("flood"), Some(&flooder)).await;
        assert_eq!(s, 201, "{v}");
    }
    let (s, v, headers) = server
        .call(
            reqwest::Method::POST,
            &path,
            Some(slow("flood")),
            Some(&flooder),
        )
        .await;
    assert_eq!(s, 429, "{v}");
    let message = v["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("3 versions waiting for their build (flood v1, flood v2, flood v3)"),
        "{message}"
    );
    assert!(headers.contains_key("retry-after"));
    // The flooder's page says what it has used.
    let web = crate::sessions::Web::new(&server);
    let session = web.login(&flooder).await;
    let page = web.get("/me", Some(&session)).await.body;
    assert!(
        page.contains("Your uploads: 3 of 3 versions waiting for their build"),
        "{page}"
    );
    // The builder is on the flooder's first build; another entrant uploads.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let other = entrant(&server, "other").await;
    let uploaded = Instant::now();
    let (s, b) = server
        .post(
            "/api/bots",
            json!({"name": "quick", "command": "python3 simple_bot.py", "build": "true",
                   "files": crate::support::simple_bot_files()}),
            Some(&other),
        )
        .await;
    assert_eq!(s, 201, "{b}");
    let quick = built_version(&server, b["bot_id"].as_i64().unwrap(), 120).await;
    let waited = uploaded.elapsed().as_millis() as i64;
    assert_eq!(quick["build_status"], "ready", "{quick}");
    let own = quick["build_ms"].as_i64().unwrap();
    let flood_v1 = {
        let (_, v) = server.get(&format!("/api/bots/{flood_bot}"), None).await;
        v["versions"][0].clone()
    };
    // The flooder's first build may still be running when the other is ready: the
    // other's wait is its own build and the rest of one of the flooder's.
    let one_flood_build = flood_v1["build_ms"].as_i64().unwrap_or(4_000).max(4_000);
    eprintln!(
        "another entrant's version: ready {waited} ms after its upload, its own build and \
         validation {own} ms, one of the flooder's builds {one_flood_build} ms"
    );
    assert!(
        waited <= own + one_flood_build + 1_500,
        "waited {waited} ms: more than its own {own} ms and one flood build {one_flood_build} ms"
    );
}

/// An owner's uploads of bots in no competition are held by the server's daily quota, a
/// new bot by its key included; its competition's bot by the competition's quota instead.
#[tokio::test]
async fn an_owners_uploads_outside_competitions_have_a_daily_quota() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &["--no-validation"],
        &[("MAZEARENA_VERSIONS_PER_DAY", "3")],
    );
    let key = entrant(&server, "busy").await;
    let bot = |name: &str| {
        json!({"name": name, "command": "python3 simple_bot.py",
               "files": crate::support::simple_bot_files()})
    };
    let (s, b) = server.post("/api/bots", bot("busy-1"), Some(&key)).await;
    assert_eq!(s, 201, "{b}");
    let id = b["bot_id"].as_i64().unwrap();
    let path = format!("/api/bots/{id}/versions");
    for _ in 0..2 {
        let (s, v) = server.post(&path, bot("busy-1"), Some(&key)).await;
        assert_eq!(s, 201, "{v}");
    }
    for (path, body) in [(path.as_str(), bot("busy-1")), ("/api/bots", bot("busy-2"))] {
        let (s, v, headers) = server
            .call(reqwest::Method::POST, path, Some(body), Some(&key))
            .await;
        assert_eq!(s, 429, "{path}: {v}");
        let message = v["error"]["message"].as_str().unwrap();
        assert!(
            message.contains("3 versions of bots that are in no competition"),
            "{message}"
        );
        let wait: u64 = headers["retry-after"].to_str().unwrap().parse().unwrap();
        assert!((86_000..=86_400).contains(&wait), "{wait}");
    }
    // The admin has no quota.
    let (s, v) = server.post(&path, bot("busy-1"), Some(ADMIN)).await;
    assert_eq!(s, 201, "{v}");
    // Entered in a competition, the bot's uploads count on the competition's quota.
    let start = mazearena::storage::now_ms();
    competition(
        &server,
        json!({
            "name": "quota-cup", "title": "Quota cup",
            "opens_at": at(start - 1_000), "closes_at": at(start + 3_600_000),
            "repeats": 1, "versions_per_day": 2, "practice_per_day": 5,
            "mazes": {"practice": [maze("q-practice", 12, 4701)],
                      "public": [maze("q-public", 12, 4702)],
                      "private": [maze("q-private", 12, 4703)]},
        }),
    )
    .await;
    let (s, v) = server
        .post(
            "/api/competitions/quota-cup/entries",
            json!({"bot_id": id}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    let (s, v) = server.post(&path, bot("busy-1"), Some(&key)).await;
    assert_eq!(s, 201, "{v}");
}

/// A wrong login from `client` to `base`, with extra `headers`: the status.
async fn wrong_login(client: &reqwest::Client, base: &str, headers: &[(&str, &str)]) -> u16 {
    let mut r = client
        .post(format!("{base}/login"))
        .form(&[("key", "not-a-key-of-anyone")]);
    for (name, value) in headers {
        r = r.header(*name, *value);
    }
    r.send().await.unwrap().status().as_u16()
}

/// Behind a real nginx, with `--trusted-proxies` naming it, each client has its own
/// budget (two clients, 127.0.0.2 and 127.0.0.3); a forged header is ignored both ways:
/// what a client puts left of nginx's entry, and anything sent straight to the server
/// by a peer that is not a trusted proxy.
#[tokio::test]
async fn behind_nginx_each_client_has_its_own_budget_and_forged_headers_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &["--jobs", "0", "--trusted-proxies", "127.0.0.1"],
        &[("MAZEARENA_LOGINS_PER_HOUR", "3")],
    );
    let Some(nginx) = crate::support::Nginx::start(&server.base, "behind_nginx") else {
        return;
    };
    let (a, b) = (
        crate::support::client_from("127.0.0.2"),
        crate::support::client_from("127.0.0.3"),
    );
    for _ in 0..3 {
        assert_eq!(wrong_login(&a, &nginx.base, &[]).await, 401);
    }
    assert_eq!(wrong_login(&a, &nginx.base, &[]).await, 429);
    // The other client has a budget of its own.
    assert_eq!(wrong_login(&b, &nginx.base, &[]).await, 401);
    // A forged entry on the left, or a Forwarded header nginx passes on, changes nothing.
    assert_eq!(
        wrong_login(&a, &nginx.base, &[("x-forwarded-for", "127.0.0.9")]).await,
        429
    );
    assert_eq!(
        wrong_login(&a, &nginx.base, &[("forwarded", "for=127.0.0.9")]).await,
        429
    );
    // Straight to the server, a client is not a trusted proxy: its header is ignored,
    // whichever address it names.
    assert_eq!(
        wrong_login(&a, &server.base, &[("x-forwarded-for", "127.0.0.3")]).await,
        429
    );
    assert_eq!(
        wrong_login(&b, &server.base, &[("x-forwarded-for", "127.0.0.2")]).await,
        401
    );
    // b has used two of its three; one more through nginx, then it is refused too.
    assert_eq!(wrong_login(&b, &nginx.base, &[]).await, 401);
    assert_eq!(wrong_login(&b, &nginx.base, &[]).await, 429);
}

/// Without `--trusted-proxies`, every client behind nginx is nginx: one client's
/// guesses use up everyone's budget (why a server behind a proxy must name it).
#[tokio::test]
async fn behind_nginx_without_trusted_proxies_everyone_shares_one_budget() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &["--jobs", "0"],
        &[("MAZEARENA_LOGINS_PER_HOUR", "2")],
    );
    let Some(nginx) = crate::support::Nginx::start(&server.base, "behind_nginx_untrusted") else {
        return;
    };
    let (a, b) = (
        crate::support::client_from("127.0.0.2"),
        crate::support::client_from("127.0.0.3"),
    );
    for _ in 0..2 {
        assert_eq!(wrong_login(&a, &nginx.base, &[]).await, 401);
    }
    assert_eq!(wrong_login(&b, &nginx.base, &[]).await, 429);
}
