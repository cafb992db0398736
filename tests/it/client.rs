//! `mazearena` as a participant's client of a real server: login, submit a folder (its
//! build followed), the version ranked in a competition, practice, matches, a log and
//! a replay, and the server's own message for every refusal.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::support::{ADMIN, TestServer, root};

/// Runs the client with its login kept in `config`, and no login from the environment.
fn client(config: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args(args)
        .env("MAZEARENA_CONFIG", config)
        .env_remove("MAZEARENA_SERVER")
        .env_remove("MAZEARENA_KEY")
        .envs(env.iter().copied())
        .output()
        .unwrap()
}

fn ok(out: &Output, what: &str) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{what} failed: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn failed(out: &Output, what: &str) -> String {
    assert!(!out.status.success(), "{what} should have failed");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A competition open now on `database`: one practice maze (public), two public-set and
/// one private-set maze (generated, hidden), one version a day.
fn competition(work: &Path, database: &str) {
    let bin = env!("CARGO_BIN_EXE_mazearena");
    for (i, name) in ["public-1", "public-2", "private-1"].iter().enumerate() {
        let out = Command::new(bin)
            .args(["maze", "generate", "--dim", "12", "--seed"])
            .arg((90_001 + i).to_string())
            .arg("-o")
            .arg(work.join(format!("{name}.txt")))
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
    }
    let now = mazearena::storage::now_ms();
    let at = |ms: i64| mazearena::competition::spec::Timestamp(ms).rfc3339();
    std::fs::write(
        work.join("competition.toml"),
        format!(
            "name = \"cli-cup\"\ntitle = \"CLI cup\"\nopens_at = {}\ncloses_at = {}\n\
             repeats = 1\nfinal_repeats = 1\nversions_per_day = 1\npractice_per_day = 5\n\
             [mazes]\npractice = [\"{}\"]\npublic = [\"public-1.txt\", \"public-2.txt\"]\n\
             private = [\"private-1.txt\"]\n",
            at(now - 3_600_000),
            at(now + 30 * 86_400_000),
            root().join("mazes/gen-12-s1.txt").display()
        ),
    )
    .unwrap();
    let out = Command::new(bin)
        .arg("competition")
        .arg("create")
        .arg(work.join("competition.toml"))
        .args(["--database", database])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_participant_submits_follows_the_build_is_ranked_and_reads_a_log_and_a_replay() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    std::fs::create_dir_all(&work).unwrap();
    let database = format!("sqlite://{}", dir.path().join("mazearena.db").display());
    let server = TestServer::start_on(dir.path(), Some(&database), &["--jobs", "2"], &[]);
    competition(&work, &database);
    let config = dir.path().join("home/.config/mazearena/client.toml");
    let key: Value = server
        .client()
        .post(format!("{}/api/entrants", server.base))
        .json(&json!({"name": "team-bea"}))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let key = key["key"].as_str().unwrap().to_string();

    // A wrong key: the server's message, and nothing kept.
    let said = failed(
        &client(
            &config,
            &["login", &server.base, "--key", "not-a-key-of-this-server"],
            &[],
        ),
        "login with a wrong key",
    );
    assert!(
        said.contains("this key is not known on this server") && said.contains("HTTP 401"),
        "{said}"
    );
    assert!(!config.exists());
    // No login: says how.
    let said = failed(&client(&config, &["status"], &[]), "status before login");
    assert!(said.contains("mazearena login"), "{said}");

    let out = ok(
        &client(&config, &["login", &server.base, "--key", &key], &[]),
        "login",
    );
    assert!(out.contains("as entrant team-bea (0 bots)"), "{out}");
    use std::os::unix::fs::PermissionsExt;
    let mode = std::fs::metadata(&config).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, 0o600);

    // Submit the C++ kit (a local build left in the copy is not sent: .gitignore).
    let bot = work.join("my-bot");
    let copied = Command::new("cp")
        .arg("-r")
        .arg(root().join("bots/cpp"))
        .arg(&bot)
        .status()
        .unwrap();
    assert!(copied.success());
    std::fs::write(bot.join("minimal_bot"), "a stale local build").unwrap();
    let out = client(
        &config,
        &["submit", bot.to_str().unwrap(), "--competition", "cli-cup"],
        &[],
    );
    let stdout = ok(&out, "submit");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("uploaded minimal-cpp version 1"),
        "{stdout}"
    );
    assert!(
        stdout.contains("entered minimal-cpp in competition cli-cup"),
        "{stdout}"
    );
    assert!(
        stdout.contains("version 1 is ready: "),
        "{stdout}\n{stderr}"
    );
    assert!(stderr.contains("version 1: building"), "{stderr}");
    let files = std::fs::read_dir(&bot)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            !n.starts_with('.') && n != "minimal_bot" && !n.ends_with(".o")
        })
        .count();
    assert!(
        stderr.contains(&format!("packed {files} files")),
        "{stderr} (expected {files} files)"
    );

    // Ranked on the public board, with nothing done by hand.
    let deadline = Instant::now() + Duration::from_secs(240);
    let status = loop {
        let v: Value =
            serde_json::from_str(&ok(&client(&config, &["status", "--json"], &[]), "status"))
                .unwrap();
        if !v["competitions"][0]["public_board"].is_null() {
            break v;
        }
        assert!(Instant::now() < deadline, "never ranked: {v}");
        tokio::time::sleep(Duration::from_millis(500)).await;
    };
    let line = &status["competitions"][0]["public_board"];
    assert_eq!(
        (line["rank"].as_i64(), line["played"].as_i64()),
        (Some(1), Some(2)),
        "{status}"
    );
    assert_eq!(status["bots"][0]["versions"][0]["build_status"], "ready");
    let text = ok(&client(&config, &["status"], &[]), "status");
    assert!(
        text.contains("entrant team-bea")
            && text.contains("1 of 1 versions used in the last 24 hours")
            && text.contains("public board: rank 1"),
        "{text}"
    );

    // Practice, then the matches, the newest one's log and replay.
    let out = ok(
        &client(&config, &["practice", "--competition", "cli-cup"], &[]),
        "practice",
    );
    assert!(
        out.contains("gen-12-s1") && out.contains("finished") && out.contains("mean score"),
        "{out}"
    );
    let out = ok(&client(&config, &["matches"], &[]), "matches");
    assert!(
        out.contains("minimal-cpp v1") && out.contains("gen-12-s1"),
        "{out}"
    );
    let out = ok(&client(&config, &["logs", "last"], &[]), "logs");
    assert!(out.contains(": finished"), "{out}");
    let html = work.join("match.html");
    ok(
        &client(
            &config,
            &["replay", "last", "-o", html.to_str().unwrap()],
            &[],
        ),
        "replay",
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("id=\"replay-data\"") && page.contains("minimal-cpp v1 on gen-12-s1"),
        "{}",
        &page[..page.len().min(400)]
    );

    // Refusals carry the server's message: a second version today (quota 1), another
    // entrant's match.
    let said = failed(
        &client(&config, &["submit", bot.to_str().unwrap()], &[]),
        "a second version",
    );
    assert!(
        said.contains("1 of 1 versions used in the last 24 hours") && said.contains("HTTP 429"),
        "{said}"
    );
    let said = failed(
        &client(&config, &["logs", "999999"], &[]),
        "the log of a match that does not exist",
    );
    assert!(
        said.contains("no match 999999") && said.contains("HTTP 404"),
        "{said}"
    );

    // Without a key on an open server: the bot is registered anonymously and its owner
    // token kept for the next version.
    let other = dir.path().join("anonymous.toml");
    let py = work.join("py-bot");
    std::fs::create_dir(&py).unwrap();
    for f in ["simple_bot.py", "mazebot.py"] {
        std::fs::copy(root().join("bots/python").join(f), py.join(f)).unwrap();
    }
    std::fs::write(
        py.join("bot.toml"),
        "name = \"anon-py\"\ncommand = \"python3 simple_bot.py\"\n",
    )
    .unwrap();
    let env = [("MAZEARENA_SERVER", server.base.as_str())];
    // A runtime the server does not offer, named in bot.toml: its message.
    std::fs::write(
        py.join("bot.toml"),
        "name = \"anon-py\"\ncommand = \"python3 simple_bot.py\"\nruntime = \"nope\"\n",
    )
    .unwrap();
    let said = failed(
        &client(&other, &["submit", py.to_str().unwrap()], &env),
        "a runtime the server does not offer",
    );
    assert!(
        said.contains("this server has no runtime named \"nope\"") && said.contains("HTTP 422"),
        "{said}"
    );
    std::fs::write(
        py.join("bot.toml"),
        "name = \"anon-py\"\ncommand = \"python3 simple_bot.py\"\n",
    )
    .unwrap();
    let out = ok(
        &client(&other, &["submit", py.to_str().unwrap()], &env),
        "anonymous submit",
    );
    assert!(out.contains("uploaded anon-py version 1"), "{out}");
    let out = ok(
        &client(&other, &["submit", py.to_str().unwrap()], &env),
        "anonymous second version",
    );
    assert!(out.contains("uploaded anon-py version 2"), "{out}");
    let kept = std::fs::read_to_string(&other).unwrap();
    assert!(kept.contains("[bots.anon-py]"), "{kept}");
    // Who a key is: the owner token acts for its bot only; the entrant's key for the
    // entrant's; no key, or a key the server does not know: 401.
    let token = kept
        .split("token = \"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .unwrap()
        .to_string();
    let (s, v) = server.get("/api/me", Some(&token)).await;
    assert_eq!(s, 200, "{v}");
    assert_eq!(v["kind"], "owner");
    let names = |v: &Value| -> Vec<String> {
        v["bots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["name"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(names(&v), vec!["anon-py"]);
    let (_, v) = server.get("/api/me", Some(&key)).await;
    assert_eq!(
        (v["kind"].as_str(), v["entrant"].as_str()),
        (Some("entrant"), Some("team-bea"))
    );
    assert_eq!(names(&v), vec!["minimal-cpp"]);
    assert_eq!(server.get("/api/me", None).await.0, 401);
    assert_eq!(
        server
            .get("/api/me", Some("unknown-key-0123456789"))
            .await
            .0,
        401
    );

    let out = ok(&client(&config, &["logout"], &[]), "logout");
    assert!(out.contains("logged out"), "{out}");
    assert!(!config.exists());
}

/// A text holding what a terminal obeys: an OSC 52 clipboard write (ended by BEL), an
/// erase, CSI as the C1 control U+009B, and a carriage return.
const HOSTILE: &str = "evil\u{1b}]52;c;ZXZpbA==\u{7}\u{1b}[2J\u{9b}31mred\rX";

/// Whether `bytes` hold nothing a terminal acts on but line breaks and tabs: no C0
/// control, no DEL, no C1 control (as UTF-8, `C2 80`..`C2 9F`).
fn assert_inert(bytes: &[u8], what: &str) {
    let text = String::from_utf8_lossy(bytes);
    let bad: Vec<char> = text
        .chars()
        .filter(|&c| (c < ' ' && c != '\n' && c != '\t') || ('\u{7f}'..='\u{9f}').contains(&c))
        .collect();
    assert!(
        bad.is_empty(),
        "{what} printed raw controls {bad:?}: {text:?}"
    );
}

/// Runs the client against the hostile server: whatever the result, stdout and stderr
/// are inert; returns both.
fn inert_run(config: &Path, args: &[&str]) -> (Output, String, String) {
    let out = client(config, args, &[]);
    let what = args.join(" ");
    assert_inert(&out.stdout, &format!("`{what}` (stdout)"));
    assert_inert(&out.stderr, &format!("`{what}` (stderr)"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out, stdout, stderr)
}

/// The escaped form of [`HOSTILE`]'s pieces, as the client shows them.
fn shows_escaped(text: &str, what: &str) {
    for piece in [
        "\\x1b]52;c;ZXZpbA==\\x07",
        "\\x1b[2J",
        "\\u{9b}31m",
        "red\\rX",
    ] {
        assert!(text.contains(piece), "{what} lacks {piece:?}: {text}");
    }
}

/// A server that answers every route the client calls with [`HOSTILE`] in every text:
/// names, statuses, quota messages, a build log, a bot's stderr, refusals.
async fn hostile_server() -> String {
    use axum::http::{Method, StatusCode, Uri};
    use axum::response::{IntoResponse, Response};

    async fn answer(method: Method, uri: Uri) -> Response {
        let h = HOSTILE;
        let ok = |v: Value| (StatusCode::OK, axum::Json(v)).into_response();
        let refuse = |status: StatusCode| {
            (status, axum::Json(json!({"error": {"message": h}}))).into_response()
        };
        let bot = json!({"bot_id": 7, "name": h, "paused": false, "versions": [
            {"version": 1, "build_status": h, "created_at": 0},
            {"version": 2, "build_status": "build_failed", "created_at": 0},
        ]});
        let line = json!({"bot_id": 7, "rank": h, "played": h, "mean_score": 1.0,
            "uncertainty": {"rank_range": h, "low": 0.5, "high": 1.5}});
        let run = json!({"match_id": 11, "bot_id": 7, "maze_id": 3, "bot_version": h,
            "status": h, "score": 1.0, "run0_steps": 9, "run1_steps": 4, "created_at": 0,
            "maze_hidden": false});
        match (method.as_str(), uri.path()) {
            ("GET", "/api/me") => ok(json!({"kind": "entrant", "entrant": h,
                "bots": [{"bot_id": 7, "name": h}]})),
            ("GET", "/api/leaderboard") => ok(json!([line])),
            ("GET", "/api/bots/7") => ok(bot),
            ("POST", "/api/bots") => ok(json!({"bot_id": 7, "version": {"version": 2}})),
            ("GET", "/api/bots/7/versions/2/build-log") => ok(json!({
                "build_log": format!("make: {h}\n\tcc -o bot bot.c\nfailed\u{8}\u{8}ok\n")})),
            ("POST", "/api/competitions/cup/entries") => refuse(StatusCode::CONFLICT),
            ("GET", "/api/competitions") => {
                ok(json!([{"name": "cup", "kind": "competition", "phase": h}]))
            }
            ("GET", "/api/competitions/cup/submissions") => ok(json!({"bot_id": 7,
                "versions_quota": {"message": h}, "practice_quota": {"message": h},
                "versions": [{"version": 1, "status": h}]})),
            ("GET", "/api/competitions/cup/leaderboard") => ok(json!({"standings": [line]})),
            ("GET", "/api/mazes") => ok(json!([
                {"maze_id": 3, "name": h, "optimum": 10, "hidden": false}])),
            ("GET", "/api/matches") => {
                let mut other = run.clone();
                other["match_id"] = json!(10);
                other["maze_id"] = json!(h);
                ok(json!({"items": [run, other]}))
            }
            ("POST", "/api/matches") => ok(json!({"match_id": 11})),
            ("GET", "/api/matches/11") => ok(run),
            ("GET", "/api/matches/11/log") => ok(json!({"status": h, "step": 3,
                "error": {"reason": h}, "redacted": false,
                "stderr_tail": format!("step 1\n\t{h}\r\nstep 2\u{1b}[1A\u{1b}[K")})),
            ("GET", "/api/matches/12") => ok(json!({"match_id": 12, "bot_id": 7})),
            ("GET", "/api/matches/12/log") => {
                ok(json!({"status": "crashed", "error": {"kind": h}}))
            }
            ("GET", "/api/matches/666") => refuse(StatusCode::FORBIDDEN),
            // Not mazearena's JSON: the start of the answer is the message.
            ("GET", "/api/matches/777") => {
                (StatusCode::INTERNAL_SERVER_ERROR, h.to_string()).into_response()
            }
            _ => (StatusCode::NOT_FOUND, "no such route").into_response(),
        }
    }

    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    tokio::spawn(async move {
        axum::serve(listener, axum::Router::new().fallback(answer))
            .await
            .unwrap();
    });
    format!("http://{addr}")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hostile_servers_texts_reach_the_terminal_escaped() {
    let base = hostile_server().await;
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("client.toml");

    let (out, stdout, _) = inert_run(&config, &["login", &base, "--key", "some-key"]);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("as entrant evil\\x1b]52;c;"), "{stdout}");
    shows_escaped(&stdout, "login");

    let (out, stdout, stderr) = inert_run(&config, &["status"]);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    shows_escaped(&stdout, "status");
    for expected in [
        "competition cup (evil\\x1b",
        "  evil\\x1b]52",
        "latest version 1: evil",
    ] {
        assert!(
            stdout.contains(expected),
            "status lacks {expected:?}: {stdout}"
        );
    }
    // As JSON: valid JSON holding the server's texts as they were, escaped as JSON does.
    let (out, stdout, _) = inert_run(&config, &["status", "--json"]);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains("\\u009b") && stdout.contains("\\u001b"),
        "{stdout}"
    );
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["entrant"], HOSTILE);
    assert_eq!(v["competitions"][0]["phase"], HOSTILE);

    let (out, stdout, _) = inert_run(&config, &["matches"]);
    assert!(out.status.success(), "{stdout}");
    shows_escaped(&stdout, "matches");
    // A maze id that is a string: shown as JSON, escaped.
    assert!(stdout.contains("\"evil\\u001b]52"), "{stdout}");

    let (out, stdout, _) = inert_run(&config, &["logs", "11"]);
    assert!(out.status.success(), "{stdout}");
    shows_escaped(&stdout, "logs");
    // The log's own lines and tab are kept; its CR and escapes are not obeyed.
    assert!(
        stdout.contains("step 1\n\tevil\\x1b]52")
            && stdout.contains("red\\rX\\r\nstep 2\\x1b[1A\\x1b[K"),
        "{stdout}"
    );
    let (out, stdout, _) = inert_run(&config, &["logs", "12"]);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains("error: {\"kind\":\"evil\\u001b]52"),
        "{stdout}"
    );

    let (out, stdout, _) = inert_run(&config, &["practice"]);
    assert!(out.status.success(), "{stdout}");
    shows_escaped(&stdout, "practice");
    assert!(stdout.contains("queued 1 match of evil\\x1b"), "{stdout}");

    // Refusals: the server's JSON message, and an answer that is not JSON.
    for (args, status) in [
        (&["logs", "666"][..], "HTTP 403"),
        (&["replay", "666"][..], "HTTP 403"),
        (&["logs", "777"][..], "HTTP 500"),
    ] {
        let (out, _, stderr) = inert_run(&config, args);
        assert!(!out.status.success(), "{args:?} should have failed");
        shows_escaped(&stderr, &format!("{args:?}"));
        assert!(stderr.contains(status), "{args:?}: {stderr}");
    }

    // Submit a new bot, entered in the same step: the build's status and its failed log.
    let bot = dir.path().join("bot");
    std::fs::create_dir(&bot).unwrap();
    std::fs::write(
        bot.join("bot.toml"),
        "name = \"plain\"\ncommand = \"./bot\"\n",
    )
    .unwrap();
    std::fs::write(bot.join("bot.c"), "int main(void) { return 0; }\n").unwrap();
    let (out, stdout, stderr) = inert_run(
        &config,
        &["submit", bot.to_str().unwrap(), "--competition", "cup"],
    );
    assert!(!out.status.success(), "a failed build fails: {stdout}");
    assert!(
        stdout.contains("uploaded plain version 2 (bot 7)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("entered plain in competition cup"),
        "{stdout}"
    );
    shows_escaped(&stderr, "submit");
    assert!(
        stderr.contains("--- build log ---\nmake: evil\\x1b")
            && stderr.contains("\n\tcc -o bot bot.c\nfailed\\x08\\x08ok"),
        "{stderr}"
    );
}

/// A folder holding the shipped simple Python bot and a `bot.toml` with `manifest`.
fn python_bot(dir: &Path, manifest: &str) {
    std::fs::create_dir_all(dir).unwrap();
    for f in ["simple_bot.py", "mazebot.py"] {
        std::fs::copy(root().join("bots/python").join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("bot.toml"), manifest).unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_maze_named_with_escapes_is_shown_escaped_by_practice_and_matches() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1"]);
    let name = "maze\u{1b}]0;pwned\u{7}\u{1b}[2J\u{9b}1m\rX";
    let (status, v) = server
        .post(
            "/api/mazes",
            json!({"name": name, "hidden": false, "generate": {"dim": 12, "seed": 7}}),
            Some(ADMIN),
        )
        .await;
    if status != 201 {
        // A server that refuses such a name: the client's own escaping is tested
        // against a hostile server above.
        assert!(
            (400..500).contains(&status) && v["error"]["message"].is_string(),
            "{status} {v}"
        );
        return;
    }
    let shown = "maze\\x1b]0;pwned\\x07\\x1b[2J\\u{9b}1m\\rX";
    let config = dir.path().join("client.toml");
    let env = [("MAZEARENA_SERVER", server.base.as_str())];
    let bot = dir.path().join("bot");
    python_bot(
        &bot,
        "name = \"plain-py\"\ncommand = \"python3 simple_bot.py\"\n",
    );
    ok(
        &client(&config, &["submit", bot.to_str().unwrap()], &env),
        "submit",
    );
    for args in [&["practice"][..], &["matches"][..]] {
        let out = client(&config, args, &env);
        let stdout = ok(&out, &format!("{args:?}"));
        assert_inert(&out.stdout, &format!("{args:?}"));
        assert_inert(&out.stderr, &format!("{args:?}"));
        assert!(stdout.contains(shown), "{args:?}: {stdout}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submit_sends_no_dot_file_unless_bot_toml_includes_it() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1"]);
    let (_, v) = server
        .post("/api/entrants", json!({"name": "team-dot"}), None)
        .await;
    let key = v["key"].as_str().unwrap().to_string();
    let config = dir.path().join("client.toml");
    ok(
        &client(&config, &["login", &server.base, "--key", &key], &[]),
        "login",
    );
    // A parent folder's .gitignore brings dot-files back; the build lists what arrived.
    let work = dir.path().join("work");
    let bot = work.join("bot");
    let manifest = "name = \"dotty\"\ncommand = \"python3 simple_bot.py\"\nbuild = \"ls -A\"\n";
    python_bot(&bot, manifest);
    std::fs::write(work.join(".gitignore"), "!.env\n!.*\n").unwrap();
    std::fs::write(bot.join(".env"), "TOKEN=not-for-the-server\n").unwrap();
    let stored = |version: i64| {
        let server = &server;
        let key = key.clone();
        async move {
            let (_, me) = server.get("/api/me", Some(&key)).await;
            let id = me["bots"][0]["bot_id"].as_i64().unwrap();
            let (_, bot) = server.get(&format!("/api/bots/{id}"), Some(&key)).await;
            let (_, log) = server
                .get(
                    &format!("/api/bots/{id}/versions/{version}/build-log"),
                    Some(&key),
                )
                .await;
            let v = bot["versions"]
                .as_array()
                .unwrap()
                .iter()
                .find(|v| v["version"] == version)
                .cloned()
                .unwrap();
            (
                v["file_count"].as_i64().unwrap(),
                log["build_log"].as_str().unwrap_or("").to_string(),
                bot["versions"].as_array().unwrap().len(),
            )
        }
    };

    let out = client(&config, &["submit", bot.to_str().unwrap()], &[]);
    ok(&out, "submit without include");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("packed 3 files"),
        "{out:?}"
    );
    let (files, log, _) = stored(1).await;
    assert_eq!(files, 3, "{log}");
    assert!(
        log.contains("simple_bot.py") && !log.contains(".env"),
        "{log}"
    );

    // Named in `include`: sent.
    std::fs::write(
        bot.join("bot.toml"),
        format!("{manifest}include = [\".env\"]\n"),
    )
    .unwrap();
    ok(
        &client(&config, &["submit", bot.to_str().unwrap()], &[]),
        "submit with include",
    );
    let (files, log, _) = stored(2).await;
    assert_eq!(files, 4, "{log}");
    assert!(log.contains(".env"), "{log}");

    // An include outside the folder, or not a regular file: refused before uploading.
    std::fs::write(work.join("secret"), "x").unwrap();
    for (include, why) in [
        ("../secret", "`..` may not be used"),
        ("/etc/passwd", "an absolute path may not be used"),
        (".missing", "there is no such file"),
    ] {
        std::fs::write(
            bot.join("bot.toml"),
            format!("{manifest}include = [{include:?}]\n"),
        )
        .unwrap();
        let said = failed(
            &client(&config, &["submit", bot.to_str().unwrap()], &[]),
            include,
        );
        assert!(said.contains(why), "{include}: {said}");
    }
    let (_, _, versions) = stored(2).await;
    assert_eq!(versions, 2);
}

/// A robot.py written for Python 2, submitted with `python3` (as a student of the
/// original task does): its validation match at upload crashes, so the version is
/// `invalid`, never plays and costs no quota; `submit` fails with the SyntaxError and
/// the hint, and the API, `status` and the bot's page say so.
#[tokio::test]
async fn a_python_2_robot_submitted_with_python3_is_invalid_at_upload_with_its_syntax_error() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1"]);
    let config = dir.path().join("client.toml");
    let bot = dir.path().join("py2");
    std::fs::create_dir(&bot).unwrap();
    std::fs::copy(
        root().join("bots/python/udacity_adapter.py"),
        bot.join("udacity_adapter.py"),
    )
    .unwrap();
    std::fs::copy(
        root().join("tests/fixtures/robot_py/py2_robot.py"),
        bot.join("robot.py"),
    )
    .unwrap();
    std::fs::write(
        bot.join("bot.toml"),
        "name = \"py2-robot\"\ncommand = \"python3 udacity_adapter.py robot.py\"\n",
    )
    .unwrap();
    let env = [("MAZEARENA_SERVER", server.base.as_str())];
    let out = client(&config, &["submit", bot.to_str().unwrap()], &env);
    let said = failed(&out, "submitting a Python 2 robot with python3");
    assert_eq!(
        out.status.code(),
        Some(1),
        "a version that cannot play exits 1"
    );
    assert!(said.contains("SyntaxError"), "{said}");
    assert!(said.contains("is this Python 2?"), "{said}");
    assert!(said.contains("version 1 is invalid"), "{said}");
    // The API: invalid, with the log; no match may be asked of it.
    let (_, bots) = server.get("/api/bots", None).await;
    let id = bots["items"]
        .as_array()
        .or(bots.as_array())
        .unwrap()
        .iter()
        .find(|b| b["name"] == "py2-robot")
        .unwrap()["bot_id"]
        .as_i64()
        .unwrap();
    let (_, b) = server.get(&format!("/api/bots/{id}"), None).await;
    assert_eq!(b["versions"][0]["build_status"], "invalid", "{b}");
    let kept = std::fs::read_to_string(&config).unwrap();
    let token = kept
        .split("token = \"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .unwrap()
        .to_string();
    let (s, log) = server
        .get(
            &format!("/api/bots/{id}/versions/1/build-log"),
            Some(&token),
        )
        .await;
    assert_eq!(s, 200, "{log}");
    let text = log["build_log"].as_str().unwrap();
    assert!(
        text.contains("[validation match on a public generated 12x12 maze: crashed")
            && text.contains("SyntaxError"),
        "{text}"
    );
    let (s, v) = server
        .post(
            "/api/matches",
            json!({"bot_id": id, "maze_id": 1, "seed": 1}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 409, "{v}");
    assert!(
        v["error"]["message"]
            .as_str()
            .unwrap()
            .contains("failed its validation match"),
        "{v}"
    );
    // `status` shows it, and so does the bot's page.
    let out = ok(&client(&config, &["status"], &env), "status");
    assert!(out.contains("invalid"), "{out}");
    let (_, page) = server.get_text(&format!("/bots/{id}")).await;
    assert!(page.contains("invalid"), "{page}");
}
