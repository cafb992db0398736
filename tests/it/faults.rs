//! Faults, tested for real: a 504-match tournament played while its processes are
//! killed with SIGKILL and started again, ten times, ends with every match recorded
//! exactly once and the same standings as the tournament played without faults:
//! - on PostgreSQL, by one API server (`serve --jobs 0`) and three `mazearena worker`
//!   processes, any of which may be killed; PostgreSQL itself crashes once too, and a
//!   process starts while it is down;
//! - on SQLite, by one server with its own workers.
//!
//! The fault-free standings come from `mazearena tournament` (local, SQLite) on the same
//! bots, mazes and seeds. The processes run with `--max-retries 10`: a re-queued match
//! is claimed again first, so ten kills may hit one match several times, and the default
//! budget of 2 (a guard against bots that bring their worker down) would record it as
//! aborted.

use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use mazearena::storage::Storage;
use mazearena::storage::leaderboard::Scope;

use crate::support::{ADMIN, FINAL, processes_matching, root, sandbox};

/// Each bot plays each shipped maze this many times: 2 bots x 9 mazes x 28 = 504.
const REPEATS: i64 = 28;
/// The bots (from bots/python): their names and commands.
const BOTS: &[(&str, &str)] = &[
    ("simple-python", "python3 simple_bot.py"),
    ("seed002-random-dfs", "python3 seed002_random_dfs.py"),
];
/// The files the two bots need.
const BOT_FILES: &[&str] = &[
    "simple_bot.py",
    "seed002_random_dfs.py",
    "mazebot.py",
    "mazemap.py",
];
/// How many times a process is killed during a tournament.
const KILLS: usize = 10;
/// The lease on a running match: a killed worker's matches come back this long after.
const LEASE_SECS: &str = "2";
/// Re-queues of a match whose worker died (see the module's doc).
const MAX_RETRIES: &str = "10";

/// A standing as compared: bot name, matches played, finished, mean score.
type Row = (String, i64, i64, f64);

/// A `mazearena` process that the test kills and starts again with the same arguments.
struct Proc {
    name: String,
    args: Vec<String>,
    log: PathBuf,
    child: Child,
}

impl Proc {
    fn start(name: &str, args: Vec<String>, dir: &Path) -> Proc {
        let log = dir.join(format!("{name}.log"));
        let child = spawn(&args, &log);
        Proc {
            name: name.to_string(),
            args,
            log,
            child,
        }
    }

    /// SIGKILL, as a crash would; then the same command again.
    fn kill_and_restart(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.child = spawn(&self.args, &self.log);
    }

