//! The hostile-bot suite: one fixture bot per attack (tests/fixtures/bots/hostile), run
//! through the real CLI and a real server in the full sandbox. Each attack must fail (the
//! bot reports `HOSTILE BLOCKED`, never `HOSTILE LEAK`) or end as a recorded limit, and no
//! process of the bot may be left.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::support::{
    ADMIN, TestServer, full_sandbox, mazearena, processes_matching, register, root, shared_maze,
    simple_bot_files, wait_match,
};

const HOSTILE: &str = "tests/fixtures/bots/hostile";

fn maze() -> PathBuf {
    shared_maze("classic/test_maze_01.txt")
}

/// Plays `script args` from the hostile folder twice, and returns both records: through
/// `mazearena run --json` (a one-shot sandbox), and through a warm sandbox kept by this
/// test's process for all its attacks, as a server, a worker or a tournament plays it.
/// `extra` holds `run`'s options (only `--scratch-mb` is used by the attacks).
fn attack(script: &str, args: &[&str], extra: &[&str]) -> [Value; 2] {
    let one_shot = attack_one_shot(script, args, extra);
    let warm = attack_warm(script, args, extra);
    [one_shot, warm]
}

fn bot_command(script: &str, args: &[&str]) -> String {
    let mut bot = format!("python3 {script}");
    for a in args {
        bot.push(' ');
        bot.push_str(&shlex::try_quote(a).unwrap());
    }
    bot
}

/// No process of `bot` is left.
fn nothing_left(bot: &str) {
    assert!(
        processes_matching(bot).is_empty(),
        "processes of {bot} outlived the match: {:?}",
        processes_matching(bot)
    );
}

fn attack_one_shot(script: &str, args: &[&str], extra: &[&str]) -> Value {
    let bot = bot_command(script, args);
    let maze = maze();
    let mut cli = vec![
        "run",
        "--maze",
        maze.to_str().unwrap(),
        "--bot",
        &bot,
        "--bot-dir",
        HOSTILE,
        "--json",
    ];
    cli.extend_from_slice(extra);
    let out = mazearena(&cli);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let record: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(record["limits"]["sandbox"], "full");
    nothing_left(&bot);
    record
}

thread_local! {
    /// The warm sandboxes of this test (a runner of many matches, finding each bot's
    /// runtime as `run` and `tournament` do), its own even where tests share a process.
    static WARM: mazearena::runner::Sandbox = mazearena::runner::Sandbox::full(
        Path::new(env!("CARGO_BIN_EXE_mazearena")),
        &mazearena::runner::sandbox::Setup {
            detect: true,
            reuse: true,
            ..Default::default()
        },
    )
    .unwrap();
}

fn attack_warm(script: &str, args: &[&str], extra: &[&str]) -> Value {
    use mazearena::runner::{BotSpec, Limits, run_match};
    let bot = bot_command(script, args);
    let mut limits = Limits::default();
    if let Some(at) = extra.iter().position(|a| *a == "--scratch-mb") {
        limits.scratch_mb = extra[at + 1].parse().unwrap();
    }
    let maze = crate::support::classic(1);
    let spec = BotSpec::new(bot.clone(), root().join(HOSTILE));
    // One core for the referee and the bot, as `run` and a server's workers have.
    mazearena::runner::affinity::pin_to_this_core();
    let sandbox = WARM.with(Clone::clone);
    let mazearena::runner::Sandbox::Full(full) = &sandbox else {
        unreachable!("a full sandbox")
    };
    let before = full.warm.matches_started();
    let record = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(run_match(&spec, &maze, 0, limits, &sandbox, |_| {}));
    let record = serde_json::to_value(record.summary()).unwrap();
    assert_eq!(record["limits"]["sandbox"], "full");
    if nix::unistd::geteuid().is_root() && full.cgroups.is_ok() {
        assert_eq!(
            full.warm.matches_started(),
            before + 1,
            "the match was played in a warm sandbox"
        );
    }
    nothing_left(&bot);
    record
}

fn stderr(r: &Value) -> &str {
    r["stderr_tail"].as_str().unwrap_or("")
}

/// No attack worked, and at least `blocked` were seen to fail.
fn contained(r: &Value, blocked: usize) {
    let log = stderr(r);
    assert!(!log.contains("HOSTILE LEAK"), "an attack worked:\n{log}");
    assert!(
        log.matches("HOSTILE BLOCKED").count() >= blocked,
        "fewer than {blocked} attacks were seen to fail:\n{log}"
    );
}

