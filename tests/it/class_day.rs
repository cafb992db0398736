//! A class on the day, as its students and its teacher meet the server: names that are
//! one name whatever their case, a crashed practice match that says why, a session that
//! another site's cookie cannot take over, and the name fields the browser checks.

use std::io::{Read, Write};
use std::net::TcpListener;

use fantoccini::Locator;
use serde_json::{Value, json};

use super::browser::Browser;
use super::sessions::Web;
use super::support::{ADMIN, TestServer, mazearena, register, root, simple_bot_files};

/// Registers entrant `name` through the API: its key.
pub(crate) async fn entrant(server: &TestServer, name: &str) -> String {
    let (s, e) = server
        .post("/api/entrants", json!({"name": name}), None)
        .await;
    assert_eq!(s, 201, "{e}");
    e["key"].as_str().unwrap().to_string()
}

#[tokio::test]
async fn names_that_differ_only_in_case_are_one_name() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let key = entrant(&server, "bob").await;
    for other in ["Bob", "BOB", "bOb"] {
        let (s, e) = server
            .post("/api/entrants", json!({"name": other}), None)
            .await;
        assert_eq!(s, 409, "{other}: {e}");
        let message = e["error"]["message"].as_str().unwrap();
        assert!(message.contains("differ only in case"), "{message}");
    }
    let files = simple_bot_files();
    let (s, b) = server
        .post(
            "/api/bots",
            json!({"name": "Runner", "command": "python3 simple_bot.py", "files": files}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{b}");
    let (s, e) = server
        .post(
            "/api/bots",
            json!({"name": "runner", "command": "python3 simple_bot.py", "files": simple_bot_files()}),
            None,
        )
        .await;
    assert_eq!(s, 409, "{e}");
    let (s, _) = server
        .post("/api/organisers", json!({"name": "Teacher"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201);
    let (s, e) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    assert_eq!(s, 409, "{e}");
    // The register form says the same in the page.
    let web = Web::new(&server);
    let page = web.post("/register", None, &[("name", "BoB")]).await;
    assert_eq!(page.status, 409, "{}", page.body);
    assert!(page.body.contains("differ only in case"), "{}", page.body);
}

#[tokio::test]
async fn a_crashed_practice_match_shows_its_owner_why_and_only_a_pruned_one_says_removed() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation", "--jobs", "1"]);
    let files = json!({
        "exits_early.py": std::fs::read_to_string(root().join("tests/fixtures/bots/exits_early.py")).unwrap(),
    });
    let (bot, token) = register(&server, "crasher", "python3 exits_early.py", files).await;
    let id = super::support::queue(&server, bot, 1, 2, &token).await;
    let played = super::support::wait_match(&server, id).await;
    assert_eq!(played["status"], "crashed", "{played}");
    let web = Web::new(&server);
    let owner = web.login(&token).await;
    let page = web.get(&format!("/matches/{id}"), Some(&owner)).await;
    assert_eq!(page.status, 200);
    let body = &page.body;
    assert!(body.contains("Reason: "), "{body}");
    assert!(
        body.contains("The end of its stderr")
            && body.contains("exits_early: giving up at the first sense"),
        "the owner sees the end of its bot's stderr: {body}"
    );
    assert!(!body.contains("was removed"), "{body}");
    assert!(!body.contains("Not played yet"), "{body}");
    // Anyone else: the reason, not the stderr.
    let (_, public) = server.get_text(&format!("/matches/{id}")).await;
    assert!(public.contains("Reason: "), "{public}");
    assert!(!public.contains("giving up"), "{public}");
    assert!(!public.contains("was removed"), "{public}");
    // Pruned: now, and only now, the page says its replay was removed.
    let out = mazearena(&[
        "prune",
        "--database",
        &server.database,
        "--older-than-days",
        "0",
    ]);
    assert!(out.status.success());
    let (_, pruned) = server.get_text(&format!("/matches/{id}")).await;
    assert!(pruned.contains("replay was removed"), "{pruned}");
}

/// Serves a blank page on a port of its own (another "site" on the same host: cookies
/// do not tell ports apart) until the test ends; its address.
fn another_port() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let mut stream = stream;
            let mut buf = [0u8; 4096];
            let _ = stream.read(&mut buf);
            let body = "<html><body>elsewhere</body></html>";
            let _ = stream.write_all(
                format!(
                    "HTTP/1.1 200 OK\r\ncontent-type: text/html\r\nconnection: close\r\ncontent-length: {}\r\n\r\n{body}",
                    body.len()
                )
                .as_bytes(),
            );
        }
    });
    format!("http://{addr}")
}

