//! The Kubernetes manifests (deploy/kubernetes/) against what they run:
//! - the image, subcommands, flags and variables they give exist in this binary (its
//!   `--help`), at this release, and the Secret holds every key they read;
//! - the worker's pod gives the sandbox what it needs and no more, its resources are
//!   what `--jobs` uses, its grace outlasts the worker's own, and the other pods meet
//!   the `restricted` Pod Security level;
//! - the scaler's query is the storage's (`WORK_FOR_WORKERS`), and the manifest's copy
//!   runs on PostgreSQL as a role that may only read, counting what workers could take;
//! - a worker stopped with SIGTERM (a scale-in) finishes its match within its grace, or
//!   gives it back to the queue, claims nothing new and exits within the pod's grace.
//!
//! The schemas themselves (Kubernetes' and KEDA's) are checked offline by
//! `.ci/kubernetes.sh`; the pod run under podman with the same options by `.ci/image.sh`.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::faults::{new_database, postgres};
use crate::support::{TestServer, processes_matching, register, root, sandbox};

fn dir() -> PathBuf {
    root().join("deploy/kubernetes")
}

/// Every object of every manifest (not the kustomization), with its file's name.
fn objects() -> Vec<(String, Value)> {
    use serde::Deserialize;
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !name.ends_with(".yaml") || name == "kustomization.yaml" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for doc in yaml_serde::Deserializer::from_str(&text) {
            let v = Value::deserialize(doc).unwrap_or_else(|e| panic!("{name}: {e}"));
            if !v.is_null() {
                out.push((name.clone(), v));
            }
        }
    }
    out
}

fn kustomization() -> Value {
    let text = std::fs::read_to_string(dir().join("kustomization.yaml")).unwrap();
    yaml_serde::from_str(&text).unwrap()
}

/// The one object of `kind` named `name`.
fn object(kind: &str, name: &str) -> Value {
    let found: Vec<Value> = objects()
        .into_iter()
        .map(|(_, v)| v)
        .filter(|v| v["kind"] == kind && v["metadata"]["name"] == name)
        .collect();
    assert_eq!(found.len(), 1, "{kind}/{name}");
    found.into_iter().next().unwrap()
}

/// The pod templates of the Deployments and Jobs: (object name, pod spec).
fn pods() -> Vec<(String, Value)> {
    objects()
        .into_iter()
        .filter(|(_, v)| v["kind"] == "Deployment" || v["kind"] == "Job")
        .map(|(_, v)| {
            (
                v["metadata"]["name"].as_str().unwrap().to_string(),
                v["spec"]["template"]["spec"].clone(),
            )
        })
        .collect()
}

/// A container's literal environment variable.
fn env_value(container: &Value, name: &str) -> Option<String> {
    container["env"]
        .as_array()?
        .iter()
        .find(|e| e["name"] == name)
        .and_then(|e| e["value"].as_str().map(str::to_string))
}

fn help(subcommand: &str) -> String {
    let out = crate::support::mazearena(&[subcommand, "--help"]);
    assert!(out.status.success(), "mazearena {subcommand} --help");
    String::from_utf8(out.stdout).unwrap()
}

