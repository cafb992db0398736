//! Helpers shared by the integration tests: paths, fixture bots, process checks.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use mazearena::engine::{Maze, mazefile};
use mazearena::runner::{BotSpec, Sandbox};

/// Taken by the tests that keep both cores busy for minutes (whole tournaments, the
/// fault test), so that they run one after another rather than starve each other's
/// bots past their time limits.
pub fn heavy() -> std::sync::MutexGuard<'static, ()> {
    static HEAVY: std::sync::Mutex<()> = std::sync::Mutex::new(());
    HEAVY
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Held by each test that builds the starter kits in bots/ where they are (`make`,
/// `go build`, a tournament's builds): two builds of one kit at once would link a bot
/// while the other test starts it (`Text file busy`).
pub fn kits_in_place() -> std::sync::MutexGuard<'static, ()> {
    static KITS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    KITS.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The crate root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A file under ../shared/mazes (beside the checkout).
pub fn shared_maze(rel: &str) -> PathBuf {
    root().join("../shared/mazes").join(rel)
}

/// Parses a maze from ../shared/mazes.
pub fn load_shared(rel: &str) -> Maze {
    let path = shared_maze(rel);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mazefile::parse(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The classic test maze `n` (1, 2 or 3).
pub fn classic(n: u32) -> Maze {
    load_shared(&format!("classic/test_maze_0{n}.txt"))
}

/// A fixture bot from tests/fixtures/bots, run with python3 from the crate root.
pub fn fixture_bot(name: &str, args: &[&str]) -> BotSpec {
    let mut command = format!("python3 tests/fixtures/bots/{name}.py");
    for a in args {
        command.push(' ');
        command.push_str(&shlex::try_quote(a).unwrap());
    }
    BotSpec::new(command, root())
}

/// The sandbox bots run under in the tests: the full one where it works. In CI
/// (`CI=true`) a missing sandbox is a failure; elsewhere the tests go on without it and
/// say so once.
pub fn sandbox() -> Sandbox {
    static SANDBOX: std::sync::OnceLock<Sandbox> = std::sync::OnceLock::new();
    SANDBOX
        .get_or_init(|| {
            match Sandbox::full(
                Path::new(env!("CARGO_BIN_EXE_mazearena")),
                &mazearena::runner::sandbox::Setup::default(),
            ) {
                Ok(s) => s,
                Err(e) if std::env::var("CI").is_ok_and(|v| v == "true") => {
                    panic!("CI=true and the sandbox is missing: {e}")
                }
                Err(e) => {
                    eprintln!("NOTE: bots run without the sandbox in these tests: {e}");
                    Sandbox::None
                }
            }
        })
        .clone()
}

/// The full sandbox, or `None` after printing why a sandbox test is skipped (outside
/// CI only: in CI [`sandbox`] panics instead).
pub fn full_sandbox(test: &str) -> Option<Sandbox> {
    match sandbox() {
        Sandbox::None => {
            eprintln!("SKIPPED {test}: the sandbox is not available here (see `mazearena doctor`)");
            None
        }
        s => Some(s),
    }
}

/// Live processes (not zombies) whose command line contains `needle`.
pub fn processes_matching(needle: &str) -> Vec<u32> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(cmd) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
            continue;
        };
        let cmd = String::from_utf8_lossy(&cmd).replace('\0', " ");
        let zombie = std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
            s.rsplit_once(')')
                .is_some_and(|(_, r)| r.trim_start().starts_with('Z'))
        });
        if cmd.contains(needle) && !zombie && pid != std::process::id() {
            found.push(pid);
        }
    }
    found
}

/// The parent of process `pid`, while it lives.
pub fn parent_of(pid: u32) -> Option<u32> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit_once(')')?
        .1
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

/// [`processes_matching`], only the descendants of process `ancestor`.
pub fn descendants_matching(needle: &str, ancestor: u32) -> Vec<u32> {
    processes_matching(needle)
        .into_iter()
        .filter(|&pid| {
            let mut at = pid;
            for _ in 0..64 {
                match parent_of(at) {
                    Some(p) if p == ancestor => return true,
                    Some(p) if p > 1 => at = p,
                    _ => return false,
                }
            }
            false
        })
        .collect()
}

