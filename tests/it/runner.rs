//! The bot runner against real subprocess bots: one fixture per failure mode, exact
//! step counts with a scripted bot, and no process left behind.

use std::time::Duration;

use mazearena::engine::{Action, solver};
use mazearena::runner::{BotSpec, Limits, MatchRecord, MatchStatus, Sandbox, run_match};

use crate::support::{classic, fixture_bot, live_group_members, root, sandbox};

fn limits() -> Limits {
    Limits {
        startup_timeout: Some(Duration::from_secs(5)),
        move_timeout: Some(Duration::from_millis(1000)),
        ..Limits::default()
    }
}

async fn play(bot: BotSpec, limits: Limits) -> MatchRecord {
    let record = run_match(&bot, &classic(1), 7, limits, &sandbox(), |_| {}).await;
    let pgid = record.bot_pid.expect("the bot was started");
    assert_eq!(
        live_group_members(pgid),
        Vec::<u32>::new(),
        "processes of the bot's group are still alive after the match"
    );
    record
}

fn reason(r: &MatchRecord) -> &str {
    &r.error.as_ref().expect("a failure is recorded").reason
}

/// Answers for one run: the solver's optimal actions as `rot,mov` arguments.
fn optimal_script(n: u32) -> Vec<String> {
    let solution = solver::solve(&classic(n)).unwrap();
    solution
        .actions
        .iter()
        .map(|a| match a {
            Action::Move { rotation, movement } => format!("{rotation},{movement}"),
            Action::Reset { .. } => "reset".to_string(),
        })
        .collect()
}

