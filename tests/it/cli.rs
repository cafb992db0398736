//! The `mazearena` binary end to end: `run` with real bots, the maze tools, and
//! clear errors for bad mazes and bad arguments.

use std::path::PathBuf;

use serde_json::Value;

use crate::support::{mazearena, mazearena_json, root, shared_maze};

fn classic_path(n: u32) -> String {
    shared_maze(&format!("classic/test_maze_0{n}.txt"))
        .display()
        .to_string()
}

fn run_json(maze: &str, bot: &str) -> Value {
    let out = mazearena(&["run", "--maze", maze, "--bot", bot, "--json"]);
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        stdout.lines().count(),
        1,
        "exactly one JSON object: {stdout}"
    );
    serde_json::from_str(&stdout).unwrap()
}

/// Checks a finished result against the score formula of RULES.md.
fn assert_finished(v: &Value) -> f64 {
    assert_eq!(v["status"], "finished", "{v}");
    let run0 = v["run0_steps"].as_u64().unwrap() as f64;
    let run1 = v["run1_steps"].as_u64().unwrap() as f64;
    let score = v["score"].as_f64().unwrap();
    assert!((score - (run1 + run0 / 30.0)).abs() < 0.0005, "{v}");
    assert_eq!(v["total_steps"].as_f64().unwrap(), run0 + run1);
    assert!(v["warnings"].as_array().unwrap().is_empty());
    assert!(v["error"].is_null());
    score
}