/// Runs the real `mazearena` binary with `args` from the crate root (bots in the
/// tests' [`sandbox`]).
pub fn mazearena(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args(args)
        .env("MAZEARENA_SANDBOX", sandbox().level())
        .current_dir(root())
        .output()
        .expect("the mazearena binary runs")
}

/// Runs `mazearena` with `args`, which must succeed (else the test fails with its
/// stderr), and parses its standard output as JSON.
pub fn mazearena_json(args: &[&str]) -> serde_json::Value {
    let out = mazearena(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Processes (not zombies) that are still members of process group `pgid`.
pub fn live_group_members(pgid: u32) -> Vec<u32> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return found;
    };
    for entry in entries.flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let Some(close) = stat.rfind(')') else {
            continue;
        };
        let fields: Vec<&str> = stat[close + 2..].split_whitespace().collect();
        // fields[0] = state, fields[2] = pgrp (stat(5) fields 3 and 5).
        if fields.len() > 2 && fields[0] != "Z" && fields[2] == pgid.to_string() {
            found.push(pid);
        }
    }
    found
}

/// The admin token the test servers use.
pub const ADMIN: &str = "test-admin-token";

/// A real `mazearena serve` process on a free port with its own database and data folder.
pub struct TestServer {
    /// `http://127.0.0.1:PORT`.
    pub base: String,
    /// The database URL.
    pub database: String,
    child: std::process::Child,
    client: reqwest::Client,
}

/// Clears the variables that rustup's proxy gives to everything `cargo test` runs when
/// they only repeat rustup's defaults, so the binary sees the environment it has when
/// installed and started from a shell.
fn as_installed(command: &mut Command) {
    let home = PathBuf::from(std::env::var_os("HOME").unwrap_or_default());
    let defaults = [("RUSTUP_HOME", ".rustup"), ("CARGO_HOME", ".cargo")];
    if defaults
        .iter()
        .all(|(key, dir)| std::env::var_os(key).is_none_or(|v| v == home.join(dir)))
    {
        for key in ["RUSTUP_HOME", "CARGO_HOME", "RUSTUP_TOOLCHAIN"] {
            command.env_remove(key);
        }
    }
}

impl TestServer {
    /// Starts the server binary in `dir` (database and bot files inside it).
    pub fn start(dir: &Path, extra: &[&str]) -> TestServer {
        TestServer::start_env(dir, extra, &[])
    }

    /// [`TestServer::start`] with variables `env` set for the server.
    pub fn start_env(dir: &Path, extra: &[&str], env: &[(&str, &str)]) -> TestServer {
        TestServer::start_on(dir, None, extra, env)
    }

    /// [`TestServer::start_env`] on `database` (default: SQLite in `dir`).
    pub fn start_on(
        dir: &Path,
        database: Option<&str>,
        extra: &[&str],
        env: &[(&str, &str)],
    ) -> TestServer {
        use std::io::BufRead;
        let database = database.map_or_else(
            || format!("sqlite://{}", dir.join("mazearena.db").display()),
            str::to_string,
        );
        let mut command = Command::new(env!("CARGO_BIN_EXE_mazearena"));
        as_installed(&mut command);
        let mut child = command
            .arg("serve")
            .args(["--bind", "127.0.0.1:0", "--database", &database])
            .arg("--data-dir")
            .arg(dir.join("data"))
            .args(extra)
            .env("MAZEARENA_ADMIN_TOKEN", ADMIN)
            .env("MAZEARENA_SANDBOX", sandbox().level())
            // Tests register many bots from one address and upload many versions of one
            // owner at once; the limits have tests of their own (crowd.rs).
            .env("MAZEARENA_REGISTRATIONS_PER_HOUR", "10000")
            .env("MAZEARENA_VERSIONS_PER_DAY", "10000")
            .env("MAZEARENA_PENDING_BUILDS_PER_OWNER", "1000")
            .envs(env.iter().copied())
            .current_dir(root())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("the server starts");
        let stdout = child.stdout.take().unwrap();
        let mut line = String::new();
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .unwrap();
        let addr = line
            .split("http://")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .unwrap_or_else(|| panic!("no address in {line:?}"))
            .to_string();
        TestServer {
            base: format!("http://{addr}"),
            database,
            child,
            client: reqwest::Client::new(),
        }
    }

