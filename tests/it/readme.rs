//! The README's examples run as written: its server section against a fresh real
//! server, one command at a time as a user would type them (letting the queued matches
//! and builds finish in between), its local viewer example, and its scale-out example
//! (an API server and a worker on PostgreSQL, each with a data folder of its own).

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::support::{ADMIN, TestServer, root, sandbox};

/// The ```sh blocks of the README section whose heading is `section`.
fn blocks(section: &str) -> Vec<String> {
    blocks_of(section, "sh")
}

/// The ```LANG blocks of the README section whose heading is `section`.
pub(crate) fn blocks_of(section: &str, lang: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut out = Vec::new();
    let mut in_section = false;
    let mut block: Option<String> = None;
    for line in text.lines() {
        if let Some(b) = block.as_mut() {
            if line.starts_with("```") {
                out.push(block.take().unwrap());
            } else {
                b.push_str(line);
                b.push('\n');
            }
            continue;
        }
        if line.starts_with("## ") {
            in_section = line.trim_start_matches("## ") == section;
        } else if in_section && line == format!("```{lang}") {
            block = Some(String::new());
        }
    }
    assert!(
        !out.is_empty(),
        "the README has a section {section:?} with examples"
    );
    out
}

/// Splits a shell block into whole commands (a command may span lines in quotes or
/// after a backslash); comments are dropped.
fn commands(block: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut acc = String::new();
    for line in block.lines() {
        if acc.is_empty() && (line.trim().is_empty() || line.trim_start().starts_with('#')) {
            continue;
        }
        acc.push_str(line);
        acc.push('\n');
        let complete = !line.ends_with('\\')
            && Command::new("bash")
                .args(["-n", "-c", &acc])
                .stderr(std::process::Stdio::null())
                .status()
                .unwrap()
                .success();
        if complete {
            out.push(std::mem::take(&mut acc));
        }
    }
    assert!(acc.is_empty(), "an unfinished command: {acc}");
    out
}

/// Runs one command in bash in `dir`, with `mazearena` being the binary under test.
fn sh(dir: &Path, command: &str, env: &[(&str, &str)]) -> String {
    let script = format!(
        "set -o pipefail\nmazearena() {{ \"{}\" \"$@\"; }}\n{command}",
        env!("CARGO_BIN_EXE_mazearena")
    );
    let out = Command::new("bash")
        .args(["-c", &script])
        .envs(env.iter().copied())
        .env("MAZEARENA_SANDBOX", sandbox().level())
        .current_dir(dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "README command failed:\n{command}\nstdout: {stdout}\nstderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

async fn settle(server: &TestServer) {
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let (_, q) = server.get("/api/matches?status=queued&limit=1", None).await;
        let (_, r) = server
            .get("/api/matches?status=running&limit=1", None)
            .await;
        let (_, bots) = server.get("/api/bots", None).await;
        let building = bots
            .as_array()
            .unwrap()
            .iter()
            .any(|b| b["build_status"] == "building");
        if q["total"] == 0 && r["total"] == 0 && !building {
            return;
        }
        assert!(Instant::now() < deadline, "the queue did not empty");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn the_readme_server_examples_run_as_written_on_a_fresh_server() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "2"]);
    let work = dir.path().join("work");
    std::fs::create_dir_all(&work).unwrap();
    std::os::unix::fs::symlink(root().join("bots"), work.join("bots")).unwrap();
    let addr = server.base.trim_start_matches("http://").to_string();
    let mut token = String::new();
    let mut ran = 0;
    for block in blocks("Running the server") {
        if block.contains("mazearena serve")
            || block.contains("docker compose")
            || block.contains("podman ")
        {
            // The test started the server itself; the container blocks are run by
            // .ci/image.sh.
            continue;
        }
        for command in commands(&block) {
            let command = command.replace("localhost:8080", &addr);
            // The commands share what they set, as in one terminal: $TOKEN is set by
            // the README itself (the admin token is the one its serve line exports).
            let out = sh(
                &work,
                &format!("{command}\necho \"__TOKEN=$TOKEN\""),
                &[("ADMIN", ADMIN), ("TOKEN", &token)],
            );
            if let Some(t) = out
                .lines()
                .find_map(|l| l.strip_prefix("__TOKEN="))
                .filter(|t| !t.is_empty())
            {
                token = t.to_string();
            }
            assert!(
                !out.contains("\"error\":{"),
                "README command answered an error:\n{command}\n{out}"
            );
            assert!(
                !command.contains("$TOKEN") || !token.is_empty(),
                "the README uses $TOKEN before it sets it: {command}"
            );
            ran += 1;
            settle(&server).await;
        }
    }
    assert!(ran >= 12, "only {ran} commands found");
    // What the examples did, checked: the match finished, the C bot was built, the
    // tournament on the hidden maze is complete.
    let (_, m) = server.get("/api/matches/1", None).await;
    assert_eq!(m["status"], "finished", "{m}");
    let (_, c) = server.get("/api/bots/3", None).await;
    assert_eq!(c["versions"][0]["build_status"], "ready", "{c}");
    assert_eq!(
        c["versions"][0]["env_names"],
        serde_json::json!(["BOT_MODE"])
    );
    let (_, t) = server.get("/api/tournaments/1", None).await;
    assert_eq!(t["done"], t["total"], "{t}");
    assert_eq!(t["total"], 6);
}

