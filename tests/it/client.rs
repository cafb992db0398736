//! `mazearena` as a participant's client of a real server: login, submit a folder (its
//! build followed), the version ranked in a competition, practice, matches, a log and
//! a replay, and the server's own message for every refusal.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::support::{TestServer, root};

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