    /// SIGTERM (a graceful stop), and wait for the exit.
    fn terminate(&mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let _ = self.child.wait();
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The end of each process's log, for a failure's message.
fn log_tails(procs: &[Proc]) -> String {
    procs
        .iter()
        .map(|p| {
            let log = std::fs::read_to_string(&p.log).unwrap_or_default();
            let lines: Vec<&str> = log.lines().collect();
            let tail = lines[lines.len().saturating_sub(20)..].join("\n");
            format!("--- {} (pid {}):\n{tail}", p.name, p.child.id())
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn spawn(args: &[String], log: &Path) -> Child {
    let out = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(log)
        .unwrap();
    Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args(args)
        .env("MAZEARENA_ADMIN_TOKEN", ADMIN)
        .env("MAZEARENA_SANDBOX", sandbox().level())
        .env("RUST_LOG", "warn")
        .current_dir(root())
        .stdout(out.try_clone().unwrap())
        .stderr(out)
        .spawn()
        .expect("mazearena starts")
}

/// A free local port.
pub(crate) use crate::support::free_port;

/// The PostgreSQL cluster of the tests (`.ci/postgres.sh`): its URL and folder, or
/// `None` after saying why the test is skipped (outside CI; in CI it fails).
pub fn postgres(test: &str) -> Option<(String, PathBuf)> {
    match (
        std::env::var("MAZEARENA_TEST_POSTGRES"),
        std::env::var("MAZEARENA_TEST_POSTGRES_DIR"),
    ) {
        (Ok(url), Ok(dir)) => Some((url, dir.into())),
        _ if std::env::var("CI").is_ok_and(|v| v == "true") => {
            panic!("CI=true but no PostgreSQL: .ci/run starts one (.ci/postgres.sh)")
        }
        _ => {
            eprintln!(
                "skipping {test}: MAZEARENA_TEST_POSTGRES(_DIR) not set \
                 (eval \"$(.ci/postgres.sh start /tmp/mazearena-pg)\" starts a cluster)"
            );
            None
        }
    }
}

/// A new, empty database in the cluster at `url`: its URL.
pub async fn new_database(url: &str, name: &str) -> String {
    use sqlx::Connection;
    sqlx::any::install_default_drivers();
    let name = format!("{name}_{}_{}", std::process::id(), free_port());
    // The fault test crashes and restarts this cluster while other tests run: wait
    // for it as a server would (30 s).
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut admin = loop {
        match sqlx::AnyConnection::connect(url).await {
            Ok(c) => break c,
            Err(e) if Instant::now() < deadline => {
                eprintln!("PostgreSQL not reachable yet ({e}); trying again");
                tokio::time::sleep(Duration::from_millis(250)).await;
            }
            Err(e) => panic!("cannot reach PostgreSQL at {url}: {e}"),
        }
    };
    sqlx::query(&format!("create database {name}"))
        .execute(&mut admin)
        .await
        .unwrap();
    admin.close().await.unwrap();
    let (base, _) = url.rsplit_once('/').unwrap();
    format!("{base}/{name}")
}

/// A tiny deterministic generator (the kill schedule is printed and repeatable).
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) % n
    }
}

async fn get(client: &reqwest::Client, base: &str, path: &str) -> Option<Value> {
    let resp = client.get(format!("{base}{path}")).send().await.ok()?;
    if !resp.status().is_success() {
        return None;
    }
    resp.json().await.ok()
}

/// Waits until at least `at` matches of tournament `id` are done, as the server at
/// `base` says (while it is down, until it answers again).
async fn wait_done(client: &reqwest::Client, base: &str, id: i64, at: u64) {
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        let v = get(client, base, &format!("/api/tournaments/{id}")).await;
        if v.and_then(|v| v["done"].as_u64())
            .is_some_and(|done| done >= at)
        {
            return;
        }
        assert!(
            Instant::now() < deadline,
            "tournament {id} did not reach {at} matches done"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// Waits until the server at `base` answers `/healthz`.
async fn wait_healthy(client: &reqwest::Client, base: &str) {
    let deadline = Instant::now() + Duration::from_secs(30);
    while get(client, base, "/healthz").await.is_none() {
        assert!(Instant::now() < deadline, "{base} did not come up");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Registers the two bots and creates the tournament through the API; its id.
async fn create_tournament(client: &reqwest::Client, base: &str) -> i64 {
    let files: serde_json::Map<String, Value> = BOT_FILES
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(root().join("bots/python").join(f)).unwrap();
            (f.to_string(), Value::String(text))
        })
        .collect();
    let mut bot_ids = Vec::new();
    for (name, command) in BOTS {
        let resp = client
            .post(format!("{base}/api/bots"))
            .json(&json!({"name": name, "command": command, "files": files}))
            .send()
            .await
            .unwrap();
        assert_eq!(resp.status(), 201);
        let v: Value = resp.json().await.unwrap();
        bot_ids.push(v["bot_id"].as_i64().unwrap());
    }
    let mazes = get(client, base, "/api/mazes").await.unwrap();
    let maze_ids: Vec<i64> = mazes["mazes"]
        .as_array()
        .or(mazes.as_array())
        .unwrap()
        .iter()
        .map(|m| m["maze_id"].as_i64().unwrap())
        .collect();
    assert_eq!(maze_ids.len(), 9, "{mazes}");
    let resp = client
        .post(format!("{base}/api/tournaments"))
        .bearer_auth(ADMIN)
        .json(&json!({"name": "under fire", "bot_ids": bot_ids, "maze_ids": maze_ids, "repeats": REPEATS}))
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 202);
    let v: Value = resp.json().await.unwrap();
    v["tournament_id"].as_i64().unwrap()
}

/// Whether tournament `id` has ended, as the server at `base` says (None: no answer).
async fn tournament_done(client: &reqwest::Client, base: &str, id: i64) -> Option<bool> {
    let v = get(client, base, &format!("/api/tournaments/{id}")).await?;
    Some(v["done"].as_i64()? == v["total"].as_i64()?)
}

/// Every match of tournament `id` in `database` has a final status and exactly one
/// record that says the same; none aborted. Returns the standings.
async fn check_records(database: &str, id: i64) -> Vec<Row> {
    let storage = Storage::open(database).await.unwrap();
    let matches = storage.tournament_matches(id).await.unwrap();
    assert_eq!(matches.len() as i64, 2 * 9 * REPEATS);
    for m in &matches {
        let status = m.status.as_str();
        assert!(FINAL.contains(&status), "match {} is {status}", m.match_id);
        assert_ne!(status, "aborted", "match {} was aborted", m.match_id);
        let record = storage
            .get_record(m.match_id)
            .await
            .unwrap()
            .unwrap_or_else(|| panic!("match {} has no record", m.match_id));
        assert_eq!(record.status.as_str(), status, "match {}", m.match_id);
        assert_eq!(record.total_steps as i64, m.total_steps.unwrap_or(-1));
    }
    standings(&storage, id).await
}

async fn standings(storage: &Storage, id: i64) -> Vec<Row> {
    let mut rows: Vec<Row> = storage
        .leaderboard(Scope::Tournament(id))
        .await
        .unwrap()
        .into_iter()
        .map(|s| (s.name, s.played, s.finished, s.mean_score))
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    rows
}

fn assert_same_standings(got: &[Row], want: &[Row], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            g.0 == w.0 && g.1 == w.1 && g.2 == w.2 && (g.3 - w.3).abs() < 1e-9,
            "{what}: {got:?} vs {want:?}"
        );
    }
}

/// The same tournament played without faults, by `mazearena tournament`.
fn fault_free_standings(dir: &Path) -> Vec<Row> {
    let bots = dir.join("bots");
    std::fs::create_dir_all(&bots).unwrap();
    let mut toml = String::new();
    for (name, command) in BOTS {
        toml.push_str(&format!(
            "[[bot]]\nname = \"{name}\"\ncommand = \"{command}\"\n\n"
        ));
    }
    std::fs::write(bots.join("bot.toml"), toml).unwrap();
    for f in BOT_FILES {
        std::fs::copy(root().join("bots/python").join(f), bots.join(f)).unwrap();
    }
    let database = format!("sqlite://{}", dir.join("fault-free.db").display());
    let repeats = REPEATS.to_string();
    crate::support::mazearena_json(&[
        "tournament",
        "--bots",
        bots.to_str().unwrap(),
        "--mazes",
        "mazes",
        "--repeats",
        &repeats,
        "--database",
        &database,
        "--json",
    ]);
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(async {
        let storage = Storage::open(&database).await.unwrap();
        standings(&storage, 1).await
    })
}

/// Plays the tournament on the server at `base` while `procs` (and PostgreSQL, with
/// `restart_postgres`) are killed and started again; waits for its end.
async fn play_under_fire(
    client: &reqwest::Client,
    base: &str,
    procs: &mut [Proc],
    restart_postgres: Option<&Path>,
    seed: u64,
) -> i64 {
    let id = create_tournament(client, base).await;
    let mut rng = Lcg(seed);
    eprintln!("kill schedule seed {seed}");
    let total = (2 * 9 * REPEATS) as u64;
    for k in 0..KILLS as u64 {
        // Kill k comes once about (k + 1) / (KILLS + 4) of the matches are done (give or
        // take a random part of a share), then after a random pause: every kill lands
        // while the tournament plays, however fast this machine plays it (the last one
        // with some 140 matches to go).
        let share = total / (KILLS as u64 + 4);
        let at = (k + 1) * share - share / 2 + rng.below(share);
        wait_done(client, base, id, at).await;
        tokio::time::sleep(Duration::from_millis(rng.below(500))).await;
        let k = k as usize;
        // Each process once (in an order the seed gives), then any.
        let n = procs.len();
        let target = if k < n {
            (k + seed as usize) % n
        } else {
            rng.below(n as u64) as usize
        };
        eprintln!("kill {}: {}", k + 1, procs[target].name);
        match restart_postgres {
            // Once, PostgreSQL crashes too, and the killed process starts while it is
            // down: it must wait for it, not exit.
            Some(dir) if k == KILLS / 2 => {
                eprintln!(
                    "PostgreSQL crashes; {} starts while it is down",
                    procs[target].name
                );
                postgres_ctl(dir, "crash");
                procs[target].kill_and_restart();
                tokio::time::sleep(Duration::from_millis(1500)).await;
                postgres_ctl(dir, "resume");
            }
            _ => procs[target].kill_and_restart(),
        }
        wait_healthy(client, base).await;
    }
    assert_eq!(
        tournament_done(client, base, id).await,
        Some(false),
        "the tournament ended before the last kill: the faults did not hit it"
    );
    let deadline = Instant::now() + Duration::from_secs(600);
    while tournament_done(client, base, id).await != Some(true) {
        assert!(Instant::now() < deadline, "tournament {id} did not end");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    id
}

/// Runs `.ci/postgres.sh CMD DIR` on the test's cluster.
fn postgres_ctl(dir: &Path, cmd: &str) {
    let status = Command::new(root().join(".ci/postgres.sh"))
        .arg(cmd)
        .arg(dir)
        .status()
        .unwrap();
    assert!(status.success(), "postgres.sh {cmd} failed");
}

fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Where one setting plays: its folder, bot files and server address.
struct Site {
    dir: PathBuf,
    data: String,
    base: String,
    bind: String,
}

impl Site {
    fn new(tmp: &Path, name: &str) -> Site {
        let dir = tmp.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let port = free_port();
        Site {
            data: dir.join("data").display().to_string(),
            dir,
            base: format!("http://127.0.0.1:{port}"),
            bind: format!("127.0.0.1:{port}"),
        }
    }

    /// Stops `procs` gracefully, then checks the records of tournament `id` in
    /// `database`, its standings against `want`, and that nothing was left running.
    fn finish(&self, procs: &mut [Proc], database: &str, id: i64, want: &[Row], what: &str) {
        for p in procs.iter_mut() {
            p.terminate();
        }
        let runtime = tokio::runtime::Runtime::new().unwrap();
        let got = runtime.block_on(check_records(database, id));
        assert_same_standings(&got, want, what);
        assert!(
            processes_matching(&self.data).is_empty(),
            "{what}: processes left behind"
        );
    }
}

#[test]
fn tournaments_survive_killed_servers_workers_and_database() {
    let _heavy = crate::support::heavy();
    let pg = postgres("tournaments_survive_killed_servers_workers_and_database");
    let tmp = tempfile::tempdir().unwrap();
    let want = fault_free_standings(tmp.path());
    assert_eq!(want.len(), 2, "{want:?}");
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let client = reqwest::Client::new();

    // PostgreSQL: one API server, three workers; any of them killed, PostgreSQL restarted.
    if let Some((url, cluster)) = &pg {
        let site = Site::new(tmp.path(), "pg");
        let database = runtime.block_on(new_database(url, "faults"));
        // Every process has a data folder of its own: the bots' files reach the
        // workers through the database, no disk is shared.
        let common = |data: &str| {
            args(&[
                "--database",
                &database,
                "--data-dir",
                data,
                "--lease-secs",
                LEASE_SECS,
                "--max-retries",
                MAX_RETRIES,
            ])
        };
        let mut api = args(&["serve", "--jobs", "0", "--bind", &site.bind]);
        api.extend(common(&site.data));
        let mut procs = vec![Proc::start("api", api, &site.dir)];
        for w in 0..3 {
            let mut worker = args(&["worker", "--jobs", "1"]);
            worker.extend(common(&format!("{}-worker{w}", site.data)));
            procs.push(Proc::start(&format!("worker{w}"), worker, &site.dir));
        }
        let id = runtime.block_on(async {
            wait_healthy(&client, &site.base).await;
            let id = play_under_fire(&client, &site.base, &mut procs, Some(cluster), 11).await;
            // The workers reported themselves (a worker restarted last reports once it
            // is up); the killed ones' rows are stale.
            let deadline = Instant::now() + Duration::from_secs(30);
            loop {
                let health = client
                    .get(format!("{}/healthz", site.base))
                    .bearer_auth(ADMIN)
                    .send()
                    .await
                    .unwrap()
                    .json::<Value>()
                    .await
                    .unwrap();
                let live = health["workers"].as_array().unwrap();
                let workers = live.iter().filter(|w| w["role"] == "worker").count();
                if workers == 3 {
                    break;
                }
                assert!(
                    Instant::now() < deadline,
                    "{workers} live workers: {health}\n{}",
                    log_tails(&procs)
                );
                tokio::time::sleep(Duration::from_millis(200)).await;
            }
            id
        });
        site.finish(&mut procs, &database, id, &want, "PostgreSQL under faults");
    }

    // SQLite: one server with its own workers, killed ten times.
    let site = Site::new(tmp.path(), "sqlite");
    let database = format!("sqlite://{}/mazearena.db", site.dir.display());
    let server = args(&[
        "serve",
        "--bind",
        &site.bind,
        "--database",
        &database,
        "--data-dir",
        &site.data,
        "--lease-secs",
        LEASE_SECS,
        "--max-retries",
        MAX_RETRIES,
    ]);
    let mut procs = vec![Proc::start("server", server, &site.dir)];
    let id = runtime.block_on(async {
        wait_healthy(&client, &site.base).await;
        play_under_fire(&client, &site.base, &mut procs, None, 7).await
    });
    site.finish(&mut procs, &database, id, &want, "SQLite under faults");
}