#[test]
fn the_readme_viewer_example_runs_as_written() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(root().join("bots"), dir.path().join("bots")).unwrap();
    std::os::unix::fs::symlink(root().join("mazes"), dir.path().join("mazes")).unwrap();
    let block = blocks("Testing a bot locally")
        .into_iter()
        .find(|b| b.contains("--html match.html"))
        .expect("the viewer example");
    for command in commands(&block) {
        sh(dir.path(), &command, &[]);
    }
    let html = std::fs::read_to_string(dir.path().join("match.html")).unwrap();
    assert!(html.contains("id=\"replay-data\"") && html.contains("\"maze_layout\""));
    // The viewer made from the replay file is titled with the bot, the maze and the seed.
    let again = std::fs::read_to_string(dir.path().join("match.html")).unwrap();
    assert!(
        again.contains("<title>python3 simple_bot.py on gen-12-s1 (seed 0)"),
        "{}",
        &again[..again.len().min(600)]
    );
}

/// Starts one long-running README command in bash (`mazearena` being the binary under
/// test, which replaces the shell), its output in `log`.
fn spawn_sh(dir: &Path, command: &str, log: &Path) -> std::process::Child {
    let script = format!(
        "mazearena() {{ exec \"{}\" \"$@\"; }}\n{command}",
        env!("CARGO_BIN_EXE_mazearena")
    );
    let out = std::fs::File::create(log).unwrap();
    Command::new("bash")
        .args(["-c", &script])
        .env("MAZEARENA_SANDBOX", sandbox().level())
        .current_dir(dir)
        .stdout(out.try_clone().unwrap())
        .stderr(out)
        .spawn()
        .unwrap()
}