#[tokio::test]
async fn a_session_cookie_tossed_by_another_site_signs_out_and_https_cookies_are_host_only() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let web = Web::new(&server);
    let victim = entrant(&server, "victim").await;
    let attacker = entrant(&server, "attacker").await;
    let mine = web.login(&victim).await;
    let theirs = web.login(&attacker).await;
    // Two session cookies: which is the visitor's cannot be known, so neither is used.
    let r = web
        .http
        .get(format!("{}/me", server.base))
        .header(
            "cookie",
            format!("mazearena_session={theirs}; mazearena_session={mine}"),
        )
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), 303, "signed out");
    let cleared: Vec<String> = r
        .headers()
        .get_all("set-cookie")
        .iter()
        .map(|v| v.to_str().unwrap().to_string())
        .collect();
    for path in ["Path=/;", "Path=/me;"] {
        assert!(
            cleared.iter().any(|c| c.starts_with("mazearena_session=;")
                && c.contains(path)
                && c.contains("Max-Age=0")),
            "{path}: {cleared:?}"
        );
    }

    // A form posted with both does nothing, for either of them.
    let token = web.get("/me", Some(&mine)).await;
    assert_eq!(token.status, 200);
    let r = web
        .http
        .post(format!("{}/me/key", server.base))
        .header(
            "cookie",
            format!("mazearena_session={theirs}; mazearena_session={mine}"),
        )
        .header("origin", &server.base)
        .form(&[("current_key", victim.as_str())])
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), 401);
    for key in [&victim, &attacker] {
        let (s, _) = server.get("/api/me", Some(key)).await;
        assert_eq!(s, 200, "the key stays");
    }
    // One cookie: signed in as before.
    assert_eq!(web.get("/me", Some(&mine)).await.status, 200);

    // Over HTTPS the cookie is `__Host-`: Secure, Path=/, no Domain.
    let r = web
        .http
        .post(format!("{}/login", server.base))
        .header("x-forwarded-proto", "https")
        .header("origin", &server.base)
        .form(&[("key", victim.as_str())])
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), 303);
    let set = r.headers()["set-cookie"].to_str().unwrap().to_string();
    assert!(set.starts_with("__Host-mazearena_session="), "{set}");
    assert!(
        set.contains("Secure") && set.contains("Path=/;") && !set.contains("Domain"),
        "{set}"
    );
    let secret = set["__Host-mazearena_session=".len()..]
        .split(';')
        .next()
        .unwrap();
    let me = |cookie: String| {
        web.http
            .get(format!("{}/me", server.base))
            .header("x-forwarded-proto", "https")
            .header("cookie", cookie)
            .send()
    };
    assert_eq!(
        me(format!("__Host-mazearena_session={secret}"))
            .await
            .unwrap()
            .status(),
        200
    );
    assert_eq!(
        me(format!("mazearena_session={secret}"))
            .await
            .unwrap()
            .status(),
        303,
        "over HTTPS only the __Host- cookie is the session"
    );
}

/// Whether the field `css`'s value `value` breaks its pattern, as the browser checks it.
async fn pattern_mismatch(b: &Browser, css: &str, value: &str) -> bool {
    b.client
        .execute(
            "const f = document.querySelector(arguments[0]); f.value = arguments[1]; return f.validity.patternMismatch;",
            vec![json!(css), json!(value)],
        )
        .await
        .unwrap()
        .as_bool()
        .unwrap()
}