#[test]
fn a_bot_cannot_read_the_database_the_data_dir_other_bots_or_the_maze() {
    let Some(_) = full_sandbox("hostile read") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("mazearena.db");
    std::fs::write(&db, "SECRET").unwrap();
    let other = tmp.path().join("data/bots/7/1");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("bot.py"), "SECRET").unwrap();
    let maze = maze();
    let paths = [&db, &tmp.path().join("data"), &other.join("bot.py"), &maze];
    let args: Vec<&str> = paths.iter().map(|p| p.to_str().unwrap()).collect();
    for r in attack("read_file.py", &args, &[]) {
        contained(&r, 4);
        assert_eq!(r["status"], "step_limit");
    }
}

#[test]
fn a_bot_cannot_read_the_servers_environment_nor_see_its_processes() {
    let Some(_) = full_sandbox("hostile environ") else {
        return;
    };
    for r in attack("parent_environ.py", &[], &[]) {
        contained(&r, 1);
    }
    for r in attack("list_processes.py", &["mazearena", "cargo"], &[]) {
        contained(&r, 1);
        // The namespace's init, the bot: the namespace holds nothing else.
        let seen = stderr(&r)
            .split("count=")
            .nth(1)
            .and_then(|s| s.split_whitespace().next())
            .and_then(|n| n.parse::<u32>().ok())
            .unwrap();
        assert!(seen <= 3, "{}", stderr(&r));
    }
}

#[test]
fn a_bot_cannot_signal_the_server_or_another_bot() {
    let Some(_) = full_sandbox("hostile signal") else {
        return;
    };
    let mut victims: Vec<std::process::Child> = (0..2)
        .map(|_| {
            std::process::Command::new("sleep")
                .arg("60")
                .spawn()
                .unwrap()
        })
        .collect();
    let pids: Vec<String> = victims.iter().map(|c| c.id().to_string()).collect();
    let args: Vec<&str> = pids.iter().map(String::as_str).collect();
    for r in attack("signal_pid.py", &args, &[]) {
        contained(&r, 2);
    }
    for v in &mut victims {
        assert!(v.try_wait().unwrap().is_none(), "a victim was killed");
        let stat = std::fs::read_to_string(format!("/proc/{}/stat", v.id())).unwrap();
        let state = stat.rsplit_once(')').unwrap().1.trim_start().chars().next();
        assert_ne!(state, Some('T'), "a victim was stopped");
        let _ = v.kill();
        let _ = v.wait();
    }
}

#[test]
fn setsid_and_a_double_fork_do_not_outlive_the_match() {
    let Some(_) = full_sandbox("hostile setsid") else {
        return;
    };
    for r in attack("setsid_escape.py", &["4171"], &[]) {
        assert!(stderr(&r).contains("grandchild"), "{}", stderr(&r));
        assert!(processes_matching("sleep 4171").is_empty());
    }
}

#[test]
fn forking_300_ends_at_the_process_limit() {
    let Some(_) = full_sandbox("hostile fork") else {
        return;
    };
    for r in attack("fork_many.py", &["300"], &[]) {
        assert_eq!(r["status"], "process_limit", "{r}");
        assert_eq!(r["error"]["limit"]["name"], "processes");
        assert_eq!(r["error"]["limit"]["value"], 64);
        contained(&r, 0);
    }
}

#[test]
fn children_holding_4_5_gib_end_at_the_memory_limit() {
    let Some(_) = full_sandbox("hostile memory") else {
        return;
    };
    for r in attack("memory_children.py", &["3", "1536"], &[]) {
        assert_eq!(r["status"], "memory_limit", "{r}");
        assert_eq!(r["error"]["limit"]["name"], "memory");
        assert_eq!(r["error"]["limit"]["value"], 1024);
    }
}

#[test]
fn spinning_children_are_counted_in_the_cpu_time_and_die_with_the_match() {
    let Some(_) = full_sandbox("hostile spin") else {
        return;
    };
    let spinning = attack("spin_children.py", &["4"], &[]);
    // The same bot without spinners, for comparison.
    let calm = attack("spin_children.py", &["0"], &[]);
    for (r, calm) in spinning.iter().zip(&calm) {
        assert_eq!(r["status"], "step_limit", "{r}");
        let ms = |r: &Value, k: &str| r["timings"][k].as_u64().unwrap();
        let (cpu, wall, calm_cpu) = (
            ms(r, "bot_cpu_ms"),
            ms(r, "wall_ms"),
            ms(calm, "bot_cpu_ms"),
        );
        // The spinners share the match's one core with the bot and the referee, and with
        // whatever else the machine runs there (under the test suite's load, several
        // other busy processes), so they get some part of it, and all of it is counted.
        // Without them counted, the two CPU times would be about the same.
        assert!(
            cpu >= calm_cpu + (wall / 10).max(50),
            "cpu {cpu} ms (without spinners {calm_cpu} ms) over a wall time of {wall} ms: {r}"
        );
    }
}