    /// Sends a request; returns the status, the JSON body (Null if none) and the headers.
    pub async fn call(
        &self,
        method: reqwest::Method,
        path: &str,
        body: Option<serde_json::Value>,
        token: Option<&str>,
    ) -> (u16, serde_json::Value, reqwest::header::HeaderMap) {
        let mut req = self.client.request(method, format!("{}{path}", self.base));
        if let Some(b) = body {
            req = req.json(&b);
        }
        if let Some(t) = token {
            req = req.bearer_auth(t);
        }
        let resp = req.send().await.expect("the server answers");
        let status = resp.status().as_u16();
        let headers = resp.headers().clone();
        let text = resp.text().await.unwrap();
        let json = serde_json::from_str(&text).unwrap_or(serde_json::Value::Null);
        (status, json, headers)
    }

    /// GET without a token returning status and the body as text (a page).
    pub async fn get_text(&self, path: &str) -> (u16, String) {
        let resp = self
            .client
            .get(format!("{}{path}", self.base))
            .send()
            .await
            .expect("the server answers");
        (resp.status().as_u16(), resp.text().await.unwrap())
    }

    /// GET with an optional token, returning status, body text and headers.
    pub async fn get_raw(
        &self,
        path: &str,
        token: Option<&str>,
    ) -> (u16, String, reqwest::header::HeaderMap) {
        let mut request = self.client.get(format!("{}{path}", self.base));
        if let Some(t) = token {
            request = request.bearer_auth(t);
        }
        let resp = request.send().await.expect("the server answers");
        let status = resp.status().as_u16();
        let headers = resp.headers().clone();
        (status, resp.text().await.unwrap(), headers)
    }

    /// GET returning status and JSON.
    pub async fn get(&self, path: &str, token: Option<&str>) -> (u16, serde_json::Value) {
        let (s, v, _) = self.call(reqwest::Method::GET, path, None, token).await;
        (s, v)
    }

    /// POST JSON returning status and JSON.
    pub async fn post(
        &self,
        path: &str,
        body: serde_json::Value,
        token: Option<&str>,
    ) -> (u16, serde_json::Value) {
        let (s, v, _) = self
            .call(reqwest::Method::POST, path, Some(body), token)
            .await;
        (s, v)
    }

    /// The raw client, for unusual requests.
    pub fn client(&self) -> &reqwest::Client {
        &self.client
    }

    /// The server's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Kills the server with SIGKILL, as a crash would.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Sends SIGTERM and waits for the process to exit.
    pub fn terminate(&mut self) -> std::process::ExitStatus {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        self.child.wait().unwrap()
    }
}

