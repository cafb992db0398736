//! Taking part and organising without a terminal, in a real headless Chromium: a student
//! from the invite code to the final rank, and an organiser from the competition file to
//! the results download. Screenshots go to `target/browser-artifacts/`.

use std::path::Path;
use std::time::{Duration, Instant};

use fantoccini::Locator;
use serde_json::{Value, json};

use super::browser::Browser;
use super::support::{ADMIN, TestServer, root, simple_bot_files};

/// RFC 3339 of unix ms.
fn at(ms: i64) -> String {
    mazearena::competition::Timestamp(ms).rfc3339()
}

/// A generated maze's numeric text.
fn layout(seed: u64) -> String {
    mazearena::engine::mazefile::numeric::write(
        &mazearena::engine::generator::generate(12, seed).unwrap(),
    )
}

/// Opens `url` again and again (the page reloads as a visitor would) until `css` is
/// there, for at most `secs`.
async fn wait_for(b: &Browser, url: &str, css: &str, secs: u64) {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        b.client.goto(url).await.unwrap();
        if b.client.find(Locator::Css(css)).await.is_ok() {
            return;
        }
        if Instant::now() > deadline {
            b.screenshot(&format!(
                "timeout-{}",
                css.replace(|c: char| !c.is_alphanumeric(), "_")
            ))
            .await;
            panic!("{url} never showed {css}: {}", b.source().await);
        }
        tokio::time::sleep(Duration::from_millis(700)).await;
    }
}

