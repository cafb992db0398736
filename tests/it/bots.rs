//! The reference bots in bots/: each starter kit's minimal bot plays a real match,
//! every manifest works with `mazearena tournament` and finishes the classic mazes, and
//! the champion finishes every contest maze whose goal room can be reached, and the Rust
//! kit's own tests and in-process champion study agree with the referee.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::support::{mazearena_json, root, shared_maze};

/// Whether `program` runs on this machine (`--version`, or Go's `version`).
fn have(program: &str) -> bool {
    ["--version", "version"].iter().any(|arg| {
        Command::new(program)
            .arg(arg)
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// The kits whose toolchain is here: (folder, tools needed). Outside CI the others are
/// skipped with a printed reason; in CI (`CI=true`) a missing toolchain fails the test.
pub(crate) fn available_kits() -> Vec<&'static str> {
    let kits: [(&str, &[&str]); 7] = [
        ("python", &["python3"]),
        ("javascript", &["node"]),
        ("rust", &["cargo"]),
        ("c", &["make", "cc"]),
        ("cpp", &["make", "g++"]),
        ("go", &["go"]),
        ("java", &["javac", "java"]),
    ];
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let mut out = Vec::new();
    for (kit, tools) in kits {
        match tools.iter().find(|t| !have(t)) {
            Some(missing) if ci => panic!(
                "the {kit} kit needs {missing}, which is not installed (.ci/run installs it)"
            ),
            Some(missing) => eprintln!("SKIPPED the {kit} kit: {missing} is not installed"),
            None => out.push(kit),
        }
    }
    out
}

pub(crate) fn build(dir: &Path, command: &[&str]) {
    // Cargo builds into the kit's own target/ (where its manifests look), whatever
    // target folder the tests themselves were built in.
    let status = Command::new(command[0])
        .args(&command[1..])
        .current_dir(dir)
        .env("CARGO_TARGET_DIR", dir.join("target"))
        .status()
        .unwrap_or_else(|e| panic!("{command:?} in {}: {e}", dir.display()));
    assert!(status.success(), "{command:?} failed in {}", dir.display());
}

fn run_json(maze: &str, bot: &str, dir: &Path) -> Value {
    mazearena_json(&[
        "run",
        "--maze",
        maze,
        "--bot",
        bot,
        "--bot-dir",
        dir.to_str().unwrap(),
        "--json",
    ])
}

/// Builds `kit`'s minimal bot where it is (in `dir`, the kit's folder) as its README
/// says; returns the command that runs it. Hold [`crate::support::kits_in_place`].
fn build_in_place(kit: &str, dir: &Path) -> String {
    match kit {
        "python" => "python3 simple_bot.py".to_string(),
        "javascript" => "node minimal_bot.js".to_string(),
        "rust" => {
            build(dir, &["cargo", "build", "--release", "--quiet"]);
            dir.join("target/release/minimal_bot").display().to_string()
        }
        "c" | "cpp" => {
            build(dir, &["make", "-s"]);
            dir.join("minimal_bot").display().to_string()
        }
        "go" => {
            build(dir, &["go", "vet", "./..."]);
            build(dir, &["go", "test", "-count=1", "./..."]);
            build(
                dir,
                &[
                    "go",
                    "build",
                    "-buildvcs=false",
                    "-o",
                    "minimal_bot",
                    "./cmd/minimal_bot",
                ],
            );
            dir.join("minimal_bot").display().to_string()
        }
        "java" => {
            let manifest = mazearena::manifest::load(dir).expect("the java kit's bot.toml");
            let words = shlex::split(manifest[0].build.as_deref().unwrap()).unwrap();
            let words: Vec<&str> = words.iter().map(String::as_str).collect();
            build(dir, &words);
            manifest[0].command.clone()
        }
        other => unreachable!("unknown kit {other}"),
    }
}

#[test]
fn each_starter_kits_minimal_bot_finishes_a_real_match() {
    let _kits = crate::support::kits_in_place();
    let maze = shared_maze("classic/test_maze_02.txt");
    for kit in available_kits() {
        let dir = root().join("bots").join(kit);
        let bot = build_in_place(kit, &dir);
        let v = run_json(maze.to_str().unwrap(), &bot, &dir);
        assert_eq!(v["status"], "finished", "{kit}: {v}");
        assert!(
            v["run1_steps"].as_u64().unwrap() >= 22,
            "{kit}: no bot beats the optimum"
        );
    }
}

#[test]
fn every_manifest_finishes_the_classic_mazes_in_a_tournament() {
    let _kits = crate::support::kits_in_place();
    let _heavy = crate::support::heavy();
    let dir = tempfile::tempdir().unwrap();
    let db = format!("sqlite://{}", dir.path().join("bots.db").display());
    let kits: Vec<String> = available_kits()
        .iter()
        .map(|k| format!("bots/{k}"))
        .collect();
    let mut args = vec!["tournament", "--bots"];
    args.extend(kits.iter().map(String::as_str));
    let classic = shared_maze("classic");
    args.extend([
        "--mazes",
        classic.to_str().unwrap(),
        "--database",
        &db,
        "--json",
    ]);
    let v = mazearena_json(&args);
    let matches = v["matches"].as_array().unwrap();
    let bots = v["standings"].as_array().unwrap().len();
    assert!(bots >= kits.len(), "every kit has at least one bot");
    assert_eq!(matches.len(), bots * 3);
    for m in matches {
        assert_eq!(m["status"], "finished", "{m}");
    }
    // The same steps and scores without the sandbox (the tests' default is the full one).
    if crate::support::sandbox().level() == "full" {
        let db2 = format!("sqlite://{}", dir.path().join("bare.db").display());
        let mut bare = args.clone();
        let at = bare.iter().position(|a| *a == db.as_str()).unwrap();
        bare[at] = &db2;
        bare.extend(["--sandbox", "none"]);
        let outside = mazearena_json(&bare);
        let key = |m: &Value| {
            let f = |k: &str| m[k].to_string();
            (
                f("bot"),
                f("maze"),
                f("status"),
                f("run0_steps"),
                f("run1_steps"),
                f("score"),
            )
        };
        let mut inside: Vec<_> = matches.iter().map(key).collect();
        let mut bare: Vec<_> = outside["matches"]
            .as_array()
            .unwrap()
            .iter()
            .map(key)
            .collect();
        inside.sort();
        bare.sort();
        assert_eq!(inside, bare, "a bot played differently inside the sandbox");
    }
}

#[test]
fn the_champion_finishes_every_contest_maze_with_a_reachable_goal() {
    let _heavy = crate::support::heavy();
    if !have("cargo") {
        eprintln!("SKIPPED the champion test: cargo is not installed");
        return;
    }
    let kit = root().join("bots/rust");
    build(&kit, &["cargo", "build", "--release", "--quiet"]);
    let dir = tempfile::tempdir().unwrap();
    // A bot sees only its own folder: the manifest's folder gets the binary.
    std::fs::copy(
        kit.join("target/release/champion"),
        dir.path().join("champion"),
    )
    .unwrap();
    let manifest = dir.path().join("bot.toml");
    std::fs::write(&manifest, "name = \"champion\"\ncommand = \"./champion\"\n").unwrap();
    let db = format!("sqlite://{}", dir.path().join("c.db").display());
    let contest = shared_maze("micromouseonline/classic");
    let v = mazearena_json(&[
        "tournament",
        "--bots",
        manifest.to_str().unwrap(),
        "--mazes",
        contest.to_str().unwrap(),
        "--database",
        &db,
        "--json",
    ]);
    // 521 files: 2 have an unreachable goal room and 13 repeat another's layout.
    assert_eq!(v["total"], 506);
    let standing = &v["standings"][0];
    assert_eq!(standing["finish_rate"], 1.0, "{standing}");
    // Far better than the fewest-step optimum plus a full 1000-step exploration.
    assert!(standing["mean_ratio"].as_f64().unwrap() < 1.5, "{standing}");
}

#[test]
fn the_rust_kits_tests_pass_and_the_champion_study_plays_like_the_referee() {
    if !have("cargo") {
        eprintln!("SKIPPED the Rust kit's tests: cargo is not installed");
        return;
    }
    let kit = root().join("bots/rust");
    build(&kit, &["cargo", "test", "--release", "--quiet"]);
    build(
        &kit,
        &[
            "cargo",
            "build",
            "--release",
            "--quiet",
            "--examples",
            "--bins",
        ],
    );
    let study = kit.join("target/release/examples/champion_study");
    let champion = kit.join("target/release/champion");
    for n in 1..=3 {
        let maze = shared_maze(&format!("classic/test_maze_0{n}.txt"));
        let maze = maze.to_str().unwrap();
        let out = Command::new(&study)
            .args(["--verbose", maze])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text.lines().next().unwrap();
        let field = |name: &str| -> u64 {
            let at = line
                .find(name)
                .unwrap_or_else(|| panic!("{name} in {line}"))
                + name.len();
            let digits: String = line[at..]
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            digits.parse().unwrap()
        };
        // The same game through the real referee and protocol.
        let v = run_json(maze, champion.to_str().unwrap(), &kit);
        assert_eq!(v["status"], "finished");
        assert_eq!(v["run0_steps"], field("run 0 "), "{line}");
        assert_eq!(v["run1_steps"], field("run 1 "), "{line}");
    }
}

#[test]
fn no_bot_crashes_on_a_maze_whose_goal_cannot_be_reached() {
    let maze = shared_maze("micromouseonline/classic/001-anomaly-test.txt");
    let _kits = crate::support::kits_in_place();
    let mut played = 0;
    for kit in available_kits() {
        let dir = root().join("bots").join(kit);
        build_in_place(kit, &dir);
        for bot in mazearena::manifest::load(&dir).unwrap() {
            let v = run_json(maze.to_str().unwrap(), &bot.command, &bot.dir);
            assert_eq!(v["status"], "step_limit", "{}: {v}", bot.name);
            played += 1;
        }
    }
    assert!(played >= 4);
}