impl Drop for TestServer {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The files of the shipped simple Python bot, as a JSON map for upload.
pub fn simple_bot_files() -> serde_json::Value {
    let read = |p: &str| std::fs::read_to_string(root().join(p)).unwrap();
    serde_json::json!({
        "mazebot.py": read("bots/python/mazebot.py"),
        "simple_bot.py": read("bots/python/simple_bot.py"),
    })
}

/// The adapter and the fixture robot.py, as a JSON map for upload.
pub fn adapter_bot_files() -> serde_json::Value {
    let read = |p: &str| std::fs::read_to_string(root().join(p)).unwrap();
    serde_json::json!({
        "udacity_adapter.py": read("bots/python/udacity_adapter.py"),
        "robot.py": read("tests/fixtures/robot_py/robot.py"),
    })
}

/// The statuses a match ends with.
pub const FINAL: &[&str] = &[
    "finished",
    "step_limit",
    "timeout",
    "crashed",
    "protocol_error",
    "memory_limit",
    "process_limit",
    "scratch_limit",
    "aborted",
];

/// Registers a bot from a JSON file map; returns its id and owner token.
pub async fn register(
    server: &TestServer,
    name: &str,
    command: &str,
    files: Value,
) -> (i64, String) {
    upload(
        server,
        json!({"name": name, "command": command, "files": files}),
    )
    .await
}

/// Registers a bot with the whole upload `body` (`POST /api/bots`), which must be
/// accepted; returns its id and owner token.
pub async fn upload(server: &TestServer, body: Value) -> (i64, String) {
    let (s, v) = server.post("/api/bots", body, None).await;
    assert_eq!(s, 201, "{v}");
    (
        v["bot_id"].as_i64().unwrap(),
        v["owner_token"].as_str().unwrap().to_string(),
    )
}

/// Queues a match of bot `bot` on maze `maze` with `seed` as the holder of `token`,
/// which must be accepted (202); returns its id.
pub async fn queue(server: &TestServer, bot: i64, maze: i64, seed: i64, token: &str) -> i64 {
    let (s, q) = server
        .post(
            "/api/matches",
            json!({"bot_id": bot, "maze_id": maze, "seed": seed}),
            Some(token),
        )
        .await;
    assert_eq!(s, 202, "{q}");
    q["match_id"].as_i64().unwrap()
}

/// The whole build log of bot `bot`'s first version, read with its owner's `token`.
pub async fn build_log(server: &TestServer, bot: i64, token: &str) -> String {
    let (_, log) = server
        .get(
            &format!("/api/bots/{bot}/versions/1/build-log"),
            Some(token),
        )
        .await;
    log["build_log"]
        .as_str()
        .map(str::to_string)
        .unwrap_or_else(|| log.to_string())
}

/// Waits (at most 120 s) until the build of bot `bot`'s latest version has ended;
/// returns that version's public view.
pub async fn wait_built(server: &TestServer, bot: i64) -> Value {
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let (_, v) = server.get(&format!("/api/bots/{bot}"), None).await;
        let last = v["versions"].as_array().unwrap().last().unwrap().clone();
        if last["build_status"] != "building" {
            return last;
        }
        assert!(Instant::now() < deadline, "the build did not end: {v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

/// Waits (at most 60 s) until match `id` has a final status; returns its view.
pub async fn wait_match(server: &TestServer, id: i64) -> Value {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let (s, v) = server.get(&format!("/api/matches/{id}"), None).await;
        assert_eq!(s, 200, "{v}");
        if FINAL.contains(&v["status"].as_str().unwrap()) {
            return v;
        }
        assert!(Instant::now() < deadline, "match {id} did not end: {v}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Checks that the standings kept as running sums equal those computed from the match
/// table, for the whole database (`all`, `ranking`) and for `tournaments`.
pub async fn assert_standings_equal_recount(database: &str, tournaments: &[i64]) {
    use mazearena::storage::leaderboard::Scope;
    let storage = mazearena::storage::Storage::open(database).await.unwrap();
    let mut scopes = vec![Scope::All, Scope::Ranking];
    scopes.extend(tournaments.iter().map(|&t| Scope::Tournament(t)));
    for scope in scopes {
        // Compared line by line, by bot and version.
        let by_version = |mut rows: Vec<mazearena::storage::leaderboard::Standing>| {
            rows.sort_by_key(|r| (r.bot_id, r.version));
            rows
        };
        let kept = by_version(storage.leaderboard(scope).await.unwrap());
        let counted = by_version(storage.leaderboard_recount(scope).await.unwrap());
        assert_eq!(kept.len(), counted.len(), "{scope:?}: {kept:?} {counted:?}");
        for (k, c) in kept.iter().zip(&counted) {
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
            // Not the positions: lines with equal means (up to the rounding of sums
            // taken in another order) may come in either order.
            assert!(
                (k.bot_id, k.version, k.played, k.finished, k.hidden_played)
                    == (c.bot_id, c.version, c.played, c.finished, c.hidden_played)
                    && close(k.mean_score, c.mean_score)
                    && close(k.finish_rate, c.finish_rate)
                    && match (k.mean_ratio, c.mean_ratio) {
                        (Some(a), Some(b)) => close(a, b),
                        (a, b) => a == b,
                    },
                "{scope:?}: kept {k:?}, counted {c:?}"
            );
        }
        if !matches!(scope, Scope::Ranking) {
            assert!(!kept.is_empty(), "{scope:?}: nothing to compare");
        }
    }
    storage.close().await;
}

/// The install folder of the Rust toolchain that builds this project (`rustup which
/// cargo` without `/bin/cargo`, else the folder of `cargo` on PATH): a runtime to list.
pub fn rust_toolchain() -> PathBuf {
    let cargo = Command::new("rustup")
        .args(["which", "cargo"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()))
        .unwrap_or_else(|| PathBuf::from(env!("CARGO")));
    let cargo = cargo.canonicalize().unwrap_or(cargo);
    cargo
        .parent()
        .and_then(Path::parent)
        .expect("cargo is in a bin folder")
        .to_path_buf()
}

/// The private set's maze ids of a competition as its organiser or the admin sees it
/// (`GET /api/competitions/{name}`).
pub fn private_maze_ids(view: &serde_json::Value) -> Vec<i64> {
    view["mazes"]
        .as_array()
        .expect("the competition's mazes")
        .iter()
        .filter(|m| m["set"] == "private")
        .filter_map(|m| m["maze_id"].as_i64())
        .collect()
}

/// A real nginx (Debian's package) in front of a server, with the README's site for it
/// (section "Running the server"): it appends each client's address to
/// `X-Forwarded-For`. Stopped when dropped.
pub struct Nginx {
    /// `http://127.0.0.1:PORT`.
    pub base: String,
    child: std::process::Child,
    _dir: tempfile::TempDir,
}

impl Nginx {
    /// nginx proxying to `upstream` (`http://127.0.0.1:PORT`), or `None` after saying why
    /// the test is skipped (outside CI only: in CI a missing nginx is a failure).
    pub fn start(upstream: &str, test: &str) -> Option<Nginx> {
        let binary = ["/usr/sbin/nginx", "/usr/local/sbin/nginx"]
            .into_iter()
            .map(PathBuf::from)
            .find(|p| p.exists());
        let Some(binary) = binary else {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true but nginx is missing: .ci/run installs it (apt-get install nginx)");
            }
            eprintln!("SKIPPED {test}: nginx is not installed (apt-get install nginx)");
            return None;
        };
        let dir = tempfile::tempdir().unwrap();
        let port = free_port();
        // The README's site, on this test's ports.
        let site = crate::readme::blocks_of("Running the server", "nginx").remove(0);
        assert!(site.contains("listen 80;") && site.contains("http://127.0.0.1:8080"));
        let site = site
            .replace("listen 80;", &format!("listen 127.0.0.1:{port};"))
            .replace("http://127.0.0.1:8080", upstream);
        let d = dir.path().display();
        let config = format!(
            "daemon off;\nworker_processes 1;\npid {d}/nginx.pid;\nerror_log {d}/error.log;\n\
             events {{ worker_connections 1024; }}\n\
             http {{\n  access_log off;\n  client_body_temp_path {d}/body;\n  proxy_temp_path {d}/proxy;\n\
               fastcgi_temp_path {d}/fastcgi;\n  uwsgi_temp_path {d}/uwsgi;\n  scgi_temp_path {d}/scgi;\n\
               {site}}}\n"
        );
        let conf = dir.path().join("nginx.conf");
        std::fs::write(&conf, config).unwrap();
        let child = Command::new(binary)
            .arg("-c")
            .arg(&conf)
            .arg("-p")
            .arg(dir.path())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("nginx starts");
        let deadline = Instant::now() + Duration::from_secs(10);
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(
                Instant::now() < deadline,
                "nginx did not listen: {}",
                std::fs::read_to_string(dir.path().join("error.log")).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        Some(Nginx {
            base: format!("http://127.0.0.1:{port}"),
            child,
            _dir: dir,
        })
    }
}

impl Drop for Nginx {
    fn drop(&mut self) {
        // nginx stops, its workers with it.
        let _ = nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(self.child.id() as i32),
            nix::sys::signal::Signal::SIGTERM,
        );
        let _ = self.child.wait();
    }
}

/// An HTTP client whose connections come from `address` (a loopback address such as
/// 127.0.0.2: one client of many on one machine), following no redirect.
pub fn client_from(address: &str) -> reqwest::Client {
    reqwest::Client::builder()
        .local_address(address.parse::<std::net::IpAddr>().unwrap())
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .unwrap()
}

/// A TCP port free on 127.0.0.1 now.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}