/// Waits (at most 10 s) until the browser is at `path` (a form post's redirect done).
async fn wait_at(b: &Browser, path: &str) {
    let deadline = Instant::now() + Duration::from_secs(10);
    while b.client.current_url().await.unwrap().path() != path {
        assert!(Instant::now() < deadline, "never got to {path}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Asserts that a form post ended (post/redirect/get) at `path` with a query that
/// starts with `query`: a reload shows the page again and posts nothing.
async fn assert_after_redirect(b: &Browser, path: &str, query: &str) {
    let url = b.client.current_url().await.unwrap();
    assert_eq!(url.path(), path, "{url}");
    assert!(url.query().unwrap_or("").starts_with(query), "{url}");
}

/// Types `text` into the field `css`.
async fn fill(b: &Browser, css: &str, text: &str) {
    b.client
        .find(Locator::Css(css))
        .await
        .unwrap_or_else(|e| panic!("no {css}: {e}"))
        .send_keys(text)
        .await
        .unwrap();
}

/// Chooses `value` in the select `css`.
async fn choose(b: &Browser, css: &str, value: &str) {
    b.client
        .find(Locator::Css(css))
        .await
        .unwrap_or_else(|e| panic!("no {css}: {e}"))
        .select_by_value(value)
        .await
        .unwrap();
}

/// Chooses the files `paths` in the file input `css`.
async fn attach(b: &Browser, css: &str, paths: &[&Path]) {
    let list: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    fill(b, css, &list.join("\n")).await;
}

/// The browser's session cookie for the server, as a `Cookie` header value.
async fn cookie_header(b: &Browser) -> String {
    b.client
        .get_all_cookies()
        .await
        .unwrap()
        .iter()
        .map(|c| format!("{}={}", c.name(), c.value()))
        .collect::<Vec<_>>()
        .join("; ")
}

#[tokio::test]
async fn a_student_takes_part_from_the_browser_alone() {
    let Some(b) = Browser::start("a_student_takes_part_from_the_browser_alone").await else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    // The organiser's side, done beforehand: invite mode, the competition.
    let (s, _) = server
        .call(
            reqwest::Method::PUT,
            "/api/registration",
            Some(json!({"mode": "invite", "invite_code": "class-of-2026"})),
            Some(ADMIN),
        )
        .await
        .into_pair();
    assert_eq!(s, 200);
    let (s, o) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{o}");
    let organiser = o["key"].as_str().unwrap().to_string();
    let now = mazearena::storage::now_ms();
    let classic =
        std::fs::read_to_string(super::support::shared_maze("classic/test_maze_01.txt")).unwrap();
    let spec = json!({
        "name": "class-cup", "title": "The Class Cup",
        "opens_at": at(now + 1500), "closes_at": at(now + 3_600_000),
        "repeats": 1, "final_repeats": 1,
        "mazes": {
            "practice": [{"name": "classic-1", "layout": classic}],
            "public": [{"name": "pub-1", "layout": layout(7101)}, {"name": "pub-2", "layout": layout(7102)}],
            "private": [{"name": "priv-1", "layout": layout(7103)}, {"name": "priv-2", "layout": layout(7104)}],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    let base = &server.base;

    // Invite code -> register: the key is shown once, with a download, and a session.
    b.open(&format!("{base}/competitions/class-cup"), "#take-part")
        .await;
    b.click("#take-part a[href='/register']").await;
    fill(&b, "input[name=name]", "ada").await;
    fill(&b, "textarea[name=members]", "Ada Lovelace").await;
    fill(&b, "input[name=invite_code]", "class-of-2026").await;
    b.screenshot("student-1-register").await;
    b.click("form button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("#new-key"))
        .await
        .unwrap();
    let key = b.text("#new-key").await;
    assert_eq!(key.len(), 64, "the key is shown: {key:?}");
    assert!(b.attr("a[download]", "href").await.unwrap().ends_with(&key));
    b.screenshot("student-2-key").await;

    // Upload a robot.py of the original task, choosing "original task".
    b.open(&format!("{base}/competitions/class-cup"), "#take-part")
        .await;
    b.click("#take-part a.button").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("form.submit"))
        .await
        .unwrap();
    fill(&b, "input[name=name]", "ada-robot").await;
    attach(
        &b,
        "input[name=files]",
        &[&root().join("tests/fixtures/robot_py/robot.py")],
    )
    .await;
    // The form reads the chosen robot.py, finds its class Robot and ticks "a robot of
    // the original task" itself.
    let deadline = Instant::now() + Duration::from_secs(10);
    while b
        .client
        .execute(
            "return [document.querySelector('input[name=original_task]').checked, document.getElementById('robot-file').value];",
            vec![],
        )
        .await
        .unwrap()
        != json!([true, "robot.py"])
    {
        assert!(Instant::now() < deadline, "the form did not choose robot.py");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    b.screenshot("student-3-submit").await;
    b.click("form.submit button[type=submit]").await;
    // The upload's redirect before the page is read again (leaving earlier would cancel it).
    wait_at(&b, "/me").await;

    // Build and validation shown on "me".
    wait_for(
        &b,
        &format!("{base}/me"),
        ".my-bot details.version .status.ready",
        120,
    )
    .await;
    let log = b.text(".my-bot pre.build-log").await;
    assert!(log.contains("validation match"), "{log}");
    assert!(
        b.text(".my-bot summary")
            .await
            .contains("udacity_adapter.py robot.py")
    );
    b.screenshot("student-4-validated").await;

    // Practice: the match, with the student's stderr in the viewer.
    b.click("form.practice button[type=submit]").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    while !b
        .client
        .current_url()
        .await
        .unwrap()
        .path()
        .starts_with("/matches/")
    {
        assert!(
            Instant::now() < deadline,
            "the practice did not lead to its match"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let deadline = Instant::now() + Duration::from_secs(90);
    loop {
        if b.client.find(Locator::Css("#viewer")).await.is_ok() {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the practice match never showed: {}",
            b.source().await
        );
        tokio::time::sleep(Duration::from_millis(700)).await;
        b.client.refresh().await.unwrap();
    }
    assert!(b.source().await.contains("You own this bot"));
    for _ in 0..3 {
        b.click("#btn-forward").await;
    }
    let step_stderr = b.text("#step-stderr").await;
    assert!(
        step_stderr.contains("robot: run 0 sensors"),
        "{step_stderr}"
    );
    b.screenshot("student-5-practice-stderr").await;

    // Ranked on the public board, and "me" says so.
    wait_for(
        &b,
        &format!("{base}/competitions/class-cup"),
        "table.board td a[href^='/bots/']",
        180,
    )
    .await;
    assert!(b.text("table.board").await.contains("ada"));
    wait_for(&b, &format!("{base}/me"), "table.submissions td.rank", 60).await;
    assert!(b.text("table.submissions td.rank").await.starts_with('1'));
    b.screenshot("student-6-ranked").await;

    // The organiser closes; after the final run the student's final rank is on "me".
    let (s, v) = server
        .call(
            reqwest::Method::PATCH,
            "/api/competitions/class-cup",
            Some(json!({"closes_at": at(mazearena::storage::now_ms())})),
            Some(&organiser),
        )
        .await
        .into_pair();
    assert_eq!(s, 200, "{v}");
    wait_for(&b, &format!("{base}/me"), ".final-result", 180).await;
    let result = b.text(".final-result").await;
    assert!(result.starts_with("Final rank 1"), "{result}");
    b.screenshot("student-7-final").await;
    b.quit().await;
}

#[tokio::test]
async fn an_organiser_runs_a_competition_from_the_browser() {
    let Some(b) = Browser::start("an_organiser_runs_a_competition_from_the_browser").await else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let base = &server.base;

    // The admin: an organiser, and open registration.
    b.open(&format!("{base}/login"), "input[name=key]").await;
    fill(&b, "input[name=key]", ADMIN).await;
    b.click("form button[type=submit]").await;
    // The login's redirect (and its cookie) before the next page.
    wait_at(&b, "/me").await;
    b.open(&format!("{base}/admin"), "form.organiser").await;
    fill(&b, "form.organiser input[name=name]", "teacher").await;
    b.click("form.organiser button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("#new-key"))
        .await
        .unwrap();
    let organiser = b.text("#new-key").await;
    assert_eq!(organiser.len(), 64);
    choose(&b, "form.registration select[name=mode]", "open").await;
    b.click("form.registration button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("p.notice"))
        .await
        .unwrap();
    assert_eq!(b.text(".mode").await, "open");
    // Post/redirect/get: the address bar is the page's, with what was done.
    assert_after_redirect(&b, "/admin", "done=registration").await;
    assert_eq!(b.text("p.notice").await, "Registration is now open.");
    b.screenshot("organiser-1-admin").await;
    b.open(&format!("{base}/me"), "form[action='/logout']")
        .await;
    b.click("form[action='/logout'] button").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    while b.client.current_url().await.unwrap().path() != "/" {
        assert!(
            Instant::now() < deadline,
            "the logout did not end on the home page"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }

    // The organiser logs in and creates the competition from its file and mazes.
    b.open(&format!("{base}/login"), "input[name=key]").await;
    fill(&b, "input[name=key]", &organiser).await;
    b.click("form button[type=submit]").await;
    wait_at(&b, "/me").await;
    let folder = dir.path().join("cup");
    std::fs::create_dir_all(folder.join("mazes")).unwrap();
    let now = mazearena::storage::now_ms();
    let mut paths = Vec::new();
    for (name, seed) in [
        ("practice", 7201),
        ("public-1", 7202),
        ("public-2", 7203),
        ("private-1", 7204),
        ("private-2", 7205),
    ] {
        let p = folder.join("mazes").join(format!("{name}.txt"));
        std::fs::write(&p, layout(seed)).unwrap();
        paths.push(p);
    }
    let file = folder.join("competition.toml");
    std::fs::write(
        &file,
        format!(
            "name = \"web-cup\"\ntitle = \"The Web Cup\"\nopens_at = {}\ncloses_at = {}\n\
             repeats = 1\nfinal_repeats = 1\n\n[mazes]\npractice = [\"mazes/practice.txt\"]\n\
             public = [\"mazes/public-1.txt\", \"mazes/public-2.txt\"]\n\
             private = [\"mazes/private-1.txt\", \"mazes/private-2.txt\"]\n",
            at(now + 1000),
            at(now + 3_600_000)
        ),
    )
    .unwrap();
    b.open(&format!("{base}/organise"), "form.create-competition")
        .await;
    attach(&b, "input[name=competition]", &[&file]).await;
    let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
    attach(&b, "input[name=mazes]", &refs).await;
    b.screenshot("organiser-2-create").await;
    b.click("form.create-competition button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("form.close"))
        .await
        .unwrap_or_else(|e| panic!("no manage page: {e}"));
    let (_, view) = server
        .get("/api/competitions/web-cup", Some(&organiser))
        .await;
    assert_eq!(view["mazes"].as_array().unwrap().len(), 5, "{view}");

    // Two entrants take part (through the API: this test is the organiser's).
    for name in ["ann", "bob"] {
        let (s, e) = server
            .post("/api/entrants", json!({"name": name}), None)
            .await;
        assert_eq!(s, 201, "{e}");
        let key = e["key"].as_str().unwrap().to_string();
        let (s, bot) = server
            .post(
                "/api/bots",
                json!({"name": format!("{name}-bot"), "command": "python3 simple_bot.py", "files": simple_bot_files()}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{bot}");
        let (s, v) = server
            .post(
                "/api/competitions/web-cup/entries",
                json!({"bot_id": bot["bot_id"]}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{v}");
    }
    let manage = format!("{base}/competitions/web-cup/manage");
    wait_for(&b, &manage, "table.entrants .status.ready", 120).await;
    assert_eq!(b.text(".entrants").await, "2");

    // Edit a quota.
    let quota = b
        .client
        .find(Locator::Css("form.edit input[name=versions_per_day]"))
        .await
        .unwrap();
    quota.clear().await.unwrap();
    quota.send_keys("3").await.unwrap();
    b.click("form.edit button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("p.notice"))
        .await
        .unwrap();
    assert_after_redirect(&b, "/competitions/web-cup/manage", "done=saved").await;
    assert_eq!(b.text("p.notice").await, "Saved.");
    let (_, view) = server.get("/api/competitions/web-cup", None).await;
    assert_eq!(view["versions_per_day"], 3, "{view}");

    // Wait until the public set is played, then rejudge ann's version.
    let deadline = Instant::now() + Duration::from_secs(180);
    loop {
        let (_, board) = server
            .get("/api/competitions/web-cup/leaderboard", None)
            .await;
        if board["standings"].as_array().is_some_and(|s| s.len() == 2) {
            break;
        }
        assert!(Instant::now() < deadline, "never ranked: {board}");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    b.client.goto(&manage).await.unwrap();
    b.client
        .find(Locator::Css("form.rejudge-version select"))
        .await
        .unwrap()
        .select_by_label("ann v1")
        .await
        .unwrap();
    fill(
        &b,
        "form.rejudge-version input[name=reason]",
        "a worker lost its disk",
    )
    .await;
    b.click("form.rejudge-version button[type=submit]").await;
    b.client
        .wait()
        .at_most(Duration::from_secs(10))
        .for_element(Locator::Css("table.rejudges"))
        .await
        .unwrap();
    let notice = b.text("p.notice").await;
    assert!(notice.contains("2 matches queued again"), "{notice}");
    assert_after_redirect(&b, "/competitions/web-cup/manage", "done=rejudged&rejudge=").await;
    let (_, rejudges) = server
        .get("/api/competitions/web-cup/rejudges", Some(&organiser))
        .await;
    assert_eq!(rejudges[0]["matches"], 2, "{rejudges}");
    assert_eq!(rejudges[0]["reason"], "a worker lost its disk");
    b.screenshot("organiser-3-rejudge").await;

    // Close now: the box must be ticked (the browser asks), then it closes.
    b.click("form.close button[type=submit]").await;
    let (_, view) = server.get("/api/competitions/web-cup", None).await;
    assert_eq!(view["phase"], "open", "unticked, nothing was sent");
    b.click("form.close input[name=confirm]").await;
    b.click("form.close button[type=submit]").await;
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let notice = match b.client.find(Locator::Css("p.notice")).await {
            Ok(e) => e.text().await.unwrap_or_default(),
            Err(_) => String::new(),
        };
        if notice.starts_with("Closed") {
            break;
        }
        assert!(Instant::now() < deadline, "not closed: {notice}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_after_redirect(&b, "/competitions/web-cup/manage", "done=closed").await;

    // The final run's progress, then the results download.
    wait_for(&b, &manage, "a.results-csv", 240).await;
    assert_eq!(
        b.text(".final-run").await,
        "4 of 4",
        "two entrants on two private mazes"
    );
    b.screenshot("organiser-4-final").await;
    let http = reqwest::Client::new();
    let csv_href = b.attr("a.results-csv", "href").await.unwrap();
    let csv = http
        .get(format!("{base}{csv_href}"))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(csv.lines().count() == 3, "a header and two entrants: {csv}");
    assert!(csv.contains("ann") && csv.contains("bob"), "{csv}");
    // The export, with the browser's session (and refused without it).
    let export_href = b.attr("a.export", "href").await.unwrap();
    let export = http
        .get(format!("{base}{export_href}"))
        .header("cookie", cookie_header(&b).await)
        .send()
        .await
        .unwrap();
    assert_eq!(export.status(), 200);
    let bytes = export.bytes().await.unwrap();
    let mut names = Vec::new();
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(&bytes[..]));
    for e in archive.entries().unwrap() {
        names.push(e.unwrap().path().unwrap().display().to_string());
    }
    assert!(
        names.contains(&"web-cup/competition.toml".to_string()),
        "{names:?}"
    );
    assert_eq!(names.len(), 6, "{names:?}");
    let anonymous = reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .unwrap()
        .get(format!("{base}{export_href}"))
        .send()
        .await
        .unwrap();
    assert_eq!(
        anonymous.status(),
        303,
        "an anonymous visitor is sent to log in"
    );
    // The rejudged matches count once, with their earlier outcome kept.
    let (_, ms) = server.get("/api/matches?limit=100", Some(ADMIN)).await;
    let superseded: Vec<&Value> = ms["items"].as_array().unwrap().iter().collect();
    let mut kept = 0;
    for m in superseded {
        let (_, full) = server
            .get(&format!("/api/matches/{}", m["match_id"]), Some(ADMIN))
            .await;
        kept += full["superseded"].as_array().map_or(0, Vec::len);
    }
    assert_eq!(kept, 2, "two earlier outcomes kept");
    b.quit().await;
}

/// `(status, body)` of a [`TestServer::call`].
trait Pair {
    fn into_pair(self) -> (u16, Value);
}

impl Pair for (u16, Value, reqwest::header::HeaderMap) {
    fn into_pair(self) -> (u16, Value) {
        (self.0, self.1)
    }
}