#[test]
fn a_bot_cannot_make_the_refused_system_calls_nor_reach_them_through_the_x32_abi() {
    let Some(_) = full_sandbox("hostile syscalls") else {
        return;
    };
    // Eighteen calls by their own numbers (six of them probes of the page cache) and
    // three through the x32 ABI, each answered by the filter (the fixture reports a LEAK
    // for any other answer); an ordinary preadv2 is not refused.
    let calls = if cfg!(target_arch = "x86_64") { 21 } else { 0 };
    for r in attack("syscalls.py", &[], &[]) {
        assert_eq!(r["status"], "step_limit", "{r}");
        contained(&r, calls);
        if calls > 0 {
            assert!(
                stderr(&r).contains("HOSTILE INFO plain preadv2 EBADF"),
                "{}",
                stderr(&r)
            );
        }
    }
}

#[test]
fn a_bot_cannot_leave_the_core_of_its_match() {
    let Some(_) = full_sandbox("hostile core") else {
        return;
    };
    for r in attack("leave_core.py", &[], &[]) {
        assert_eq!(r["status"], "step_limit", "{r}");
        contained(&r, 2);
        let core = r["core"]
            .as_u64()
            .expect("the match ran on a core of its own");
        assert!(
            stderr(&r).contains(&format!("BLOCKED cores={core}\n"))
                && stderr(&r).contains(&format!("BLOCKED child cores={core}\n")),
            "core {core}: {}",
            stderr(&r)
        );
    }
}

#[test]
fn filling_the_scratch_area_ends_at_the_scratch_limit_and_leaves_nothing() {
    let Some(_) = full_sandbox("hostile scratch") else {
        return;
    };
    for r in attack("fill_scratch.py", &["200"], &["--scratch-mb", "16"]) {
        assert_eq!(r["status"], "scratch_limit", "{r}");
        assert!(stderr(&r).contains("Errno 28"), "{}", stderr(&r));
    }
    assert!(!root().join(HOSTILE).join("fill_scratch.bin").exists());
}

#[test]
fn a_bot_cannot_write_outside_its_scratch_area() {
    let Some(_) = full_sandbox("hostile write") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let next_to = root().join(HOSTILE).join("pwned.txt");
    let outside = tmp.path().join("pwned.txt");
    let args = [
        next_to.to_str().unwrap(),
        outside.to_str().unwrap(),
        "/etc/mazearena-pwned",
        "_hostile.py",
        "/usr/local/mazearena-pwned",
    ];
    let before = std::fs::read(root().join(HOSTILE).join("_hostile.py")).unwrap();
    for r in attack("write_outside.py", &args, &[]) {
        contained(&r, 5);
    }
    let fixed = [
        Path::new("/etc/mazearena-pwned"),
        Path::new("/usr/local/mazearena-pwned"),
    ];
    for p in [next_to.as_path(), outside.as_path()]
        .into_iter()
        .chain(fixed)
    {
        assert!(!p.exists(), "{} was written", p.display());
    }
    assert_eq!(
        std::fs::read(root().join(HOSTILE).join("_hostile.py")).unwrap(),
        before
    );
}

#[test]
fn a_bot_cannot_reach_a_loopback_listener() {
    let Some(_) = full_sandbox("hostile network") else {
        return;
    };
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    listener.set_nonblocking(true).unwrap();
    let port = listener.local_addr().unwrap().port().to_string();
    for r in attack("network.py", &[&port], &[]) {
        contained(&r, 1);
    }
    assert!(listener.accept().is_err(), "the bot connected");
}

#[test]
fn nothing_a_bot_writes_survives_its_match() {
    let Some(_) = full_sandbox("hostile keep") else {
        return;
    };
    for _ in 0..2 {
        for r in attack("keep_file.py", &[], &[]) {
            contained(&r, 0);
            assert!(stderr(&r).contains("HOSTILE INFO none"), "{}", stderr(&r));
        }
    }
    assert!(!root().join(HOSTILE).join("kept.txt").exists());
}

