//! The hostile suite, second round: nothing of the owner's reaches the jail's helper
//! (a preloaded library), no file of the host's user reaches a bot (a home folder on
//! PATH), runtimes by their install folder (one under /tmp, a numpy venv by absolute
//! path), builds as locked down as matches (setuid, disk-filling, sparse files), and
//! uids that two runner processes never share. Each through `mazearena run` and, where
//! an owner can do it, through a real server.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{Value, json};

use crate::support::{
    TestServer, full_sandbox, mazearena, processes_matching, root, shared_maze, wait_built,
    wait_match,
};

const HOSTILE: &str = "tests/fixtures/bots/hostile";

fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

fn maze() -> String {
    shared_maze("classic/test_maze_01.txt")
        .display()
        .to_string()
}

fn stderr(r: &Value) -> &str {
    r["stderr_tail"].as_str().unwrap_or("")
}

/// `mazearena run --json` of `bot` in `dir` with `extra` arguments and `env`.
fn run_in(dir: &Path, bot: &str, extra: &[&str], env: &[(&str, &str)]) -> Value {
    let maze = maze();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mazearena"));
    cmd.args(["run", "--maze", &maze, "--bot", bot, "--json", "--bot-dir"])
        .arg(dir)
        .args(extra)
        .env("MAZEARENA_SANDBOX", "full")
        .current_dir(root());
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["limits"]["sandbox"], "full");
    assert!(
        processes_matching(bot).is_empty(),
        "{bot} outlived its match"
    );
    r
}

/// A bot folder with the hostile helper and `scripts`.
fn hostile_dir(scripts: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for s in scripts.iter().chain(&["_hostile.py"]) {
        std::fs::copy(root().join(HOSTILE).join(s), dir.path().join(s)).unwrap();
    }
    dir
}

/// gcc, or `None` (a skip with a reason outside CI; a failure in CI).
fn gcc(test: &str) -> Option<()> {
    let ok = Command::new("gcc")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(!in_ci(), "CI=true and gcc is missing for {test}");
        eprintln!("SKIPPED {test}: gcc is not installed");
        return None;
    }
    Some(())
}

fn no_leak(log: &str, blocked: usize) {
    assert!(!log.contains("HOSTILE LEAK"), "an attack worked:\n{log}");
    assert!(
        log.matches("HOSTILE BLOCKED").count() >= blocked,
        "fewer than {blocked} attacks were seen to fail:\n{log}"
    );
}