#[tokio::test]
async fn the_browser_checks_name_fields_and_a_cookie_from_another_port_signs_out() {
    let Some(b) =
        Browser::start("the_browser_checks_name_fields_and_a_cookie_from_another_port_signs_out")
            .await
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let base = &server.base;
    let now = mazearena::storage::now_ms();
    let (_, o) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    let spec = json!({
        "name": "cup", "title": "The Cup",
        "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "mazes": {
            "public": [{"name": "p1", "layout": mazearena::engine::mazefile::numeric::write(
                &mazearena::engine::generator::generate(12, 9001).unwrap())}],
            "private": [{"name": "q1", "layout": mazearena::engine::mazefile::numeric::write(
                &mazearena::engine::generator::generate(12, 9002).unwrap())}],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, o["key"].as_str())
        .await;
    assert_eq!(s, 201, "{c}");

    // The name field's pattern is one the browser compiles, so it checks the field.
    b.open(&format!("{base}/register"), "input[name=name]")
        .await;
    assert!(pattern_mismatch(&b, "input[name=name]", "bad name!").await);
    assert!(!pattern_mismatch(&b, "input[name=name]", "ok-name_1.x").await);

    let victim = entrant(&server, "victim").await;
    let attacker = entrant(&server, "attacker").await;
    let theirs = Web::new(&server).login(&attacker).await;
    b.open(&format!("{base}/login"), "input[name=key]").await;
    b.client
        .find(Locator::Css("input[name=key]"))
        .await
        .unwrap()
        .send_keys(&victim)
        .await
        .unwrap();
    b.click("form button[type=submit]").await;
    // The login's redirect (and its cookie) before the next page.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while b.client.current_url().await.unwrap().path() != "/me" {
        assert!(std::time::Instant::now() < deadline, "never logged in");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    b.open(&format!("{base}/me"), ".who").await;
    assert_eq!(b.text(".who").await, "entrant victim");
    b.open(
        &format!("{base}/competitions/cup/submit"),
        "input[name=name]",
    )
    .await;
    assert!(pattern_mismatch(&b, "input[name=name]", "a bot").await);
    assert!(!pattern_mismatch(&b, "input[name=name]", "a-bot_2.0").await);

    // A page of another port sets a session cookie for the submit form's path.
    let elsewhere = another_port();
    b.client.goto(&elsewhere).await.unwrap();
    b.client
        .execute(
            "document.cookie = arguments[0]; return document.cookie;",
            vec![json!(format!(
                "mazearena_session={theirs}; path=/competitions/cup/submit"
            ))],
        )
        .await
        .unwrap();
    // The submit form is not the attacker's: the visitor is signed out there.
    b.client
        .goto(&format!("{base}/competitions/cup/submit"))
        .await
        .unwrap();
    let url = b.client.current_url().await.unwrap();
    assert_eq!(url.path(), "/login", "sent to log in: {}", b.source().await);
    assert!(!b.source().await.contains("attacker"));
    // And the answer cleared both cookies.
    b.client.goto(&format!("{base}/me")).await.unwrap();
    assert_eq!(b.client.current_url().await.unwrap().path(), "/login");
    let left: Vec<Value> = b
        .client
        .get_all_cookies()
        .await
        .unwrap()
        .iter()
        .map(|c| json!(c.name()))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    b.quit().await;
}

/// A competition open now on two generated public mazes, made by a new organiser: the
/// organiser's key.
pub(crate) async fn open_competition(server: &TestServer, name: &str) -> String {
    let (_, o) = server
        .post(
            "/api/organisers",
            json!({"name": format!("{name}-teacher")}),
            Some(ADMIN),
        )
        .await;
    let key = o["key"].as_str().unwrap().to_string();
    let now = mazearena::storage::now_ms();
    let layout = |dim, seed| {
        mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(dim, seed).unwrap(),
        )
    };
    let layout12 = |seed| layout(12, seed);
    let spec = json!({
        "name": name, "title": "The Class Cup", "repeats": 1,
        "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "mazes": {
            // Two 14x14 practice mazes, as generated practice mazes of another size than
            // the ranking mazes can be: the validation plays them first.
            "practice": [{"name": "warm-up", "layout": layout(14, 9300)}, {"name": "warm-up-2", "layout": layout(14, 9304)}],
            "public": [{"name": "p1", "layout": layout12(9301)}, {"name": "p2", "layout": layout12(9302)}],
            "private": [{"name": "q1", "layout": layout12(9303)}],
        },
    });
    let (s, c) = server.post("/api/competitions", spec, Some(&key)).await;
    assert_eq!(s, 201, "{c}");
    key
}