/// A Python 2.7 interpreter, if this machine has one.
fn python2() -> Option<String> {
    let mut candidates = vec!["python2.7".to_string(), "python2".to_string()];
    if let Some(home) = std::env::var_os("HOME") {
        let versions = PathBuf::from(home).join(".pyenv/versions");
        if let Ok(entries) = std::fs::read_dir(versions) {
            for e in entries.flatten() {
                if e.file_name().to_string_lossy().starts_with("2.7") {
                    candidates.push(e.path().join("bin/python2.7").display().to_string());
                }
            }
        }
    }
    candidates.into_iter().find(|c| {
        std::process::Command::new(c)
            .args(["-c", "import sys; assert sys.version_info[0] == 2"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

#[test]
fn the_simple_python_bot_finishes_the_classic_mazes() {
    for n in 1..=3 {
        let v = run_json(&classic_path(n), "python3 bots/python/simple_bot.py");
        let score = assert_finished(&v);
        // No bot can beat the optimum: run 1 alone needs 17 / 22 / 25 steps.
        let floor = [17.0, 22.0, 25.0][n as usize - 1];
        assert!(score > floor, "maze {n}: {score}");
    }
}

#[test]
fn the_adapter_runs_an_unchanged_robot_py_that_prints_on_every_step() {
    for n in 1..=3 {
        let v = run_json(
            &classic_path(n),
            "python3 bots/python/udacity_adapter.py tests/fixtures/robot_py/robot.py",
        );
        assert_finished(&v);
        // The robot's prints went to stderr, not into the protocol.
        assert!(v["stderr_tail"].as_str().unwrap().contains("robot:"));
        same_without_the_sandbox(
            &v,
            &classic_path(n),
            "python3 bots/python/udacity_adapter.py tests/fixtures/robot_py/robot.py",
        );
    }
}

#[test]
fn the_adapter_runs_under_python_2_7() {
    let Some(py2) = python2() else {
        eprintln!("SKIPPED the_adapter_runs_under_python_2_7: no python2.7 on this machine");
        return;
    };
    for n in 1..=3 {
        let bot = format!("{py2} bots/python/udacity_adapter.py tests/fixtures/robot_py/robot.py");
        let inside = run_json(&classic_path(n), &bot);
        assert_finished(&inside);
        same_without_the_sandbox(&inside, &classic_path(n), &bot);
    }
}

/// Plays `bot` again with `--sandbox none` and checks the same steps and score.
fn same_without_the_sandbox(inside: &Value, maze: &str, bot: &str) {
    if inside["limits"]["sandbox"] != "full" {
        return;
    }
    let out = mazearena(&[
        "run",
        "--maze",
        maze,
        "--bot",
        bot,
        "--json",
        "--sandbox",
        "none",
    ]);
    let outside: Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in ["status", "score", "run0_steps", "run1_steps", "total_steps"] {
        assert_eq!(
            inside[k], outside[k],
            "{k} differs inside the sandbox for {bot}"
        );
    }
}

#[test]
fn the_adapter_makes_a_randomized_robot_reproducible_from_the_seed() {
    let maze = classic_path(2);
    let bot = "python3 bots/python/udacity_adapter.py tests/fixtures/robot_py/robot.py";
    let run = |seed: &str| {
        let out = mazearena(&[
            "run", "--maze", &maze, "--bot", bot, "--json", "--seed", seed,
        ]);
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            v["run0_steps"].clone(),
            v["run1_steps"].clone(),
            v["stderr_tail"].clone(),
        )
    };
    assert_eq!(run("5"), run("5"));
}

#[test]
fn run_prints_progress_and_the_score_like_the_original_tester() {
    let out = mazearena(&[
        "run",
        "--maze",
        &classic_path(1),
        "--bot",
        "python3 bots/python/simple_bot.py",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("Starting run 0."), "{text}");
    assert!(text.contains("Starting run 1."), "{text}");
    let score_line = text
        .lines()
        .find(|l| l.starts_with("Task complete! Score: "))
        .unwrap();
    let score = score_line.trim_start_matches("Task complete! Score: ");
    assert_eq!(
        score.split('.').nth(1).map(str::len),
        Some(3),
        "3 decimals: {score}"
    );
}

#[test]
fn run_writes_a_replay_with_every_step() {
    let dir = tempfile::tempdir().unwrap();
    let replay = dir.path().join("replay.json");
    let out = mazearena(&[
        "run",
        "--maze",
        &classic_path(1),
        "--bot",
        "python3 bots/python/simple_bot.py",
        "--seed",
        "3",
        "--replay",
        replay.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&std::fs::read(&replay).unwrap()).unwrap();
    let trace = v["trace"].as_array().unwrap();
    assert_eq!(trace.len() as u64, v["total_steps"].as_u64().unwrap());
    assert_eq!(trace[0]["sensors"], serde_json::json!([0, 11, 0]));
    assert_eq!(trace[0]["step"], 1);
    assert_eq!(v["seed"], 3);
    for key in ["position", "heading", "action", "answer_us", "run"] {
        assert!(!trace[0][key].is_null(), "{key} missing in {}", trace[0]);
    }
    assert_eq!(v["maze_hash"].as_str().unwrap().len(), 64);
    assert!(v["engine_version"].is_string());
    assert!(v["limits"]["move_timeout_ms"].is_u64());
}

#[test]
fn run_reports_a_failing_bot_with_exit_0_and_its_status() {
    let v = run_json(&classic_path(1), "python3 tests/fixtures/bots/not_json.py");
    assert_eq!(v["status"], "protocol_error");
    assert!(v["score"].is_null());
    assert_eq!(v["total_steps"], 1);
    assert!(v["error"]["reason"].as_str().unwrap().contains("not JSON"));
}

#[test]
fn run_refuses_a_bad_maze_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "4\n1,5,7,5\n3,5,14\n").unwrap();
    let out = mazearena(&[
        "run",
        "--maze",
        bad.to_str().unwrap(),
        "--bot",
        "python3 x.py",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("line 3"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn run_refuses_bad_arguments() {
    let out = mazearena(&["run", "--maze", &classic_path(1)]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--bot"));
    let out = mazearena(&[
        "run",
        "--maze",
        &classic_path(1),
        "--bot",
        "x",
        "--seed",
        "abc",
    ]);
    assert!(!out.status.success());
    let out = mazearena(&[
        "run",
        "--maze",
        &classic_path(1),
        "--bot",
        "x",
        "--bot-dir",
        "/nonexistent",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("does not exist"));
}

/// One bad file per case of RULES.md "Maze file"; each error must name its line.
#[test]
fn every_bad_maze_case_names_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(shared_maze("classic/test_maze_01.txt")).unwrap();
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    let with = |edit: &dyn Fn(&mut Vec<String>)| {
        let mut l = lines.clone();
        edit(&mut l);
        l.join("\n") + "\n"
    };
    let mut big = good.repeat(10 * 1024 * 1024 / good.len() + 1);
    big.truncate(10 * 1024 * 1024);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "too few rows",
            with(&|l| {
                l.pop();
            })
            .into_bytes(),
            "line 13",
        ),
        (
            "too many rows",
            with(&|l| l.push(l[1].clone())).into_bytes(),
            "line 14",
        ),
        (
            "too few numbers",
            with(&|l| l[3] = "1,5,7".into()).into_bytes(),
            "line 4",
        ),
        (
            "too many numbers",
            with(&|l| l[4].push_str(",5")).into_bytes(),
            "line 5",
        ),
        (
            "not a number",
            with(&|l| l[5] = l[5].replacen("5", "x", 1)).into_bytes(),
            "line 6",
        ),
        (
            "value over 15",
            with(&|l| l[6] = l[6].replacen("5", "16", 1)).into_bytes(),
            "line 7",
        ),
        ("CRLF", good.replace('\n', "\r\n").into_bytes(), "line 1"),
        (
            "blank trailing lines",
            format!("{good}\n\n").into_bytes(),
            "line 14",
        ),
        ("10 MB file", big.into_bytes(), "line "),
        ("empty file", Vec::new(), "line 1"),
        ("odd side", b"3\n0,0,0\n0,0,0\n0,0,0\n".to_vec(), "line 1"),
        (
            "open perimeter",
            with(&|l| l[1] = l[1].replacen("1", "9", 1)).into_bytes(),
            "line 2",
        ),
        // (0,0) is 1 in maze 01; making it 3 opens its right side while (1,0) stays closed.
        (
            "inconsistent wall",
            with(&|l| l[1] = l[1].replacen("1", "3", 1)).into_bytes(),
            "line 2",
        ),
    ];
    lines.clear();
    for (name, bytes, want) in cases {
        let path = dir.path().join("maze.txt");
        std::fs::write(&path, &bytes).unwrap();
        let out = mazearena(&["maze", "validate", path.to_str().unwrap()]);
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
        if name == "inconsistent wall" {
            assert!(
                err.contains("(0, 0)") && err.contains("(1, 0)"),
                "{name}: {err}"
            );
        }
    }
}

#[test]
fn validate_strict_checks_the_task_rules() {
    let out = mazearena(&["maze", "validate", "--strict", &classic_path(1)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A valid 2x2 maze is playable but not a task maze.
    let dir = tempfile::tempdir().unwrap();
    let tiny = dir.path().join("tiny.txt");
    std::fs::write(&tiny, "2\n3,6\n9,12\n").unwrap();
    assert!(
        mazearena(&["maze", "validate", tiny.to_str().unwrap()])
            .status
            .success()
    );
    let out = mazearena(&["maze", "validate", "--strict", tiny.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("12 <= n <= 16") && err.contains("wall on its right"),
        "{err}"
    );
}

#[test]
fn generated_mazes_pass_strict_validation_and_are_reproducible() {
    let dir = tempfile::tempdir().unwrap();
    for dim in [12, 14, 16] {
        for seed in 0..12 {
            let path = dir.path().join(format!("g{dim}-{seed}.txt"));
            let p = path.to_str().unwrap();
            let out = mazearena(&[
                "maze",
                "generate",
                "--dim",
                &dim.to_string(),
                "--seed",
                &seed.to_string(),
                "-o",
                p,
            ]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let out = mazearena(&["maze", "validate", "--strict", p]);
            assert!(
                out.status.success(),
                "dim {dim} seed {seed}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    let a = mazearena(&["maze", "generate", "--dim", "14", "--seed", "99"]).stdout;
    let b = mazearena(&["maze", "generate", "--dim", "14", "--seed", "99"]).stdout;
    let c = mazearena(&["maze", "generate", "--dim", "14", "--seed", "100"]).stdout;
    assert_eq!(a, b);
    assert_ne!(a, c);
    let out = mazearena(&["maze", "generate", "--dim", "13", "--seed", "1"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn solve_gives_the_reference_figures() {
    for (n, want) in [(1, 17), (2, 22), (3, 25)] {
        let v = mazearena_json(&["maze", "solve", "--json", &classic_path(n)]);
        assert_eq!(v["steps"], want);
        assert_eq!(v["actions"].as_array().unwrap().len(), want as usize);
    }
    let out = mazearena(&["maze", "solve", &classic_path(1)]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("Fewest run-1 steps: 17"));
    // A move asked longer than the way is open stops at a wall, and says so.
    assert!(
        text.contains("  3: rotation  90, movement  3 -> (1, 0)  (a wall stops it after 2)"),
        "{text}"
    );
    assert!(
        text.contains("  2: rotation  90, movement  1 -> (1, 2)\n"),
        "{text}"
    );
}

#[test]
fn convert_turns_an_ascii_mazefile_into_the_numeric_format() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = shared_maze("micromouseonline/classic/japan2017eq.txt");
    let out_path = dir.path().join("japan.txt");
    let out = mazearena(&[
        "maze",
        "convert",
        ascii.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&out_path).unwrap();
    assert!(text.starts_with("16\n"));
    assert_eq!(text.lines().count(), 17);
    // Both files describe the same maze: validating prints the same hash.
    let hash = |p: &str| {
        let o = mazearena(&["maze", "validate", p]);
        String::from_utf8(o.stdout)
            .unwrap()
            .split("sha256 ")
            .nth(1)
            .unwrap()
            .to_string()
    };
    assert_eq!(
        hash(ascii.to_str().unwrap()),
        hash(out_path.to_str().unwrap())
    );
}

#[test]
fn render_draws_an_svg_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("m.svg");
    let out = mazearena(&[
        "maze",
        "render",
        &classic_path(1),
        "-o",
        svg.to_str().unwrap(),
        "--path",
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") || text.starts_with("<?xml"));
    assert!(text.contains("polyline"));
    assert!(text.trim_end().ends_with("</svg>"));
}

#[test]
fn the_shipped_mazes_are_valid_task_mazes() {
    let mut count = 0;
    for entry in std::fs::read_dir(root().join("mazes")).unwrap().flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "txt") {
            let out = mazearena(&["maze", "validate", "--strict", path.to_str().unwrap()]);
            assert!(out.status.success(), "{}", path.display());
            count += 1;
        }
    }
    assert!(
        count >= 9,
        "mazes/ should hold a few mazes of each size, found {count}"
    );
}

#[tokio::test]
async fn a_local_tournament_writes_every_match_and_prints_standings() {
    let dir = tempfile::tempdir().unwrap();
    // Two manifests: the simple Python bot, and the adapter with the fixture robot.
    let simple_dir = dir.path().join("simple");
    std::fs::create_dir(&simple_dir).unwrap();
    // A bot sees only its own folder: each gets a copy of its files.
    for f in ["simple_bot.py", "mazebot.py"] {
        std::fs::copy(root().join("bots/python").join(f), simple_dir.join(f)).unwrap();
    }
    std::fs::write(
        simple_dir.join("bot.toml"),
        "name = \"simple-python\"\ncommand = \"python3 simple_bot.py\"\n",
    )
    .unwrap();
    let adapter_dir = dir.path().join("adapter");
    std::fs::create_dir(&adapter_dir).unwrap();
    std::fs::copy(
        root().join("tests/fixtures/robot_py/robot.py"),
        adapter_dir.join("robot.py"),
    )
    .unwrap();
    std::fs::copy(
        root().join("bots/python/udacity_adapter.py"),
        adapter_dir.join("udacity_adapter.py"),
    )
    .unwrap();
    std::fs::write(
        adapter_dir.join("bot.toml"),
        "name = \"robot-py\"\nlanguage = \"python\"\ncommand = \"python3 udacity_adapter.py robot.py\"\n",
    )
    .unwrap();
    let db = format!("sqlite://{}", dir.path().join("t.db").display());
    let v = mazearena_json(&[
        "tournament",
        "--bots",
        simple_dir.to_str().unwrap(),
        adapter_dir.to_str().unwrap(),
        "--mazes",
        shared_maze("classic").to_str().unwrap(),
        "--repeats",
        "2",
        "--jobs",
        "2",
        "--database",
        &db,
        "--json",
    ]);
    assert_eq!(v["total"], 12);
    assert_eq!(v["done"], 12);
    let standings = v["standings"].as_array().unwrap();
    assert_eq!(standings.len(), 2);
    assert!(standings[0]["mean_score"].as_f64() <= standings[1]["mean_score"].as_f64());
    // The records are in the database, one per (bot, maze, repeat).
    let storage = mazearena::storage::Storage::open(&db).await.unwrap();
    let id = v["tournament_id"].as_i64().unwrap();
    let rows = storage.tournament_matches(id).await.unwrap();
    assert_eq!(rows.len(), 12);
    assert!(rows.iter().all(|r| r.status == "finished"), "{rows:?}");
    // A second run reuses the registered bots and mazes (no new versions).
    let again = mazearena(&[
        "tournament",
        "--bots",
        simple_dir.to_str().unwrap(),
        "--mazes",
        shared_maze("classic/test_maze_01.txt").to_str().unwrap(),
        "--database",
        &db,
        "--json",
    ]);
    assert!(again.status.success());
    let bots = storage.list_bots().await.unwrap();
    assert_eq!(bots.len(), 2);
    assert!(bots.iter().all(|b| b.version == 1));
    assert_eq!(storage.count_mazes().await.unwrap(), 3);
}

#[test]
fn tournament_refuses_a_bad_manifest() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bot.toml"), "name = \"x\"\n").unwrap();
    let out = mazearena(&[
        "tournament",
        "--bots",
        dir.path().to_str().unwrap(),
        "--mazes",
        "mazes",
        "--database",
        &format!("sqlite://{}", dir.path().join("t.db").display()),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bot.toml"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_local_tournament_on_a_servers_database_never_changes_an_uploaded_bot() {
    let dir = tempfile::tempdir().unwrap();
    let server = crate::support::TestServer::start(dir.path(), &["--jobs", "1"]);
    let (bot, _token) = crate::support::register(
        &server,
        "simple-python",
        "python3 simple_bot.py",
        crate::support::simple_bot_files(),
    )
    .await;
    // A local bot of the same name, in a tournament on the server's own database file.
    let local = dir.path().join("local");
    std::fs::create_dir(&local).unwrap();
    for f in ["simple_bot.py", "mazebot.py"] {
        std::fs::copy(root().join("bots/python").join(f), local.join(f)).unwrap();
    }
    std::fs::write(
        local.join("bot.toml"),
        "name = \"simple-python\"\ncommand = \"python3 simple_bot.py --other\"\n",
    )
    .unwrap();
    let out = mazearena(&[
        "tournament",
        "--bots",
        local.to_str().unwrap(),
        "--mazes",
        shared_maze("classic/test_maze_01.txt").to_str().unwrap(),
        "--database",
        &server.database,
        "--json",
    ]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "the tournament changed the server's bot"
    );
    assert!(
        said.contains(&format!("taken by bot {bot}")) && said.contains("through the API"),
        "{said}"
    );
    let (_, v) = server.get(&format!("/api/bots/{bot}"), None).await;
    assert_eq!(v["versions"].as_array().map(Vec::len), Some(1), "{v}");
    assert_eq!(v["versions"][0]["command"], "python3 simple_bot.py", "{v}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn prune_removes_old_practice_traces_and_leaves_every_result_and_standing() {
    let dir = tempfile::tempdir().unwrap();
    let server = crate::support::TestServer::start(dir.path(), &["--jobs", "1"]);
    let (bot, token) = crate::support::register(
        &server,
        "simple",
        "python3 simple_bot.py",
        crate::support::simple_bot_files(),
    )
    .await;
    let id = crate::support::queue(&server, bot, 1, 2, &token).await;
    let played = crate::support::wait_match(&server, id).await;
    let (s, replay) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_eq!(s, 200, "{replay}");
    let boards = || async {
        let mut all = Vec::new();
        for scope in ["ranking", "all"] {
            all.push(
                server
                    .get(
                        &format!("/api/leaderboard?scope={scope}"),
                        Some(crate::support::ADMIN),
                    )
                    .await
                    .1,
            );
        }
        all
    };
    let before = boards().await;
    let out = mazearena(&[
        "prune",
        "--database",
        &server.database,
        "--older-than-days",
        "0",
    ]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("removed the traces of 1 practice match "),
        "{said}"
    );
    assert_eq!(boards().await, before, "a standing changed");
    let (_, after) = server.get(&format!("/api/matches/{id}"), None).await;
    for key in ["status", "score", "run0_steps", "run1_steps", "total_steps"] {
        assert_eq!(after[key], played[key], "{key}");
    }
    let (s, gone) = server.get(&format!("/api/matches/{id}/replay"), None).await;
    assert_eq!(s, 409, "{gone}");
    assert!(
        gone["error"]["message"]
            .as_str()
            .unwrap()
            .contains("removed"),
        "{gone}"
    );
    let (s, page) = server.get_text(&format!("/matches/{id}")).await;
    assert_eq!(s, 200);
    assert!(page.contains("replay was removed"), "the page says why");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_owner_over_its_storage_cap_queues_nothing_until_pruned() {
    let dir = tempfile::tempdir().unwrap();
    let server = crate::support::TestServer::start(
        dir.path(),
        &[
            "--jobs",
            "1",
            "--max-stored-mib-per-owner",
            "0.01",
            "--no-validation",
        ],
    );
    // 60 KiB of stderr that does not compress, then it quits: over 10 KiB stored.
    let noisy = "import os, sys\nsys.stdin.readline()\nsys.stdin.readline()\n\
                 sys.stderr.write(os.urandom(30000).hex())\nsys.stderr.flush()\n";
    let (bot, token) = crate::support::register(
        &server,
        "noisy",
        "python3 bot.py",
        serde_json::json!({"bot.py": noisy}),
    )
    .await;
    let queue = || async {
        server
            .post(
                "/api/matches",
                serde_json::json!({"bot_id": bot, "maze_id": 1}),
                Some(&token),
            )
            .await
    };
    let (s, q) = queue().await;
    assert_eq!(s, 202, "{q}");
    crate::support::wait_match(&server, q["match_id"].as_i64().unwrap()).await;
    let (s, refused) = queue().await;
    assert_eq!(s, 409, "{refused}");
    let msg = refused["error"]["message"].as_str().unwrap();
    assert!(
        msg.contains(&format!("owner of bot {bot}")) && msg.contains("cap"),
        "{msg}"
    );
    // The admin is not held to it; and once pruned, the owner queues again.
    let (s, by_admin) = server
        .post(
            "/api/matches",
            serde_json::json!({"bot_id": bot, "maze_id": 1}),
            Some(crate::support::ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{by_admin}");
    crate::support::wait_match(&server, by_admin["match_id"].as_i64().unwrap()).await;
    let out = mazearena(&[
        "prune",
        "--database",
        &server.database,
        "--older-than-days",
        "0",
    ]);
    assert!(out.status.success());
    let (s, q) = queue().await;
    assert_eq!(s, 202, "{q}");
}

#[test]
fn a_bot_file_outside_the_bots_folder_is_named_with_the_flags_that_work() {
    let elsewhere = tempfile::tempdir().unwrap();
    let robot = elsewhere.path().join("robot.py");
    std::fs::copy(root().join("bots/python/simple_bot.py"), &robot).unwrap();
    let bot = format!("python3 {}", robot.display());
    let out = mazearena(&["run", "--maze", &classic_path(1), "--bot", &bot, "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let real = robot.canonicalize().unwrap();
    assert!(
        stderr.contains(&format!(
            "the bot's command names {}, which is outside the bot's folder",
            real.display()
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!(
            "--bot-dir {} --bot 'python3 robot.py'",
            real.parent().unwrap().display()
        )),
        "{stderr}"
    );
    assert!(
        stderr.starts_with("warning: "),
        "said before the match: {stderr}"
    );
    if crate::support::sandbox().level() == "full" {
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["status"], "crashed", "it cannot open it: {v}");
    }
    // A file inside the folder, and a system file, are fine.
    let v = run_json(&classic_path(1), "python3 bots/python/simple_bot.py");
    assert_finished(&v);
}

#[test]
fn doctor_exits_1_when_the_full_sandbox_cannot_run_and_0_when_it_can() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .arg("doctor")
        .env("PATH", "/nonexistent")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("bubblewrap"),
        "{out:?}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(stdout.contains("sandbox level: none"));
    let line = |text: &str, name: &str| -> (bool, String) {
        let l = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} line: {text}"))
            .to_string();
        (l.split_whitespace().nth(1) == Some("ok"), l)
    };
    let (warm_ok, warm) = line(&stdout, "warm");
    assert!(
        !warm_ok && warm.contains("not used here: no sandbox"),
        "{warm}"
    );
    if crate::support::sandbox().level() == "full" {
        let out = mazearena(&["doctor"]);
        assert_eq!(out.status.code(), Some(0), "{out:?}");
        // Warm sandboxes wherever each match can have its own uid and cgroup.
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let (cgroups_ok, _) = line(&stdout, "cgroups");
        let (warm_ok, warm) = line(&stdout, "warm");
        let root = nix::unistd::geteuid().is_root();
        assert_eq!(warm_ok, root && cgroups_ok, "{warm}");
    }
    // A usage error stays 2.
    assert_eq!(
        mazearena(&["doctor", "--no-such-flag"]).status.code(),
        Some(2)
    );
}

/// `mazearena run` proves the sandbox with the match itself (no test command first): a
/// bot that cannot start because the sandbox does not work here is reported as the
/// sandbox's failure, never as the bot's, and the command fails as before.
#[test]
fn run_reports_a_sandbox_that_does_not_work_not_a_crashed_bot() {
    let Some(_) = crate::support::full_sandbox("run with a broken sandbox") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("bwrap");
    std::fs::write(
        &fake,
        "#!/bin/sh\necho 'bwrap: Creating new namespace failed: Operation not permitted' >&2\nexit 1\n",
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args([
            "run",
            "--maze",
            "mazes/gen-12-s1.txt",
            "--bot",
            "python3 simple_bot.py",
        ])
        .args(["--bot-dir", "bots/python", "--sandbox", "full", "--json"])
        .env("PATH", format!("{}:/usr/bin:/bin", dir.path().display()))
        .current_dir(root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the sandbox is not available")
            && err.contains("Creating new namespace failed")
            && err.contains("mazearena doctor"),
        "{err}"
    );
    assert!(
        out.stdout.is_empty(),
        "no result is printed: {:?}",
        out.stdout
    );
}

/// A command that prints what it reads ends quietly when its reader has gone
/// (`mazearena logs ID | head`): killed by SIGPIPE as other tools are, no panic.
#[test]
fn a_reader_that_goes_away_ends_a_printing_command_quietly() {
    let out = std::process::Command::new("bash")
        .args([
            "-c",
            &format!(
                "{{ sleep 0.3; '{}' maze generate --dim 16; }} | true; echo \"status ${{PIPESTATUS[0]}}\"",
                env!("CARGO_BIN_EXE_mazearena")
            ),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stdout.contains("status 141"), "{stdout} {stderr}");
}