#[test]
fn a_preloaded_library_of_the_owner_runs_only_in_the_bot_after_the_walls() {
    let Some(_) = full_sandbox("preload") else {
        return;
    };
    let Some(()) = gcc("preload") else { return };
    let dir = hostile_dir(&["report_uid.py"]);
    let built = Command::new("gcc")
        .args(["-shared", "-fPIC", "-o"])
        .arg(dir.path().join("evil.so"))
        .arg(root().join(HOSTILE).join("preload.c"))
        .status()
        .unwrap();
    assert!(built.success());
    // A secret outside the view, as the server's database would be.
    let secret = tempfile::NamedTempFile::new().unwrap();
    std::fs::write(secret.path(), "SECRET maze layouts").unwrap();
    let secret_arg = format!("HOSTILE_SECRET={}", secret.path().display());
    let r = run_in(
        dir.path(),
        "python3 report_uid.py",
        &[
            "--bot-env",
            "LD_PRELOAD=/sandbox/work/evil.so",
            "--bot-env",
            &secret_arg,
        ],
        &[],
    );
    let log = stderr(&r);
    // The bot's own program (and only it) loaded the library, after the walls.
    no_leak(log, 2);
    assert!(
        log.contains("preload ran only after the walls, in python3"),
        "{log}"
    );
    assert!(!log.contains("mazearena"), "{log}");
    assert_eq!(r["status"], "step_limit", "{r}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_applies_an_uploaded_bots_variables_only_to_the_bot() {
    let Some(_) = full_sandbox("preload on a server") else {
        return;
    };
    let Some(()) = gcc("preload on a server") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let server = TestServer::start(tmp.path(), &["--jobs", "1"]);
    let db = tmp.path().join("mazearena.db").display().to_string();
    let read = |f: &str| std::fs::read_to_string(root().join(HOSTILE).join(f)).unwrap();
    let (bot, token) = crate::support::upload(
        &server,
        json!({
            "name": "preloader",
            "command": "python3 report_uid.py",
            // Built by the server's builder: the library is the owner's own file.
            "build": "gcc -shared -fPIC -o evil.so preload.c",
            "env": {"LD_PRELOAD": "/sandbox/work/evil.so", "HOSTILE_SECRET": db},
            "files": {"report_uid.py": read("report_uid.py"),
                      "_hostile.py": read("_hostile.py"),
                      "preload.c": read("preload.c")},
        }),
    )
    .await;
    let v = wait_built(&server, bot).await;
    assert_eq!(v["build_status"], "ready", "{v}");
    let id = queue_on_a_public_maze(&server, bot, &token).await;
    let m = wait_match(&server, id).await;
    assert_eq!(m["status"], "step_limit", "{m}");
    let (_, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(&token))
        .await;
    let tail = log["stderr_tail"].as_str().unwrap_or("");
    no_leak(tail, 2);
    assert!(tail.contains("after the walls, in python3"), "{tail}");
    let (status, _) = server.get("/healthz", None).await;
    assert_eq!(status, 200);
}

/// Queues a match of `bot` on classic maze 01 (stored as a public maze the first time).
async fn queue_on_a_public_maze(server: &TestServer, bot: i64, token: &str) -> i64 {
    let layout = std::fs::read_to_string(shared_maze("classic/test_maze_01.txt")).unwrap();
    let (s, v) = server
        .post(
            "/api/mazes",
            json!({"name": format!("c1-{bot}"), "layout": layout, "hidden": false}),
            Some(crate::support::ADMIN),
        )
        .await;
    let maze = match s {
        201 => v["maze_id"].as_i64().unwrap(),
        409 => {
            let (_, all) = server.get("/api/mazes", None).await;
            all.as_array()
                .unwrap()
                .iter()
                .find(|m| m["name"].as_str().is_some_and(|n| n.starts_with("c1-")))
                .and_then(|m| m["maze_id"].as_i64())
                .expect("the classic maze stored before")
        }
        _ => panic!("{v}"),
    };
    crate::support::queue(server, bot, maze, 1, token).await
}

/// A home folder with `bin/` (to put on PATH) and a planted `.ssh/id_rsa`.
fn planted_home() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let home = tempfile::tempdir().unwrap();
    let bin = home.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::create_dir_all(home.path().join(".ssh")).unwrap();
    let key = home.path().join(".ssh/id_rsa");
    std::fs::write(&key, "-----BEGIN OPENSSH PRIVATE KEY----- SECRET").unwrap();
    (home, bin, key)
}

fn path_with(dir: &Path) -> String {
    format!(
        "{}:{}",
        dir.display(),
        std::env::var("PATH").unwrap_or_default()
    )
}

