//! Mice written for the mms simulator, through `mazearena run --protocol mms` with real
//! processes, in the sandbox: every answer of the protocol as the mouse reads it, a mouse
//! that prints garbage and waits for ever, one that hard-codes 16x16 on a 12x12 maze, and
//! the kit's flood-fill mouse finishing the classic mazes with the same score in the
//! sandbox and out.

use serde_json::Value;

use super::support::{mazearena, processes_matching, shared_maze};

/// `run --protocol mms` of `mouse` on classic maze `n`, with `extra` flags: the whole
/// record with its trace (`--replay`; the run may end in any status: the exit code is
/// not looked at).
fn run_mouse(mouse: &str, n: u32, extra: &[&str]) -> Value {
    let maze = shared_maze(&format!("classic/test_maze_0{n}.txt"));
    let bot = format!("python3 {mouse}");
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
    // Classic maze 1, added as a public maze.
    let layout = std::fs::read_to_string(shared_maze("classic/test_maze_01.txt")).unwrap();
    let (s, maze) = server
        .post(
            "/api/mazes",
            json!({"name": "classic-1", "layout": layout}),
            Some(super::support::ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{maze}");
    let classic = maze["maze_id"].as_i64().unwrap();
    let m = queue(&server, id, classic, 1, &token).await;
    let done = wait_match(&server, m).await;
    assert_eq!(done["status"], "finished", "{done}");
    assert_eq!(done["score"], 25.0, "the same as `run` gives: {done}");
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