/// Logs the browser in with `key` (as a new visitor: no cookie of an earlier one) and
/// waits for the redirect to /me.
pub(crate) async fn browser_login(b: &Browser, base: &str, key: &str) {
    b.client.goto(&format!("{base}/favicon.svg")).await.unwrap();
    b.client.delete_all_cookies().await.unwrap();
    b.open(&format!("{base}/login"), "input[name=key]").await;
    b.client
        .find(Locator::Css("input[name=key]"))
        .await
        .unwrap()
        .send_keys(key)
        .await
        .unwrap();
    b.click("form button[type=submit]").await;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while b.client.current_url().await.unwrap().path() != "/me" {
        assert!(std::time::Instant::now() < deadline, "never logged in");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
}

/// Waits (at most `secs`) until competition `name`'s public board ranks `bot`.
pub(crate) async fn wait_ranked(server: &TestServer, name: &str, bot: &str, secs: u64) -> Value {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(secs);
    loop {
        let (_, board) = server
            .get(&format!("/api/competitions/{name}/leaderboard"), None)
            .await;
        if let Some(line) = board["standings"]
            .as_array()
            .and_then(|s| s.iter().find(|l| l["bot_name"] == bot))
        {
            return line.clone();
        }
        assert!(
            std::time::Instant::now() < deadline,
            "{bot} never ranked: {board}"
        );
        tokio::time::sleep(std::time::Duration::from_millis(500)).await;
    }
}

/// Uploads `files` (paths) through the submit form as bot `bot`, an original-task robot,
/// and waits until the form has chosen `robot_file` as the file with class Robot.
async fn upload_robot(
    b: &Browser,
    base: &str,
    competition: &str,
    bot: &str,
    files: &[std::path::PathBuf],
    robot_file: &str,
) {
    b.open(
        &format!("{base}/competitions/{competition}/submit"),
        "form.submit",
    )
    .await;
    b.client
        .find(Locator::Css("input[name=name]"))
        .await
        .unwrap()
        .send_keys(bot)
        .await
        .unwrap();
    let paths: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    b.client
        .find(Locator::Css("input[name=files]"))
        .await
        .unwrap()
        .send_keys(&paths.join("\n"))
        .await
        .unwrap();
    // The form offers the uploaded .py files and chooses the one with class Robot.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    loop {
        let chosen = b
            .client
            .execute(
                "const s = document.getElementById('robot-file'); return [s.value, s.options.length, document.querySelector('input[name=original_task]').checked];",
                vec![],
            )
            .await
            .unwrap();
        if chosen == json!([robot_file, files.len() + 1, true]) {
            break;
        }
        assert!(std::time::Instant::now() < deadline, "{chosen}");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    b.click("form.submit button[type=submit]").await;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while b.client.current_url().await.unwrap().path() != "/me" {
        assert!(
            std::time::Instant::now() < deadline,
            "the upload never ended on /me: {}",
            b.source().await
        );
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
}

#[tokio::test]
async fn robots_shut_out_before_enter_and_are_ranked_through_the_browser() {
    let Some(b) =
        Browser::start("robots_shut_out_before_enter_and_are_ranked_through_the_browser").await
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let base = &server.base;
    open_competition(&server, "final-cup").await;

    // A robot whose file is not robot.py, importing a helper module.
    let key = entrant(&server, "student").await;
    browser_login(&b, base, &key).await;
    let folder = root().join("tests/fixtures/robot_final");
    upload_robot(
        &b,
        base,
        "final-cup",
        "finalist",
        &[folder.join("robot_final.py"), folder.join("astar_final.py")],
        "robot_final.py",
    )
    .await;

    // A robot that raises at its first step on the 14x14 practice mazes only.
    let other = entrant(&server, "sizes").await;
    browser_login(&b, base, &other).await;
    upload_robot(
        &b,
        base,
        "final-cup",
        "two-sizes",
        &[root().join("tests/fixtures/robot_sizes/robot.py")],
        "robot.py",
    )
    .await;

    let line = wait_ranked(&server, "final-cup", "finalist", 180).await;
    assert_eq!(line["played"], 2, "{line}");
    let (_, bot) = server
        .get(&format!("/api/bots/{}", line["bot_id"]), None)
        .await;
    assert_eq!(
        bot["versions"][0]["command"], "python3 udacity_adapter.py robot_final.py",
        "{bot}"
    );
    let line = wait_ranked(&server, "final-cup", "two-sizes", 180).await;
    assert_eq!(line["played"], 2, "{line}");
    // Its owner sees the warning, with the robot's traceback, on its page.
    b.open(&format!("{base}/me"), "section.my-bot").await;
    assert_eq!(b.text("span.warned").await, "with a warning");
    let log = b.text("pre.build-log").await;
    assert!(
        log.contains("KeyError: 14")
            && log.contains("warning: it failed before its first move on the mazes above"),
        "{log}"
    );
    assert!(log.contains("without a fault"), "{log}");
    b.quit().await;
}

/// A competition open now (public and private sets of generated 12x12 mazes from
/// `seed` on), made by organiser key `organiser`.
async fn create_open(server: &TestServer, organiser: &str, name: &str, seed: u64) {
    let now = mazearena::storage::now_ms();
    let layout = |seed| {
        mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, seed).unwrap(),
        )
    };
    let spec = json!({
        "name": name, "title": format!("The {name}"),
        "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "mazes": {
            "public": [{"name": "p1", "layout": layout(seed)}],
            "private": [{"name": "q1", "layout": layout(seed + 1)}],
        },
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(organiser))
        .await;
    assert_eq!(s, 201, "{c}");
}

