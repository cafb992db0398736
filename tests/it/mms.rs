//! Mice written for the mms simulator, through `mazearena run --protocol mms` with real
//! processes, in the sandbox: every answer of the protocol as the mouse reads it, a mouse
//! that prints garbage and waits for ever, one that hard-codes 16x16 on a 12x12 maze, and
//! the kit's flood-fill mouse finishing the classic mazes with the same score in the
//! sandbox and out.

use serde_json::Value;

use super::support::{mazearena, processes_matching, shared_maze};

/// The command that runs `mouse`: a Python file through `python3`, anything else as it is.
fn command_of(mouse: &str) -> String {
    if mouse.split(' ').next().is_some_and(|m| m.ends_with(".py")) {
        format!("python3 {mouse}")
    } else {
        mouse.to_string()
    }
}

/// `run --protocol mms` of `mouse` on classic maze `n`, with `extra` flags: the whole
/// record with its trace (`--replay`; the run may end in any status: the exit code is
/// not looked at).
fn run_mouse(mouse: &str, n: u32, extra: &[&str]) -> Value {
    let maze = shared_maze(&format!("classic/test_maze_0{n}.txt"));
    let bot = command_of(mouse);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("record.json");
    let mut args = vec![
        "run",
        "--maze",
        maze.to_str().unwrap(),
        "--bot",
        &bot,
        "--protocol",
        "mms",
        "--json",
        "--replay",
        file.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = mazearena(&args);
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| {
        panic!(
            "{e}: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    serde_json::from_str(&text).unwrap()
}

#[test]
fn a_mouse_reads_every_answer_of_the_protocol_and_none_where_mms_gives_none() {
    let record = run_mouse("tests/fixtures/bots/mms/transcript.py", 1, &[]);
    assert_eq!(record["bot_protocol"], "mms");
    // Classic maze 1: 12x12, the start reads [0, 11, 0].
    let expected = "\
mazeWidth -> 12
mazeHeight -> 12
wallFront -> false
wallLeft -> true
wallRight -> true
wallBack -> true
wallFront 21 -> false
wallFront 23 -> true
wasReset -> false
getStat total-distance -> 0
turnLeft -> ack
turnRight -> ack
turnLeft90 -> ack
turnRight90 -> ack
turnLeft45 -> ack
turnRight45 -> ack
setColor 0 0 G -> -
setText 0 0 hi -> -
setWall 0 0 n -> -
clearWall 0 0 n -> -
clearColor 0 0 -> -
clearAllColor -> -
clearText 0 0 -> -
clearAllText -> -
fly -> -
turnLeft 1 -> -
getStat nothing -> -
moveForward 2 -> ack
getStat total-distance -> 2
moveForward 0 -> crash
";
    assert_eq!(record["stderr_tail"], expected);
    // Its one move was one step of two cells; then it exited.
    assert_eq!(
        record["trace"][0]["action"]["movement"], 2,
        "{}",
        record["trace"][0]
    );
    assert_eq!(record["status"], "crashed");
    let notices = record["notices"].to_string();
    assert!(
        notices.contains("3 unknown mms commands") && notices.contains("\\\"fly\\\""),
        "{notices}"
    );
}

#[test]
fn a_mouse_that_prints_garbage_and_waits_times_out_and_leaves_nothing_running() {
    let record = run_mouse(
        "tests/fixtures/bots/mms/silent.py",
        1,
        &["--startup-timeout-ms", "300"],
    );
    assert_eq!(record["status"], "timeout", "{record}");
    assert!(
        record["notices"]
            .to_string()
            .contains("2 unknown mms commands")
    );
    assert!(processes_matching("fixtures/bots/mms/silent.py").is_empty());
}

#[test]
fn a_mouse_that_hard_codes_16x16_fails_clearly_on_a_12x12_maze() {
    let record = run_mouse("tests/fixtures/bots/mms/fixed16.py", 1, &[]);
    assert_eq!(record["status"], "crashed", "{record}");
    assert!(
        record["error"]["reason"]
            .as_str()
            .unwrap()
            .contains("exited with status 3"),
        "{record}"
    );
    // Eleven cells went in steps of 3, 3, 3 and 2; the crash was its answer.
    let moves: Vec<i64> = record["trace"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["action"]["movement"].as_i64().unwrap())
        .collect();
    assert_eq!(moves, [3, 3, 3, 2]);
    assert!(
        record["stderr_tail"]
            .as_str()
            .unwrap()
            .contains("only knows 16x16")
    );
}

#[test]
fn the_kits_flood_fill_mouse_finishes_the_classic_mazes_alike_in_the_sandbox_and_out() {
    for n in 1..=3 {
        let inside = run_mouse("bots/mms/python/floodfill.py", n, &[]);
        assert_eq!(inside["status"], "finished", "maze {n}: {inside}");
        assert_eq!(inside["limits"]["sandbox"], "full");
        let outside = run_mouse("bots/mms/python/floodfill.py", n, &["--sandbox", "none"]);
        for field in ["status", "score", "run0_steps", "run1_steps", "total_steps"] {
            assert_eq!(inside[field], outside[field], "maze {n}: {field}");
        }
        // It raced: run 1 is shorter than run 0.
        assert!(inside["run1_steps"].as_i64() < inside["run0_steps"].as_i64());
        // Its setColor commands are the replay's drawing: step 1 paints the start.
        assert_eq!(
            inside["trace"][0]["debug"]["colors"][0],
            serde_json::json!([0, 0, "#006400"]),
            "maze {n}"
        );
    }
}

#[tokio::test]
async fn an_mms_mouse_uploaded_with_protocol_mms_is_validated_and_plays_on_a_server() {
    use super::support::{TestServer, queue, wait_built, wait_match};
    use serde_json::json;
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let mouse =
        std::fs::read_to_string(super::support::root().join("bots/mms/python/floodfill.py"))
            .unwrap();
    // The protocol is checked like every field.
    let (s, e) = server
        .post(
            "/api/bots",
            json!({"name": "m0", "command": "python3 floodfill.py", "protocol": "mmx",
                   "files": {"floodfill.py": mouse}}),
            None,
        )
        .await;
    assert_eq!(s, 422, "{e}");
    assert!(
        e["error"]["message"]
            .as_str()
            .unwrap()
            .contains("unknown protocol")
    );
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "mouse", "command": "python3 floodfill.py", "protocol": "mms",
                   "files": {"floodfill.py": mouse}}),
            None,
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    assert_eq!(bot["version"]["protocol"], "mms");
    let id = bot["bot_id"].as_i64().unwrap();
    let token = bot["owner_token"].as_str().unwrap().to_string();
    let built = wait_built(&server, id).await;
    assert_eq!(
        built["build_status"], "ready",
        "the validation match played it: {built}"
    );
    // Outside a competition, an mms mouse is validated on a 16x16 maze, the size such
    // mice are written for.
    let log = super::support::build_log(&server, id, &token).await;
    assert!(
        log.contains("on a public generated 16x16 maze without a fault"),
        "{log}"
    );
    // The classic mazes, added as public mazes: the scores `run` gives.
    for n in 1..=3 {
        let layout =
            std::fs::read_to_string(shared_maze(&format!("classic/test_maze_0{n}.txt"))).unwrap();
        let (s, maze) = server
            .post(
                "/api/mazes",
                json!({"name": format!("classic-{n}"), "layout": layout}),
                Some(super::support::ADMIN),
            )
            .await;
        assert_eq!(s, 201, "{maze}");
        let classic = maze["maze_id"].as_i64().unwrap();
        let m = queue(&server, id, classic, 1, &token).await;
        let done = wait_match(&server, m).await;
        assert_eq!(done["status"], "finished", "maze {n}: {done}");
        let local = run_mouse("bots/mms/python/floodfill.py", n, &[]);
        assert_eq!(
            done["score"], local["score"],
            "maze {n}: the same as `run` gives"
        );
        assert_eq!(done["total_steps"], local["total_steps"], "maze {n}");
    }
}

#[test]
fn the_c_kits_mouse_calls_ack_reset_at_the_centre_and_finishes_the_classic_mazes() {
    let _kits = super::support::kits_in_place();
    let root = super::support::root();
    let made = std::process::Command::new("make")
        .args(["-s", "-C"])
        .arg(root.join("bots/mms/c"))
        .status()
        .unwrap();
    assert!(made.success());
    for n in 1..=3 {
        let maze = shared_maze(&format!("classic/test_maze_0{n}.txt"));
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("record.json");
        let out = mazearena(&[
            "run",
            "--maze",
            maze.to_str().unwrap(),
            "--bot",
            "bots/mms/c/floodfill",
            "--protocol",
            "mms",
            "--replay",
            file.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let record: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        assert_eq!(record["status"], "finished", "maze {n}");
        // Its ackReset was the task's reset, played at the centre: the step before run
        // 1 ended in a goal cell.
        let trace = record["trace"].as_array().unwrap();
        let reset = trace
            .iter()
            .position(|s| s["event"] == "reset_accepted")
            .unwrap_or_else(|| panic!("maze {n}: no reset in the trace"));
        let before = &trace[reset - 1]["position"];
        let dim = record["maze_dim"].as_i64().unwrap();
        let goal = |v: &Value| (dim / 2 - 1..=dim / 2).contains(&v.as_i64().unwrap());
        assert!(
            goal(&before["x"]) && goal(&before["y"]),
            "maze {n}: {before}"
        );
        // Its race moved several cells at once somewhere.
        assert!(
            trace[reset..]
                .iter()
                .any(|s| s["action"]["movement"].as_i64() > Some(1)),
            "maze {n}"
        );
    }
}

/// The cells a mouse process goes through under mms's rules (docs/PROTOCOL-mms.md, the
/// facts of MMS-NOTES.md), answered here from the true maze: until it enters the goal
/// room, calls `ackReset`, or has gone `cap` cells. Written from those rules, not from
/// the referee.
fn under_mms_rules(mouse: &str, maze: &mazearena::engine::Maze, cap: usize) -> Vec<(u32, u32)> {
    use mazearena::engine::{Heading, Position};
    use std::io::{BufRead, Write};
    let words = shlex::split(&command_of(mouse)).unwrap();
    let mut child = std::process::Command::new(&words[0])
        .args(&words[1..])
        .current_dir(super::support::root())
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let output = std::io::BufReader::new(child.stdout.take().unwrap());
    let (mut at, mut heading) = (Position { x: 0, y: 0 }, Heading::Up);
    let mut path = vec![(0, 0)];
    let dim = maze.dim();
    'lines: for line in output.lines() {
        let Ok(line) = line else { break };
        let words: Vec<&str> = line.split(' ').filter(|w| !w.is_empty()).collect();
        let turn = |h: Heading, quarters: usize| Heading::from_index(h.index() + quarters);
        let answer = match words.as_slice() {
            ["mazeWidth"] | ["mazeHeight"] => dim.to_string(),
            [q, rest @ ..] if q.starts_with("wall") && rest.len() <= 1 => {
                let rel = match *q {
                    "wallFront" => 0,
                    "wallRight" => 1,
                    "wallBack" => 2,
                    "wallLeft" => 3,
                    _ => continue,
                };
                let n: u32 = rest.first().map_or(1, |t| t.parse().unwrap());
                let open = maze.dist_to_wall(at, turn(heading, rel));
                (open <= (n - 1) / 2).to_string()
            }
            ["turnLeft"] | ["turnLeft90"] => {
                heading = turn(heading, 3);
                "ack".into()
            }
            ["turnRight"] | ["turnRight90"] => {
                heading = turn(heading, 1);
                "ack".into()
            }
            ["moveForward", rest @ ..] => {
                let n: i64 = rest.first().map_or(1, |t| t.parse().unwrap());
                let mut answer = if n < 1 { "crash" } else { "ack" };
                for _ in 0..n.max(0) {
                    if !maze.is_open(at, heading) {
                        answer = "crash";
                        break;
                    }
                    at = at.step(heading, dim).unwrap();
                    path.push((at.x, at.y));
                    if maze.is_goal(at) || path.len() >= cap {
                        break 'lines;
                    }
                }
                answer.into()
            }
            ["wasReset"] => "false".into(),
            ["ackReset"] => break,
            _ => continue, // display commands and anything else: no answer
        };
        if writeln!(input, "{answer}").is_err() {
            break;
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    path
}

/// The cells the robot went through in run 0 of `record`, until it first entered the
/// goal room.
fn run0_cells(record: &Value) -> Vec<(u32, u32)> {
    let dim = record["maze_dim"].as_u64().unwrap() as u32;
    let goal = |(x, y): (u32, u32)| {
        (dim / 2 - 1..=dim / 2).contains(&x) && (dim / 2 - 1..=dim / 2).contains(&y)
    };
    let mut path = vec![(0u32, 0u32)];
    for s in record["trace"].as_array().unwrap() {
        if s["run"] != 0 || s["event"] == "reset_accepted" {
            break;
        }
        let (tx, ty) = (
            s["position"]["x"].as_u64().unwrap() as u32,
            s["position"]["y"].as_u64().unwrap() as u32,
        );
        let (mut x, mut y) = *path.last().unwrap();
        while (x, y) != (tx, ty) {
            x = (x as i64 + (tx as i64 - x as i64).signum()) as u32;
            y = (y as i64 + (ty as i64 - y as i64).signum()) as u32;
            path.push((x, y));
            if goal((x, y)) {
                return path;
            }
        }
    }
    path
}

#[test]
fn community_style_mice_take_their_mms_paths_in_run_0() {
    let mice = [
        "tests/fixtures/bots/mms/left_wall.py",
        "tests/fixtures/bots/mms/stop_at_goal.py",
        "tests/fixtures/bots/mms/dash.py",
        "bots/mms/python/floodfill.py",
        // Calls ackReset at the centre.
        "bots/mms/c/floodfill",
    ];
    let _kits = super::support::kits_in_place();
    let made = std::process::Command::new("make")
        .args(["-s", "-C"])
        .arg(super::support::root().join("bots/mms/c"))
        .status()
        .unwrap();
    assert!(made.success());
    for n in 1..=3 {
        let text =
            std::fs::read_to_string(shared_maze(&format!("classic/test_maze_0{n}.txt"))).unwrap();
        let maze = mazearena::engine::mazefile::parse(text.as_bytes()).unwrap();
        for mouse in mice {
            let record = run_mouse(mouse, n, &[]);
            let refereed = run0_cells(&record);
            let model = under_mms_rules(mouse, &maze, 5000);
            assert!(refereed.len() > 3, "{mouse} on maze {n}: {refereed:?}");
            let reached = refereed
                .last()
                .is_some_and(|&(x, y)| maze.is_goal(mazearena::engine::Position { x, y }));
            if reached {
                assert_eq!(refereed, model, "{mouse} on maze {n}");
            } else {
                // The step budget ran out first: the same cells as far as it went.
                // The step budget ran out, or the mouse gave up, before the centre: the
                // same cells as far as the referee went.
                assert!(model.len() >= refereed.len(), "{mouse} on maze {n}");
                assert_eq!(refereed, model[..refereed.len()], "{mouse} on maze {n}");
            }
            if mouse.ends_with("stop_at_goal.py") {
                // Asked wasReset at the centre: told true, it ran again and finished.
                assert_eq!(record["status"], "finished", "{mouse} on maze {n}");
            }
        }
    }
}

/// The mouse's lines and the referee's answers in `text` (`mouse: LINE  [referee: ]ANSWER`),
/// as a recording of the relay fixture and docs/PROTOCOL-mms.md show them.
fn exchange_lines(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter_map(|l| l.strip_prefix("mouse: "))
        .filter_map(|l| {
            let (line, rest) = l.split_once("  ")?;
            let answer = rest.trim();
            let answer = answer.strip_prefix("referee: ").unwrap_or(answer);
            Some((line.trim().to_string(), answer.to_string()))
        })
        .collect()
}

#[test]
fn a_mouse_that_exits_at_the_goal_is_told_how_to_get_its_second_run() {
    let record = run_mouse("tests/fixtures/bots/mms/stop_at_goal.py --exit", 1, &[]);
    assert_eq!(record["status"], "crashed", "{record}");
    let reason = record["error"]["reason"].as_str().unwrap();
    assert!(
        reason.contains("exited with status 0") && reason.contains("asking wasReset"),
        "{reason}"
    );
}

#[test]
fn the_protocols_doc_shows_a_real_exchange_and_the_kits_real_scores() {
    let doc = std::fs::read_to_string(super::support::root().join("docs/PROTOCOL-mms.md")).unwrap();
    // The exchange in the doc: its mouse lines, in order, with their answers.
    let block = doc
        .split("## A whole exchange")
        .nth(1)
        .and_then(|s| s.split("```text").nth(1))
        .and_then(|s| s.split("```").next())
        .expect("the doc's exchange");
    // A move's answer comes after its step: the doc shows the step (`-> ...`) there.
    let shown: Vec<(String, String)> = exchange_lines(block)
        .into_iter()
        .map(|(line, answer)| {
            let answer = if answer.starts_with("->") {
                "ack".to_string()
            } else {
                answer
            };
            (line, answer)
        })
        .collect();
    assert!(shown.len() > 10, "{shown:?}");
    let record = run_mouse(
        "tests/fixtures/bots/mms/relay.py python3 bots/mms/python/floodfill.py",
        1,
        &[],
    );
    assert_eq!(record["status"], "finished", "{record}");
    let log = record["stderr_tail"].as_str().unwrap();
    let real = exchange_lines(log);
    // Each shown exchange is the real one, in the same order (the doc leaves some out).
    let mut at = 0;
    for (line, answer) in &shown {
        let found = real[at..]
            .iter()
            .position(|(l, a)| l == line && a == answer)
            .unwrap_or_else(|| {
                panic!("{line} -> {answer} is not in the real exchange after line {at}")
            });
        at += found + 1;
    }
    // The doc's first lines are the real first lines.
    assert_eq!(real[..shown.len().min(6)], shown[..shown.len().min(6)]);
    // And its scores are the kit's.
    let scores: Vec<String> = (1..=3)
        .map(|n| {
            let r = run_mouse("bots/mms/python/floodfill.py", n, &[]);
            format!("{:.3}", r["score"].as_f64().unwrap())
        })
        .collect();
    let line = format!("{}, {} and {}", scores[0], scores[1], scores[2]);
    assert!(
        doc.contains(&line),
        "the doc gives the kit's scores as {line}"
    );
}