#[test]
fn a_home_folder_on_the_runners_path_is_not_in_the_view() {
    let Some(_) = full_sandbox("home on PATH") else {
        return;
    };
    let (home, bin, key) = planted_home();
    // A runtime-looking folder under /tmp on PATH too: it once made the sandbox refuse.
    let tmp_runtime = tempfile::tempdir_in("/tmp").unwrap();
    std::fs::create_dir_all(tmp_runtime.path().join("bin")).unwrap();
    let path = format!(
        "{}:{}",
        tmp_runtime.path().join("bin").display(),
        path_with(&bin)
    );
    let dir = hostile_dir(&["read_file.py"]);
    let bot = format!(
        "python3 read_file.py {} {}",
        key.display(),
        home.path().display()
    );
    let r = run_in(
        dir.path(),
        &bot,
        &[],
        &[
            ("PATH", path.as_str()),
            ("HOME", home.path().to_str().unwrap()),
        ],
    );
    no_leak(stderr(&r), 2);
    assert_eq!(r["status"], "step_limit", "{r}");
    // The home folder is refused as a runtime, with the reason, when named.
    let out = Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .arg("doctor")
        .arg("--runtime")
        .arg(home.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let said =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("dotfile (.ssh)"), "{said}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_whose_path_holds_a_home_folder_shows_none_of_it() {
    let Some(_) = full_sandbox("home on a server's PATH") else {
        return;
    };
    let (home, bin, key) = planted_home();
    let tmp = tempfile::tempdir().unwrap();
    let path = path_with(&bin);
    let server = TestServer::start_env(
        tmp.path(),
        &["--jobs", "1"],
        &[("PATH", &path), ("HOME", home.path().to_str().unwrap())],
    );
    let read = |f: &str| std::fs::read_to_string(root().join(HOSTILE).join(f)).unwrap();
    let command = format!(
        "python3 read_file.py {} {}",
        key.display(),
        home.path().display()
    );
    let (bot, token) = crate::support::register(
        &server,
        "reader",
        &command,
        json!({"read_file.py": read("read_file.py"), "_hostile.py": read("_hostile.py")}),
    )
    .await;
    let id = queue_on_a_public_maze(&server, bot, &token).await;
    let m = wait_match(&server, id).await;
    assert_eq!(m["status"], "step_limit", "{m}");
    let (_, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(&token))
        .await;
    no_leak(log["stderr_tail"].as_str().unwrap_or(""), 2);
}

/// Makes a venv with numpy under /tmp, or says why it cannot (None).
fn numpy_venv(test: &str) -> Option<tempfile::TempDir> {
    let dir = tempfile::tempdir_in("/tmp").unwrap();
    let venv = dir.path().join("sci");
    let made = Command::new("python3")
        .args(["-m", "venv"])
        .arg(&venv)
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "python3 -m venv: {}",
        String::from_utf8_lossy(&made.stderr)
    );
    let pip = Command::new(venv.join("bin/pip"))
        .args(["install", "--quiet", "--disable-pip-version-check", "numpy"])
        .output()
        .unwrap();
    if !pip.status.success() {
        let why = String::from_utf8_lossy(&pip.stderr).to_string();
        assert!(!in_ci(), "CI=true and pip cannot install numpy: {why}");
        eprintln!("SKIPPED {test}: pip cannot install numpy here: {why}");
        return None;
    }
    Some(dir)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_numpy_robot_runs_from_a_venv_under_tmp_by_absolute_path_and_by_the_runtime_list() {
    let Some(_) = full_sandbox("numpy venv") else {
        return;
    };
    let Some(dir) = numpy_venv("numpy venv") else {
        return;
    };
    let python = dir.path().join("sci/bin/python");
    let plain = format!(
        "{} bots/python/udacity_adapter.py tests/fixtures/robot_py/robot.py",
        python.display()
    );
    let with_numpy = format!(
        "{} bots/python/udacity_adapter.py tests/fixtures/robot_py/numpy_robot.py",
        python.display()
    );
    let by_path = run_in(root(), &with_numpy, &[], &[]);
    assert_eq!(by_path["status"], "finished", "{by_path}");
    // numpy changed nothing of the moves: the same score as the plain robot, inside
    // the sandbox and out.
    let plain_r = run_in(root(), &plain, &[], &[]);
    assert_eq!(by_path["score"], plain_r["score"]);
    let maze = maze();
    let outside = mazearena(&[
        "run",
        "--maze",
        &maze,
        "--bot",
        &with_numpy,
        "--json",
        "--sandbox",
        "none",
    ]);
    let outside: Value = serde_json::from_slice(&outside.stdout).unwrap();
    assert_eq!(outside["score"], by_path["score"]);
    // Listed as a runtime, its python3 is the bots' python3.
    let venv = dir.path().join("sci");
    let listed = run_in(
        root(),
        "python3 bots/python/udacity_adapter.py tests/fixtures/robot_py/numpy_robot.py",
        &["--runtime", venv.to_str().unwrap()],
        &[],
    );
    assert_eq!(listed["status"], "finished", "{listed}");
    assert_eq!(listed["score"], by_path["score"]);
    // Without it, the system's python3 has no numpy: the runtime is what made it work.
    let without = mazearena(&[
        "run",
        "--maze",
        &maze,
        "--bot",
        "/usr/bin/python3 bots/python/udacity_adapter.py tests/fixtures/robot_py/numpy_robot.py",
        "--json",
    ]);
    let without: Value = serde_json::from_slice(&without.stdout).unwrap();
    if without["status"] != "finished" {
        assert!(stderr(&without).contains("numpy"), "{without}");
    }
    // On a server, where the operator lists the venv after another without numpy:
    // the same robot, uploaded, named by the venv's absolute path, plays to the same
    // score; so does one that names the venv as its runtime and calls a bare python3.
    let plain_venv = dir.path().join("plain");
    let made = Command::new("python3")
        .args(["-m", "venv"])
        .arg(&plain_venv)
        .output()
        .unwrap();
    assert!(made.status.success(), "{made:?}");
    let tmp = tempfile::tempdir().unwrap();
    let server = TestServer::start(
        tmp.path(),
        &[
            "--jobs",
            "1",
            "--runtime",
            plain_venv.to_str().unwrap(),
            "--runtime",
            venv.to_str().unwrap(),
        ],
    );
    // The server says what it offers: both venvs (numpy in one), and the system's.
    let (_, offered) = server.get("/api/runtimes", None).await;
    let names: Vec<&str> = offered
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    // The two venvs in the operator's order, the system's last, and nothing else: the
    // base interpreter the venvs bring is mounted for them, not offered as a runtime of
    // its own (its site-packages are the operator's).
    let at = |n: &str| names.iter().position(|x| *x == n);
    assert!(at("plain") < at("sci") && at("sci").is_some(), "{names:?}");
    assert_eq!(names.last(), Some(&"system"), "{names:?}");
    assert_eq!(names.len(), 3, "{names:?}");
    let sci = &offered[at("sci").unwrap()];
    // No path of the server's in what it says.
    assert!(!offered.to_string().contains("/tmp/"), "{offered}");
    assert!(
        sci["packages"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["name"] == "numpy"),
        "{sci}"
    );
    assert!(
        sci["programs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["program"] == "python3"
                && p["version"].as_str().unwrap().starts_with("Python 3")),
        "{sci}"
    );
    let (_, home) = server.get_text("/").await;
    assert!(
        home.contains("Runtimes for bots") && home.contains("numpy"),
        "the home page lists them"
    );
    let read = |f: &str| std::fs::read_to_string(root().join(f)).unwrap();
    let (bot, token) = crate::support::register(
        &server,
        "numpy-robot",
        &format!("{} udacity_adapter.py numpy_robot.py", python.display()),
        json!({
            "udacity_adapter.py": read("bots/python/udacity_adapter.py"),
            "robot.py": read("tests/fixtures/robot_py/robot.py"),
            "numpy_robot.py": read("tests/fixtures/robot_py/numpy_robot.py"),
        }),
    )
    .await;
    let id = queue_on_a_public_maze(&server, bot, &token).await;
    let m = wait_match(&server, id).await;
    assert_eq!(m["status"], "finished", "{m}");
    let seeded = run_in(root(), &with_numpy, &["--seed", "1"], &[]);
    assert_eq!(m["score"], seeded["score"], "{m}");
    let files = json!({
        "udacity_adapter.py": read("bots/python/udacity_adapter.py"),
        "robot.py": read("tests/fixtures/robot_py/robot.py"),
        "numpy_robot.py": read("tests/fixtures/robot_py/numpy_robot.py"),
    });
    let bare = "python3 udacity_adapter.py numpy_robot.py";
    let (named, named_token) = crate::support::upload(
        &server,
        json!({"name": "named-runtime", "command": bare, "runtime": "sci", "files": files}),
    )
    .await;
    let id = queue_on_a_public_maze(&server, named, &named_token).await;
    let m = wait_match(&server, id).await;
    assert_eq!(
        (&m["status"], &m["score"]),
        (&json!("finished"), &seeded["score"]),
        "{m}"
    );
    // Without naming it, the bare python3 is the first runtime's: no numpy there.
    let (unnamed, unnamed_token) = crate::support::upload(
        &server,
        json!({"name": "unnamed-runtime", "command": bare, "files": files}),
    )
    .await;
    // Its validation match at upload crashes: the version is invalid, and its log
    // says why (numpy's import error) with a hint.
    let version = crate::support::wait_built(&server, unnamed).await;
    assert_eq!(version["build_status"], "invalid", "{version}");
    let (_, log) = server
        .get(
            &format!("/api/bots/{unnamed}/versions/1/build-log"),
            Some(&unnamed_token),
        )
        .await;
    let text = log["build_log"].as_str().unwrap_or_default();
    assert!(
        text.contains("numpy") && text.contains("hint: a module is missing"),
        "{log}"
    );
    // A traceback through a runtime's library names the runtime, not the server's
    // folder: numpy's own files show under /runtimes/sci.
    let (failing, failing_token) = crate::support::upload(
        &server,
        json!({"name": "numpy-traceback", "command": "python3 t.py", "runtime": "sci",
               "files": {"t.py": "import sys, numpy\nsys.stdin.readline()\nnumpy.loadtxt('missing.txt')\n"}}),
    )
    .await;
    let version = crate::support::wait_built(&server, failing).await;
    assert_eq!(version["build_status"], "invalid", "{version}");
    let (_, log) = server
        .get(
            &format!("/api/bots/{failing}/versions/1/build-log"),
            Some(&failing_token),
        )
        .await;
    let text = log["build_log"].as_str().unwrap_or_default();
    assert!(
        text.contains("/runtimes/sci/") && text.contains("numpy"),
        "{text}"
    );
    assert!(
        !text.contains(venv.to_str().unwrap()),
        "the server's folder shows: {text}"
    );
    // A runtime the server does not offer: refused with those it offers.
    let (s, v) = server
        .post(
            "/api/bots",
            json!({"name": "no-such-runtime", "command": bare, "runtime": "nope", "files": files}),
            None,
        )
        .await;
    assert_eq!(s, 422, "{v}");
    let msg = v["error"]["message"].as_str().unwrap();
    assert!(
        msg.contains("no runtime named \"nope\"")
            && msg.contains("it offers plain, ")
            && msg.contains("sci"),
        "{msg}"
    );
}

/// Uploads a bot whose build is `build`; returns the ended version's view, its build
/// log, and the server.
async fn build_on_server(
    build: &str,
    extra: &[&str],
) -> (Value, String, TestServer, tempfile::TempDir) {
    let tmp = tempfile::tempdir().unwrap();
    let mut args = vec!["--jobs", "1"];
    args.extend_from_slice(extra);
    let server = TestServer::start(tmp.path(), &args);
    let (bot, token) = crate::support::upload(
        &server,
        json!({"name": "builder", "command": "python3 bot.py", "build": build,
               "files": {"bot.py": "print('x')\n"}}),
    )
    .await;
    let v = wait_built(&server, bot).await;
    let log = crate::support::build_log(&server, bot, &token).await;
    (v, log, server, tmp)
}

/// Nothing of the build is left in the server's build folder, and it still answers.
async fn build_left_nothing(server: &TestServer, data: &Path) {
    let builds = data.join("data/builds");
    let left: Vec<_> = std::fs::read_dir(&builds)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    assert!(left.is_empty(), "left in {}: {left:?}", builds.display());
    let (status, _) = server.get("/healthz", None).await;
    assert_eq!(status, 200, "the server stopped answering");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_build_runs_as_its_own_uid_and_cannot_keep_a_setuid_file() {
    let Some(_) = full_sandbox("setuid build") else {
        return;
    };
    let (v, log, server, tmp) = build_on_server(
        "sh -c 'id -u; cp /usr/bin/id ./id && chmod 4755 ./id && ls -ln ./id'",
        &[],
    )
    .await;
    assert_eq!(v["build_status"], "build_failed", "{log}");
    assert!(log.contains("setuid"), "{log}");
    let uid: u64 = log
        .lines()
        .next()
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or_else(|| panic!("no uid in {log}"));
    if nix::unistd::geteuid().is_root() {
        assert!(uid >= 2_000_000_000, "the build ran as uid {uid}: {log}");
    }
    build_left_nothing(&server, tmp.path()).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_build_that_fills_the_disk_fails_at_its_bound() {
    let Some(_) = full_sandbox("disk-filling build") else {
        return;
    };
    let (v, log, server, tmp) = build_on_server(
        "sh -c 'dd if=/dev/zero of=fill bs=1M count=512; sleep 5'",
        &["--build-write-mib", "32"],
    )
    .await;
    assert_eq!(v["build_status"], "build_failed", "{log}");
    assert!(log.contains("the build wrote more than 32 MiB"), "{log}");
    build_left_nothing(&server, tmp.path()).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_build_that_leaves_a_sparse_file_fails_without_it_being_read() {
    let Some(_) = full_sandbox("sparse build") else {
        return;
    };
    // 20 MiB of holes: under the bundle limit, refused as sparse; 2 GiB: over the
    // file-size limit of the build, which ends it.
    let (v, log, server, tmp) = build_on_server("truncate -s 20M holes", &[]).await;
    assert_eq!(v["build_status"], "build_failed", "{log}");
    assert!(log.contains("sparse"), "{log}");
    build_left_nothing(&server, tmp.path()).await;
    drop(server);
    let (v, log, server, tmp) = build_on_server("truncate -s 2G holes", &[]).await;
    assert_eq!(v["build_status"], "build_failed", "{log}");
    build_left_nothing(&server, tmp.path()).await;
}

/// The uid a run of `report_uid.py` reported.
fn reported_uid(r: &Value) -> u64 {
    stderr(r)
        .split("uid=")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no uid reported: {r}"))
}

#[test]
fn two_runner_processes_whose_pids_agree_modulo_4096_get_different_uids() {
    let Some(_) = full_sandbox("uids across processes") else {
        return;
    };
    if !nix::unistd::geteuid().is_root() {
        eprintln!("SKIPPED uids across processes: matches get their own uid only as root");
        return;
    }
    let dir = hostile_dir(&["report_uid.py"]);
    let maze = maze();
    let start = |pause: &str| {
        Command::new(env!("CARGO_BIN_EXE_mazearena"))
            .args(["run", "--maze", &maze, "--json", "--bot"])
            .arg(format!("python3 report_uid.py {pause}"))
            .arg("--bot-dir")
            .arg(dir.path())
            .env("MAZEARENA_SANDBOX", "full")
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    // The first runs for about 30 s (30 ms a step).
    let mut first = start("0.03");
    let target = first.id() % 4096;
    // Use up pids until the next one agrees with the first's modulo 4096 (other
    // processes of the machine may take one meanwhile: a few tries).
    let mut second = None;
    for _ in 0..2 {
        loop {
            let p = Command::new("true").spawn().unwrap();
            let pid = p.id();
            let mut p = p;
            p.wait().unwrap();
            if (pid + 1) % 4096 == target {
                break;
            }
        }
        let candidate = start("0");
        if candidate.id() % 4096 == target {
            second = Some(candidate);
            break;
        }
        let _ = candidate.wait_with_output();
    }
    let second = second.unwrap_or_else(|| {
        eprintln!("NOTE: no second runner with a colliding pid could be made; using the last");
        start("0")
    });
    let b: Value = serde_json::from_slice(&second.wait_with_output().unwrap().stdout).unwrap();
    assert!(
        first.try_wait().unwrap().is_none(),
        "the first runner ended before the second: they did not overlap"
    );
    let a: Value = serde_json::from_slice(&first.wait_with_output().unwrap().stdout).unwrap();
    assert_eq!(a["status"], "step_limit", "{a}");
    assert_eq!(b["status"], "step_limit", "{b}");
    let (ua, ub) = (reported_uid(&a), reported_uid(&b));
    assert!(ua >= 2_000_000_000 && ub >= 2_000_000_000, "{ua} {ub}");
    assert_ne!(ua, ub, "two runner processes gave their matches one uid");
}
