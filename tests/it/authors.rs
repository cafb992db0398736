//! Answers for bot authors on the command line: what the bot said and thought at each
//! step, why it failed in a tournament, a stored match shown again, the variables it
//! was given, and the hint when its answers sit in an output buffer.

use std::process::Command;

use serde_json::Value;

use crate::support::{mazearena, mazearena_json, root, sandbox};

fn fixture(name: &str) -> String {
    format!("python3 tests/fixtures/bots/{name}.py")
}

#[test]
fn stderr_lines_and_debug_objects_are_kept_by_step_with_their_limits() {
    let dir = tempfile::tempdir().unwrap();
    let replay = dir.path().join("r.json");
    let out = mazearena(&[
        "run",
        "--maze",
        "mazes/gen-12-s1.txt",
        "--bot",
        &fixture("chatty"),
        "--replay",
        replay.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{out:?}");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&replay).unwrap()).unwrap();
    assert_eq!(r["status"], "protocol_error");
    let trace = r["trace"].as_array().unwrap();
    assert_eq!(trace.len(), 30);
    for s in trace {
        let step = s["step"].as_u64().unwrap();
        let stderr: Vec<&str> = s["stderr"]
            .as_array()
            .map(|a| a.iter().map(|l| l.as_str().unwrap()).collect())
            .unwrap_or_default();
        // Each step's own line is in that step (the first also has the start's lines).
        assert!(
            stderr.contains(&format!("thinking about step {step}").as_str()),
            "step {step}: {stderr:?}"
        );
        match step {
            3 | 4 => assert!(s.get("debug").is_none(), "step {step}: dropped"),
            _ => assert_eq!(s["debug"]["cells"][0][2], step, "step {step}"),
        }
    }
    let notices: Vec<String> = r["notices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["message"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(notices.len(), 2, "{notices:?}");
    assert!(notices[0].contains("step 3") && notices[0].contains("not a JSON object"));
    assert!(notices[1].contains("step 4") && notices[1].contains("16384"));
    // The scoring is untouched by the debug objects.
    assert_eq!(r["total_steps"], 31);
    assert_eq!(r["warnings"], serde_json::json!([]));
}

#[test]
fn run_verbose_prints_every_exchange_and_streams_stderr() {
    let out = mazearena(&[
        "run",
        "--maze",
        "mazes/gen-12-s1.txt",
        "--bot",
        &fixture("chatty"),
        "--verbose",
    ]);
    assert!(out.status.success(), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("step    1 run 0: sensors [0, ")
            && stdout.contains(r#"-> {"rotation":0,"movement":0}"#),
        "{stdout}"
    );
    assert!(stdout.contains("debug: step 2 <b>not bold</b>"), "{stdout}");
    assert!(
        stderr.contains("bot stderr | thinking about step 30"),
        "{stderr}"
    );
}

#[test]
fn bot_env_reaches_the_bot_and_nothing_else_of_ours_does() {
    let out = Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args([
            "run",
            "--maze",
            "mazes/gen-12-s1.txt",
            "--bot",
            &fixture("chatty"),
            "--json",
        ])
        .args(["--bot-env", "ALPHA=0.5", "--bot-env", "MODE=fast=yes"])
        .env("MAZEARENA_SANDBOX", sandbox().level())
        .env("SECRET_OF_THE_SERVER", "do-not-leak")
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let tail = v["stderr_tail"].as_str().unwrap();
    assert!(
        tail.contains("env ALPHA=0.5\n") && tail.contains("env MODE=fast=yes\n"),
        "{tail}"
    );
    assert!(
        !tail.contains("SECRET_OF_THE_SERVER") && !tail.contains("do-not-leak"),
        "{tail}"
    );
    assert!(!tail.contains("env MAZEARENA_"), "{tail}");
    for bad in [
        "PATH=/evil",
        "MAZEARENA_ADMIN_TOKEN=x",
        "1BAD=x",
        "NOEQUALS",
    ] {
        let out = mazearena(&[
            "run",
            "--maze",
            "mazes/gen-12-s1.txt",
            "--bot",
            "x",
            "--bot-env",
            bad,
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad}");
        assert!(!out.stderr.is_empty(), "{bad}: a message");
    }
}

#[test]
fn a_bot_that_does_not_flush_times_out_with_a_hint() {
    let v = mazearena_json(&[
        "run",
        "--maze",
        "mazes/gen-12-s1.txt",
        "--bot",
        &fixture("unflushed"),
        "--json",
        "--startup-timeout-ms",
        "1500",
    ]);
    assert_eq!(v["status"], "timeout");
    let reason = v["error"]["reason"].as_str().unwrap();
    assert!(
        reason.contains("step 1") && reason.contains("flush stdout"),
        "{reason}"
    );
}

#[test]
fn a_tournament_says_why_a_bot_failed_and_match_show_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let bots = dir.path().join("bots");
    std::fs::create_dir_all(&bots).unwrap();
    std::fs::copy(
        root().join("tests/fixtures/bots/exits_early.py"),
        bots.join("bot.py"),
    )
    .unwrap();
    std::fs::write(
        bots.join("bot.toml"),
        "name = \"quitter\"\ncommand = \"python3 bot.py\"\n",
    )
    .unwrap();
    let db = format!("sqlite://{}", dir.path().join("t.db").display());
    let out = mazearena(&[
        "tournament",
        "--bots",
        bots.to_str().unwrap(),
        "--mazes",
        "mazes/gen-12-s1.txt",
        "mazes/gen-12-s2.txt",
        "--database",
        &db,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{out:?}");
    assert!(stdout.contains("Matches that did not finish:"), "{stdout}");
    assert!(stdout.contains("quitter: 2 of 2 (2 crashed)"), "{stdout}");
    assert!(stdout.contains("before answering step 1"), "{stdout}");
    let id: String = stdout
        .split("mazearena match show ")
        .nth(1)
        .unwrap()
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    // --json carries every match's reason.
    let v = mazearena_json(&[
        "tournament",
        "--bots",
        bots.to_str().unwrap(),
        "--mazes",
        "mazes/gen-12-s1.txt",
        "--database",
        &db,
        "--json",
    ]);
    let m = &v["matches"][0];
    assert_eq!(m["status"], "crashed");
    assert!(
        m["reason"]
            .as_str()
            .unwrap()
            .contains("before answering step 1"),
        "{m}"
    );
    assert_eq!(m["step"], 1);
    // match show: the record, the reason, the stderr tail, and its HTML replay.
    let html = dir.path().join("m.html");
    let out = mazearena(&[
        "match",
        "show",
        &id,
        "--database",
        &db,
        "--html",
        html.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{out:?}");
    assert!(
        text.contains("quitter v1") && text.contains("status: crashed"),
        "{text}"
    );
    assert!(
        text.contains("reason (step 1): the bot exited with status 3 before answering step 1"),
        "{text}"
    );
    assert!(
        text.contains("| exits_early: giving up at the first sense"),
        "{text}"
    );
    assert!(
        std::fs::read_to_string(&html)
            .unwrap()
            .contains("id=\"replay-data\"")
    );
    let out = mazearena(&["match", "show", "999", "--database", &db]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no match 999"));
    // --json prints JSON only; --trace adds the trace.
    let summary = mazearena_json(&["match", "show", &id, "--database", &db, "--json"]);
    assert_eq!(summary["status"], "crashed", "{summary}");
    assert!(summary.get("trace").is_none());
    let whole = mazearena_json(&["match", "show", &id, "--database", &db, "--json", "--trace"]);
    assert_eq!(whole["status"], "crashed");
    // (This match crashed at its first step: its trace is empty.)
    assert!(
        whole["maze_layout"].is_string() && whole["stderr_tail"].is_string(),
        "{whole}"
    );
    let out = mazearena(&["match", "show", &id, "--database", &db, "--trace"]);
    assert_eq!(out.status.code(), Some(2), "--trace needs --json");
    // Without a database: an error naming it, and no empty database made.
    let empty = tempfile::tempdir().unwrap();
    let missing = format!("sqlite://{}", empty.path().join("mazearena.db").display());
    let out = mazearena(&["match", "show", "1", "--database", &missing]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no database at"),
        "{out:?}"
    );
    assert!(!empty.path().join("mazearena.db").exists());
}

#[test]
fn replay_refuses_files_that_are_not_replays() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"hello\": 1}").unwrap();
    let out = mazearena(&["replay", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("is not a mazearena replay"));
}
