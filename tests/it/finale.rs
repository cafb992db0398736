//! The final night on a real server and in Chromium: a 12-entrant competition (two
//! entrants tied, one that does badly on the public maze and well on the private ones)
//! holds its results; the organiser rehearses the reveal from the last place to the
//! first and watches the race of the 12 on a private maze; nobody else sees either
//! until the results are published, and afterwards nobody else sees a hidden maze; the
//! offline files play with the server stopped. Every order and move is checked against
//! the match records, not against the page's own numbers.

use std::collections::BTreeMap;
use std::time::Duration;

use fantoccini::Locator;
use mazearena::engine::generator::generate;
use mazearena::engine::mazefile::numeric;
use reqwest::Method;
use serde_json::{Value, json};

use crate::browser::{Browser, artifacts};
use crate::class_day::browser_login;
use crate::competitions::wait_for;
use crate::sessions::Web;
use crate::support::{ADMIN, TestServer};

fn at(ms: i64) -> String {
    mazearena::competition::Timestamp(ms).rfc3339()
}

fn maze(name: &str, dim: u32, seed: u64) -> Value {
    json!({"name": name, "layout": numeric::write(&generate(dim, seed).unwrap())})
}

/// The entrants: name and the dawdler's arguments (W run-0 steps and P run-1 steps of
/// standing still: W/30 + P added to simple_bot's score). The public maze is 12 cells
/// wide, the private ones 16: `mover` dawdles 40 run-1 steps on the public maze only.
const ENTRANTS: [(&str, &str); 12] = [
    ("ada", "0 0"),
    ("mover", "15 0 12:0:40"),
    ("twin-a", "30 1"),
    ("twin-b", "30 1"),
    ("bea", "0 3"),
    ("cal", "60 3"),
    ("dot", "0 6"),
    ("eve", "90 6"),
    ("fay", "0 10"),
    ("gus", "0 12"),
    ("hal", "30 14"),
    ("ivy", "0 20"),
];

/// A match's score in thirtieths from its record (a match that did not finish: none).
fn score30(m: &Value) -> Option<i64> {
    (m["status"] == "finished")
        .then(|| m["run1_steps"].as_i64().unwrap() * 30 + m["run0_steps"].as_i64().unwrap())
}

#[test]
fn the_final_night_reveals_last_to_first_races_twelve_and_seals_what_it_must() {
    let _heavy = crate::support::heavy();
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(final_night());
}

