//! Limits that do not depend on the machine's load: the move limit counts the CPU time
//! of the bot's processes, so a deterministic bot that thinks ~600 ms of CPU a move
//! under a 1000 ms limit gives the same result alone and beside four CPU hogs on this
//! machine (where each of its answers then takes well over a second of wall-clock
//! time), through `mazearena run` and through a server.

use std::process::{Child, Command};
use std::time::Duration;

use serde_json::{Value, json};

use crate::support::{ADMIN, TestServer, mazearena, root, shared_maze, wait_match};

/// Processes that keep a CPU busy until dropped. Each is the leader of a session of
/// its own, as an independent program (or another match's bot) is: with the kernel's
/// autogroup scheduling, processes of one session share one CPU share, so four hogs in
/// the test's session would weigh no more than one.
struct Hogs(Vec<Child>);

impl Hogs {
    fn start(n: usize) -> Hogs {
        use std::os::unix::process::CommandExt;
        Hogs(
            (0..n)
                .map(|_| {
                    let mut c = Command::new("python3");
                    c.args(["-c", "while True: pass"]);
                    // SAFETY: setsid is async-signal-safe and touches no memory.
                    unsafe {
                        c.pre_exec(|| {
                            libc::setsid();
                            Ok(())
                        });
                    }
                    c.spawn().expect("python3 runs")
                })
                .collect(),
        )
    }
}

impl Drop for Hogs {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// The bot's arguments: 600 ms of CPU before each of its answers to steps 2 to 7,
/// then the optimal route of classic maze 1 twice (the match finishes: 17.600).
fn burner_args() -> Vec<String> {
    let solution = mazearena::engine::solver::solve(&crate::support::classic(1)).expect("solvable");
    let route: Vec<String> = solution
        .actions
        .iter()
        .map(|a| match a {
            mazearena::engine::Action::Move { rotation, movement } => {
                format!("{rotation},{movement}")
            }
            mazearena::engine::Action::Reset { .. } => "reset".to_string(),
        })
        .collect();
    // Run 0: the route, then the reset; run 1: the route again.
    let mut args: Vec<String> = ["--burn-ms", "600", "--burn-steps", "6"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(route.iter().cloned());
    args.push("reset".into());
    args.extend(route);
    args
}

/// What must not change with the load: status, steps and score.
fn result(v: &Value) -> Value {
    json!([
        v["status"],
        v["run0_steps"],
        v["run1_steps"],
        v["total_steps"],
        v["score"]
    ])
}

/// `mazearena run` of the burner on classic maze 1 (no time bank: the move limit alone
/// holds): its result and the longest wall-clock answer of steps 2 to 7, in µs.
fn run_once() -> (Value, u64) {
    let dir = tempfile::tempdir().unwrap();
    let replay = dir.path().join("match.json");
    let mut bot = String::from("python3 tests/fixtures/bots/scripted.py");
    for a in burner_args() {
        bot.push(' ');
        bot.push_str(&a);
    }
    let maze = shared_maze("classic/test_maze_01.txt");
    let out = mazearena(&[
        "run",
        "--maze",
        maze.to_str().unwrap(),
        "--bot",
        &bot,
        "--bot-dir",
        root().to_str().unwrap(),
        "--seed",
        "7",
        "--move-timeout-ms",
        "1000",
        "--time-bank-ms",
        "0",
        "--json",
        "--replay",
        replay.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let record: Value = serde_json::from_slice(&std::fs::read(&replay).unwrap()).unwrap();
    let record = if record["record"].is_object() {
        &record["record"]
    } else {
        &record
    };
    let slowest = record["trace"].as_array().unwrap()[1..7]
        .iter()
        .map(|s| s["answer_us"].as_u64().unwrap())
        .max()
        .unwrap();
    (result(&v), slowest)
}

#[test]
fn a_bot_that_thinks_600_ms_a_move_scores_the_same_alone_and_beside_four_cpu_hogs_in_run() {
    let (alone, _) = run_once();
    assert_eq!(alone[0], "finished", "{alone}");
    let (loaded, slowest) = {
        let _hogs = Hogs::start(4);
        std::thread::sleep(Duration::from_millis(300));
        run_once()
    };
    assert_eq!(alone, loaded, "the load changed the result");
    // The load was real: a wall-clock limit of 1000 ms would have ended the match.
    assert!(
        slowest > 1_000_000,
        "the slowest burning answer took only {slowest} µs: the hogs did not load the machine"
    );
}

#[tokio::test]
async fn a_bot_that_thinks_600_ms_a_move_scores_the_same_alone_and_beside_four_cpu_hogs_on_a_server()
 {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--jobs", "1"]);
    let layout = std::fs::read_to_string(shared_maze("classic/test_maze_01.txt")).unwrap();
    let (s, m) = server
        .post(
            "/api/mazes",
            json!({"name": "classic-1", "layout": layout}),
            Some(ADMIN),
        )
        .await;
    assert!(s == 201 || s == 200, "{m}");
    let maze_id = m["maze_id"].as_i64().unwrap();
    let mut command = String::from("python3 scripted.py");
    for a in burner_args() {
        command.push(' ');
        command.push_str(&a);
    }
    let files = json!({
        "scripted.py": std::fs::read_to_string(root().join("tests/fixtures/bots/scripted.py")).unwrap()
    });
    let (s, b) = server
        .post(
            "/api/bots",
            json!({"name": "burner", "command": command, "files": files}),
            None,
        )
        .await;
    assert_eq!(s, 201, "{b}");
    let (bot, key) = (
        b["bot_id"].as_i64().unwrap(),
        b["owner_token"].as_str().unwrap().to_string(),
    );
    crate::support::wait_built(&server, bot).await;
    let play = || async {
        let (s, v) = server
            .post(
                "/api/matches",
                json!({"bot_id": bot, "maze_id": maze_id, "seed": 7}),
                Some(&key),
            )
            .await;
        assert_eq!(s, 202, "{v}");
        wait_match(&server, v["match_id"].as_i64().unwrap()).await
    };
    let alone = play().await;
    assert_eq!(alone["status"], "finished", "{alone}");
    let loaded = {
        let _hogs = Hogs::start(4);
        tokio::time::sleep(Duration::from_millis(300)).await;
        play().await
    };
    assert_eq!(result(&alone), result(&loaded), "{alone} {loaded}");
    // The load was real: the slowest answer took longer than the move limit.
    let slowest = loaded["timings"]["max_answer_us"].as_u64().unwrap_or(0);
    assert!(slowest > 1_000_000, "{loaded}");
    // And `run` gives the same result as the server.
    let (run, _) = run_once();
    assert_eq!(run, result(&alone));
}