#[tokio::test(flavor = "multi_thread")]
async fn the_readme_scale_out_example_runs_as_written_on_postgresql() {
    let Some((url, _)) =
        crate::faults::postgres("the_readme_scale_out_example_runs_as_written_on_postgresql")
    else {
        return;
    };
    let database = crate::faults::new_database(&url, "readme").await;
    let dir = tempfile::tempdir().unwrap();
    let port = crate::support::free_port();
    let block = blocks("Scaling out: PostgreSQL, API servers and workers").remove(0);
    let cmds = commands(&block);
    assert_eq!(cmds.len(), 2, "{block}");
    // The machine-specific parts replaced: the database, the address and each
    // process's own data folder (they share no disk).
    let mut procs = Vec::new();
    for (k, command) in cmds.iter().enumerate() {
        assert!(command.contains("postgres://"), "{command}");
        let data = dir.path().join(format!("data{k}"));
        let command = command
            .replace(
                "postgres://mazearena:secret@db.example/mazearena",
                &database,
            )
            .replace("0.0.0.0:8080", &format!("127.0.0.1:{port}"))
            .replace("/var/lib/mazearena", data.to_str().unwrap());
        procs.push(spawn_sh(
            dir.path(),
            &command,
            &dir.path().join(format!("{k}.log")),
        ));
    }
    let base = format!("http://127.0.0.1:{port}");
    let client = reqwest::Client::new();
    // The answer's JSON (Null when there is none yet).
    let answer = |req: reqwest::RequestBuilder| async move {
        match req.send().await {
            Ok(resp) => resp.json::<serde_json::Value>().await.unwrap_or_default(),
            Err(_) => serde_json::Value::Null,
        }
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    while answer(client.get(format!("{base}/healthz")))
        .await
        .is_null()
    {
        assert!(Instant::now() < deadline, "the API server did not come up");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let bot = answer(
        client
            .post(format!("{base}/api/bots"))
            .json(&serde_json::json!({
        "name": "simple", "command": "python3 simple_bot.py",
        "files": crate::support::simple_bot_files()})),
    )
    .await;
    let queued = answer(
        client
            .post(format!("{base}/api/matches"))
            .bearer_auth(
                bot["owner_token"]
                    .as_str()
                    .unwrap_or_else(|| panic!("{bot}")),
            )
            .json(&serde_json::json!({"bot_id": bot["bot_id"], "maze_id": 1})),
    )
    .await;
    let id = queued["match_id"]
        .as_i64()
        .unwrap_or_else(|| panic!("{queued}"));
    let deadline = Instant::now() + Duration::from_secs(60);
    let (played, health) = loop {
        let m = answer(client.get(format!("{base}/api/matches/{id}"))).await;
        if m["status"] != "queued" && m["status"] != "running" {
            let health = client
                .get(format!("{base}/healthz"))
                .bearer_auth("use-a-long-random-secret");
            break (m, answer(health).await);
        }
        assert!(Instant::now() < deadline, "the match was not played: {m}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    for p in &mut procs {
        let _ = nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(p.id() as i32),
            nix::sys::signal::Signal::SIGTERM,
        );
    }
    for p in &mut procs {
        assert!(p.wait().unwrap().success());
    }
    assert_eq!(played["status"], "finished", "{played}");
    let workers = health["workers"].as_array().unwrap();
    assert!(
        workers
            .iter()
            .any(|w| w["role"] == "worker" && w["jobs"] == 2),
        "{health}"
    );
}

#[tokio::test(flavor = "multi_thread")]
async fn the_readme_competition_example_runs_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    std::fs::create_dir_all(work.join("maze-cup")).unwrap();
    for link in ["bots", "mazes"] {
        std::os::unix::fs::symlink(root().join(link), work.join(link)).unwrap();
    }
    let database = format!("sqlite://{}", work.join("mazearena.db").display());
    let server = TestServer::start_on(dir.path(), Some(&database), &["--jobs", "2"], &[]);
    let addr = server.base.trim_start_matches("http://").to_string();
    let file = blocks_of("Running a competition", "toml").remove(0);
    std::fs::write(work.join("maze-cup/competition.toml"), file).unwrap();
    // The README read top to bottom: the competition made and entered, a second
    // entrant taking part with the client, then the close.
    let mut blocks = blocks("Running a competition");
    assert_eq!(blocks.len(), 2, "{blocks:?}");
    blocks.extend(self::blocks("Closing a competition"));
    assert_eq!(blocks.len(), 5, "{blocks:?}");
    let run = |block: &str| sh(&work, &block.replace("localhost:8080", &addr), &[]);
    // The mazes and the competition, from its file.
    run(&blocks[0]);
    let (_, c) = server.get("/api/competitions/maze-cup", None).await;
    assert_eq!(
        (c["phase"].as_str(), c["mazes"].as_array().map(Vec::len)),
        (Some("open"), Some(5)),
        "{c}"
    );
    // An entrant enters a bot; it is ranked with nothing done by hand.
    let out = run(&blocks[1]);
    assert!(out.contains("\"competition\":\"maze-cup\""), "{out}");
    let deadline = Instant::now() + Duration::from_secs(180);
    loop {
        let (_, b) = server
            .get("/api/competitions/maze-cup/leaderboard", None)
            .await;
        if b["standings"].as_array().is_some_and(|r| r.len() == 1) {
            assert_eq!(b["standings"][0]["played"], 4, "{b}");
            break;
        }
        assert!(Instant::now() < deadline, "never ranked: {b}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    // A second entrant takes part with the client, as the README's walkthrough says.
    let walkthrough = self::blocks("Take part");
    assert_eq!(walkthrough.len(), 1, "{walkthrough:?}");
    let config = dir.path().join("client.toml");
    let out = sh(
        &work,
        &format!(
            "set -e\n{}",
            walkthrough[0].replace("localhost:8080", &addr)
        ),
        &[("MAZEARENA_CONFIG", config.to_str().unwrap())],
    );
    assert!(
        out.contains("logged in to")
            && out.contains("version 1 is ready")
            && out.contains("mean score"),
        "{out}"
    );
    let html = std::fs::read_to_string(work.join("match.html")).unwrap();
    assert!(html.contains("id=\"replay-data\""));
    loop {
        let (_, b) = server
            .get("/api/competitions/maze-cup/leaderboard", None)
            .await;
        if b["standings"].as_array().is_some_and(|r| r.len() == 2) {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the second entrant never ranked: {b}"
        );
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    // Before the close no bot has played a private maze: no such match exists for
    // anyone (the admin sees every match), and the private board is empty.
    let (_, org) = server
        .get("/api/competitions/maze-cup", Some(crate::support::ADMIN))
        .await;
    let private = crate::support::private_maze_ids(&org);
    assert_eq!(private.len(), 2, "{org}");
    let (_, all) = server
        .get("/api/matches?limit=200", Some(crate::support::ADMIN))
        .await;
    let items = all["items"].as_array().unwrap();
    assert!(!items.is_empty());
    assert!(
        items
            .iter()
            .all(|m| !private.contains(&m["maze_id"].as_i64().unwrap())),
        "a private-set match before the close: {all}"
    );
    let (_, board) = server
        .get("/api/competitions/maze-cup/leaderboard?board=private", None)
        .await;
    assert_eq!(
        (board["sealed"].as_bool(), board["final_run"].is_null()),
        (Some(true), true),
        "{board}"
    );
    // Closed now; the results come after the final run, which the README's `results
    // --wait` waits for.
    run(&blocks[2]);
    let out = run(&blocks[3]);
    let (_, c) = server.get("/api/competitions/maze-cup", None).await;
    assert_eq!(c["state"], "final", "{c}");
    // The final run: 2 entrants' selected versions x 2 private mazes x 3 repeats.
    assert_eq!(
        c["final_run"],
        serde_json::json!({"played": 12, "total": 12}),
        "{c}"
    );
    let (_, board) = server
        .get("/api/competitions/maze-cup/leaderboard?board=private", None)
        .await;
    assert_eq!(
        board["standings"].as_array().map(Vec::len),
        Some(2),
        "{board}"
    );
    let (_, results) = server.get("/api/competitions/maze-cup/results", None).await;
    assert_eq!(results["recount_equal"], true, "{results}");
    assert!(out.contains("team-ada: bot ada-bot"), "the entrants: {out}");
    assert!(
        out.contains("1 of 5 versions used in the last 24 hours"),
        "{out}"
    );
    assert_eq!(
        out.matches("team-ada").count(),
        3,
        "the entrants and the CLI's and the API's CSV: {out}"
    );
    // The final night's offline files: the reveal of both entrants and the race of both
    // on a private maze, each one HTML file with its data inside.
    let out = run(&blocks[4]);
    assert!(out.contains("the reveal of 2 entrants"), "{out}");
    assert!(out.contains("2 robots on private-1 (seed 1)"), "{out}");
    for file in ["maze-cup-reveal.html", "maze-cup-race.html"] {
        let html = std::fs::read_to_string(work.join(file)).unwrap();
        assert!(html.contains("id=\"finale-data\""), "{file}");
        assert!(!html.contains("src=\"http"), "{file} loads nothing");
    }
    // The export makes the same competition again on another database.
    let again = sh(
        &work,
        "mazearena competition create maze-cup-export/competition.toml --database sqlite://other.db",
        &[],
    );
    assert!(again.contains("maze-cup: Closed"), "{again}");
}

/// What the README's examples write in the checkout is ignored by git.
#[test]
fn what_the_readme_examples_write_is_ignored_by_git() {
    let written = [
        "match.html",
        "match.json",
        "bot.tar.gz",
        "c-bot.tar.gz",
        "ada-bot.tar.gz",
        "mazearena.db",
        "mazearena-data/bots/x",
        "maze-cup/mazes/public-1.txt",
        "maze-cup-export/competition.toml",
        "maze-cup-reveal.html",
        "maze-cup-race.html",
        "maze-16.txt",
        "maze-16.svg",
        "tournament.db",
        "mms.db",
        "bots/mms/c/floodfill",
        "bots/c/minimal_bot",
        "bots/cpp/minimal_bot",
        "bots/cpp/mazebot.o",
        "bots/go/minimal_bot",
        "bots/java/classes/MinimalBot.class",
    ];
    for path in written {
        let out = Command::new("git")
            .args(["check-ignore", "--no-index", "-q", path])
            .current_dir(root())
            .status()
            .expect("git runs");
        assert!(out.success(), "{path} is not ignored by .gitignore");
    }
}

/// Each compiled kit's README (C, C++, Go, Java): its build and run blocks work as
/// written, in order, from the repository's root (on a copy of the kit, built from
/// clean). The kits whose toolchain is missing are skipped outside CI only.
#[test]
fn each_compiled_kits_readme_runs_as_written() {
    let kits = crate::bots::available_kits();
    for (kit, built) in [
        ("c", "minimal_bot"),
        ("cpp", "minimal_bot"),
        ("go", "minimal_bot"),
        ("java", "classes/MinimalBot.class"),
    ] {
        if kits.contains(&kit) {
            a_kits_readme_runs_as_written(kit, built);
        }
    }
}

fn a_kits_readme_runs_as_written(kit: &str, built: &str) {
    let dir = tempfile::tempdir().unwrap();
    let repo = dir.path().join("repo");
    std::fs::create_dir_all(repo.join("bots")).unwrap();
    let copied = Command::new("cp")
        .arg("-r")
        .arg(root().join("bots").join(kit))
        .arg(repo.join("bots").join(kit))
        .status()
        .unwrap();
    assert!(copied.success());
    // From clean: what a local build left in the kit is not part of it.
    let _ = std::fs::remove_file(repo.join("bots").join(kit).join(built));
    let _ = std::fs::remove_dir_all(repo.join("bots").join(kit).join("classes"));
    let _ = Command::new("make")
        .args(["-C", &format!("bots/{kit}"), "clean"])
        .current_dir(&repo)
        .output();
    std::os::unix::fs::symlink(root().join("mazes"), repo.join("mazes")).unwrap();
    std::os::unix::fs::symlink(root().join("../shared"), dir.path().join("shared")).unwrap();
    let text = std::fs::read_to_string(root().join("bots").join(kit).join("README.md")).unwrap();
    let mut blocks = Vec::new();
    let mut block: Option<String> = None;
    for line in text.lines() {
        match (&mut block, line) {
            (Some(b), "```") => {
                blocks.push(std::mem::take(b));
                block = None;
            }
            (Some(b), _) => {
                b.push_str(line);
                b.push('\n');
            }
            (None, "```sh") => block = Some(String::new()),
            _ => {}
        }
    }
    // Build, then run (a tournament block writes a database under /tmp: skipped).
    let ran: Vec<&String> = blocks
        .iter()
        .filter(|b| !b.contains("tournament"))
        .take(2)
        .collect();
    assert!(
        ran.len() == 2 && !ran[0].contains("mazearena") && ran[1].contains("mazearena run"),
        "{kit}: {ran:?}"
    );
    for block in ran {
        sh(&repo, block, &[]);
    }
    assert!(repo.join("bots").join(kit).join(built).exists(), "{kit}");
}

/// The README's numpy robot: a venv with numpy, and the adapter running a robot that
/// imports it, as written (pip needs PyPI: outside CI, skipped with the reason if it
/// cannot reach it).
#[test]
fn the_readme_numpy_robot_example_runs_as_written() {
    let block = blocks("Testing a bot locally")
        .into_iter()
        .find(|b| b.contains("pip install"))
        .expect("the numpy example");
    let dir = tempfile::tempdir().unwrap();
    for link in ["bots", "mazes", "tests"] {
        std::os::unix::fs::symlink(root().join(link), dir.path().join(link)).unwrap();
    }
    let mut lines = block.lines();
    let setup = lines.next().unwrap();
    let made = Command::new("bash")
        .args(["-c", setup])
        .current_dir(dir.path())
        .output()
        .unwrap();
    if !made.status.success() {
        let why = String::from_utf8_lossy(&made.stderr).into_owned();
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and the venv cannot be made: {why}"
        );
        eprintln!("SKIPPED the README's numpy example: {why}");
        return;
    }
    let rest: Vec<&str> = lines.collect();
    let out = sh(dir.path(), &rest.join("\n"), &[]);
    assert!(out.contains("Task complete! Score:"), "{out}");
}

/// The README's Python 2.7 runtime: pyenv's 2.7, a virtualenv and numpy 1.16 from the
/// package index, and a Python-2-only robot.py played through it, as written.
#[test]
fn the_readme_python_27_runtime_recipe_runs_as_written() {
    let block = blocks("Testing a bot locally")
        .into_iter()
        .find(|b| b.contains("virtualenv<20.22"))
        .expect("the Python 2.7 recipe");
    let home = std::env::var("PYENV_ROOT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| {
            std::path::PathBuf::from(std::env::var("HOME").unwrap()).join(".pyenv")
        });
    if !home.join("versions/2.7.18/bin/python").exists() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and pyenv's Python 2.7.18 is missing"
        );
        eprintln!("SKIPPED the README's Python 2.7 recipe: no pyenv 2.7.18");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for link in ["bots", "mazes", "tests"] {
        std::os::unix::fs::symlink(root().join(link), dir.path().join(link)).unwrap();
    }
    // Its own folder for the runtime, so that runs at once do not meet.
    let venv = dir.path().join("py27");
    let block = block.replace("/tmp/py27", venv.to_str().unwrap());
    let out = sh(dir.path(), &block, &[]);
    assert!(out.contains("Task complete! Score:"), "{out}");
}

/// The README's local examples that have no test of their own run as written, top to
/// bottom in one folder laid out as the checkout (with ../shared beside it): the
/// adapter's robot.py, the tournament without a server, the maze tools.
#[test]
fn the_readme_local_examples_run_top_to_bottom() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    std::fs::create_dir_all(&work).unwrap();
    for link in ["bots", "mazes", "tests"] {
        std::os::unix::fs::symlink(root().join(link), work.join(link)).unwrap();
    }
    std::os::unix::fs::symlink(root().join("../shared"), dir.path().join("shared")).unwrap();
    let mut ran = 0;
    let _kits = super::support::kits_in_place();
    for section in [
        "Testing a bot locally",
        "Tournaments without a server",
        "Bring your mms mouse",
        "Maze tools",
    ] {
        for block in blocks(section) {
            if has_a_test_of_its_own(&block) {
                continue;
            }
            let out = sh(&work, &block, &[]);
            ran += 1;
            if block.contains("udacity_adapter.py") {
                assert!(out.contains("Task complete! Score:"), "{out}");
            }
            if block.contains("--protocol mms") {
                assert!(out.contains("Task complete! Score: 25.000"), "{out}");
                assert!(
                    out.contains("mms-floodfill-c") && out.contains("mms-floodfill-python"),
                    "{out}"
                );
            } else if block.contains("mazearena tournament") {
                assert!(out.contains("rank") && out.contains("minimal"), "{out}");
            }
            if block.contains("maze solve") {
                assert!(work.join("maze-16.svg").exists(), "{out}");
            }
        }
    }
    assert_eq!(
        ran, 4,
        "the adapter, the tournament, the mms mice, the maze tools"
    );
}