/// An organiser's key.
async fn organiser(server: &TestServer, name: &str) -> (i64, String) {
    let (s, o) = server
        .post("/api/organisers", json!({"name": name}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{o}");
    (
        o["organiser_id"].as_i64().unwrap(),
        o["key"].as_str().unwrap().to_string(),
    )
}

#[tokio::test]
async fn a_class_link_registers_with_its_competitions_code_and_its_organiser_gives_lost_keys_back()
{
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    // The server's own registration is closed: only a competition's code registers.
    let (s, _, _) = server
        .call(
            reqwest::Method::PUT,
            "/api/registration",
            Some(json!({"mode": "closed"})),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 200);
    let (a_id, a) = organiser(&server, "teacher-a").await;
    let (_, b) = organiser(&server, "teacher-b").await;
    create_open(&server, &a, "cup-a", 9500).await;
    create_open(&server, &b, "cup-b", 9510).await;
    let put = |key: String, body: Value| {
        let server = &server;
        async move {
            let (s, v, _) = server
                .call(
                    reqwest::Method::PUT,
                    "/api/competitions/cup-a/invite",
                    Some(body),
                    Some(&key),
                )
                .await;
            (s, v)
        }
    };
    // Only its organiser (or the admin) sets the code; a random one, then a chosen one.
    assert_eq!(put(b.clone(), json!({})).await.0, 403);
    let (s, random) = put(a.clone(), json!({})).await;
    assert_eq!(s, 200, "{random}");
    let random_code = random["invite_code"].as_str().unwrap().to_string();
    assert_eq!(random_code.len(), 17, "{random}");
    let (s, bad) = put(a.clone(), json!({"invite_code": "a b"})).await;
    assert_eq!(s, 422, "{bad}");
    let (s, set) = put(a.clone(), json!({"invite_code": "class-of-2026"})).await;
    assert_eq!(s, 200, "{set}");
    assert_eq!(
        set["link"],
        "/competitions/cup-a?invite=class-of-2026#take-part"
    );
    let (_, seen) = server.get("/api/competitions/cup-a", None).await;
    assert_eq!(
        (seen["invite_code"].clone(), seen["invite_link"].clone()),
        (Value::Null, Value::Null),
        "{seen}"
    );
    let (_, own) = server.get("/api/competitions/cup-a", Some(&a)).await;
    assert_eq!(own["invite_code"], "class-of-2026");
    // The rotated-away random code registers no one.
    let (s, e) = server
        .post(
            "/api/entrants",
            json!({"name": "late", "invite_code": random_code}),
            None,
        )
        .await;
    assert_eq!(s, 403, "{e}");

    // The class's link: the page carries the code to the registration, which names
    // the competition; the registration leads to the upload.
    let (_, page) = server
        .get_text("/competitions/cup-a?invite=class-of-2026")
        .await;
    assert!(
        page.contains("href=\"/register?invite=class-of-2026\""),
        "{page}"
    );
    let (_, page) = server.get_text("/register?invite=class-of-2026").await;
    assert!(
        page.contains("You are registering for") && page.contains("The cup-a"),
        "{page}"
    );
    assert!(page.contains("value=\"class-of-2026\""), "{page}");
    let (_, page) = server.get_text("/register?invite=not-a-code-at-all").await;
    assert!(page.contains("this invite code is not known"), "{page}");
    let web = Web::new(&server);
    let done = web
        .post(
            "/register",
            None,
            &[("name", "student-1"), ("invite_code", "class-of-2026")],
        )
        .await;
    assert_eq!(done.status, 200, "{}", done.body);
    assert!(
        done.body.contains("href=\"/competitions/cup-a/submit\""),
        "{}",
        done.body
    );
    let (s, e) = server
        .post(
            "/api/entrants",
            json!({"name": "student-2", "invite_code": "class-of-2026"}),
            None,
        )
        .await;
    assert_eq!(s, 201, "{e}");
    assert_eq!(e["competition"], "cup-a");
    let student = e["entrant_id"].as_i64().unwrap();
    let old_key = e["key"].as_str().unwrap().to_string();
    let (s, e) = server
        .post(
            "/api/entrants",
            json!({"name": "stray", "invite_code": "nope-nope-nope"}),
            None,
        )
        .await;
    assert_eq!(s, 403, "{e}");
    assert!(
        e["error"]["message"]
            .as_str()
            .unwrap()
            .contains("not known"),
        "{e}"
    );

    // A lost key: the competition's organiser gives a new one (not another organiser).
    let path = format!("/api/entrants/{student}/key");
    let (s, _) = server.post(&path, json!({}), Some(&b)).await;
    assert_eq!(s, 403);
    let (s, k) = server.post(&path, json!({}), Some(&a)).await;
    assert_eq!(s, 200, "{k}");
    let new_key = k["key"].as_str().unwrap().to_string();
    assert_eq!(server.get("/api/me", Some(&old_key)).await.0, 401);
    assert_eq!(server.get("/api/me", Some(&new_key)).await.0, 200);
    // An entrant that also takes part in another organiser's competition: the admin's.
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "two-cups", "command": "python3 simple_bot.py", "files": simple_bot_files()}),
            Some(&new_key),
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    for cup in ["cup-a", "cup-b"] {
        let (s, v) = server
            .post(
                &format!("/api/competitions/{cup}/entries"),
                json!({"bot_id": bot["bot_id"]}),
                Some(&new_key),
            )
            .await;
        assert_eq!(s, 201, "{v}");
    }
    let (s, refused) = server.post(&path, json!({}), Some(&a)).await;
    assert_eq!(s, 403, "{refused}");
    assert!(
        refused["error"]["message"]
            .as_str()
            .unwrap()
            .contains("the admin"),
        "{refused}"
    );
    assert_eq!(server.post(&path, json!({}), Some(ADMIN)).await.0, 200);

    // The admin's list of entrants, searched; an organiser's key replaced.
    let (s, found) = server
        .get("/api/entrants?search=STUDENT", Some(ADMIN))
        .await;
    assert_eq!(s, 200, "{found}");
    assert_eq!(found["total"], 2, "{found}");
    assert_eq!(server.get("/api/entrants", Some(&a)).await.0, 403);
    let (s, k) = server
        .post(
            &format!("/api/organisers/{a_id}/key"),
            json!({}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 200, "{k}");
    assert_eq!(
        server.get("/api/competitions/cup-a", Some(&a)).await.1["invite_code"],
        Value::Null
    );
    let a = k["key"].as_str().unwrap().to_string();
    assert_eq!(
        server.get("/api/competitions/cup-a", Some(&a)).await.1["invite_code"],
        "class-of-2026"
    );

    // The same from the pages: the admin finds an entrant and gives a new key; the
    // organiser gives one to an entrant of its competition from the manage page.
    let admin = web.login(ADMIN).await;
    let page = web.get("/admin?search=student", Some(&admin)).await;
    assert_eq!(page.status, 200, "{}", page.body);
    assert!(
        page.body.contains("student-1")
            && page.body.contains("student-2")
            && !page.body.contains(">stray<"),
        "{}",
        page.body
    );
    let token = page.csrf();
    let handed = web
        .post(
            &format!("/admin/entrants/{student}/key"),
            Some(&admin),
            &[("csrf", &token)],
        )
        .await;
    assert_eq!(handed.status, 200, "{}", handed.body);
    assert_eq!(handed.headers["cache-control"], "no-store");
    assert!(
        handed.body.contains("A new key for entrant student-2"),
        "{}",
        handed.body
    );
    let (_, one) = server
        .get("/api/entrants?search=student-1", Some(ADMIN))
        .await;
    let first = one["items"][0]["entrant_id"].as_i64().unwrap();
    let mine = web.login(&a).await;
    let manage = web.get("/competitions/cup-a/manage", Some(&mine)).await;
    assert!(
        manage.body.contains("Registered with the invite code"),
        "{}",
        manage.body
    );
    let token = manage.csrf();
    let handed = web
        .post(
            &format!("/competitions/cup-a/entrants/{first}/key"),
            Some(&mine),
            &[("csrf", &token)],
        )
        .await;
    assert_eq!(handed.status, 200, "{}", handed.body);
    assert!(
        handed.body.contains("A new key for entrant student-1"),
        "{}",
        handed.body
    );
    // Another organiser's manage page gives no key to the first's entrants.
    let (_, b_id_key) = organiser(&server, "teacher-c").await;
    let theirs = web.login(&b_id_key).await;
    let refused = web.get("/competitions/cup-a/manage", Some(&theirs)).await;
    assert_eq!(refused.status, 403);

    // Practice mazes come and go while it is open; the validation rule changes.
    let layout = mazearena::engine::mazefile::numeric::write(
        &mazearena::engine::generator::generate(14, 9520).unwrap(),
    );
    let (s, added) = server
        .post(
            "/api/competitions/cup-a/practice",
            json!({"name": "extra", "layout": layout}),
            Some(&a),
        )
        .await;
    assert_eq!(s, 201, "{added}");
    let (s, _) = server
        .post(
            "/api/competitions/cup-a/practice",
            json!({"name": "extra", "layout": layout}),
            Some(&b),
        )
        .await;
    assert_eq!(s, 403);
    let (_, view) = server.get("/api/competitions/cup-a", None).await;
    assert!(
        view["mazes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|m| m["set"] == "practice" && m["maze_id"] == added["maze_id"]),
        "{view}"
    );
    let (s, _, _) = server
        .call(
            reqwest::Method::DELETE,
            &format!("/api/competitions/cup-a/practice/{}", added["maze_id"]),
            None,
            Some(&a),
        )
        .await;
    assert_eq!(s, 204);
    let (_, view) = server.get("/api/competitions/cup-a", None).await;
    assert!(
        !view["mazes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|m| m["set"] == "practice"),
        "{view}"
    );
    assert_eq!(view["validation"], "start");
    let (s, v, _) = server
        .call(
            reqwest::Method::PATCH,
            "/api/competitions/cup-a",
            Some(json!({"validation": "match"})),
            Some(&a),
        )
        .await;
    assert_eq!((s, v["validation"].clone()), (200, json!("match")), "{v}");
    // Removed, the code registers no one.
    let (s, _, _) = server
        .call(
            reqwest::Method::DELETE,
            "/api/competitions/cup-a/invite",
            None,
            Some(&a),
        )
        .await;
    assert_eq!(s, 204);
    let (s, _) = server
        .post(
            "/api/entrants",
            json!({"name": "student-3", "invite_code": "class-of-2026"}),
            None,
        )
        .await;
    assert_eq!(s, 403);
}

/// Presses Tab (at most `max` times) until the focused element matches `css`; how many
/// presses it took.
async fn tab_to(b: &Browser, css: &str, max: usize) -> usize {
    for presses in 0..=max {
        let here = b
            .client
            .execute(
                "return document.activeElement ? document.activeElement.matches(arguments[0]) : false;",
                vec![json!(css)],
            )
            .await
            .unwrap();
        if here == json!(true) {
            return presses;
        }
        keys(b, "\u{e004}").await;
    }
    panic!("{css} is not reached with {max} presses of Tab");
}

/// Types `text` into whatever has the focus (as a keyboard does).
async fn keys(b: &Browser, text: &str) {
    use fantoccini::actions::InputSource;
    let actions = fantoccini::actions::KeyActions::new("keyboard".to_string());
    let mut actions = actions;
    for c in text.chars() {
        actions = actions
            .then(fantoccini::actions::KeyAction::Down { value: c })
            .then(fantoccini::actions::KeyAction::Up { value: c });
    }
    b.client.perform_actions(actions).await.unwrap();
}

#[tokio::test]
async fn a_student_registers_and_submits_with_the_keyboard_alone() {
    let Some(b) = Browser::start("a_student_registers_and_submits_with_the_keyboard_alone").await
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let base = &server.base;
    open_competition(&server, "keys-cup").await;
    // Register: the skip link first, then the form's fields in order, Enter to send.
    b.open(&format!("{base}/register"), "input[name=name]")
        .await;
    keys(&b, "\u{e004}").await;
    let first = b
        .client
        .execute("return document.activeElement.className;", vec![])
        .await
        .unwrap();
    assert_eq!(first, json!("skip"), "the first Tab stop is the skip link");
    keys(&b, "\u{e007}").await; // Enter: to the content
    tab_to(&b, "input[name=name]", 5).await;
    keys(&b, "keyboard-kid").await;
    tab_to(&b, "textarea[name=members]", 2).await;
    keys(&b, "Kim").await;
    tab_to(&b, "form button[type=submit]", 3).await;
    keys(&b, "\u{e007}").await;
    b.client
        .wait()
        .at_most(std::time::Duration::from_secs(10))
        .for_element(Locator::Css("#new-key"))
        .await
        .unwrap();
    // Submit a robot: every field reached with Tab, the file named as a file chooser
    // opened with the keyboard would, the form sent with Enter.
    b.open(
        &format!("{base}/competitions/keys-cup/submit"),
        "form.submit",
    )
    .await;
    tab_to(&b, "input[name=name]", 20).await;
    keys(&b, "kb-robot").await;
    tab_to(&b, "input[name=files]", 3).await;
    let robot = root().join("tests/fixtures/robot_py/robot.py");
    b.client
        .active_element()
        .await
        .unwrap()
        .send_keys(&robot.display().to_string())
        .await
        .unwrap();
    tab_to(&b, "input[name=original_task]", 3).await;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while b
        .client
        .execute("return document.activeElement.checked;", vec![])
        .await
        .unwrap()
        != json!(true)
    {
        assert!(
            std::time::Instant::now() < deadline,
            "the form did not tick it"
        );
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    tab_to(&b, "form.submit button[type=submit]", 10).await;
    keys(&b, "\u{e007}").await;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while b.client.current_url().await.unwrap().path() != "/me" {
        assert!(
            std::time::Instant::now() < deadline,
            "the upload never ended on /me: {}",
            b.source().await
        );
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    wait_ranked(&server, "keys-cup", "kb-robot", 120).await;
    b.quit().await;
}

#[tokio::test]
async fn each_competition_validates_by_its_own_rule_and_its_organiser_changes_it_and_its_practice_mazes()
 {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let (_, teacher) = organiser(&server, "rules-teacher").await;
    let now = mazearena::storage::now_ms();
    let layout = |dim, seed| {
        mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(dim, seed).unwrap(),
        )
    };
    let robot =
        std::fs::read_to_string(root().join("tests/fixtures/robot_sizes/robot.py")).unwrap();
    let mut logs = Vec::new();
    for (i, rule) in ["start", "match", "off"].iter().enumerate() {
        let name = format!("cup-{rule}");
        let seed = 9600 + 10 * i as u64;
        let spec = json!({
            "name": name, "title": name, "validation": rule,
            "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
            "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
            "mazes": {
                "practice": [{"name": "warm-up", "layout": layout(14, seed)}],
                "public": [{"name": "p1", "layout": layout(12, seed + 1)}],
                "private": [{"name": "q1", "layout": layout(12, seed + 2)}],
            },
        });
        let (s, c) = server.post("/api/competitions", spec, Some(&teacher)).await;
        assert_eq!(s, 201, "{c}");
        assert_eq!(c["validation"], *rule);
        // Registered and entered in one step: validated by the competition's rule.
        let key = entrant(&server, &format!("student-{rule}")).await;
        let (s, bot) = server
            .post(
                "/api/bots",
                json!({"name": format!("sizes-{rule}"), "original_task": true,
                       "competition": name, "files": {"robot.py": robot}}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 201, "{bot}");
        let id = bot["bot_id"].as_i64().unwrap();
        let built = super::support::wait_built(&server, id).await;
        let log = super::support::build_log(&server, id, &key).await;
        logs.push((rule.to_string(), built["build_status"].clone(), log));
    }
    let (_, status, log) = &logs[0];
    assert_eq!(status, "ready", "{log}");
    assert!(
        log.contains("KeyError: 14") && log.contains("warning: "),
        "{log}"
    );
    assert!(
        log.contains("public generated 16x16 maze without a fault"),
        "{log}"
    );
    let (_, status, log) = &logs[1];
    assert_eq!(status, "invalid", "{log}");
    assert!(
        log.contains("KeyError: 14") && log.contains("This version is invalid"),
        "{log}"
    );
    assert!(
        !log.contains("16x16"),
        "match: the first practice maze only: {log}"
    );
    let (_, status, log) = &logs[2];
    assert_eq!(status, "ready", "{log}");
    assert!(!log.contains("validation match"), "off: {log}");

    // The organiser's page: practice mazes added and removed, the rule changed; each
    // form answers with the page and what was done.
    let web = Web::new(&server);
    let session = web.login(&teacher).await;
    let token = web
        .get("/competitions/cup-off/manage", Some(&session))
        .await
        .csrf();
    let form = reqwest::multipart::Form::new()
        .text("csrf", token.clone())
        .part(
            "maze",
            reqwest::multipart::Part::text(layout(16, 9700)).file_name("big-one.txt"),
        );
    let added = web
        .http
        .post(format!("{}/competitions/cup-off/practice", server.base))
        .header("cookie", format!("mazearena_session={session}"))
        .header("origin", &server.base)
        .multipart(form)
        .send()
        .await
        .unwrap();
    assert_eq!(added.status(), 303);
    assert_eq!(
        added.headers()["location"],
        "/competitions/cup-off/manage?done=practice_added"
    );
    let (_, view) = server.get("/api/competitions/cup-off", None).await;
    let practice: Vec<Value> = view["mazes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["set"] == "practice")
        .cloned()
        .collect();
    assert_eq!(practice.len(), 2, "{view}");
    let first = practice[0]["maze_id"].to_string();
    let removed = web
        .post(
            "/competitions/cup-off/practice",
            Some(&session),
            &[("csrf", &token), ("remove", &first)],
        )
        .await;
    assert_eq!(removed.status, 303, "{}", removed.body);
    let saved = web
        .post(
            "/competitions/cup-off/edit",
            Some(&session),
            &[("csrf", &token), ("validation", "match")],
        )
        .await;
    assert_eq!(saved.status, 303, "{}", saved.body);
    let (_, view) = server.get("/api/competitions/cup-off", None).await;
    assert_eq!(view["validation"], "match", "{view}");
    let names = practice_names(&view);
    assert_eq!(names, ["big-one"], "{view}");

    // And on the server's machine, the command line.
    let maze_file = dir.path().join("extra-maze.txt");
    std::fs::write(&maze_file, layout(12, 9710)).unwrap();
    let out = mazearena(&[
        "competition",
        "edit",
        "cup-off",
        "--validation",
        "off",
        "--add-practice",
        maze_file.to_str().unwrap(),
        "--remove-practice",
        "big-one",
        "--database",
        &server.database,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, view) = server.get("/api/competitions/cup-off", None).await;
    assert_eq!(view["validation"], "off", "{view}");
    let names = practice_names(&view);
    assert_eq!(names, ["extra-maze"], "{view}");
}

/// The names of a competition's practice mazes in its API view, in order.
fn practice_names(view: &Value) -> Vec<String> {
    view["mazes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["set"] == "practice")
        .map(|m| m["name"].as_str().unwrap().to_string())
        .collect()
}

#[tokio::test]
async fn guessing_invite_codes_through_the_registration_page_spends_guesses_and_the_right_code_never_does()
 {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--logins-per-hour", "3"]);
    let (_, teacher) = organiser(&server, "guess-teacher").await;
    create_open(&server, &teacher, "guess-cup", 9800).await;
    let (s, _, _) = server
        .call(
            reqwest::Method::PUT,
            "/api/competitions/guess-cup/invite",
            Some(json!({"invite_code": "the-right-one"})),
            Some(&teacher),
        )
        .await;
    assert_eq!(s, 200);
    // The page is no free oracle: each wrong code costs a guess, then 429.
    let mut statuses = Vec::new();
    for i in 0..5 {
        let (s, _) = server
            .get_text(&format!("/register?invite=wrong-guess-{i}"))
            .await;
        statuses.push(s);
    }
    assert_eq!(statuses, [200, 200, 200, 429, 429]);
    // The class, from the same address, is not held up by it.
    for _ in 0..5 {
        let (s, page) = server.get_text("/register?invite=the-right-one").await;
        assert_eq!(s, 200);
        assert!(page.contains("You are registering for"), "{page}");
    }
    for i in 0..5 {
        let (s, e) = server
            .post(
                "/api/entrants",
                json!({"name": format!("pupil-{i}"), "invite_code": "the-right-one"}),
                None,
            )
            .await;
        assert_eq!(s, 201, "{e}");
    }
}
