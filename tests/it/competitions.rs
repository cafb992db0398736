//! A whole competition on a real server, on SQLite and on PostgreSQL: entrants register,
//! upload and are ranked automatically, hit their quotas, cannot see the private set
//! before the close (on any route or page), see it after; the final snapshot equals a
//! recount; the CSV has one row per entrant.

use std::time::{Duration, Instant};

use mazearena::engine::generator::generate;
use mazearena::engine::mazefile::numeric;
use reqwest::Method;
use serde_json::{Value, json};

use crate::faults::{new_database, postgres};
use crate::support::{ADMIN, TestServer, assert_standings_equal_recount, simple_bot_files};

/// The competition opens this long after the test creates it.
const OPENS_IN_MS: i64 = 3000;

/// RFC 3339 of unix ms.
fn at(ms: i64) -> String {
    mazearena::competition::Timestamp(ms).rfc3339()
}

fn now_ms() -> i64 {
    mazearena::storage::now_ms()
}

/// A generated maze as the API takes it.
fn maze(name: &str, seed: u64) -> Value {
    json!({"name": name, "layout": numeric::write(&generate(12, seed).unwrap())})
}

/// Waits (at most 180 s) for `check` to hold of GET `path`'s JSON (as `token`).
pub(crate) async fn wait_for(
    server: &TestServer,
    path: &str,
    token: Option<&str>,
    check: impl Fn(&Value) -> bool,
) -> Value {
    let deadline = Instant::now() + Duration::from_secs(180);
    loop {
        let (_, v) = server.get(path, token).await;
        if check(&v) {
            return v;
        }
        assert!(Instant::now() < deadline, "{path} never got there: {v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

#[tokio::test]
async fn a_whole_competition_on_sqlite() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    play_a_competition(&server).await;
}

#[tokio::test]
async fn a_whole_competition_on_postgres() {
    let Some((url, _)) = postgres("a_whole_competition_on_postgres") else {
        return;
    };
    let database = new_database(&url, "competition").await;
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_on(dir.path(), Some(&database), &[], &[]);
    play_a_competition(&server).await;
}

async fn play_a_competition(server: &TestServer) {
    let call = |method: Method, path: String, body: Option<Value>, token: Option<String>| async move {
        let (s, v, _) = server.call(method, &path, body, token.as_deref()).await;
        (s, v)
    };
    // The admin makes an organiser; the organiser creates the competition.
    let (s, o) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{o}");
    let organiser = o["key"].as_str().unwrap().to_string();
    let start = now_ms();
    let spec = json!({
        "name": "class-2027", "title": "Class of 2027",
        "description": "Find the centre, fast.", "rules": "One bot per team.",
        "opens_at": at(start + OPENS_IN_MS), "closes_at": at(start + 3_600_000),
        "repeats": 2, "final_repeats": 1, "versions_per_day": 2, "practice_per_day": 1,
        "selection": "best_public",
        "limits": {"move_timeout_ms": 2000},
        "mazes": {
            "practice": [maze("warm-up", 9001)],
            "public": [maze("pub-a", 9002), maze("pub-b", 9003)],
            "private": [maze("priv-a", 9004), maze("priv-b", 9005)],
        },
    });
    let (s, v) = server.post("/api/competitions", spec.clone(), None).await;
    assert_eq!(s, 401, "{v}");
    let (s, c) = server
        .post("/api/competitions", spec.clone(), Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    assert_eq!(c["phase"], "upcoming");
    let (s, v) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 409, "{v}");
    // Anyone sees the practice maze's id, not the ranking mazes' ids or hashes, nor seeds.
    let (_, public_view) = server.get("/api/competitions/class-2027", None).await;
    let mazes = public_view["mazes"].as_array().unwrap();
    let practice = mazes.iter().find(|m| m["set"] == "practice").unwrap()["maze_id"]
        .as_i64()
        .unwrap();
    assert!(
        mazes
            .iter()
            .filter(|m| m["set"] != "practice")
            .all(|m| m["maze_id"].is_null() && m["hash"].is_null())
    );
    assert!(public_view["seeds"].is_null());
    let (_, org_view) = server
        .get("/api/competitions/class-2027", Some(&organiser))
        .await;
    assert_eq!(org_view["seeds"].as_array().unwrap().len(), 70);

    // Three entrants register, each with a bot, and enter it.
    let mut teams: Vec<(String, i64)> = Vec::new();
    for name in ["ada", "brian", "claude"] {
        let (s, e) = server
            .post(
                "/api/entrants",
                json!({"name": name, "members": [name]}),
                None,
            )
            .await;
        assert_eq!(s, 201, "{e}");
        let key = e["key"].as_str().unwrap().to_string();
        let body = json!({"name": format!("{name}-bot"), "command": "python3 simple_bot.py", "files": simple_bot_files()});
        let (s, b) = server.post("/api/bots", body, Some(&key)).await;
        assert_eq!(s, 201, "{b}");
        let bot = b["bot_id"].as_i64().unwrap();
        let (s, v) = server
            .post(
                "/api/competitions/class-2027/entries",
                json!({"bot_id": bot}),
                None,
            )
            .await;
        assert_eq!(s, 401, "{v}");
        let (s, v) = server
            .post(
                "/api/competitions/class-2027/entries",
                json!({"bot_id": bot}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{v}");
        teams.push((key, bot));
    }
    // An entrant's key manages no competition; an organiser's key is no admin token
    // (no organiser made, no registration mode, no paused bot resumed) and owns no bot.
    let entrant = Some(teams[0].0.clone());
    let (s, v) = call(
        Method::PATCH,
        "/api/competitions/class-2027".into(),
        Some(json!({"title": "mine"})),
        entrant,
    )
    .await;
    assert_eq!(s, 403, "{v}");
    let org = Some(organiser.clone());
    for (method, path, body) in [
        (
            Method::POST,
            "/api/organisers".to_string(),
            json!({"name": "another"}),
        ),
        (
            Method::PUT,
            "/api/registration".to_string(),
            json!({"mode": "closed"}),
        ),
        (
            Method::POST,
            format!("/api/bots/{}/resume", teams[0].1),
            json!({}),
        ),
        (
            Method::POST,
            "/api/matches".to_string(),
            json!({"bot_id": teams[0].1, "maze_id": practice}),
        ),
    ] {
        let (s, v) = call(method, path.clone(), Some(body), org.clone()).await;
        assert_eq!(s, 403, "{path}: {v}");
    }
    let (_, reg) = server.get("/api/registration", None).await;
    assert_eq!(reg["mode"], "open", "{reg}");
    // Another entrant's bot cannot be entered by a key that is not its entrant's.
    let (s, v) = server
        .post(
            "/api/competitions/class-2027/entries",
            json!({"bot_id": teams[1].1}),
            Some(&teams[0].0),
        )
        .await;
    assert!(s == 403 || s == 409, "{s} {v}");

    // Nothing is ranked before the opening; then, on the server's clock, every entered
    // bot is, with nothing done by hand: the public board fills in.
    let (_, mine) = server
        .get(
            "/api/competitions/class-2027/submissions",
            Some(&teams[2].0),
        )
        .await;
    if now_ms() < start + OPENS_IN_MS {
        assert_eq!(mine["versions"][0]["status"], "waiting", "{mine}");
    }
    let (_, board) = server
        .get("/api/competitions/class-2027/leaderboard", Some(&organiser))
        .await;
    assert!(now_ms() >= start + OPENS_IN_MS || board["standings"].as_array().unwrap().is_empty());
    let board = wait_for(
        server,
        "/api/competitions/class-2027/leaderboard",
        None,
        |v| v["standings"].as_array().is_some_and(|r| r.len() == 3),
    )
    .await;
    assert!(
        board["standings"]
            .as_array()
            .unwrap()
            .iter()
            .all(|r| r["played"] == 4),
        "{board}"
    );
    // Each line states how sure it is: an interval around its mean, a rank range; over
    // the hidden public set, for anyone but its organiser, nothing the means do not say
    // (an interval over 2 runs on a maze would show each run's score).
    for r in board["standings"].as_array().unwrap() {
        assert_interval(r, "mean_score");
        let u = &r["uncertainty"];
        assert_eq!(u["withheld"], true, "{r}");
        assert_eq!(
            (&u["low"], &u["high"]),
            (&r["mean_score"], &r["mean_score"]),
            "{r}"
        );
    }
    let (_, org_board) = server
        .get("/api/competitions/class-2027/leaderboard", Some(&organiser))
        .await;
    for r in org_board["standings"].as_array().unwrap() {
        assert_eq!(r["uncertainty"]["withheld"], false, "{r}");
    }

    // Before the close no bot has played a private maze, by construction: no match of
    // the private set exists (the admin sees every match), the private board is empty for
    // everyone, its organiser included, and says the final run comes after the close.
    let private_t = org_view["public_tournament_id"].as_i64().unwrap() + 1;
    let private_ids = crate::support::private_maze_ids(&org_view);
    assert_eq!(private_ids.len(), 2, "{org_view}");
    let no_private_match = |list: &Value| {
        list["items"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| !private_ids.contains(&m["maze_id"].as_i64().unwrap()))
    };
    let (_, all) = server.get("/api/matches?limit=200", Some(ADMIN)).await;
    assert!(all["items"].as_array().unwrap().len() >= 12, "{all}");
    assert!(
        no_private_match(&all),
        "a private-set match before the close: {all}"
    );
    for token in [None, Some(teams[0].0.clone()), Some(organiser.clone())] {
        let (s, v) = call(
            Method::GET,
            "/api/competitions/class-2027/leaderboard?board=private".into(),
            None,
            token.clone(),
        )
        .await;
        assert_eq!(s, 200, "{v}");
        assert_eq!(
            (
                v["sealed"].as_bool(),
                v["standings"].as_array().map(Vec::len),
                v["final_run"].is_null()
            ),
            (Some(true), Some(0), true),
            "{v}"
        );
        let (_, list) = call(
            Method::GET,
            format!("/api/matches?tournament_id={private_t}"),
            None,
            token.clone(),
        )
        .await;
        assert_eq!(list["items"].as_array().unwrap().len(), 0, "{list}");
    }
    // An entrant's own view holds no private-set match, and its hidden public-set
    // matches show no seed (the competition's seeds are secret until the results).
    let (_, mine) = server
        .get(
            &format!("/api/matches?bot_id={}&limit=200", teams[0].1),
            Some(&teams[0].0),
        )
        .await;
    assert_eq!(mine["items"].as_array().unwrap().len(), 4, "{mine}");
    assert!(no_private_match(&mine), "{mine}");
    for m in mine["items"].as_array().unwrap() {
        assert_eq!(m["maze_hidden"], true, "{m}");
        assert!(m["seed"].is_null(), "a hidden match shows its seed: {m}");
        assert!(m["score"].is_null(), "{m}");
    }
    for page in [format!("/tournaments/{private_t}")] {
        assert_eq!(server.get_text(&page).await.0, 404, "{page}");
    }
    let (s, page) = server.get_text("/competitions/class-2027").await;
    assert_eq!(s, 200);
    assert!(
        page.contains("No bot plays a private maze before the close") && page.contains("ada-bot"),
        "{page}"
    );
    assert_eq!(
        page.matches("<table class=\"data board\">").count(),
        1,
        "only the public board: {page}"
    );
    let (_, list) = server.get_text("/competitions").await;
    assert!(
        list.contains("/competitions/class-2027") && list.contains("/competitions/ranking"),
        "{list}"
    );
    let (_, pages) = server.get_text("/tournaments").await;
    assert!(
        !pages.contains("private ranking"),
        "the tournaments page lists the private set"
    );

    // Another organiser: no edit, no sealed view, no handing over (the admin's).
    let (s, o) = server
        .post(
            "/api/organisers",
            json!({"name": "other-teacher"}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{o}");
    let other = o["key"].as_str().unwrap().to_string();
    for body in [
        json!({"title": "mine now"}),
        json!({"closes_at": at(now_ms())}),
        json!({"organiser": "other-teacher"}),
    ] {
        let (s, v) = call(
            Method::PATCH,
            "/api/competitions/class-2027".into(),
            Some(body),
            Some(other.clone()),
        )
        .await;
        assert_eq!(s, 403, "{v}");
    }
    let (s, v) = call(
        Method::PATCH,
        "/api/competitions/class-2027".into(),
        Some(json!({"organiser": "other-teacher"})),
        Some(organiser.clone()),
    )
    .await;
    assert_eq!(s, 403, "only the admin hands a competition over: {v}");
    let (_, other_view) = server
        .get("/api/competitions/class-2027", Some(&other))
        .await;
    assert!(other_view["seeds"].is_null(), "{other_view}");
    assert!(
        other_view["mazes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["set"] != "practice")
            .all(|m| m["maze_id"].is_null()),
        "{other_view}"
    );
    // A hidden ranking maze of this competition is refused in another one, and the
    // answer names neither the competition nor the maze.
    let reuse = json!({
        "name": "other-cup", "title": "Other cup",
        "opens_at": at(now_ms()), "closes_at": at(now_ms() + 3_600_000),
        "mazes": {"practice": [], "public": [maze("copied", 9002)], "private": [maze("x", 9106)]},
    });
    let (s, v) = server.post("/api/competitions", reuse, Some(&other)).await;
    assert_eq!(s, 409, "{v}");
    let message = v["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("hidden ranking maze of another competition"),
        "{message}"
    );
    assert!(
        !message.contains("class-2027") && !message.contains("pub-a"),
        "{message}"
    );

    // The public set's tournament shows its standings on the competition's board only.
    let public_t = private_t - 1;
    let (s, v) = server
        .get(&format!("/api/leaderboard?tournament={public_t}"), None)
        .await;
    assert_eq!(s, 409, "{v}");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("/api/competitions/class-2027/leaderboard")
    );
    let (_, t) = server
        .get(&format!("/api/tournaments/{public_t}"), Some(&teams[0].0))
        .await;
    assert_eq!(
        (
            t["standings_sealed"].as_bool(),
            t["standings"].as_array().map(Vec::len)
        ),
        (Some(true), Some(0)),
        "{t}"
    );
    let (_, t) = server
        .get(&format!("/api/tournaments/{public_t}"), Some(&organiser))
        .await;
    assert_eq!(t["standings"].as_array().map(Vec::len), Some(3), "{t}");
    // The competition's tournament on the home page leads to the competition's page
    // (its standings are the competition's boards), and the home page shows the
    // competition's public board as its page does: means and ranks, no interval.
    let (s, page) = server.get_text(&format!("/?tournament={public_t}")).await;
    assert_eq!(s, 200, "{page}");
    assert!(page.contains("Class of 2027"), "{page}");
    let (_, home) = server.get_text("/").await;
    assert!(
        home.contains("href=\"/competitions/class-2027\"") && home.contains("ada-bot"),
        "the home page leaves the competition out: {home}"
    );
    assert!(!home.contains("/?tournament={public_t}"), "{home}");
    // The tournament's own page says where its standings are, instead of promising
    // them for later.
    let (_, page) = server.get_text(&format!("/tournaments/{public_t}")).await;
    assert!(
        page.contains("ranks for the competition")
            && page.contains("href=\"/competitions/class-2027\"")
            && !page.contains("The standings appear once"),
        "{page}"
    );
    // Frozen from now on (2 hours before a close 1 hour away): a version uploaded now
    // shows on the public board to the organisers, not to anyone else.
    let (s, v) = call(
        Method::PATCH,
        "/api/competitions/class-2027".into(),
        Some(json!({"freeze_hours": 2})),
        Some(organiser.clone()),
    )
    .await;
    assert_eq!((s, v["phase"].as_str()), (200, Some("frozen")), "{v}");

    // Quotas: 2 versions a day (the first counts); the third is refused and says when.
    // Four uploads sent at once: one is the second version, the other three are
    // refused (each passes the check made before its files are read; the quota is
    // counted again where the version is added).
    let (ada, ada_bot) = (teams[0].0.clone(), teams[0].1);
    let upload = json!({"command": "python3 simple_bot.py", "files": simple_bot_files()});
    let path = format!("/api/bots/{ada_bot}/versions");
    let at_once = futures_util::future::join_all(
        (0..4).map(|_| server.post(&path, upload.clone(), Some(&ada))),
    )
    .await;
    let mut statuses: Vec<u16> = at_once.iter().map(|(s, _)| *s).collect();
    statuses.sort_unstable();
    assert_eq!(statuses, [201, 429, 429, 429], "{at_once:?}");
    let (s, v) = server
        .post(
            &format!("/api/bots/{ada_bot}/versions"),
            upload.clone(),
            Some(&ada),
        )
        .await;
    assert_eq!(s, 429, "{v}");
    let message = v["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("2 of 2 versions used in the last 24 hours; the next one at"),
        "{message}"
    );
    let (s, mine) = server
        .get("/api/competitions/class-2027/submissions", Some(&ada))
        .await;
    assert_eq!(s, 200, "{mine}");
    assert_eq!(mine["versions"].as_array().unwrap().len(), 2, "{mine}");
    // Nothing of the final is told early: no final result, not the final phase.
    assert!(mine["final_result"].is_null(), "{mine}");
    assert_ne!(mine["phase"], "final", "{mine}");
    assert!(
        mine["versions_quota"]["message"]
            .as_str()
            .unwrap()
            .starts_with("2 of 2 versions"),
        "{mine}"
    );
    let (s, _) = server
        .get("/api/competitions/class-2027/submissions", None)
        .await;
    assert_eq!(s, 401);
    // Practice: 1 a day on the practice maze. Three asked at once: one is queued.
    let practice_match = json!({"bot_id": ada_bot, "maze_id": practice, "seed": 1});
    let at_once = futures_util::future::join_all(
        (0..3).map(|_| server.post("/api/matches", practice_match.clone(), Some(&ada))),
    )
    .await;
    let mut statuses: Vec<u16> = at_once.iter().map(|(s, _)| *s).collect();
    statuses.sort_unstable();
    assert_eq!(statuses, [202, 429, 429], "{at_once:?}");
    let v = at_once.into_iter().find(|(s, _)| *s == 202).unwrap().1;
    // Its stderr is Ada's: not another entrant's, not the organiser's.
    let practice_id = v["match_id"].as_i64().unwrap();
    for token in [&teams[1].0, &organiser] {
        let (s, log) = server
            .get(&format!("/api/matches/{practice_id}/log"), Some(token))
            .await;
        assert_eq!(s, 403, "{log}");
    }
    let (s, v) = server
        .post("/api/matches", practice_match, Some(&ada))
        .await;
    assert_eq!(s, 429, "{v}");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("1 of 1 practice matches"),
        "{v}"
    );
    // The quota is the entrant's, all its bots together: a second bot of Ada's, not
    // entered, is refused the practice maze too.
    let second = json!({"name": "ada-spare", "command": "python3 simple_bot.py", "files": simple_bot_files()});
    let (s, b) = server.post("/api/bots", second, Some(&ada)).await;
    assert_eq!(s, 201, "{b}");
    let spare = json!({"bot_id": b["bot_id"], "maze_id": practice, "seed": 2});
    let (s, v) = server.post("/api/matches", spare, Some(&ada)).await;
    assert_eq!(
        s, 429,
        "a second bot practises past the entrant's quota: {v}"
    );
    // Ada's second version gets ranked too; she sees its public numbers, the public
    // board (frozen) still shows her first version but to the organisers.
    wait_for(
        server,
        "/api/competitions/class-2027/submissions",
        Some(&ada),
        |v| v["versions"][0]["status"] == "ranked",
    )
    .await;
    // Its validation match was played on the competition's practice maze (public),
    // under the competition's limits.
    let (s, log) = server
        .get(
            &format!("/api/bots/{ada_bot}/versions/2/build-log"),
            Some(&ada),
        )
        .await;
    assert_eq!(s, 200, "{log}");
    assert!(
        log["build_log"]
            .as_str()
            .unwrap_or_default()
            .contains("on the practice maze warm-up of competition class-2027 without a fault"),
        "{log}"
    );
    let version_of_ada = |board: &Value| {
        board["standings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["entrant"] == "ada")
            .unwrap()["version"]
            .as_i64()
    };
    for token in [None, Some(ada.as_str())] {
        let (_, board) = server
            .get("/api/competitions/class-2027/leaderboard", token)
            .await;
        assert_eq!(version_of_ada(&board), Some(1), "{board}");
        assert!(board["frozen_at"].is_string(), "{board}");
    }
    let (_, board) = server
        .get("/api/competitions/class-2027/leaderboard", Some(&organiser))
        .await;
    assert_eq!(version_of_ada(&board), Some(2), "{board}");
    // No results before the close.
    let (s, _) = server
        .get("/api/competitions/class-2027/results", None)
        .await;
    assert_eq!(s, 409);

    // The organiser closes it now: no new versions (409 with the time).
    let (s, v) = call(
        Method::PATCH,
        "/api/competitions/class-2027".into(),
        Some(json!({"closes_at": at(now_ms())})),
        Some(organiser.clone()),
    )
    .await;
    assert_eq!((s, v["phase"].as_str()), (200, Some("closed")), "{v}");
    let (s, v) = server
        .post(
            &format!("/api/bots/{}/versions", teams[1].1),
            upload,
            Some(&teams[1].0),
        )
        .await;
    assert_eq!(s, 409, "{v}");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("closed at"),
        "{v}"
    );
    let (s, v) = call(
        Method::PATCH,
        "/api/competitions/class-2027".into(),
        Some(json!({"versions_per_day": 9})),
        Some(organiser.clone()),
    )
    .await;
    assert_eq!(s, 409, "{v}");

    // The final selection and run, then the results: public, one row per entrant.
    let c = wait_for(server, "/api/competitions/class-2027", None, |v| {
        v["state"] == "final"
    })
    .await;
    // The final run was the private set's only run: 3 selected versions x 2 mazes.
    assert_eq!(c["final_run"], json!({"played": 6, "total": 6}), "{c}");
    assert_eq!(
        c["seeds"].as_array().unwrap().len(),
        70,
        "the seeds are public with the results"
    );
    let (_, private_board) = server
        .get(
            "/api/competitions/class-2027/leaderboard?board=private",
            None,
        )
        .await;
    assert_eq!(
        private_board["standings"].as_array().unwrap().len(),
        3,
        "{private_board}"
    );
    let (s, results) = server
        .get("/api/competitions/class-2027/results", None)
        .await;
    assert_eq!(s, 200, "{results}");
    assert_eq!(results["recount_equal"], true, "{results}");
    let rows = results["results"].as_array().unwrap();
    assert_eq!(rows.len(), 3, "{results}");
    for row in rows {
        // The final run: each selected version once on each of the 2 private mazes.
        assert_eq!(row["played"], 2, "{row}");
        assert_interval(row, "mean_score");
        let manifest: Value = serde_json::from_str(row["manifest"].as_str().unwrap()).unwrap();
        assert_eq!(manifest["recount"]["equal"], true, "{manifest}");
        assert_eq!(manifest["mazes"].as_array().unwrap().len(), 2);
        assert_eq!(manifest["seeds"].as_array().unwrap().len(), 1);
        assert_eq!(manifest["limits"]["move_timeout_ms"], 2000);
        // Everything a re-run needs but secrets: the runtime, the build, the declared
        // variables' names (none here).
        for key in ["runtime", "build_command", "env", "command"] {
            assert!(manifest.get(key).is_some(), "{key}: {manifest}");
        }
        assert_eq!(
            manifest["bundle_sha256"].as_str().map(str::len),
            Some(64),
            "{manifest}"
        );
    }
    let (_, page) = server.get_text("/competitions/class-2027").await;
    assert!(
        page.contains("Final results") && !page.contains("before the close: the private"),
        "{page}"
    );
    assert!(
        page.contains("95% interval") && page.contains("equal means share a rank"),
        "{page}"
    );
    // Every limit, as the matches are played under it: the competition's 2000 ms per
    // move, the server's for the rest, all in CPU time.
    for said in [
        "CPU time per move (move_timeout_ms)",
        "2000 ms",
        "(time_bank_ms)",
        "30000 ms",
        "(memory_limit_mb)",
        "wall-clock backstop",
    ] {
        assert!(page.contains(said), "{said}: {page}");
    }
    assert_eq!(
        page.matches("<table class=\"data board\">").count(),
        2,
        "both boards: {page}"
    );
    // Any row's match plays again exactly with `mazearena run`, from its manifest.
    let manifest: Value = serde_json::from_str(rows[0]["manifest"].as_str().unwrap()).unwrap();
    let played = &manifest["matches"][0];
    assert_eq!(
        manifest["matches"].as_array().unwrap().len(),
        2,
        "{manifest}"
    );
    let (_, mazes) = server.get("/api/mazes", Some(ADMIN)).await;
    let id = mazes
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["hash"] == played["maze_hash"])
        .unwrap()["maze_id"]
        .as_i64()
        .unwrap();
    let (_, m) = server.get(&format!("/api/mazes/{id}"), Some(ADMIN)).await;
    let layout = m["layout"].as_str().unwrap().to_string();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("maze.txt");
    std::fs::write(&file, layout).unwrap();
    let seed = played["seed"].to_string();
    let again = crate::support::mazearena_json(&[
        "run",
        "--maze",
        file.to_str().unwrap(),
        "--bot",
        "python3 simple_bot.py",
        "--bot-dir",
        "bots/python",
        "--seed",
        &seed,
        "--move-timeout-ms",
        "2000",
        "--json",
    ]);
    assert_eq!(again["score"], played["score"], "{again} {played}");
    assert_eq!(again["status"], played["status"]);
    let csv = server
        .client()
        .get(format!(
            "{}/api/competitions/class-2027/results.csv",
            server.base
        ))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 4, "{csv}");
    assert!(
        lines[0].starts_with("rank,rank_range,tie_group,entrant,bot,version,played,finished,mean_score,score_low,score_high"),
        "{csv}"
    );
    for name in ["ada", "brian", "claude"] {
        assert_eq!(
            lines
                .iter()
                .filter(|l| l.contains(&format!(",{name},")))
                .count(),
            1,
            "{csv}"
        );
    }
    // The final run's tournament is open to all now; the matches played under the
    // competition's limits.
    let final_t = manifest["tournament_id"].as_i64().unwrap();
    let (_, list) = server
        .get(
            &format!("/api/matches?tournament_id={final_t}&limit=1"),
            None,
        )
        .await;
    assert_eq!(
        list["items"][0]["limits"]["move_timeout_ms"], 2000,
        "{list}"
    );
    // The ranking's running sums leave out the competition's tournaments, as the
    // count from the match table does; each of its tournaments has its own.
    assert_standings_equal_recount(&server.database, &[public_t, final_t]).await;
}

/// A standing line states its uncertainty: an interval that holds `mean`, and a rank
/// range that holds its rank.
fn assert_interval(line: &Value, mean: &str) {
    let u = &line["uncertainty"];
    let (low, high, m) = (
        u["low"].as_f64().unwrap(),
        u["high"].as_f64().unwrap(),
        line[mean].as_f64().unwrap(),
    );
    assert!(low <= m && m <= high, "{line}");
    let rank = line["rank"].as_i64().unwrap();
    assert!(
        u["rank_best"].as_i64().unwrap() <= rank && rank <= u["rank_worst"].as_i64().unwrap(),
        "{line}"
    );
    assert!(u["tie_group"].as_i64().unwrap() >= 1, "{line}");
}

/// Twins, the same program entered by three entrants and another by two, share a rank
/// with equal printed means in the results' JSON, results.csv, the CLI's table and the
/// competition's page: means are kept as exact sums of thirtieths, not as floats
/// whose last bits depend on the order the matches were added up in.
#[tokio::test]
async fn twins_share_a_rank_and_print_equal_means_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (_, o) = server
        .post(
            "/api/organisers",
            json!({"name": "twins-teacher"}),
            Some(ADMIN),
        )
        .await;
    let organiser = o["key"].as_str().unwrap().to_string();
    let start = now_ms();
    let spec = json!({
        "name": "twins", "title": "Twins",
        "opens_at": at(start), "closes_at": at(start + 3_600_000),
        "repeats": 1, "final_repeats": 2, "reveal_private_mazes": true,
        "mazes": {
            "public": [maze("twin-pub", 9102)],
            "private": [maze("twin-a", 9103), maze("twin-b", 9104), maze("twin-c", 9105)],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    let read = |p: &str| std::fs::read_to_string(crate::support::root().join(p)).unwrap();
    let smart = json!({
        "mazebot.py": read("bots/python/mazebot.py"),
        "mazemap.py": read("bots/python/mazemap.py"),
        "seed000_smart_map.py": read("bots/python/seed000_smart_map.py"),
    });
    let programs = [
        (
            "python3 simple_bot.py",
            simple_bot_files(),
            ["s1", "s2", "s3"].as_slice(),
        ),
        (
            "python3 seed000_smart_map.py",
            smart,
            ["m1", "m2"].as_slice(),
        ),
    ];
    let mut keys: Vec<(String, String)> = Vec::new();
    for (command, files, names) in &programs {
        for name in names.iter() {
            let (s, e) = server
                .post("/api/entrants", json!({"name": name}), None)
                .await;
            assert_eq!(s, 201, "{e}");
            let key = e["key"].as_str().unwrap().to_string();
            keys.push((name.to_string(), key.clone()));
            let body = json!({"name": format!("{name}-bot"), "command": command, "files": files});
            let (s, b) = server.post("/api/bots", body, Some(&key)).await;
            assert_eq!(s, 201, "{b}");
            let (s, v) = server
                .post(
                    "/api/competitions/twins/entries",
                    json!({"bot_id": b["bot_id"]}),
                    Some(&key),
                )
                .await;
            assert_eq!(s, 201, "{v}");
        }
    }
    // Every version ranked on the public set, then the close now and the final run.
    wait_for(
        &server,
        "/api/competitions/twins/leaderboard",
        Some(&organiser),
        |v| v["standings"].as_array().is_some_and(|a| a.len() == 5),
    )
    .await;
    let (s, v, _) = server
        .call(
            Method::PATCH,
            "/api/competitions/twins",
            Some(json!({"closes_at": at(now_ms())})),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    wait_for(&server, "/api/competitions/twins", None, |v| {
        v["state"] == "final"
    })
    .await;

    // The results' JSON: each program's entrants share one rank and one printed mean.
    let (_, results) = server.get("/api/competitions/twins/results", None).await;
    let rows = results["results"].as_array().unwrap();
    assert_eq!(rows.len(), 5, "{results}");
    let of = |prefix: &str| -> Vec<&Value> {
        rows.iter()
            .filter(|r| r["entrant_name"].as_str().unwrap().starts_with(prefix))
            .collect()
    };
    let mut printed = Vec::new();
    for (prefix, n) in [("s", 3), ("m", 2)] {
        let twins = of(prefix);
        assert_eq!(twins.len(), n, "{results}");
        for t in &twins {
            assert_eq!(t["rank"], twins[0]["rank"], "{results}");
            assert_eq!(
                t["mean_score"].to_string(),
                twins[0]["mean_score"].to_string()
            );
            assert_eq!(t["score_sum30"], twins[0]["score_sum30"], "{results}");
            // Shown with 3 decimals at most.
            let shown = t["mean_score"].to_string();
            assert!(
                shown.split('.').nth(1).is_none_or(|d| d.len() <= 3),
                "{shown}"
            );
        }
        printed.push((
            twins[0]["rank"].as_i64().unwrap(),
            format!("{:.3}", twins[0]["mean_score"].as_f64().unwrap()),
        ));
    }
    // The two programs differ: their ranks are 1 and 4, or 1 and 3.
    let mut ranks: Vec<i64> = printed.iter().map(|p| p.0).collect();
    ranks.sort_unstable();
    assert!(
        ranks == [1, 4] || ranks == [1, 3] || ranks == [1, 1],
        "{results}"
    );

    // results.csv: the same ranks and the same printed means.
    let csv = server
        .client()
        .get(format!(
            "{}/api/competitions/twins/results.csv",
            server.base
        ))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (rank, entrant, mean) = (f[0], f[3], f[8]);
        let (want_rank, want_mean) = &printed[if entrant.starts_with('s') { 0 } else { 1 }];
        assert_eq!(
            (rank, mean),
            (want_rank.to_string().as_str(), want_mean.as_str()),
            "{csv}"
        );
    }

    // The CLI's table from the server's database.
    let out = crate::support::mazearena(&[
        "competition",
        "results",
        "twins",
        "--database",
        &server.database,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout).to_string();
    for (prefix, n) in [("s", 3), ("m", 2)] {
        let (rank, mean) = &printed[if prefix == "s" { 0 } else { 1 }];
        let lines: Vec<&str> = table
            .lines()
            .filter(|l| {
                l.split_whitespace()
                    .nth(1)
                    .is_some_and(|e| e.starts_with(prefix) && e.len() == 2)
            })
            .collect();
        assert_eq!(lines.len(), n, "{table}");
        for l in lines {
            let words: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(
                (words[0], words[4]),
                (rank.to_string().as_str(), mean.as_str()),
                "{table}"
            );
        }
    }

    // Each entrant's own submissions say the phase and their final result.
    for (name, key) in &keys {
        let (s, mine) = server
            .get("/api/competitions/twins/submissions", Some(key))
            .await;
        assert_eq!(s, 200, "{mine}");
        assert_eq!(mine["phase"], "final", "{mine}");
        let row = rows
            .iter()
            .find(|r| r["entrant_name"] == name.as_str())
            .unwrap();
        assert_eq!(mine["final_result"]["rank"], row["rank"], "{mine}");
        assert_eq!(
            mine["final_result"]["mean_score"], row["mean_score"],
            "{mine}"
        );
        // Its public line has a real rank among the board's lines, not 0.
        let public = &mine["versions"][0]["public"];
        assert!(public["rank"].as_i64().is_some_and(|r| r >= 1), "{mine}");
    }
    let (_, c) = server.get("/api/competitions/twins", None).await;
    assert_eq!(c["phase"], "final", "{c}");
    // A final-run match on a revealed private maze has its replay, right after.
    let manifest: Value = serde_json::from_str(rows[0]["manifest"].as_str().unwrap()).unwrap();
    let id = manifest["matches"][0]["match_id"].as_i64().unwrap();
    let (s, replay) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_eq!(s, 200, "{replay}");
    let (_, page) = server.get_text(&format!("/matches/{id}")).await;
    assert!(!page.contains("removed to save space"), "{page}");

    // The page: each twin's row shows the shared rank and the same mean.
    let (_, page) = server.get_text("/competitions/twins").await;
    for (prefix, n) in [("s", 3), ("m", 2)] {
        let (_, mean) = &printed[if prefix == "s" { 0 } else { 1 }];
        assert!(
            page.matches(&format!(">{mean}<")).count() >= n,
            "{mean} is not shown {n} times: {page}"
        );
    }
}

#[tokio::test]
async fn a_rejudge_plays_matches_again_keeps_the_earlier_records_and_counts_the_results_again() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let (_, o) = server
        .post("/api/organisers", json!({"name": "judge"}), Some(ADMIN))
        .await;
    let organiser = o["key"].as_str().unwrap().to_string();
    let (_, other) = server
        .post("/api/organisers", json!({"name": "stranger"}), Some(ADMIN))
        .await;
    let stranger = other["key"].as_str().unwrap().to_string();
    let start = now_ms();
    let spec = json!({
        "name": "rejudge-cup", "title": "Rejudges",
        "opens_at": at(start + 1500), "closes_at": at(start + 3_600_000),
        "repeats": 1, "final_repeats": 1,
        "mazes": {
            "public": [maze("p1", 8101), maze("p2", 8102)],
            "private": [maze("q1", 8103), maze("q2", 8104)],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    let mut versions = Vec::new();
    for name in ["ann", "bob"] {
        let (_, e) = server
            .post("/api/entrants", json!({"name": name}), None)
            .await;
        let key = e["key"].as_str().unwrap().to_string();
        let body = json!({"name": format!("{name}-bot"), "command": "python3 simple_bot.py", "files": simple_bot_files()});
        let (s, b) = server.post("/api/bots", body, Some(&key)).await;
        assert_eq!(s, 201, "{b}");
        versions.push(b["version"]["bot_version_id"].as_i64().unwrap());
        let (s, v) = server
            .post(
                "/api/competitions/rejudge-cup/entries",
                json!({"bot_id": b["bot_id"]}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{v}");
    }
    wait_for(
        &server,
        "/api/competitions/rejudge-cup/leaderboard",
        None,
        |v| v["standings"].as_array().is_some_and(|s| s.len() == 2),
    )
    .await;
    // Only its organiser (or the admin) rejudges, and only what is in the competition.
    let path = "/api/competitions/rejudge-cup/rejudges";
    let ask = |mut body: Value| {
        body["reason"] = json!("the worker's disk failed");
        body
    };
    let (s, _) = server
        .post(
            path,
            ask(json!({"bot_version_id": versions[0]})),
            Some(&stranger),
        )
        .await;
    assert_eq!(s, 403);
    let (s, _) = server
        .post(path, ask(json!({"bot_version_id": versions[0]})), None)
        .await;
    assert_eq!(s, 401);
    let (s, e) = server.post(path, ask(json!({})), Some(&organiser)).await;
    assert_eq!(s, 422, "{e}");
    let (s, e) = server
        .post(path, ask(json!({"maze_id": 1})), Some(&organiser))
        .await;
    assert_eq!(s, 422, "a maze of no competition: {e}");
    let (s, e) = server
        .post(
            path,
            json!({"bot_version_id": versions[0], "reason": ""}),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 422, "a reason is needed: {e}");
    // Close, and wait for the results.
    let (s, v, _) = server
        .call(
            Method::PATCH,
            "/api/competitions/rejudge-cup",
            Some(json!({"closes_at": at(now_ms())})),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    let view = wait_for(
        &server,
        "/api/competitions/rejudge-cup",
        Some(&organiser),
        |v| v["state"] == "final",
    )
    .await;
    let (s, first) = server
        .get("/api/competitions/rejudge-cup/results", None)
        .await;
    assert_eq!(s, 200, "{first}");
    // A private maze's matches played again: the results are withdrawn until they are.
    let private = crate::support::private_maze_ids(&view);
    let (s, r) = server
        .post(path, ask(json!({"maze_id": private[0]})), Some(&organiser))
        .await;
    assert_eq!(s, 201, "{r}");
    assert_eq!(r["matches"], 2, "two entrants, one repeat: {r}");
    assert_eq!(
        r["requested_by"],
        format!("organiser:{}", o["organiser_id"])
    );
    let (_, now_view) = server
        .get("/api/competitions/rejudge-cup", Some(&organiser))
        .await;
    assert_ne!(
        now_view["state"], "final",
        "the results wait for the rejudged matches"
    );
    wait_for(&server, "/api/competitions/rejudge-cup", None, |v| {
        v["state"] == "final"
    })
    .await;
    let (s, second) = server
        .get("/api/competitions/rejudge-cup/results", None)
        .await;
    assert_eq!(s, 200, "{second}");
    // The same deterministic bots on the same seeds: the same results, counted again.
    for (a, b) in first["results"]
        .as_array()
        .unwrap()
        .iter()
        .zip(second["results"].as_array().unwrap())
    {
        assert_eq!(a["entrant"], b["entrant"]);
        assert_eq!(a["rank"], b["rank"]);
        assert_eq!(a["score_sum30"], b["score_sum30"], "{a} / {b}");
    }
    // Each rejudged match keeps its earlier outcome, and counts once.
    let (_, matches) = server
        .get(
            &format!("/api/matches?maze_id={}&limit=50", private[0]),
            Some(ADMIN),
        )
        .await;
    let items = matches["items"].as_array().unwrap();
    assert_eq!(items.len(), 2, "{matches}");
    for m in items {
        let (_, full) = server
            .get(&format!("/api/matches/{}", m["match_id"]), Some(ADMIN))
            .await;
        let kept = full["superseded"].as_array().expect("its earlier outcome");
        assert_eq!(kept.len(), 1, "{full}");
        assert_eq!(kept[0]["rejudge_id"], r["rejudge_id"]);
        assert_eq!(
            kept[0]["score"], full["score"],
            "the same bot, the same seed"
        );
        // The private mazes stay hidden: an earlier outcome shows what the match's own
        // row shows to anyone but the admin (its status only), in the API and the page.
        assert!(
            kept[0]["total_steps"].as_i64().is_some_and(|n| n > 0),
            "{full}"
        );
        let (_, seen) = server
            .get(&format!("/api/matches/{}", m["match_id"]), None)
            .await;
        assert_eq!(seen["total_steps"], Value::Null, "{seen}");
        let earlier = &seen["superseded"][0];
        assert_eq!(earlier["status"], kept[0]["status"], "{seen}");
        for field in ["score", "total_steps", "finished_at"] {
            assert_eq!(earlier[field], Value::Null, "{field}: {seen}");
        }
        let page = reqwest::get(format!("{}/matches/{}", server.base, m["match_id"]))
            .await
            .unwrap()
            .text()
            .await
            .unwrap();
        let at = page
            .find("<tr class=\"superseded\">")
            .expect("the earlier outcome's row");
        let row = &page[at..at + page[at..].find("</tr>").unwrap()];
        let steps = kept[0]["total_steps"].as_i64().unwrap();
        assert!(
            !row.contains(&format!(">{steps}<")) && row.contains(">hidden<"),
            "the earlier outcome's steps on the page: {row}"
        );
        let cells: Vec<&str> = row.split("<td").skip(1).collect();
        assert_eq!(cells.len(), 5, "{row}");
        assert!(cells[4].starts_with("></td>"), "its end time: {row}");
    }
    // The results written again equal a recount from the match records.
    let out = crate::support::mazearena(&[
        "competition",
        "results",
        "rejudge-cup",
        "--database",
        &server.database,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("every row equals a recount"));
    let (_, list) = server.get(path, Some(&organiser)).await;
    assert_eq!(list.as_array().unwrap().len(), 1, "{list}");
    // The command line does the same on the server's database.
    let out = crate::support::mazearena(&[
        "competition",
        "rejudge",
        "rejudge-cup",
        "--version-id",
        &versions[1].to_string(),
        "--reason",
        "a referee fix",
        "--database",
        &server.database,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    // Its two public matches and its two of the final run.
    assert!(text.contains("rejudge 2: 4 matches"), "{text}");
}