/// Whether a README shell block is run by a test of its own (the viewer, the numpy
/// venv, the Python 2.7 runtime).
fn has_a_test_of_its_own(block: &str) -> bool {
    block.contains("--html match.html") || block.contains("pip install")
}

/// Every shell example of the README is run by a test: by the section tests above, in
/// the README's order, or by `.ci/image.sh` (the container blocks); the Quick start's
/// first command by `the_quick_start_serves_the_demo_as_written`, its second is what CI
/// itself runs (`cargo test`). A new section
/// with examples fails here until a test runs it.
#[test]
fn every_readme_shell_example_is_run_by_a_test() {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let tested = [
        "Quick start",
        "Testing a bot locally",
        "Running the server",
        "Running a competition",
        "Take part",
        "Closing a competition",
        "Scaling out: PostgreSQL, API servers and workers",
        "Tournaments without a server",
        "Bring your mms mouse",
        "Maze tools",
    ];
    let mut section = String::new();
    let mut seen = Vec::new();
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("## ") {
            section = h.to_string();
        } else if line == "```sh" {
            assert!(
                tested.contains(&section.as_str()),
                "the README's section {section:?} has a shell example no test runs"
            );
            seen.push(section.clone());
        }
    }
    for s in tested {
        assert!(
            seen.iter().any(|x| x == s),
            "no shell example left in {s:?}"
        );
    }
    // In reading order, a competition is made and entered, taken part in, then closed.
    let at = |h: &str| text.find(&format!("## {h}\n")).unwrap();
    assert!(
        at("Running a competition") < at("Take part")
            && at("Take part") < at("Closing a competition"),
        "the README closes the competition before its entrants take part"
    );
}