async fn final_night() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let base = server.base.clone();
    let mut organisers = Vec::new();
    for name in ["night-teacher", "other-teacher"] {
        let (s, o) = server
            .post("/api/organisers", json!({"name": name}), Some(ADMIN))
            .await;
        assert_eq!(s, 201, "{o}");
        organisers.push(o["key"].as_str().unwrap().to_string());
    }
    let (organiser, other) = (organisers[0].clone(), organisers[1].clone());
    let start = mazearena::storage::now_ms();
    let spec = json!({
        "name": "night", "title": "Night",
        "opens_at": at(start), "closes_at": at(start + 3_600_000),
        "repeats": 1, "final_repeats": 1, "hold_results": true, "reveal_private_mazes": false,
        "mazes": {
            "public": [maze("pub", 12, 4101)],
            "private": [maze("priv-a", 16, 4102), maze("priv-b", 16, 4103)],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    assert_eq!(c["hold_results"], true, "{c}");
    let read = |p: &str| std::fs::read_to_string(crate::support::root().join(p)).unwrap();
    let files = json!({
        "dawdler.py": read("tests/fixtures/bots/dawdler.py"),
        "simple_bot.py": read("bots/python/simple_bot.py"),
        "mazebot.py": read("bots/python/mazebot.py"),
    });
    let mut keys = BTreeMap::new();
    for (name, args) in ENTRANTS {
        let (s, e) = server
            .post("/api/entrants", json!({"name": name}), None)
            .await;
        assert_eq!(s, 201, "{e}");
        let key = e["key"].as_str().unwrap().to_string();
        let body = json!({"name": format!("{name}-bot"), "command": format!("python3 dawdler.py {args}"), "files": files});
        let (s, b) = server.post("/api/bots", body, Some(&key)).await;
        assert_eq!(s, 201, "{b}");
        let (s, v) = server
            .post(
                "/api/competitions/night/entries",
                json!({"bot_id": b["bot_id"]}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{v}");
        keys.insert(name, key);
    }
    let public = wait_for(
        &server,
        "/api/competitions/night/leaderboard",
        Some(&organiser),
        |v| v["standings"].as_array().is_some_and(|a| a.len() == 12),
    )
    .await;
    let (s, v, _) = server
        .call(
            Method::PATCH,
            "/api/competitions/night",
            Some(json!({"closes_at": at(mazearena::storage::now_ms())})),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    wait_for(&server, "/api/competitions/night", None, |v| {
        v["state"] == "held"
    })
    .await;

    // Held: the organisers' alone, on every route.
    let entrant = keys["ada"].clone();
    for (who, token) in [
        ("anonymous", None),
        ("an entrant", Some(entrant.as_str())),
        ("another organiser", Some(other.as_str())),
    ] {
        for path in [
            "/api/competitions/night/reveal",
            "/api/competitions/night/races",
            "/api/competitions/night/race/priv-a/0",
            "/api/competitions/night/race/pub/0",
        ] {
            let (s, v) = server.get(path, token).await;
            assert_eq!(s, 403, "{who} {path}: {v}");
        }
        let (s, v) = server.get("/api/competitions/night/results", token).await;
        assert_eq!(s, 409, "{who}: {v}");
        let (_, board) = server
            .get("/api/competitions/night/leaderboard?board=private", token)
            .await;
        assert!(
            board["standings"].as_array().is_none_or(|a| a.is_empty()),
            "{who}: {board}"
        );
    }
    let web = Web::new(&server);
    for path in [
        "/competitions/night/reveal",
        "/competitions/night/race",
        "/competitions/night/race/priv-a/0",
        "/competitions/night/reveal?download=1",
    ] {
        let a = web.get(path, None).await;
        assert_eq!(a.status, 403, "{path}: {}", a.body);
        assert!(!a.body.contains("finale-data"), "{path}");
    }
    for key in [&entrant, &other] {
        let session = web.login(key).await;
        for path in [
            "/competitions/night/reveal",
            "/competitions/night/race/pub/0",
            "/competitions/night/race/priv-a/0?download=1",
        ] {
            let a = web.get(path, Some(&session)).await;
            assert_eq!(a.status, 403, "{path}: {}", a.body);
            assert!(!a.body.contains("finale-data"), "{path}");
        }
    }
    let (s, results) = server
        .get("/api/competitions/night/results", Some(&organiser))
        .await;
    assert_eq!(s, 200, "{results}");

    // The reveal, as the organiser: ranks, ties and moves from the records.
    let (s, reveal) = server
        .get("/api/competitions/night/reveal", Some(&organiser))
        .await;
    assert_eq!(s, 200, "{reveal}");
    assert_eq!(reveal["published"], false);
    assert_eq!(
        reveal["organiser_copy"], true,
        "hidden private mazes drawn for the organiser"
    );
    let lines = reveal["lines"].as_array().unwrap();
    assert_eq!(lines.len(), 12, "{reveal}");
    let rows = results["results"].as_array().unwrap();
    // Each entrant's private matches, from the match records (as the admin lists them).
    let (_, view) = server
        .get("/api/competitions/night", Some(&organiser))
        .await;
    let maze_id = |name: &str| -> i64 {
        view["mazes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["name"] == name)
            .unwrap()["maze_id"]
            .as_i64()
            .unwrap()
    };
    let private = [maze_id("priv-a"), maze_id("priv-b")];
    let mut sums: BTreeMap<String, i64> = BTreeMap::new();
    for r in rows {
        let mut sum = 0;
        for m in private {
            let (_, page) = server
                .get(
                    &format!("/api/matches?bot_id={}&maze_id={m}", r["bot_id"]),
                    Some(ADMIN),
                )
                .await;
            let items = page["items"].as_array().unwrap();
            assert_eq!(
                items.len(),
                1,
                "one final-run match per private maze: {page}"
            );
            sum += score30(&items[0]).unwrap_or(30_000);
        }
        let name = r["entrant_name"].as_str().unwrap().to_string();
        assert_eq!(
            r["score_sum30"].as_i64().unwrap(),
            sum,
            "{name}: the result is its records' sum"
        );
        sums.insert(name, sum);
    }
    // The expected order: by the exact sum, equal sums tied (competition ranking).
    let mut by_sum: Vec<(&String, &i64)> = sums.iter().collect();
    by_sum.sort_by_key(|(n, s)| (**s, (*n).clone()));
    let rank_of =
        |name: &str| -> i64 { 1 + by_sum.iter().filter(|(_, s)| **s < sums[name]).count() as i64 };
    for l in lines {
        let name = l["entrant"].as_str().unwrap();
        assert_eq!(
            l["rank"].as_i64().unwrap(),
            rank_of(name),
            "{name}: {reveal}"
        );
        assert_eq!(l["score_sum30"].as_i64().unwrap(), sums[name], "{name}");
    }
    assert_eq!(
        rank_of("twin-a"),
        rank_of("twin-b"),
        "the twins tie: {sums:?}"
    );
    assert_eq!(rank_of("ada"), 1, "{sums:?}");
    assert_eq!(rank_of("mover"), 2, "{sums:?}");
    // Public ranks from the public board as everyone saw it, and the moves.
    let (_, open_board) = server
        .get("/api/competitions/night/leaderboard", None)
        .await;
    let public_rank = |name: &str| -> i64 {
        open_board["standings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["entrant"] == name)
            .unwrap()["rank"]
            .as_i64()
            .unwrap()
    };
    assert_eq!(public_rank("mover"), 12, "{public}");
    for l in lines {
        let name = l["entrant"].as_str().unwrap();
        assert_eq!(
            l["public_rank"].as_i64().unwrap(),
            public_rank(name),
            "{name}"
        );
        assert_eq!(
            l["moved"].as_i64().unwrap(),
            public_rank(name) - rank_of(name),
            "{name}"
        );
    }
    let mover = lines.iter().find(|l| l["entrant"] == "mover").unwrap();
    assert_eq!(mover["moved"], 10, "{mover}");
    // Best and worst: the entrant's lowest and highest private score, playable offline.
    for l in lines {
        let (best, worst) = (&l["best"], &l["worst"]);
        assert!(
            best["match_id"].is_i64() && worst["match_id"].is_i64(),
            "{l}"
        );
        assert!(best["score"].as_f64() <= worst["score"].as_f64(), "{l}");
        for m in [best, worst] {
            let play = &reveal["plays"][m["match_id"].as_i64().unwrap().to_string()];
            assert_eq!(play["runners"].as_array().unwrap().len(), 1, "{play}");
        }
    }

    // The race of the 12 on a private maze, against the records.
    let (s, race) = server
        .get("/api/competitions/night/race/priv-a/0", Some(&organiser))
        .await;
    assert_eq!(s, 200, "{race}");
    assert_eq!(race["organiser_copy"], true);
    let runners = race["runners"].as_array().unwrap();
    assert_eq!(runners.len(), 12, "{race}");
    let mut finish: Vec<(i64, i64, String)> = Vec::new();
    for r in runners {
        let (s, m) = server
            .get(&format!("/api/matches/{}", r["match_id"]), Some(ADMIN))
            .await;
        assert_eq!(s, 200, "{m}");
        assert_eq!(m["maze_id"].as_i64(), Some(private[0]), "{m}");
        assert_eq!(r["run1_steps"], m["run1_steps"], "{m}");
        assert_eq!(r["run0_steps"], m["run0_steps"], "{m}");
        assert_eq!(r["score30"].as_i64(), score30(&m), "{m}");
        assert_eq!(
            r["run0"].as_array().unwrap().len() as i64,
            m["run0_steps"].as_i64().unwrap() + 1,
            "{m}"
        );
        assert_eq!(
            r["run1"].as_array().unwrap().len() as i64,
            m["run1_steps"].as_i64().unwrap() + 1,
            "{m}"
        );
        finish.push((
            m["run1_steps"].as_i64().unwrap(),
            score30(&m).unwrap(),
            r["name"].as_str().unwrap().to_string(),
        ));
    }
    finish.sort();
    let expected_finish: Vec<String> = finish.iter().map(|f| f.2.clone()).collect();

    // Chromium: the organiser's rehearsal, last place to first, then the race.
    let Some(b) = Browser::start("the_final_night").await else {
        return;
    };
    browser_login(&b, &base, &organiser).await;
    b.open(&format!("{base}/competitions/night/reveal"), "#reveal-next")
        .await;
    assert!(b.text(".fn-rehearsal").await.contains("held"));
    assert!(
        b.text(".fn-organiser-copy")
            .await
            .contains("not to be shared")
    );
    let groups = reveal_groups(lines);
    check_reveal(&b, &groups, Some("final-night-reveal")).await;
    // A best match plays in the dialog.
    let play = b
        .attr(".reveal-entrant .fn-play-match", "data-match")
        .await
        .unwrap();
    b.click(".reveal-entrant .fn-play-match").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("#reveal-play .fn-race[data-playing]"))
        .await
        .unwrap();
    assert!(play.parse::<i64>().is_ok());
    b.client
        .execute("document.getElementById('reveal-play').close()", vec![])
        .await
        .unwrap();

    let axe = crate::access::axe_source("the_final_night");
    let mut found = Vec::new();
    if let Some(axe) = &axe {
        found.extend(crate::access::violations(&b, axe, "the reveal").await);
        b.open(&format!("{base}/competitions/night/race"), "main")
            .await;
        found.extend(crate::access::violations(&b, axe, "the races").await);
    }
    b.open(
        &format!("{base}/competitions/night/race/priv-a/0"),
        ".fn-race",
    )
    .await;
    if let Some(axe) = &axe {
        found.extend(crate::access::violations(&b, axe, "a race").await);
    }
    assert!(found.is_empty(), "axe-core found:\n{}", found.join("\n"));
    race_to(&b, 0.45).await;
    b.screenshot("final-night-race").await;
    let standing = race_to_end(&b).await;
    let finished: Vec<String> = standing.into_iter().take(expected_finish.len()).collect();
    assert_eq!(
        finished, expected_finish,
        "the race's finish order is the records'"
    );

    // Published: everyone sees the reveal, without the hidden mazes; races of public mazes.
    let a = web
        .post("/competitions/night/publish", None, &[("confirm", "yes")])
        .await;
    assert!(a.status == 401 || a.status == 403, "{}", a.body);
    let (s, v) = server
        .post("/api/competitions/night/publish", json!({}), Some(&other))
        .await;
    assert_eq!(s, 403, "{v}");
    let (s, v) = server
        .post(
            "/api/competitions/night/publish",
            json!({}),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(v["state"], "final", "{v}");
    let (s, v) = server
        .post(
            "/api/competitions/night/publish",
            json!({}),
            Some(&organiser),
        )
        .await;
    assert_eq!(s, 409, "published once: {v}");
    // The organiser's copy, made first, is never what anyone else is answered (the
    // reveals and races are kept a few seconds, by who asks).
    let (s, mine) = server
        .get("/api/competitions/night/reveal", Some(&organiser))
        .await;
    assert_eq!((s, &mine["organiser_copy"]), (200, &json!(true)), "{mine}");
    let (s, mine) = server
        .get("/api/competitions/night/race/priv-a/0", Some(&organiser))
        .await;
    assert_eq!(s, 200, "{mine}");
    for (who, token) in [
        ("anonymous", None),
        ("an entrant", Some(entrant.as_str())),
        ("another organiser", Some(other.as_str())),
    ] {
        let (s, open) = server.get("/api/competitions/night/reveal", token).await;
        assert_eq!(s, 200, "{who}: {open}");
        assert_eq!(open["organiser_copy"], false, "{who}");
        assert_eq!(open["private_hidden"], true, "{who}");
        assert!(
            open["plays"].as_object().unwrap().is_empty(),
            "{who}: no match on a hidden maze"
        );
        for l in open["lines"].as_array().unwrap() {
            assert!(l["best"].is_null() && l["worst"].is_null(), "{who}: {l}");
            let mine = lines.iter().find(|m| m["entrant"] == l["entrant"]).unwrap();
            assert_eq!(
                (&l["rank"], &l["moved"]),
                (&mine["rank"], &mine["moved"]),
                "{who}"
            );
        }
        let (s, races) = server.get("/api/competitions/night/races", token).await;
        assert_eq!(s, 200, "{who}: {races}");
        let sets: Vec<&str> = races["races"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["set"].as_str().unwrap())
            .collect();
        assert_eq!(sets, ["public"], "{who}: {races}");
        let (s, v) = server
            .get("/api/competitions/night/race/priv-a/0", token)
            .await;
        assert_eq!(s, 403, "{who}: {v}");
        let (s, v) = server
            .get("/api/competitions/night/race/pub/0", token)
            .await;
        assert_eq!(s, 200, "{who}: {v}");
        assert_eq!(v["runners"].as_array().unwrap().len(), 12);
    }
    // A competition's tournaments race by its rules: the public set's for anyone, the
    // final run's on a hidden maze for its organisers only.
    let (_, view) = server
        .get("/api/competitions/night", Some(&organiser))
        .await;
    let public_t = view["public_tournament_id"].as_i64().unwrap();
    let (s, v) = server
        .get(
            &format!("/api/tournaments/{public_t}/race/{}/0", maze_id("pub")),
            None,
        )
        .await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(v["runners"].as_array().unwrap().len(), 12);
    let final_match = &race["runners"][0]["match_id"];
    let (_, m) = server
        .get(&format!("/api/matches/{final_match}"), Some(ADMIN))
        .await;
    let final_t = m["tournament_id"].as_i64().unwrap();
    let path = format!("/api/tournaments/{final_t}/race/{}/0", private[0]);
    let (s, v) = server.get(&path, None).await;
    assert_eq!(s, 403, "{v}");
    let (s, v) = server.get(&path, Some(&organiser)).await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(v["runners"].as_array().unwrap().len(), 12);
    for path in [
        "/competitions/night/race/priv-a/0",
        "/competitions/night/race/priv-a/0?download=1",
    ] {
        let a = web.get(path, None).await;
        assert_eq!(a.status, 403, "{path}");
    }
    let a = web.get("/competitions/night/reveal?download=1", None).await;
    assert_eq!(a.status, 200);
    assert!(
        a.headers["content-disposition"]
            .to_str()
            .unwrap()
            .starts_with("attachment")
    );
    assert!(
        !a.body.contains("\"layout\""),
        "no maze in the anonymous reveal's file"
    );
    let session = web.login(&organiser).await;
    let a = web
        .get(
            "/competitions/night/race/priv-a/0?download=1",
            Some(&session),
        )
        .await;
    assert_eq!(a.status, 200);
    assert!(a.body.contains("finale-data") && a.body.contains("\"layout\""));

    // The offline files, from the command line on the server's database.
    let reveal_file = dir.path().join("night-reveal.html");
    let race_file = dir.path().join("night-race.html");
    for args in [
        vec![
            "competition",
            "reveal",
            "night",
            "-o",
            reveal_file.to_str().unwrap(),
            "--database",
            &server.database,
        ],
        vec![
            "competition",
            "race",
            "night",
            "--maze",
            "priv-a",
            "-o",
            race_file.to_str().unwrap(),
            "--database",
            &server.database,
        ],
    ] {
        let out = crate::support::mazearena(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("organiser's copy"));
    }
    let mut server = server;
    server.kill();
    b.open(&format!("file://{}", reveal_file.display()), "#reveal-next")
        .await;
    assert!(
        b.text(".fn-organiser-copy")
            .await
            .contains("not to be shared")
    );
    check_reveal(&b, &groups, None).await;
    b.open(&format!("file://{}", race_file.display()), ".fn-race")
        .await;
    let standing = race_to_end(&b).await;
    let finished: Vec<String> = standing.into_iter().take(expected_finish.len()).collect();
    assert_eq!(finished, expected_finish, "the offline race's finish order");
    let _ = std::fs::copy(&reveal_file, artifacts().join("night-reveal.html"));
    b.quit().await;
}

/// The reveal's groups, last place first: (rank, entrants, moved of each).
fn reveal_groups(lines: &[Value]) -> Vec<(i64, Vec<(String, i64)>)> {
    let mut groups: Vec<(i64, Vec<(String, i64)>)> = Vec::new();
    for l in lines {
        let rank = l["rank"].as_i64().unwrap();
        let e = (
            l["entrant"].as_str().unwrap().to_string(),
            l["moved"].as_i64().unwrap(),
        );
        match groups.last_mut() {
            Some((r, g)) if *r == rank => g.push(e),
            _ => groups.push((rank, vec![e])),
        }
    }
    groups.reverse();
    groups
}

/// Steps through the reveal from the last place to the first, checking each card.
async fn check_reveal(b: &Browser, groups: &[(i64, Vec<(String, i64)>)], shot: Option<&str>) {
    assert_eq!(b.attr("#finale", "data-shown").await.as_deref(), Some("0"));
    for (i, (rank, entrants)) in groups.iter().enumerate() {
        b.click("#reveal-next").await;
        assert_eq!(
            b.attr("#reveal-current", "data-rank").await,
            Some(rank.to_string()),
            "step {i}"
        );
        let cards = b
            .client
            .find_all(Locator::Css("#reveal-current .reveal-entrant"))
            .await
            .unwrap();
        let mut shown = Vec::new();
        for c in &cards {
            shown.push((
                c.attr("data-entrant").await.unwrap().unwrap(),
                c.attr("data-moved")
                    .await
                    .unwrap()
                    .unwrap()
                    .parse::<i64>()
                    .unwrap(),
            ));
        }
        shown.sort();
        let mut want = entrants.clone();
        want.sort();
        assert_eq!(shown, want, "place {rank}");
        if let (Some(name), true) = (shot, *rank == 2) {
            b.screenshot(name).await;
        }
    }
    assert_eq!(
        b.attr("#reveal-next", "disabled").await.as_deref(),
        Some("true")
    );
    let rows = b
        .client
        .find_all(Locator::Css("#reveal-table tbody tr"))
        .await
        .unwrap();
    assert_eq!(rows.len(), groups.iter().map(|g| g.1.len()).sum::<usize>());
    let first = rows[0].attr("data-rank").await.unwrap();
    assert_eq!(first.as_deref(), Some("1"), "the table reads best first");
}

/// Moves the race to `fraction` of its frames.
async fn race_to(b: &Browser, fraction: f64) {
    let last: f64 = b.attr(".fn-slider", "max").await.unwrap().parse().unwrap();
    let frame = (last * fraction) as i64;
    b.client
        .execute(
            "const s = document.querySelector('.fn-slider'); s.value = String(arguments[0]); s.dispatchEvent(new Event('input'));",
            vec![json!(frame)],
        )
        .await
        .unwrap();
}

/// Plays the race to its end (the End key) and reads the standing's names in order.
async fn race_to_end(b: &Browser) -> Vec<String> {
    b.client
        .execute(
            "const r = document.querySelector('.fn-race'); r.focus(); r.dispatchEvent(new KeyboardEvent('keydown', {key: 'End', bubbles: true}));",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(b.attr(".fn-race", "data-run").await.as_deref(), Some("1"));
    let items = b
        .client
        .find_all(Locator::Css(".fn-standing li"))
        .await
        .unwrap();
    let mut names = Vec::new();
    for li in items {
        if li
            .attr("class")
            .await
            .unwrap()
            .unwrap_or_default()
            .contains("fn-row-goal")
        {
            names.push(li.attr("data-name").await.unwrap().unwrap());
        }
    }
    names
}

/// A tournament outside competitions races every bot on one of its mazes, for anyone
/// who sees the tournament; not on a hidden maze.
#[tokio::test]
async fn a_tournaments_race_plays_every_bot_on_one_maze() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let read = |p: &str| std::fs::read_to_string(crate::support::root().join(p)).unwrap();
    let files = json!({
        "dawdler.py": read("tests/fixtures/bots/dawdler.py"),
        "simple_bot.py": read("bots/python/simple_bot.py"),
        "mazebot.py": read("bots/python/mazebot.py"),
    });
    let mut bots = Vec::new();
    for (name, args) in [("quick", "0 0"), ("slow", "60 4"), ("slower", "0 9")] {
        let body =
            json!({"name": name, "command": format!("python3 dawdler.py {args}"), "files": files});
        bots.push(crate::support::upload(&server, body).await.0);
    }
    let mut mazes = Vec::new();
    for (name, hidden, seed) in [("open-12", false, 77), ("secret-12", true, 78)] {
        let layout = numeric::write(&generate(12, seed).unwrap());
        let body = json!({"name": name, "hidden": hidden, "layout": layout});
        let (s, m) = server.post("/api/mazes", body, Some(ADMIN)).await;
        assert_eq!(s, 201, "{m}");
        mazes.push(m["maze_id"].as_i64().unwrap());
    }
    let body = json!({"name": "race-cup", "bot_ids": bots, "maze_ids": mazes, "repeats": 1});
    let (s, t) = server.post("/api/tournaments", body, Some(ADMIN)).await;
    assert_eq!(s, 202, "{t}");
    let id = t["tournament_id"].as_i64().unwrap();
    wait_for(&server, &format!("/api/tournaments/{id}"), None, |v| {
        v["done"].is_i64() && v["done"] == v["total"]
    })
    .await;
    let path = |maze: i64, repeat: i64| format!("/api/tournaments/{id}/race/{maze}/{repeat}");
    let (s, race) = server.get(&path(mazes[0], 0), None).await;
    assert_eq!(s, 200, "{race}");
    let runners = race["runners"].as_array().unwrap();
    assert_eq!(runners.len(), 3, "{race}");
    // Best first, by the exact score from each match's record.
    let mut scores = Vec::new();
    for r in runners {
        let (_, m) = server
            .get(&format!("/api/matches/{}", r["match_id"]), None)
            .await;
        assert_eq!(r["score30"].as_i64(), score30(&m), "{m}");
        scores.push(score30(&m).unwrap());
    }
    assert!(scores.windows(2).all(|w| w[0] <= w[1]), "{scores:?}");
    let names: Vec<&str> = runners
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["quick", "slow", "slower"]);
    // A crowd asking for the same race at once is answered the same (from one making).
    let same = path(mazes[0], 0);
    let crowd = (0..50).map(|_| server.get_text(&same));
    let answers = futures_util::future::join_all(crowd).await;
    assert!(
        answers.iter().all(|a| a.0 == 200 && a.1 == answers[0].1),
        "every answer is the race"
    );
    let (s, v) = server.get(&path(mazes[1], 0), None).await;
    assert_eq!(s, 403, "a hidden maze's race: {v}");
    let (s, v) = server.get(&path(mazes[1], 0), Some(ADMIN)).await;
    assert_eq!(s, 200, "{v}");
    let (s, v) = server.get(&path(mazes[0], 5), None).await;
    assert_eq!(s, 404, "{v}");
    let (s, page) = server.get_text(&format!("/tournaments/{id}")).await;
    assert_eq!(s, 200);
    let link = |maze: i64| format!("/tournaments/{id}/race/{maze}/0");
    assert!(page.contains(&link(mazes[0])), "the page links its race");
    assert!(
        !page.contains(&link(mazes[1])),
        "no race link on a hidden maze"
    );
    let (s, page) = server.get_text(&link(mazes[0])).await;
    assert_eq!(s, 200);
    assert!(page.contains("id=\"finale-data\""));
}