/// A container's arguments (the subcommand first).
fn args_of(container: &Value) -> Vec<&str> {
    container["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect()
}

#[test]
fn the_manifests_run_this_release_with_flags_and_variables_it_has() {
    let k = kustomization();
    // Every manifest is applied, and nothing else is listed.
    let listed: BTreeSet<String> = k["resources"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap().to_string())
        .collect();
    let files: BTreeSet<String> = objects().into_iter().map(|(f, _)| f).collect();
    assert_eq!(listed, files, "kustomization.yaml's resources");
    // The image is this release's.
    let version = env!("CARGO_PKG_VERSION");
    let images = k["images"].as_array().unwrap();
    assert_eq!(images.len(), 1);
    assert_eq!(images[0]["name"], "mazearena");
    assert_eq!(images[0]["newTag"], version, "the image tag is the release");
    let out = crate::support::mazearena(&["--version"]);
    assert_eq!(
        String::from_utf8(out.stdout).unwrap().trim(),
        format!("mazearena {version}")
    );
    let secret = object("Secret", "mazearena");
    let keys: BTreeSet<&str> = secret["stringData"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    let mut checked = 0;
    for (name, pod) in pods() {
        for c in pod["containers"].as_array().unwrap() {
            assert_eq!(c["image"], "mazearena", "{name}: the image kustomize names");
            let args = args_of(c);
            let text = help(args[0]);
            for flag in args[1..].iter().filter(|a| a.starts_with("--")) {
                assert!(
                    text.contains(&format!("{flag} ")),
                    "{name}: `mazearena {}` has no {flag}",
                    args[0]
                );
            }
            for e in c["env"].as_array().unwrap() {
                let var = e["name"].as_str().unwrap();
                if var.starts_with("MAZEARENA_") {
                    assert!(
                        text.contains(&format!("[env: {var}")),
                        "{name}: `mazearena {}` reads no {var}",
                        args[0]
                    );
                    checked += 1;
                }
                if let Some(key) = e["valueFrom"]["secretKeyRef"]["key"].as_str() {
                    assert_eq!(e["valueFrom"]["secretKeyRef"]["name"], "mazearena");
                    assert!(keys.contains(key), "{name}: the Secret has no {key}");
                }
            }
        }
    }
    assert!(checked >= 10, "only {checked} variables checked");
    // The placeholders cannot run: the API server refuses tokens that short, and the
    // database's host is in `.invalid`, which never resolves.
    for key in ["database-url", "scaler-database-url"] {
        let url = secret["stringData"][key].as_str().unwrap();
        assert!(url.contains(".invalid:"), "{key}: {url}");
    }
    for key in ["admin-token", "metrics-token"] {
        let tmp = tempfile::tempdir().unwrap();
        let placeholder = secret["stringData"][key].as_str().unwrap();
        let mut serve = Command::new(env!("CARGO_BIN_EXE_mazearena"));
        serve
            .args(["serve", "--jobs", "0", "--bind", "127.0.0.1:0"])
            .arg("--database")
            .arg(format!("sqlite://{}", tmp.path().join("db").display()))
            .arg("--data-dir")
            .arg(tmp.path().join("data"))
            .env(
                "MAZEARENA_ADMIN_TOKEN",
                "a-real-admin-token-of-32-characters",
            )
            .stdout(Stdio::null());
        if key == "admin-token" {
            serve.env("MAZEARENA_ADMIN_TOKEN", placeholder);
        } else {
            serve.env("MAZEARENA_METRICS_TOKEN", placeholder);
        }
        let out = serve.output().unwrap();
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && said.contains("too short"),
            "the placeholder {key} was taken: {said}"
        );
    }
    let scaler = object("TriggerAuthentication", "mazearena-scaler");
    let key = scaler["spec"]["secretTargetRef"][0]["key"]
        .as_str()
        .unwrap();
    assert!(keys.contains(key), "the scaler's {key}");
}

/// A pod's container's security context, with the pod's own merged under it.
fn security(pod: &Value) -> (Value, Value) {
    (
        pod["securityContext"].clone(),
        pod["containers"][0]["securityContext"].clone(),
    )
}

#[test]
fn the_worker_pod_gives_the_sandbox_what_it_needs_and_nothing_more() {
    let worker = object("Deployment", "mazearena-worker");
    let pod = &worker["spec"]["template"]["spec"];
    let (p, c) = security(pod);
    // What the sandbox needs (docs/SECURITY.md, "Running in a container").
    assert_eq!(p["seccompProfile"]["type"], "Unconfined");
    assert_eq!(p["appArmorProfile"]["type"], "Unconfined");
    assert_eq!(c["procMount"], "Unmasked");
    assert_eq!(
        pod["hostUsers"], false,
        "Unmasked /proc only in a user namespace"
    );
    // And nothing more.
    assert_eq!(c["privileged"], false);
    assert_eq!(c["allowPrivilegeEscalation"], false);
    assert_eq!(c["capabilities"]["drop"], json!(["ALL"]));
    assert!(c["capabilities"].get("add").is_none());
    assert_eq!(c["readOnlyRootFilesystem"], true);
    assert_eq!(p["runAsNonRoot"], true);
    assert_eq!(pod["automountServiceAccountToken"], false);
    // The image's user.
    let dockerfile = std::fs::read_to_string(root().join("Dockerfile")).unwrap();
    let user = format!("USER {}:{}", p["runAsUser"], p["runAsGroup"]);
    assert!(dockerfile.contains(&user), "the Dockerfile has no {user}");
    // A worker reads the database and nothing else of the Secret.
    let container = &pod["containers"][0];
    let secrets: Vec<&str> = container["env"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e["valueFrom"]["secretKeyRef"]["key"].as_str())
        .collect();
    assert_eq!(secrets, ["database-url"]);
    // Resources are what --jobs uses: a core a slot, a match's memory a slot, and the
    // Guaranteed class (requests = limits).
    let jobs: u64 = env_value(container, "MAZEARENA_JOBS")
        .unwrap()
        .parse()
        .unwrap();
    let res = &container["resources"];
    assert_eq!(res["requests"], res["limits"]);
    assert_eq!(res["limits"]["cpu"], jobs.to_string());
    let mib: u64 = res["limits"]["memory"]
        .as_str()
        .unwrap()
        .strip_suffix("Mi")
        .unwrap()
        .parse()
        .unwrap();
    let per_slot =
        mazearena::runner::DEFAULT_MEMORY_LIMIT_MB + mazearena::runner::DEFAULT_SCRATCH_MB;
    assert!(
        mib >= jobs * per_slot + 128,
        "{mib} MiB for {jobs} slots of {per_slot} MiB and the worker"
    );
    // The pod outlasts the worker's own grace, with time to give matches back.
    let grace: u64 = env_value(container, "MAZEARENA_SHUTDOWN_GRACE_SECS")
        .unwrap()
        .parse()
        .unwrap();
    let pod_grace = pod["terminationGracePeriodSeconds"].as_u64().unwrap();
    assert!(
        pod_grace >= grace + 10,
        "{pod_grace} s for a {grace} s grace"
    );
    // The API servers pause before SIGTERM (so that no proxy still sends them requests),
    // well within their grace.
    let api = object("Deployment", "mazearena-api");
    let api_pod = &api["spec"]["template"]["spec"];
    let pause = api_pod["containers"][0]["lifecycle"]["preStop"]["sleep"]["seconds"]
        .as_u64()
        .unwrap();
    assert!(pause >= 1 && pause + 10 <= api_pod["terminationGracePeriodSeconds"].as_u64().unwrap());
    // Every other pod meets the `restricted` Pod Security level.
    for (name, pod) in pods() {
        if name == "mazearena-worker" {
            continue;
        }
        let (p, c) = security(&pod);
        assert_eq!(p["runAsNonRoot"], true, "{name}");
        assert_eq!(p["seccompProfile"]["type"], "RuntimeDefault", "{name}");
        assert_eq!(c["allowPrivilegeEscalation"], false, "{name}");
        assert_eq!(c["capabilities"]["drop"], json!(["ALL"]), "{name}");
        assert_eq!(c["readOnlyRootFilesystem"], true, "{name}");
        assert!(
            pod.get("hostUsers").is_none() && c.get("procMount").is_none(),
            "{name}"
        );
    }
}

/// `sql` with its whitespace made single spaces.
fn squeeze(sql: &str) -> String {
    sql.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[tokio::test]
async fn the_scalers_query_is_the_storages_and_counts_on_postgresql_as_a_read_only_role() {
    use mazearena::storage::Storage;
    use sqlx::Connection;
    let scaled = object("ScaledObject", "mazearena-worker");
    assert_eq!(scaled["spec"]["scaleTargetRef"]["name"], "mazearena-worker");
    let trigger = &scaled["spec"]["triggers"][0];
    assert_eq!(trigger["type"], "postgresql");
    assert_eq!(trigger["authenticationRef"]["name"], "mazearena-scaler");
    let query = trigger["metadata"]["query"].as_str().unwrap();
    assert_eq!(
        squeeze(query),
        squeeze(mazearena::storage::matches::queue::WORK_FOR_WORKERS),
        "the manifest's query is the storage's"
    );
    let target: f64 = trigger["metadata"]["targetQueryValue"]
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!(target >= 1.0);

    let Some((cluster, _)) = postgres("the scaler's query") else {
        return;
    };
    let url = new_database(&cluster, "scaler").await;
    let db = Storage::open(&url).await.unwrap();
    // The role of docs/DEPLOY.md: it may read the three tables and nothing else.
    let role = format!("scaler_{}", std::process::id());
    let mut admin = sqlx::PgConnection::connect(&url).await.unwrap();
    // docs/DEPLOY.md's statements, as written there (its one `sql` block).
    let doc = std::fs::read_to_string(root().join("docs/DEPLOY.md")).unwrap();
    let block = doc
        .split("```sql\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("docs/DEPLOY.md has the scaler role's SQL");
    let statements: Vec<String> = block
        .lines()
        .filter(|l| !l.trim_start().starts_with("--"))
        .collect::<Vec<_>>()
        .join("\n")
        .split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.replace("mazearena_scaler", &role)
                .replace("CHOOSE-ONE", "scaler")
        })
        .collect();
    assert!(statements.len() >= 4, "{statements:?}");
    for sql in &statements {
        sqlx::query(sql).execute(&mut admin).await.unwrap();
    }
    let (base, name) = url.rsplit_once('/').unwrap();
    let host = base.rsplit_once('@').unwrap().1;
    let as_scaler = format!("postgres://{role}:scaler@{host}/{name}");
    let mut scaler = sqlx::PgConnection::connect(&as_scaler).await.unwrap();
    let by_scaler = async |scaler: &mut sqlx::PgConnection| -> i64 {
        sqlx::query_scalar(query).fetch_one(scaler).await.unwrap()
    };
    let version =
        |command: &'static str, build: Option<&'static str>| mazearena::storage::bots::NewVersion {
            command,
            dir: "/x",
            files_sha256: "s",
            file_count: 1,
            build_command: build,
            env: &[],
            bundle_sha256: None,
            runtime: None,
            protocol: None,
        };
    let maze = db
        .insert_maze(&mazearena::storage::mazes::NewMaze {
            name: "m",
            hash: "h",
            dim: 12,
            layout: "{}",
            hidden: false,
            optimum: Some(10),
        })
        .await
        .unwrap()
        .maze_id;
    assert_eq!(by_scaler(&mut scaler).await, 0, "an empty queue");
    let ready = db.create_bot("a", "ha", &version("a", None)).await.unwrap();
    for seed in 0..5 {
        db.queue_match(ready.bot_version_id, maze, seed)
            .await
            .unwrap();
    }
    assert_eq!(by_scaler(&mut scaler).await, 5, "five claimable matches");
    let paused = db.create_bot("b", "hb", &version("b", None)).await.unwrap();
    db.queue_match(paused.bot_version_id, maze, 0)
        .await
        .unwrap();
    db.pause_bot(paused.bot_id, "test").await.unwrap();
    assert_eq!(
        by_scaler(&mut scaler).await,
        5,
        "a paused bot's match waits for no worker"
    );
    let building = db
        .create_bot("c", "hc", &version("c", Some("make")))
        .await
        .unwrap();
    db.queue_match(building.bot_version_id, maze, 0)
        .await
        .unwrap();
    assert_eq!(
        by_scaler(&mut scaler).await,
        6,
        "a build, not yet its match"
    );
    let claimed = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
    assert_eq!(
        by_scaler(&mut scaler).await,
        6,
        "a running match is work too"
    );
    db.release_match(claimed.match_id, "w").await.unwrap();
    assert_eq!(by_scaler(&mut scaler).await, 6, "given back");
    // One match played, in 4 s: the five pieces left are 20 s of work.
    sqlx::query(
        "update match set status = 'finished', score = 20, started_at = 1000, finished_at = 5000
         where match_id = $1",
    )
    .bind(claimed.match_id)
    .execute(&mut admin)
    .await
    .unwrap();
    assert_eq!(by_scaler(&mut scaler).await, 20, "in seconds of a slot");
    assert_eq!(
        db.work_for_workers().await.unwrap(),
        20,
        "the storage's own count"
    );
    // The role reads the columns the query needs and nothing else: not a score before it
    // is published, not a record, a bot's variables or an owner's token hash; it writes
    // nothing and makes nothing.
    for sql in [
        "select score from match",
        "select record from match",
        "select env from bot_version",
        "select owner_token_hash from bot",
        "select count(*) from entrant",
        "update match set status = 'finished'",
        "create table scaler_probe (x int)",
    ] {
        let done = sqlx::query(sql).execute(&mut scaler).await;
        let said = done.map_or_else(|e| e.to_string(), |_| "done".to_string());
        assert!(
            said.contains("permission denied"),
            "the scaler's role could: {sql} ({said})"
        );
    }
    scaler.close().await.unwrap();
    admin.close().await.unwrap();
    db.close().await;
}

/// Waits until match `id`'s status (from the database) is one `wanted` takes, described
/// as `what`; on failure, says what the worker logged in `log`.
async fn wait_until(
    db: &mazearena::storage::Storage,
    id: i64,
    wanted: impl Fn(&str) -> bool,
    what: &str,
    within: Duration,
    log: &std::path::Path,
) {
    let deadline = Instant::now() + within;
    loop {
        let row = db.get_match(id).await.unwrap().unwrap();
        if wanted(row.status.as_str()) {
            return;
        }
        assert!(
            Instant::now() < deadline,
            "match {id} is {}, not {what}; the worker's log:\n{}",
            row.status,
            std::fs::read_to_string(log).unwrap_or_default()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// A container's literal variables, as the pod gives them (those from the Secret are the
/// test's own).
fn literal_env(container: &Value) -> Vec<(String, String)> {
    container["env"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| {
            Some((
                e["name"].as_str()?.to_string(),
                e["value"].as_str()?.to_string(),
            ))
        })
        .collect()
}

/// `mazearena worker` with the worker pod's arguments and variables (its data folder
/// `data` instead of the pod's volume), on `database`; its stderr in `log`.
fn start_worker(
    container: &Value,
    database: &str,
    data: &std::path::Path,
    log: &std::path::Path,
) -> std::process::Child {
    let out = std::fs::File::create(log).unwrap();
    Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args(args_of(container))
        .envs(literal_env(container))
        .env("MAZEARENA_DATABASE", database)
        .env("MAZEARENA_DATA_DIR", data)
        .env("MAZEARENA_SANDBOX", sandbox().level())
        // The test's bots are slow on purpose: no validation match before their own.
        .env("MAZEARENA_NO_VALIDATION", "true")
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(out)
        .spawn()
        .unwrap()
}

/// SIGTERM to `child`; its exit status and how long it took.
fn terminate(child: &mut std::process::Child) -> (std::process::ExitStatus, Duration) {
    let t0 = Instant::now();
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGTERM,
    )
    .unwrap();
    let status = child.wait().unwrap();
    (status, t0.elapsed())
}

/// The API server and the workers run with their pods' arguments and variables (so the
/// values parse), on PostgreSQL, with the worker pod's slots and graces.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_stopped_for_a_scale_in_finishes_or_gives_back_its_matches_within_the_pods_grace()
{
    let Some((cluster, _)) = postgres("the workers' SIGTERM") else {
        return;
    };
    let worker = object("Deployment", "mazearena-worker");
    let pod = &worker["spec"]["template"]["spec"];
    let container = &pod["containers"][0];
    let slots: i64 = env_value(container, "MAZEARENA_JOBS")
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(slots, 1, "the test is written for one slot");
    let grace: u64 = env_value(container, "MAZEARENA_SHUTDOWN_GRACE_SECS")
        .unwrap()
        .parse()
        .unwrap();
    let grace = Duration::from_secs(grace);
    let pod_grace = Duration::from_secs(pod["terminationGracePeriodSeconds"].as_u64().unwrap());
    let tmp = tempfile::tempdir().unwrap();
    let database = new_database(&cluster, "sigterm").await;
    // The API server with the API pod's arguments and variables.
    let api = object("Deployment", "mazearena-api");
    let api = &api["spec"]["template"]["spec"]["containers"][0];
    let api_args = args_of(api);
    assert_eq!(api_args[0], "serve");
    let api_env = literal_env(api);
    let api_env: Vec<(&str, &str)> = api_env
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    let server = TestServer::start_on(tmp.path(), Some(&database), &api_args[1..], &api_env);
    let db = mazearena::storage::Storage::open(&database).await.unwrap();
    let code = std::fs::read_to_string(root().join("tests/fixtures/bots/scripted.py")).unwrap();
    // 1000 idle steps: about 3 s for the quick bot, 60 s for the slow one.
    let (quick, quick_token) = register(
        &server,
        "quick",
        "python3 scripted.py --delay-ms 2",
        json!({"scripted.py": code}),
    )
    .await;
    let (slow, slow_token) = register(
        &server,
        "slow",
        "python3 scripted.py --delay-ms 60",
        json!({"scripted.py": code}),
    )
    .await;
    let maze = 1;
    let first = crate::support::queue(&server, quick, maze, 0, &quick_token).await;
    let second = crate::support::queue(&server, quick, maze, 1, &quick_token).await;
    let data = tmp.path().join("worker");

    // A match that ends within the grace is finished, and nothing new is claimed.
    let log = tmp.path().join("worker-1.log");
    let mut child = start_worker(container, &database, &data, &log);
    wait_until(
        &db,
        first,
        |s| s == "running",
        "running",
        Duration::from_secs(60),
        &log,
    )
    .await;
    let (status, took) = terminate(&mut child);
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(status.success(), "{status:?}\n{text}");
    assert!(took < grace, "{took:?}\n{text}");
    assert!(text.contains("mazearena worker stopped"), "{text}");
    let ended = |s: &str| crate::support::FINAL.contains(&s) && s != "aborted";
    wait_until(&db, first, ended, "ended", Duration::ZERO, &log).await;
    let row = db.get_match(second).await.unwrap().unwrap();
    assert_eq!(
        (row.status.as_str(), row.attempts),
        ("queued", 0),
        "nothing claimed after SIGTERM"
    );

    // A match that cannot end within the grace is given back to the queue, and the
    // worker exits within the pod's grace.
    let long = crate::support::queue(&server, slow, maze, 1, &slow_token).await;
    let log = tmp.path().join("worker-2.log");
    let mut child = start_worker(container, &database, &data, &log);
    wait_until(
        &db,
        long,
        |s| s == "running",
        "running",
        Duration::from_secs(60),
        &log,
    )
    .await;
    let (status, took) = terminate(&mut child);
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(status.success(), "{status:?}\n{text}");
    assert!(
        took >= grace && took < pod_grace,
        "stopped after {took:?}: the grace is {grace:?}, the pod's {pod_grace:?}\n{text}"
    );
    let row = db.get_match(long).await.unwrap().unwrap();
    assert_eq!(row.status, "queued", "given back to the queue");
    assert!(
        processes_matching("scripted.py --delay-ms 60").is_empty(),
        "the slow bot is still running"
    );
    // Another worker takes it at once, not after the lease runs out.
    let log = tmp.path().join("worker-3.log");
    let mut child = start_worker(container, &database, &data, &log);
    wait_until(
        &db,
        long,
        |s| s == "running",
        "running",
        Duration::from_secs(10),
        &log,
    )
    .await;
    let (status, _) = terminate(&mut child);
    assert!(status.success());
    db.close().await;
}

/// docs/DEPLOY.md's capacity plan is the one BENCHMARKS.md's figures give, each figure
/// named by its section and row, and the scaler's target is the plan's.
#[test]
fn the_capacity_plan_is_benchmarks_md_s() {
    let out = Command::new("python3")
        .arg(root().join("benches/capacity.py"))
        .arg("--check")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let doc = std::fs::read_to_string(root().join("docs/DEPLOY.md")).unwrap();
    let plan = doc.split("<!-- capacity:begin -->").nth(1).unwrap();
    let cited = plan
        .lines()
        .filter(|l| l.starts_with("| ") && l.contains("*: "))
        .count();
    assert!(
        cited >= 9,
        "only {cited} figures name their BENCHMARKS.md row"
    );
    for entrants in ["100", "1,000", "10,000"] {
        for lang in ["Python", "C", "Java"] {
            assert!(
                plan.contains(&format!("| {entrants} | {lang} |")),
                "no row for {entrants} entrants' {lang} bots"
            );
        }
    }
}