/// The Quick start's first command as written (`cargo run --release -- ARGS`, run as the
/// built binary with ARGS, here on any free port): a demo server whose pages show bots
/// that have played and an open competition; started again it goes on where it was.
#[tokio::test]
async fn the_quick_start_serves_the_demo_as_written() {
    use std::io::BufRead;
    let first = commands(&blocks("Quick start")[0])
        .into_iter()
        .next()
        .unwrap();
    let args: Vec<String> = first
        .trim()
        .strip_prefix("cargo run --release -- ")
        .unwrap_or_else(|| panic!("the Quick start's first command runs the binary: {first}"))
        .split_whitespace()
        .map(str::to_string)
        .collect();
    assert_eq!(args, ["serve", "--demo"], "{first}");
    let dir = tempfile::tempdir().unwrap();
    let start = || {
        let mut child = Command::new(env!("CARGO_BIN_EXE_mazearena"))
            .args(&args)
            .env("MAZEARENA_BIND", "127.0.0.1:0")
            .env("MAZEARENA_SANDBOX", sandbox().level())
            .current_dir(dir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("the server starts");
        let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
        let mut said = String::new();
        while !said.contains("the demo, in") {
            let mut line = String::new();
            assert!(out.read_line(&mut line).unwrap() > 0, "it ended: {said}");
            said.push_str(&line);
        }
        let base = said
            .split("open http://")
            .nth(1)
            .and_then(|rest| rest.split('/').next())
            .map(|addr| format!("http://{addr}"))
            .unwrap_or_else(|| panic!("no address in {said}"));
        (child, base, said)
    };
    let (mut child, base, said) = start();
    assert!(said.contains("competition demo-cup is open"), "{said}");
    let http = reqwest::Client::new();
    let json = |path: String| {
        let http = &http;
        async move {
            http.get(path)
                .send()
                .await
                .unwrap()
                .json::<serde_json::Value>()
                .await
                .unwrap()
        }
    };
    let bots = json(format!("{base}/api/bots")).await;
    let count = bots.as_array().unwrap().len();
    assert!(count >= 4, "the Python kit's bots at least: {bots}");
    let tournament = said
        .split("tournament ")
        .nth(1)
        .and_then(|rest| rest.split(';').next())
        .unwrap()
        .to_string();
    // Within a couple of minutes every bot has played the shipped mazes and is ranked
    // in the open competition.
    let deadline = Instant::now() + Duration::from_secs(240);
    loop {
        let t = json(format!("{base}/api/tournaments/{tournament}")).await;
        let board = json(format!("{base}/api/competitions/demo-cup/leaderboard")).await;
        let ranked = board["standings"].as_array().map_or(0, Vec::len);
        if t["done"] == t["total"]
            && t["total"].as_i64() == Some(9 * count as i64)
            && ranked == count
        {
            break;
        }
        assert!(Instant::now() < deadline, "not played yet: {t} {board}");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    for (path, text) in [
        ("/", "mazearena"),
        ("/competitions/demo-cup", "The Demo Cup"),
        ("/register", "Register"),
    ] {
        let page = http.get(format!("{base}{path}")).send().await.unwrap();
        assert_eq!(page.status(), 200, "{path}");
        assert!(page.text().await.unwrap().contains(text), "{path}");
    }
    let page = http
        .get(format!("{base}/tournaments/{tournament}"))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(page.contains("simple-python"), "{page}");
    // Stopped and started again: the same demo, nothing registered twice.
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGINT,
    )
    .unwrap();
    child.wait().unwrap();
    let (mut child, base, said) = start();
    assert!(said.contains("as it was left"), "{said}");
    let again = json(format!("{base}/api/bots")).await;
    assert_eq!(again.as_array().unwrap().len(), count, "{again}");
    let _ = child.kill();
    let _ = child.wait();
}