fn hostile_files(script: &str) -> Value {
    let dir = root().join(HOSTILE);
    json!({
        script: std::fs::read_to_string(dir.join(script)).unwrap(),
        "_hostile.py": std::fs::read_to_string(dir.join("_hostile.py")).unwrap(),
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hostile_bots_on_a_real_server_are_contained_and_an_honest_match_is_unaffected() {
    let Some(_) = full_sandbox("hostile server") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let server = TestServer::start(tmp.path(), &["--jobs", "2", "--no-validation"]);
    let (status, health) = server.get("/healthz", None).await;
    assert_eq!((status, health["sandbox"].as_str()), (200, Some("full")));
    // What keeps the limits, as `doctor` finds it on this machine.
    let doctor = crate::support::mazearena(&["doctor"]);
    let text = String::from_utf8_lossy(&doctor.stdout).into_owned();
    let cgroups_ok = text
        .lines()
        .any(|l| l.starts_with("cgroups") && l.split_whitespace().nth(1) == Some("ok"));
    assert_eq!(
        health["limits"].as_str(),
        Some(if cgroups_ok { "cgroup" } else { "watchdog" }),
        "{health}\n{text}"
    );
    let server_pid = server.pid().to_string();
    let db = tmp.path().join("mazearena.db").display().to_string();
    let attackers = [
        ("killer", "signal_pid.py", server_pid.as_str(), "step_limit"),
        ("forker", "fork_many.py", "301", "process_limit"),
        ("hog", "memory_children.py", "3 1537", "memory_limit"),
        ("spinner", "spin_children.py", "5", "step_limit"),
        ("reader", "read_file.py", db.as_str(), "step_limit"),
    ];
    let (honest, honest_token) = register(
        &server,
        "honest",
        "python3 simple_bot.py",
        simple_bot_files(),
    )
    .await;
    let layout = std::fs::read_to_string(shared_maze("classic/test_maze_02.txt")).unwrap();
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": "c2", "layout": layout, "hidden": false}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 201, "{v}");
    let maze = v["maze_id"].as_i64().unwrap();
    let mut matches = Vec::new();
    for (name, script, args, want) in attackers {
        let command = format!("python3 {script} {args}");
        let (id, token) = register(&server, name, &command, hostile_files(script)).await;
        let (s, m) = server
            .post(
                "/api/matches",
                json!({"bot_id": id, "maze_id": maze, "seed": 3}),
                Some(&token),
            )
            .await;
        assert_eq!(s, 202, "{m}");
        // An honest match beside every attacker.
        let (s, h) = server
            .post(
                "/api/matches",
                json!({"bot_id": honest, "maze_id": maze, "seed": 3}),
                Some(&honest_token),
            )
            .await;
        assert_eq!(s, 202, "{h}");
        matches.push((m["match_id"].as_i64().unwrap(), want, token));
        matches.push((
            h["match_id"].as_i64().unwrap(),
            "finished",
            honest_token.clone(),
        ));
    }
    let mut honest_scores = Vec::new();
    for (id, want, token) in &matches {
        let m = wait_match(&server, *id).await;
        assert_eq!(m["status"], *want, "{m}");
        let (_, log) = server
            .get(&format!("/api/matches/{id}/log"), Some(token))
            .await;
        let tail = log["stderr_tail"].as_str().unwrap_or("");
        assert!(!tail.contains("HOSTILE LEAK"), "{tail}");
        if *want == "finished" {
            honest_scores.push(m["score"].as_f64().unwrap());
        }
    }
    // The honest bot scores exactly as it does alone (the CLI, same maze and seed).
    let alone = mazearena(&[
        "run",
        "--maze",
        shared_maze("classic/test_maze_02.txt").to_str().unwrap(),
        "--bot",
        "python3 bots/python/simple_bot.py",
        "--seed",
        "3",
        "--json",
    ]);
    let alone: Value = serde_json::from_slice(&alone.stdout).unwrap();
    let alone = alone["score"].as_f64().unwrap();
    assert!(
        honest_scores.iter().all(|s| *s == alone),
        "{honest_scores:?} vs {alone}"
    );
    let (status, _) = server.get("/healthz", None).await;
    assert_eq!(status, 200, "the server stopped answering");
    if nix::unistd::geteuid().is_root() && health["limits"] == "cgroup" {
        // As root with cgroups, the server's workers played in warm sandboxes: the
        // honest matches above ran right after each attack in the same ones.
        assert!(
            !crate::support::descendants_matching("sandbox-serve", server.pid()).is_empty(),
            "the server keeps warm sandboxes"
        );
    }
    for (_, script, args, _) in attackers {
        let command = format!("python3 {script} {args}");
        assert!(
            processes_matching(&command).is_empty(),
            "{command} left processes"
        );
    }
}

/// An API server (`serve --jobs 0`) runs no bot, so it starts where the sandbox cannot
/// be had (as in a container started without the sandbox's options) and says so; a
/// server that plays matches there refuses to start.
#[tokio::test]
async fn an_api_only_server_needs_no_sandbox_and_one_that_plays_refuses_without_it() {
    let tmp = tempfile::tempdir().unwrap();
    // No bubblewrap on this PATH: the full sandbox cannot be had.
    let env = [("MAZEARENA_SANDBOX", "full"), ("PATH", "/nonexistent")];
    let played = std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args([
            "serve",
            "--jobs",
            "1",
            "--bind",
            "127.0.0.1:0",
            "--data-dir",
        ])
        .arg(tmp.path().join("refused"))
        .arg("--database")
        .arg(format!(
            "sqlite://{}",
            tmp.path().join("refused.db").display()
        ))
        .env("MAZEARENA_ADMIN_TOKEN", crate::support::ADMIN)
        .envs(env)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&played.stderr);
    assert!(
        !played.status.success() && text.contains("refusing to serve without the sandbox"),
        "{text}"
    );
    let server = TestServer::start_on(tmp.path(), None, &["--jobs", "0"], &env);
    let (status, health) = server.get("/healthz", None).await;
    assert_eq!(status, 200);
    assert_eq!(
        (health["sandbox"].as_str(), health["limits"].as_str()),
        (Some("unused"), Some("unused")),
        "{health}"
    );
    // The counts are the admin's.
    assert!(health.get("workers").is_none(), "{health}");
    let (_, health) = server.get("/healthz", Some(ADMIN)).await;
    assert_eq!(health["workers"], json!([]), "{health}");
}

/// A full sandbox of its own that keeps warm sandboxes, as a runner of many matches
/// has; `None` (the test skipped, said why) without the sandbox or when not root.
fn warm_runner(test: &str) -> Option<mazearena::runner::Sandbox> {
    full_sandbox(test)?;
    if !nix::unistd::geteuid().is_root() {
        eprintln!("SKIPPED {test}: warm sandboxes are used by a runner that is root");
        return None;
    }
    let setup = mazearena::runner::sandbox::Setup {
        reuse: true,
        ..Default::default()
    };
    Some(
        mazearena::runner::Sandbox::full(Path::new(env!("CARGO_BIN_EXE_mazearena")), &setup)
            .unwrap(),
    )
}

/// A runner of many matches keeps a warm sandbox for them (servers, workers,
/// tournaments): every attack that tries to carry something from one match to the next
/// finds nothing, and no limit hit or CPU time of a match shows in the next one's
/// record, while the same sandbox plays them all.
#[tokio::test]
async fn a_warm_sandbox_carries_nothing_from_one_match_to_the_next() {
    use mazearena::runner::{BotSpec, Limits, MatchStatus, run_match};
    let Some(warm) = warm_runner("hostile warm") else {
        return;
    };
    let mazearena::runner::Sandbox::Full(full) = &warm else {
        unreachable!("a full sandbox was asked for")
    };
    let limits = Limits {
        memory_limit_mb: Some(256),
        process_limit: Some(32),
        ..Limits::default()
    };
    let maze = crate::support::classic(1);
    let mut supervisor: Option<Vec<u32>> = None;
    let mut play = async |script: &str| {
        let bot = BotSpec::new(format!("python3 {script}"), root().join(HOSTILE));
        let r = run_match(&bot, &maze, 0, limits, &warm, |_| {}).await;
        // One warm sandbox plays every match: the same one is idle after each.
        let serving = full.warm.idle_pids();
        assert_eq!(serving.len(), 1, "one warm sandbox, reused: {serving:?}");
        match &supervisor {
            None => supervisor = Some(serving),
            Some(first) => assert_eq!(&serving, first, "the same warm sandbox"),
        }
        assert!(processes_matching("carry-over-daemon").is_empty());
        r
    };
    for round in 0..2 {
        let r = play("carry_over.py").await;
        let log = &r.stderr_tail;
        assert!(!log.contains("HOSTILE LEAK"), "round {round}: {log}");
        assert!(log.contains("HOSTILE INFO none"), "round {round}: {log}");
        assert!(log.contains("HOSTILE INFO pid=2"), "round {round}: {log}");
        assert!(
            log.contains("HOSTILE INFO lastpid=2"),
            "round {round}: {log}"
        );
    }
    let forks = play("fork_many.py 300").await;
    assert_eq!(forks.status, MatchStatus::ProcessLimit, "{:?}", forks.error);
    let after_forks = play("carry_over.py").await;
    assert_ne!(after_forks.status, MatchStatus::ProcessLimit);
    assert!(after_forks.stderr_tail.contains("HOSTILE INFO none"));
    let memory = play("memory_children.py 2 200").await;
    assert_eq!(
        memory.status,
        MatchStatus::MemoryLimit,
        "{:?}",
        memory.error
    );
    let after_memory = play("carry_over.py").await;
    assert_eq!(after_memory.status, after_forks.status);
    let spin = play("spin_children.py 2").await;
    let after_spin = play("report_uid.py").await;
    let cpu = |r: &mazearena::runner::MatchRecord| r.timings.bot_cpu_ms.unwrap();
    let quiet = cpu(&after_spin);
    // Counted from the match's start, the quiet bot's time is its own. A running total
    // would hold at least the earlier matches' times on top: the spinning match's, and
    // those of the fork bomb, the memory hog and the matches after them (a sum that
    // does not shrink when a loaded machine gives the spinners little of the core).
    let earlier: u64 = [&forks, &after_forks, &memory, &after_memory, &spin]
        .into_iter()
        .map(cpu)
        .sum();
    assert!(
        quiet < earlier,
        "the earlier matches' CPU time ({earlier} ms) must not reach the next one ({quiet} ms)"
    );
    // The sandbox's processes (bubblewrap's two and the supervisor) end with its runner.
    let outer = supervisor.clone().unwrap()[0];
    let family = |pid: u32| {
        pid == outer
            || crate::support::parent_of(pid) == Some(outer)
            || crate::support::parent_of(pid).and_then(crate::support::parent_of) == Some(outer)
    };
    let ours: Vec<u32> = processes_matching("sandbox-serve")
        .into_iter()
        .filter(|&pid| family(pid))
        .collect();
    assert_eq!(ours.len(), 3, "{ours:?}");
    drop(warm);
    assert!(
        processes_matching("sandbox-serve")
            .iter()
            .all(|pid| !ours.contains(pid)),
        "the warm sandbox ends with its runner"
    );
}

/// A warm sandbox hands each match parts that no other match had, while the same sandbox
/// plays them all: its network and mount namespaces, its scratch area's and its bot
/// folder's mounts (ids the kernel never hands out twice, which the bot reports), and
/// its cgroup (read from outside while the match plays), which is not the sandbox's own
/// and is gone once the match is over.
#[tokio::test]
async fn a_warm_sandbox_hands_no_namespace_cgroup_or_mount_to_two_matches() {
    use mazearena::runner::{BotSpec, Limits, run_match};
    use std::collections::HashSet;
    let Some(warm) = warm_runner("hostile fresh parts") else {
        return;
    };
    let mazearena::runner::Sandbox::Full(full) = &warm else {
        unreachable!("a full sandbox was asked for")
    };
    let limits = Limits {
        max_steps: 50,
        process_limit: Some(32),
        ..Limits::default()
    };
    let maze = crate::support::classic(1);
    const ROUNDS: usize = 5;
    let mut seen: std::collections::BTreeMap<String, Vec<String>> = Default::default();
    let mut cgroups: Vec<Vec<String>> = Vec::new();
    let mut sandboxes = HashSet::new();
    for round in 0..ROUNDS {
        let marker = format!("fresh-parts-{}-{round}", std::process::id());
        let bot = BotSpec::new(
            format!("python3 identity.py {marker}"),
            root().join(HOSTILE),
        );
        let mut lines: Vec<String> = Vec::new();
        let r = run_match(&bot, &maze, 0, limits, &warm, |_| {
            if lines.is_empty() {
                for pid in processes_matching(&marker) {
                    let text =
                        std::fs::read_to_string(format!("/proc/{pid}/cgroup")).unwrap_or_default();
                    lines.extend(
                        text.lines()
                            // The hierarchies a match's limits and counter are in (v1),
                            // or the one hierarchy (v2); not the ones left at the root.
                            .filter(|l| {
                                let controllers = l.split(':').nth(1).unwrap_or("");
                                let path = l.splitn(3, ':').nth(2).unwrap_or("/");
                                path != "/"
                                    && (controllers.is_empty()
                                        || ["pids", "memory", "cpuacct"]
                                            .iter()
                                            .any(|c| controllers.split(',').any(|x| x == *c)))
                            })
                            .map(str::to_string),
                    );
                }
            }
        })
        .await;
        let log = &r.stderr_tail;
        for kind in ["net", "mounts", "scratch", "folder"] {
            let id = log
                .split(&format!("HOSTILE INFO {kind}="))
                .nth(1)
                .and_then(|s| s.split_whitespace().next())
                .unwrap_or_else(|| panic!("round {round}: no {kind} id:\n{log}"));
            assert!(
                id.parse::<u64>().is_ok(),
                "round {round}: {kind}={id}\n{log}"
            );
            seen.entry(kind.to_string())
                .or_default()
                .push(id.to_string());
        }
        assert!(
            !lines.is_empty(),
            "round {round}: the bot's cgroup was not seen"
        );
        cgroups.push(lines);
        sandboxes.extend(full.warm.idle_pids());
    }
    assert_eq!(sandboxes.len(), 1, "one warm sandbox played every match");
    for (kind, ids) in &seen {
        let distinct: HashSet<_> = ids.iter().collect();
        assert_eq!(
            distinct.len(),
            ROUNDS,
            "a {kind} handed to two matches: {ids:?}"
        );
    }
    let distinct: HashSet<_> = cgroups.iter().flatten().collect();
    assert_eq!(
        distinct.len(),
        cgroups.iter().map(Vec::len).sum::<usize>(),
        "a cgroup handed to two matches: {cgroups:?}"
    );
    // Not the sandbox's own cgroup, whose processes the match never joins.
    let outer = *sandboxes.iter().next().unwrap();
    let own = std::fs::read_to_string(format!("/proc/{outer}/cgroup")).unwrap();
    for line in cgroups.iter().flatten() {
        assert!(
            !own.lines().any(|l| l == line),
            "the sandbox's own cgroup: {line}"
        );
    }
    // Each used cgroup is removed once its match is over (off the match's path).
    let gone = |line: &str| {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next(), parts.next().unwrap(), parts.next().unwrap());
        let base = match controllers {
            "" => "/sys/fs/cgroup".to_string(),
            c => format!("/sys/fs/cgroup/{}", c.split(',').next().unwrap()),
        };
        !Path::new(&format!("{base}{path}")).exists()
    };
    let until = std::time::Instant::now() + std::time::Duration::from_secs(5);
    while !cgroups.iter().flatten().all(|l| gone(l)) {
        assert!(
            std::time::Instant::now() < until,
            "a used cgroup is still there: {cgroups:?}"
        );
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
    }
}

/// A bot folder of 1,500 entries with names of 200 bytes plays in a warm sandbox like any
/// other: its names never travel to the sandbox (the match's init lists the folder,
/// behind the walls), so no request grows with them.
#[tokio::test]
async fn a_folder_of_many_long_names_plays_in_a_warm_sandbox() {
    use mazearena::runner::{BotSpec, Limits, MatchStatus, run_match};
    let Some(_) = full_sandbox("hostile warm names") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("bot");
    std::fs::create_dir(&dir).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    for (name, text) in simple_bot_files().as_object().unwrap() {
        std::fs::write(dir.join(name), text.as_str().unwrap()).unwrap();
    }
    for i in 0..1500 {
        std::fs::write(dir.join(format!("{i:04}{}", "n".repeat(196))), "").unwrap();
    }
    let sandbox = WARM.with(Clone::clone);
    let mazearena::runner::Sandbox::Full(full) = &sandbox else {
        unreachable!("a full sandbox")
    };
    let before = full.warm.matches_started();
    let bot = BotSpec::new("python3 simple_bot.py", &dir);
    let r = run_match(
        &bot,
        &crate::support::classic(1),
        0,
        Limits::default(),
        &sandbox,
        |_| {},
    )
    .await;
    assert_eq!(
        r.status,
        MatchStatus::Finished,
        "{:?} {}",
        r.error,
        r.stderr_tail
    );
    if nix::unistd::geteuid().is_root() && full.cgroups.is_ok() {
        assert_eq!(full.warm.matches_started(), before + 1, "played warm");
    }
}

/// Nothing of one match reaches the next through the runners people use: a `tournament`
/// (the carry-over fixture four times in a row, one warm sandbox) and a real server
/// (four of its matches queued one after the other). Every match finds nothing an
/// earlier one left: files, processes, IPC, abstract sockets, the network namespace's
/// counters, a sysctl, the hostname.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_tournament_and_a_server_carry_nothing_from_one_match_to_the_next() {
    let Some(_) = full_sandbox("hostile carry-over") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let bot = tmp.path().join("carry");
    let mazes = tmp.path().join("mazes");
    std::fs::create_dir(&bot).unwrap();
    std::fs::create_dir(&mazes).unwrap();
    use std::os::unix::fs::PermissionsExt;
    for dir in [&bot, &mazes] {
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    for f in ["carry_over.py", "_hostile.py"] {
        std::fs::copy(root().join(HOSTILE).join(f), bot.join(f)).unwrap();
    }
    std::fs::write(
        bot.join("bot.toml"),
        "name = \"carry\"\ncommand = \"python3 carry_over.py carry-check-daemon\"\n",
    )
    .unwrap();
    std::fs::copy(maze(), mazes.join("m1.txt")).unwrap();
    let database = format!("sqlite://{}", tmp.path().join("t.db").display());
    let out = mazearena(&[
        "tournament",
        "--bots",
        bot.to_str().unwrap(),
        "--mazes",
        mazes.to_str().unwrap(),
        "--repeats",
        "4",
        "--jobs",
        "1",
        "--database",
        &database,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for id in 1..=4 {
        let shown = mazearena(&["match", "show", &id.to_string(), "--database", &database]);
        let text = String::from_utf8_lossy(&shown.stdout).into_owned();
        assert!(shown.status.success(), "{text}");
        assert!(
            !text.contains("HOSTILE LEAK"),
            "tournament match {id}: {text}"
        );
        assert!(
            text.contains("HOSTILE INFO none"),
            "tournament match {id}: {text}"
        );
        assert!(text.contains("HOSTILE INFO counters-moved="), "{text}");
    }
    nothing_left("carry-check-daemon");

    let server = TestServer::start(tmp.path(), &["--jobs", "1"]);
    let (bot_id, token) = register(
        &server,
        "carry",
        "python3 carry_over.py carry-check-daemon",
        hostile_files("carry_over.py"),
    )
    .await;
    for round in 0..4 {
        let tail = played_on_server(&server, bot_id, &token, round).await;
        assert!(
            !tail.contains("HOSTILE LEAK"),
            "server round {round}: {tail}"
        );
        assert!(
            tail.contains("HOSTILE INFO none"),
            "server round {round}: {tail}"
        );
    }
    nothing_left("carry-check-daemon");
}

/// A warm match's mount table names no host path of the server: the bot's folder is an
/// overlay of a detached tree (shown as `/`), and the runner's program is not mounted in
/// the match at all. Through the library's warm sandbox (the hostile folder and the test
/// binary's paths) and a real server (its data folder).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_warm_matchs_mount_table_names_no_host_path_of_the_server() {
    let Some(_) = full_sandbox("hostile mount table") else {
        return;
    };
    if !nix::unistd::geteuid().is_root() {
        eprintln!("SKIPPED hostile mount table: warm sandboxes are used by a runner that is root");
        return;
    }
    let folder = root().join(HOSTILE).display().to_string();
    let program = env!("CARGO_BIN_EXE_mazearena").to_string();
    let r = tokio::task::spawn_blocking(move || {
        attack_warm("mount_table.py", &[&folder, &program], &[])
    })
    .await
    .unwrap();
    assert_eq!(r["status"], "step_limit", "{r}");
    contained(&r, 2);

    let tmp = tempfile::tempdir().unwrap();
    let server = TestServer::start(tmp.path(), &["--jobs", "1"]);
    let data = tmp.path().display().to_string();
    let (bot_id, token) = register(
        &server,
        "mounts",
        &format!("python3 mount_table.py {data}"),
        hostile_files("mount_table.py"),
    )
    .await;
    let tail = played_on_server(&server, bot_id, &token, 0).await;
    assert!(!tail.contains("HOSTILE LEAK"), "{tail}");
    assert!(tail.contains("HOSTILE BLOCKED not-found"), "{tail}");
}

/// Plays bot `bot_id` (a hostile fixture that plays to the step limit) once on the
/// server's first public maze with `seed`, and returns its stderr's tail as its owner
/// reads it.
async fn played_on_server(server: &TestServer, bot_id: i64, token: &str, seed: i64) -> String {
    let (s, m) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot_id, "maze_id": 1, "seed": seed}),
            Some(token),
        )
        .await;
    assert_eq!(s, 202, "{m}");
    let id = m["match_id"].as_i64().unwrap();
    let played = wait_match(server, id).await;
    assert_eq!(played["status"], "step_limit", "{played}");
    let (_, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(token))
        .await;
    log["stderr_tail"].as_str().unwrap_or("").to_string()
}

/// The walls are the protocol's business of no one: an mms mouse is held as a v1 bot is.
/// Each attack runs at the mouse's start; the mouse then waits for a start message that
/// an mms mouse never gets, and times out.
#[test]
fn an_mms_mouse_is_held_by_the_same_walls() {
    let Some(_) = full_sandbox("hostile mms") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("mazearena.db");
    std::fs::write(&db, "SECRET").unwrap();
    let outside = tmp.path().join("pwned.txt");
    let mms = ["--protocol", "mms", "--startup-timeout-ms", "500"];
    let r = attack_one_shot("read_file.py", &[db.to_str().unwrap()], &mms);
    contained(&r, 1);
    assert_eq!(r["status"], "timeout", "{r}");
    let r = attack_one_shot("parent_environ.py", &[], &mms);
    contained(&r, 1);
    let r = attack_one_shot("write_outside.py", &[outside.to_str().unwrap()], &mms);
    contained(&r, 1);
    assert!(!outside.exists());
    let r = attack_one_shot("setsid_escape.py", &["4172"], &mms);
    assert!(stderr(&r).contains("grandchild"), "{}", stderr(&r));
    assert!(processes_matching("sleep 4172").is_empty());
}