#[tokio::test]
async fn not_json_is_a_protocol_error_with_the_line() {
    let r = play(fixture_bot("not_json", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(reason(&r).contains("not JSON"), "{}", reason(&r));
    assert_eq!(r.error.as_ref().unwrap().line.as_deref(), Some("hello"));
    assert_eq!(r.total_steps, 1);
    assert_eq!(r.score, None);
}

#[tokio::test]
async fn not_an_object_is_a_protocol_error() {
    let r = play(fixture_bot("not_object", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(reason(&r).contains("not an object"), "{}", reason(&r));
}

#[tokio::test]
async fn a_float_movement_is_a_protocol_error() {
    let r = play(fixture_bot("float_move", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(
        reason(&r).contains("\"movement\" must be a JSON integer"),
        "{}",
        reason(&r)
    );
}

#[tokio::test]
async fn a_missing_field_is_a_protocol_error() {
    let r = play(fixture_bot("missing_field", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(
        reason(&r).contains("no \"movement\" field"),
        "{}",
        reason(&r)
    );
}

#[tokio::test]
async fn invalid_utf8_is_a_protocol_error() {
    let r = play(fixture_bot("invalid_utf8", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(reason(&r).contains("UTF-8"), "{}", reason(&r));
    assert!(r.error.as_ref().unwrap().line.is_some());
}

#[tokio::test]
async fn a_100_kb_line_is_a_protocol_error_cut_to_200_bytes() {
    let r = play(fixture_bot("long_line", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::ProtocolError);
    assert!(
        reason(&r).contains("longer than 65536 bytes"),
        "{}",
        reason(&r)
    );
    let line = r.error.as_ref().unwrap().line.as_ref().unwrap();
    assert!(line.len() <= 200 + 3, "excerpt is {} bytes", line.len());
}

#[tokio::test]
async fn a_silent_bot_times_out_at_startup() {
    let limits = Limits {
        startup_timeout: Some(Duration::from_millis(1500)),
        ..limits()
    };
    let r = play(fixture_bot("silent", &[]), limits).await;
    assert_eq!(r.status, MatchStatus::Timeout);
    assert!(
        reason(&r).contains("startup limit of 1500 ms"),
        "{}",
        reason(&r)
    );
    assert_eq!(r.total_steps, 1);
}

#[tokio::test]
async fn a_slow_start_times_out() {
    let limits = Limits {
        startup_timeout: Some(Duration::from_millis(1000)),
        ..limits()
    };
    let r = play(fixture_bot("slow_start", &[]), limits).await;
    assert_eq!(r.status, MatchStatus::Timeout);
    assert!(reason(&r).contains("startup"), "{}", reason(&r));
}

#[tokio::test]
async fn each_step_records_the_cpu_time_the_bot_spent_on_it_with_and_without_the_sandbox() {
    for sandbox in [Sandbox::None, sandbox()] {
        let bot = fixture_bot("busy_step", &[]);
        let limits = Limits {
            max_steps: 8,
            ..limits()
        };
        let r = run_match(&bot, &classic(1), 7, limits, &sandbox, |_| {}).await;
        assert_eq!(r.status, MatchStatus::StepLimit, "{:?}", r.error);
        let cpu: Vec<u64> = r.trace.iter().map(|s| s.cpu_us.unwrap()).collect();
        // 200 ms of CPU before the third answer, and little before the others (the first
        // holds Python's start).
        assert!(
            (190_000..=r.trace[2].answer_us).contains(&cpu[2]),
            "{cpu:?}"
        );
        for (i, &c) in cpu.iter().enumerate().skip(3) {
            assert!(c < 20_000, "step {}: {cpu:?}", i + 1);
        }
    }
}

#[tokio::test]
async fn one_shot_matches_in_a_row_each_count_only_their_own_cpu_time() {
    // As root with cgroups, one-shot matches take up the cgroups kept on the host
    // between them (their counters go on from match to match): each match's figures
    // are its own.
    let sandbox = sandbox();
    let bot = fixture_bot("busy_step", &[]);
    let limits = Limits {
        max_steps: 8,
        ..limits()
    };
    for round in 0..4 {
        let r = run_match(&bot, &classic(1), 7, limits, &sandbox, |_| {}).await;
        assert_eq!(r.status, MatchStatus::StepLimit, "{:?}", r.error);
        let steps: u64 = r.trace.iter().map(|s| s.cpu_us.unwrap()).sum();
        assert!(
            (190_000..600_000).contains(&steps),
            "round {round}: {steps}"
        );
        let whole = r.timings.bot_cpu_ms.unwrap();
        assert!((190..900).contains(&whole), "round {round}: {whole} ms");
    }
}

/// The cgroups of one-shot matches and a match's limits, where kept cgroups are made
/// (as root with cgroups; CI=true has them); `None`, with the reason printed, elsewhere.
fn kept_cgroups() -> Option<(
    mazearena::runner::sandbox::cgroup::CgroupRoot,
    mazearena::runner::sandbox::cgroup::CgroupLimits,
)> {
    let Sandbox::Full(full) = sandbox() else {
        println!("SKIP: no sandbox here");
        return None;
    };
    let root = match (&full.cgroups, nix::unistd::geteuid().is_root()) {
        (Ok(root), true) => root.clone(),
        (e, _) => {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true runs as root with cgroups: {e:?}"
            );
            println!("SKIP: kept cgroups are made as root with cgroups");
            return None;
        }
    };
    let limits = mazearena::runner::sandbox::cgroup::CgroupLimits {
        memory_bytes: Some(64 << 20),
        pids: Some(8),
        core: None,
    };
    Some((root, limits))
}

#[test]
fn a_process_left_in_a_kept_cgroup_dies_before_the_next_match_takes_it_up() {
    // A runner killed before it could empty its kept cgroup leaves its bot there,
    // running: whichever match takes the cgroup up next kills it first.
    let Some((root, limits)) = kept_cgroups() else {
        return;
    };
    let first = root.kept(limits).unwrap();
    let files = first.join_files();
    drop(first);
    let script = files
        .iter()
        .map(|f| format!("echo $$ > {}", f.display()))
        .chain(["exec sleep 60".to_string()])
        .collect::<Vec<_>>()
        .join("; ");
    let mut left = std::process::Command::new("sh")
        .args(["-c", &script])
        .spawn()
        .unwrap();
    let procs = files[0].with_file_name("cgroup.procs");
    let until = std::time::Instant::now() + Duration::from_secs(10);
    while std::fs::read_to_string(&procs).unwrap().trim().is_empty() {
        assert!(
            std::time::Instant::now() < until,
            "the process never joined"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    // Every free kept cgroup is taken up until that one is: the others stay held, so
    // that one is taken up either here or by a match of another test.
    let mut held = Vec::new();
    for _ in 0..=16 {
        let group = root.kept(limits).unwrap();
        let same = group.join_files() == files;
        held.push(group);
        if same {
            break;
        }
    }
    let until = std::time::Instant::now() + Duration::from_secs(5);
    let status = loop {
        if let Some(status) = left.try_wait().unwrap() {
            break status;
        }
        assert!(
            std::time::Instant::now() < until,
            "the process left in a kept cgroup still runs"
        );
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(status.code().is_none(), "killed, not ended: {status:?}");
    drop(held);
}

#[test]
fn a_kept_cgroup_that_still_counts_an_ended_process_is_not_taken_up() {
    let Some((root, limits)) = kept_cgroups() else {
        return;
    };
    let first = root.kept(limits).unwrap();
    let files = first.join_files();
    // A process that joins it and ends, not yet reaped (its parent, this test, has not
    // waited for it): the cgroup still counts it.
    let script = files
        .iter()
        .map(|f| format!("echo $$ > {}", f.display()))
        .collect::<Vec<_>>()
        .join("; ");
    let mut child = std::process::Command::new("sh")
        .args(["-c", &script])
        .spawn()
        .unwrap();
    let pids_dir = files
        .iter()
        .map(|f| f.parent().unwrap().to_path_buf())
        .find(|d| d.join("pids.current").exists())
        .unwrap();
    let counted = || {
        std::fs::read_to_string(pids_dir.join("pids.current"))
            .unwrap()
            .trim()
            .parse::<u64>()
            .unwrap()
    };
    let member = || {
        !std::fs::read_to_string(pids_dir.join("cgroup.procs"))
            .unwrap()
            .trim()
            .is_empty()
    };
    // Until it has joined (counted) and ended (no longer a member).
    let until = std::time::Instant::now() + Duration::from_secs(10);
    while (counted() == 0 || member()) && std::time::Instant::now() < until {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(counted(), 1, "the ended process is still counted");
    drop(first);
    // Taken up, that cgroup would count it against the next match's process limit: the
    // next match gets one that counts nothing (another, or that one made anew).
    let second = root.kept(limits).unwrap();
    let counts = |files: &[std::path::PathBuf]| {
        files
            .iter()
            .map(|f| f.parent().unwrap().join("pids.current"))
            .find(|p| p.exists())
            .map(|p| std::fs::read_to_string(p).unwrap().trim().to_string())
    };
    assert_eq!(counts(&second.join_files()).as_deref(), Some("0"));
    drop(second);
    child.wait().unwrap();
}

#[tokio::test]
async fn stderr_written_before_each_answer_is_kept_with_its_step() {
    for sandbox in [Sandbox::None, sandbox()] {
        let bot = fixture_bot("stderr_each_step", &[]);
        let r = run_match(&bot, &classic(1), 7, limits(), &sandbox, |_| {}).await;
        assert_eq!(r.status, MatchStatus::StepLimit, "{:?}", r.error);
        assert_eq!(r.trace.len(), 1000);
        for (i, s) in r.trace.iter().enumerate() {
            let step = i + 1;
            let want: Vec<String> = (0..step % 4)
                .map(|l| format!("step {step} line {l}"))
                .collect();
            assert_eq!(s.stderr, want, "step {step} ({})", sandbox.level());
        }
    }
}

#[tokio::test]
async fn a_slow_move_times_out_at_step_2() {
    let limits = Limits {
        move_timeout: Some(Duration::from_millis(300)),
        ..limits()
    };
    let r = play(fixture_bot("slow_move", &[]), limits).await;
    assert_eq!(r.status, MatchStatus::Timeout);
    assert_eq!(r.total_steps, 2);
    assert!(
        reason(&r).contains("move limit of 300 ms"),
        "{}",
        reason(&r)
    );
    assert_eq!(r.trace.len(), 1);
}

#[tokio::test]
async fn a_bot_that_exits_early_has_crashed_with_its_exit_code_and_stderr() {
    let r = play(fixture_bot("exits_early", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::Crashed);
    let error = r.error.as_ref().unwrap();
    assert_eq!(error.exit_code, Some(3));
    assert_eq!(error.signal, None);
    assert!(!r.stderr_tail.trim().is_empty(), "the stderr tail is kept");
    // The reason says how it ended, not only that stdout closed (and nothing of its
    // stderr, which is its owner's).
    assert_eq!(
        error.reason,
        "the bot exited with status 3 before answering step 1"
    );
}

#[tokio::test]
async fn a_bot_killed_by_a_signal_has_crashed_with_the_signal() {
    let r = play(fixture_bot("killed_by_signal", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::Crashed);
    let error = r.error.as_ref().unwrap();
    assert_eq!(error.signal, Some(9));
    assert_eq!(error.exit_code, None);
}

#[tokio::test]
async fn a_forking_bot_leaves_no_process_behind() {
    let limits = Limits {
        startup_timeout: Some(Duration::from_millis(1500)),
        ..limits()
    };
    // `play` asserts that the whole process group, the `sleep` child included, is gone.
    let r = play(fixture_bot("forker", &[]), limits).await;
    assert_eq!(r.status, MatchStatus::Timeout);
}

#[tokio::test]
async fn a_stderr_flood_is_kept_to_a_bounded_tail() {
    let r = play(fixture_bot("stderr_flood", &[]), limits()).await;
    assert_eq!(r.status, MatchStatus::StepLimit);
    assert_eq!(r.total_steps, 1000);
    assert!(
        r.stderr_tail.len() <= 64 * 1024 + 100,
        "{}",
        r.stderr_tail.len()
    );
    assert!(r.stderr_tail.starts_with("[... "));
}

/// Plays `bot` on its own thread (as a worker plays each match), measuring that thread's
/// CPU clock: the record and the referee's CPU time over the match, in ms.
fn play_measured(bot: BotSpec) -> (MatchRecord, f64) {
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        let before = mazearena::runner::flood::thread_cpu_us().unwrap();
        let record = rt.block_on(run_match(
            &bot,
            &classic(1),
            7,
            limits(),
            &sandbox(),
            |_| {},
        ));
        let after = mazearena::runner::flood::thread_cpu_us().unwrap();
        (record, (after - before) as f64 / 1000.0)
    })
    .join()
    .unwrap()
}

/// A flood of output (short stderr lines, one endless stderr line, an mms mouse's
/// display commands: hundreds of MiB made from one buffer, written a pipe's worth at a
/// time) costs the referee's thread no more CPU time than the bot is charged for it,
/// measured with the thread's own clock against the same bot played quietly; the
/// match's result and the stderr tail are the quiet match's.
#[test]
fn a_flood_of_output_costs_the_referee_no_more_cpu_than_its_bot() {
    for (mode, mib) in [("stderr", "16"), ("stderr-long", "16"), ("mms", "4")] {
        let bot = |mib: &str| {
            let mut b = fixture_bot("flood", &[mode, mib, "20"]);
            if mode == "mms" {
                b.protocol = mazearena::runner::BotProtocol::Mms;
            }
            b
        };
        let (quiet, quiet_referee) = play_measured(bot("0"));
        let (flood, flood_referee) = play_measured(bot(mib));
        let cpu = |r: &MatchRecord| r.timings.bot_cpu_ms.unwrap() as f64;
        let referee = flood_referee - quiet_referee;
        let charged = cpu(&flood) - cpu(&quiet);
        eprintln!(
            "{mode}: {mib} MiB x 20 steps: the referee's thread {flood_referee:.0} ms \
             ({quiet_referee:.0} quiet), the bot {} ms ({} quiet)",
            cpu(&flood),
            cpu(&quiet)
        );
        assert!(
            referee <= charged * 1.1 + 30.0,
            "{mode}: the flood cost the referee {referee:.0} ms more than the quiet match, \
             and its bot {charged:.0} ms more"
        );
        assert!(
            referee > 0.0 && charged > 0.0,
            "{mode}: no flood was taken in"
        );
        assert_eq!(
            (flood.status, flood.total_steps, flood.score),
            (quiet.status, quiet.total_steps, quiet.score),
            "{mode}: {:?}",
            flood.error
        );
        if mode != "mms" {
            assert!(flood.stderr_tail.starts_with("[... "), "{mode}");
            assert!(flood.stderr_tail.len() >= 60 * 1024, "{mode}");
        }
    }
}

#[tokio::test]
async fn a_command_that_cannot_start_has_crashed() {
    let bot = BotSpec::new("./no-such-bot --fast", root());
    let r = run_match(&bot, &classic(1), 0, limits(), &sandbox(), |_| {}).await;
    assert_eq!(r.status, MatchStatus::Crashed);
    assert!(reason(&r).contains("could not start"), "{}", reason(&r));
    assert_eq!(r.total_steps, 0);
}

#[tokio::test]
async fn an_optimal_script_scores_exactly_by_the_rules() {
    // Run 0: the 17 optimal steps, then a reset (step 18, counted in run 0);
    // run 1: the same 17 steps. Score = 17 + 18/30 = 17.600.
    let script = optimal_script(1);
    assert_eq!(script.len(), 17);
    let mut args: Vec<&str> = script.iter().map(String::as_str).collect();
    args.push("reset");
    args.extend(script.iter().map(String::as_str));
    let r = play(fixture_bot("scripted", &args), limits()).await;
    assert_eq!(r.status, MatchStatus::Finished, "{:?}", r.error);
    assert_eq!(r.run0_steps, Some(18));
    assert_eq!(r.run1_steps, Some(17));
    assert_eq!(r.total_steps, 35);
    assert_eq!(r.score, Some(17.6));
    assert_eq!(r.trace.len(), 35);
    assert_eq!(r.trace[0].report.sensors, [0, 11, 0]);
    assert!(r.warnings.is_empty());
}

#[tokio::test]
async fn an_early_reset_and_lenient_answers_are_counted_and_warned() {
    // Step 1: reset before the goal (rejected, costs a step); step 2: rotation 45
    // (no rotation, warning); step 3: movement 9 (clamped to 3, warning).
    let r = play(fixture_bot("scripted", &["reset", "45,0", "0,9"]), limits()).await;
    assert_eq!(r.status, MatchStatus::StepLimit);
    assert_eq!(r.total_steps, 1000);
    assert_eq!(r.run0_steps, None);
    let kinds: Vec<String> = r
        .warnings
        .iter()
        .map(|w| format!("{}:{:?}", w.step, w.kind))
        .collect();
    assert_eq!(
        kinds,
        ["1:ResetRejected", "2:InvalidRotation", "3:MovementClamped"]
    );
    // Maze 01 has 11 open cells ahead at the start: the clamped move goes 3 up.
    assert_eq!(
        r.trace[2].report.position,
        mazearena::engine::Position::new(0, 3)
    );
}

#[tokio::test]
async fn many_matches_run_at_once() {
    let script = optimal_script(1);
    let mut args: Vec<String> = script.clone();
    args.push("reset".into());
    args.extend(script);
    let tasks: Vec<_> = (0..8)
        .map(|seed| {
            let args = args.clone();
            tokio::spawn(async move {
                let args: Vec<&str> = args.iter().map(String::as_str).collect();
                run_match(
                    &fixture_bot("scripted", &args),
                    &classic(1),
                    seed,
                    limits(),
                    &sandbox(),
                    |_| {},
                )
                .await
            })
        })
        .collect();
    for t in tasks {
        let r = t.await.unwrap();
        assert_eq!(r.status, MatchStatus::Finished);
        assert_eq!(r.score, Some(17.6));
    }
}

#[tokio::test]
async fn a_memory_hog_is_stopped_by_the_memory_limit() {
    let limits = Limits {
        memory_limit_mb: Some(512),
        ..limits()
    };
    let r = play(fixture_bot("memory_hog", &[]), limits).await;
    match sandbox() {
        // All processes together: the cgroup's OOM kill (or the watchdog) ends it.
        mazearena::runner::Sandbox::Full(_) => {
            assert_eq!(r.status, MatchStatus::MemoryLimit, "{:?}", r.error);
            let hit = r.error.as_ref().unwrap().limit.as_ref().unwrap();
            assert_eq!((hit.name.as_str(), hit.value), ("memory", 512));
        }
        // Per process: the address-space limit makes the allocation fail.
        mazearena::runner::Sandbox::None => {
            assert_eq!(r.status, MatchStatus::Crashed);
            assert!(r.stderr_tail.contains("MemoryError"), "{}", r.stderr_tail);
        }
    }
    assert_eq!(r.limits.memory_limit_mb, Some(512));
}

#[test]
fn a_match_runs_on_one_core_and_its_bot_is_pinned_to_it_in_the_sandbox_too() {
    let out = crate::support::mazearena(&[
        "run",
        "--maze",
        "mazes/gen-12-s1.txt",
        "--bot",
        "python3 tests/fixtures/bots/reports_cpus.py",
        "--json",
    ]);
    assert!(out.status.success(), "{out:?}");
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["status"], "step_limit", "{r}");
    let core = r["core"].as_u64().expect("the record names its core");
    let tail = r["stderr_tail"].as_str().unwrap();
    assert_eq!(tail.trim(), format!("cpus {core}"), "{r}");
    assert_eq!(r["limits"]["sandbox"], sandbox().level());
}
