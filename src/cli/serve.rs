//! `mazearena serve`: the match server (HTTP API + match workers).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use clap::Args;
use tokio::net::TcpListener;
use tokio::sync::Notify;
use tokio_util::task::TaskTracker;

use crate::api::{self, AppState, Settings, auth};
use crate::metrics::Metrics;
use crate::registry::{self, RegistryError};
use crate::storage::{Backend, Storage, with_patience};
use crate::work::worker::{self, Shutdown};

use super::pool::PoolArgs;

/// The project's own mazes, loaded as the default public set on first start.
pub const DEFAULT_MAZES: &[(&str, &str)] = &[
    ("gen-12-s1", include_str!("../../mazes/gen-12-s1.txt")),
    ("gen-12-s2", include_str!("../../mazes/gen-12-s2.txt")),
    ("gen-12-s3", include_str!("../../mazes/gen-12-s3.txt")),
    ("gen-14-s1", include_str!("../../mazes/gen-14-s1.txt")),
    ("gen-14-s2", include_str!("../../mazes/gen-14-s2.txt")),
    ("gen-14-s3", include_str!("../../mazes/gen-14-s3.txt")),
    ("gen-16-s1", include_str!("../../mazes/gen-16-s1.txt")),
    ("gen-16-s2", include_str!("../../mazes/gen-16-s2.txt")),
    ("gen-16-s3", include_str!("../../mazes/gen-16-s3.txt")),
];

/// How often the competitions' clock runs when nothing wakes it: a competition closes
/// within this long of its time, and a version made ready elsewhere (another server's
/// build) is queued on its competition's ranking sets within this long.
const COMPETITION_TICK: Duration = Duration::from_millis(500);

/// How often the competitions' clock looks while a competition is closing.
const CLOSING_TICK: Duration = Duration::from_millis(50);

/// Settings of `mazearena serve`; every flag can also come from its `MAZEARENA_*` variable.
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Address to listen on (port 0: any free port; the chosen address is printed).
    #[arg(long, env = "MAZEARENA_BIND", default_value = "127.0.0.1:8080")]
    bind: String,
    /// Try the server: a database and data folder of their own in `--demo-dir`, the
    /// starter kits' bots (Python, and JavaScript if `node` is installed) registered and
    /// playing the shipped mazes, and a competition open (`demo-cup`) to take part in.
    /// `--database` and `--data-dir` are not used.
    #[arg(long)]
    demo: bool,
    /// The demo's folder (its SQLite database and data), made if missing; a demo started
    /// again goes on where it was.
    #[arg(long, default_value = "mazearena-demo")]
    demo_dir: PathBuf,
    /// The database: `sqlite://FILE` (created on first start) or
    /// `postgres://USER:PASSWORD@HOST/DB` (several servers and workers on one database).
    #[arg(
        long,
        env = "MAZEARENA_DATABASE",
        default_value = "sqlite://mazearena.db"
    )]
    database: String,
    /// A local folder: the cache of bots' files, build folders, and the place uploads
    /// are checked in (bots' files themselves are stored in the database).
    #[arg(long, env = "MAZEARENA_DATA_DIR", default_value = "mazearena-data")]
    data_dir: PathBuf,
    /// The admin token (uploading mazes, tournaments). If unset, one is generated and
    /// printed at start.
    #[arg(long, env = "MAZEARENA_ADMIN_TOKEN", hide_env_values = true)]
    admin_token: Option<String>,
    /// A token that may read `/metrics` (Prometheus' `bearer_token` in its scrape
    /// config), besides the admin token: the counters and times of matches on hidden
    /// mazes are the operator's. At least 16 characters.
    #[arg(long, env = "MAZEARENA_METRICS_TOKEN", hide_env_values = true)]
    metrics_token: Option<String>,
    /// The most matches that may wait in the queue; more are refused with 429.
    #[arg(long, env = "MAZEARENA_MAX_QUEUE", default_value_t = 10_000)]
    max_queue: i64,
    /// The most matches one owner (one owner token) may have waiting; more are refused
    /// with 429 saying whose limit it is. The admin has none.
    #[arg(long, env = "MAZEARENA_MAX_QUEUED_PER_OWNER", default_value_t = 50,
          value_parser = clap::value_parser!(i64).range(1..))]
    max_queued_per_owner: i64,
    /// Bots and entrants that may be registered without any key per hour from one client
    /// address, on a server whose registration is open (0: no limit); more are refused
    /// with 429 and Retry-After. A registration with an entrant's key, an organiser's
    /// or the invite code spends nothing of it.
    #[arg(long, env = "MAZEARENA_REGISTRATIONS_PER_HOUR", default_value_t = 20)]
    registrations_per_hour: u32,
    /// Wrong tries per hour from one client address: keys that are not known at
    /// `/login` and wrong invite codes (0: no limit); more are refused with 429. A right
    /// key or code is never refused and spends nothing.
    #[arg(long, env = "MAZEARENA_LOGINS_PER_HOUR", default_value_t = 60)]
    logins_per_hour: u32,
    /// Entrants that may register with the right invite code per hour, everyone
    /// together (0: no limit): a code that leaks cannot fill the database.
    #[arg(
        long,
        env = "MAZEARENA_INVITE_REGISTRATIONS_PER_HOUR",
        default_value_t = 600
    )]
    invite_registrations_per_hour: u32,
    /// Versions of bots entered in no competition that one owner (an entrant, or the
    /// owner token of a bot of no entrant) may upload in any 24 hours, a new bot
    /// included; failed builds and invalid versions do not count (0: no limit). A
    /// competition's bots have its quota instead.
    #[arg(long, env = "MAZEARENA_VERSIONS_PER_DAY", default_value_t = 20)]
    versions_per_day: u32,
    /// Versions of one owner that may wait for their build (and validation match) at
    /// once; another upload is refused with 429 naming them (0: no limit).
    #[arg(long, env = "MAZEARENA_PENDING_BUILDS_PER_OWNER", default_value_t = 3)]
    pending_builds_per_owner: u32,
    /// Minutes of building and validation matches one owner's versions may take in any
    /// 24 hours, failed and invalid ones included; past them uploads are refused with
    /// 429 until the oldest leaves the window (0: no limit).
    #[arg(long, env = "MAZEARENA_BUILD_MINUTES_PER_DAY", default_value_t = 60)]
    build_minutes_per_day: u32,
    /// Reverse proxies whose forwarding header gives the client's address (addresses
    /// or networks, separated by commas: `127.0.0.1,10.0.0.0/8`). From anyone else the
    /// header is ignored. Behind a proxy, list it, or every client has its address.
    #[arg(long, env = "MAZEARENA_TRUSTED_PROXIES", default_value = "")]
    trusted_proxies: String,
    /// The header the trusted proxies write the client's address in.
    #[arg(long, env = "MAZEARENA_PROXY_HEADER", value_enum, default_value_t = api::client_address::ProxyHeader::XForwardedFor)]
    proxy_header: api::client_address::ProxyHeader,
    /// The server is reached over HTTPS (directly or through a proxy): session cookies
    /// are marked `Secure`. (A proxy's `X-Forwarded-Proto: https` also does it.)
    #[arg(long, env = "MAZEARENA_SECURE_COOKIES")]
    secure_cookies: bool,
    /// The most MiB of stored match records (compressed traces) one owner may have;
    /// past it, its new matches are refused until old ones are pruned (0: no cap).
    #[arg(
        long,
        env = "MAZEARENA_MAX_STORED_MIB_PER_OWNER",
        default_value_t = 256.0
    )]
    max_stored_mib_per_owner: f64,
    /// Remove the stored traces (steps, stderr, debug drawings) of practice matches
    /// (not in a tournament) once they ended this many days ago, checked every hour;
    /// their results and every standing stay (0: keep them all).
    #[arg(long, env = "MAZEARENA_PRUNE_PRACTICE_AFTER_DAYS", default_value_t = 0)]
    prune_practice_after_days: u32,
    /// The most connections open at once; a client over it is closed at once.
    #[arg(long, env = "MAZEARENA_MAX_CONNECTIONS", default_value_t = 4096,
          value_parser = clap::value_parser!(u32).range(1..))]
    max_connections: u32,
    /// The most connections open at once from one client address.
    #[arg(long, env = "MAZEARENA_MAX_CONNECTIONS_PER_ADDRESS", default_value_t = 256,
          value_parser = clap::value_parser!(u32).range(1..))]
    max_connections_per_address: u32,
    /// Seconds a client may take to send a request's head (on a new connection, or on a
    /// kept-alive one between requests); then the connection is closed.
    #[arg(long, env = "MAZEARENA_HEAD_TIMEOUT_SECS", default_value_t = 10,
          value_parser = clap::value_parser!(u64).range(1..=3600))]
    head_timeout_secs: u64,
    #[command(flatten)]
    pool: PoolArgs,
    #[command(flatten)]
    sandbox: super::sandbox::SandboxArgs,
}

/// Runs the server until SIGINT or SIGTERM.
///
/// # Errors
/// When the database, the data directory or the address cannot be used.
pub fn run(args: ServeArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(serve(args))
}

/// What `/healthz` says of the sandbox and the limits on an API-only server (`--jobs 0`):
/// it plays no match; each worker in `workers` reports its own.
const API_ONLY: &str = "unused";

async fn serve(mut args: ServeArgs) -> anyhow::Result<()> {
    if args.demo {
        std::fs::create_dir_all(&args.demo_dir).with_context(|| {
            format!("cannot create the demo folder {}", args.demo_dir.display())
        })?;
        args.database = format!("sqlite://{}", args.demo_dir.join("mazearena.db").display());
        args.data_dir = args.demo_dir.join("data");
    }
    let trusted =
        api::client_address::TrustedProxies::parse(&args.trusted_proxies, args.proxy_header)
            .map_err(|e| anyhow::anyhow!("--trusted-proxies: {e}"))?;
    std::fs::create_dir_all(&args.data_dir).with_context(|| {
        format!(
            "cannot create the data directory {}",
            args.data_dir.display()
        )
    })?;
    let data_dir = args
        .data_dir
        .canonicalize()
        .with_context(|| format!("cannot resolve {}", args.data_dir.display()))?;
    let jobs = args.pool.jobs(0);
    let hide = hidden_paths(&data_dir, &args.database);
    // An API server (`--jobs 0`) runs no bot and builds nothing, so it needs no sandbox
    // (in a container it runs without the options the sandbox needs); it still lists the
    // runtimes it was given, as its workers offer them.
    let sandbox = if jobs == 0 {
        None
    } else {
        Some(
            args.sandbox
                .open(&hide, false)
                .context("refusing to serve without the sandbox")?,
        )
    };
    let storage = args
        .pool
        .storage(super::open_database(&args.database).await?);
    // PostgreSQL may restart while the server starts: the start-up work (all of it safe
    // to do twice) is tried again for as long as the connection itself would be.
    match storage.backend() {
        Backend::Postgres => with_patience(|| prepare(&storage, &data_dir)).await?,
        Backend::Sqlite => prepare(&storage, &data_dir).await?,
    }

    let demo = if args.demo {
        let shipped: Vec<i64> = storage
            .list_mazes()
            .await?
            .into_iter()
            .filter(|m| !m.hidden && DEFAULT_MAZES.iter().any(|(name, _)| *name == m.name))
            .map(|m| m.maze_id)
            .collect();
        let with_node = crate::runner::sandbox::find_program("node").is_some();
        registry::demo::seed(
            &storage,
            &data_dir,
            &shipped,
            with_node,
            crate::storage::now_ms(),
        )
        .await
        .map_err(|e| anyhow::anyhow!("cannot set up the demo: {e}"))?
    } else {
        None
    };
    let admin_token = admin_token(args.admin_token.as_deref(), &data_dir)?;
    if let Some(t) = &args.metrics_token {
        anyhow::ensure!(
            t.chars().count() >= MIN_ADMIN_TOKEN_CHARS,
            "the metrics token is too short ({} characters): use at least {MIN_ADMIN_TOKEN_CHARS}, \
             e.g. MAZEARENA_METRICS_TOKEN=$(openssl rand -hex 32)",
            t.chars().count()
        );
    }
    let offered = match &sandbox {
        Some(crate::runner::Sandbox::Full(f)) => f.runtimes.clone(),
        Some(crate::runner::Sandbox::None) => Vec::new(),
        None => crate::runner::sandbox::listed_runtimes(&args.sandbox.runtimes(), &hide)
            .map_err(|e| anyhow::anyhow!("{e}"))?,
    };
    let runtimes = Arc::new(crate::runner::runtimes::probe(&offered).await);
    let metrics = Metrics::new();
    let wake = Arc::new(Notify::new());
    let clock_wake = wake.clone();
    let state = AppState {
        storage: storage.clone(),
        settings: Arc::new(Settings {
            admin_token_hash: auth::hash_token(&admin_token),
            metrics_token_hash: args.metrics_token.as_deref().map(auth::hash_token),
            data_dir,
            max_queue: args.max_queue,
            sandbox_level: sandbox.as_ref().map_or(API_ONLY, |s| s.level()),
            limits: sandbox.as_ref().map_or(API_ONLY, |s| s.limits()),
            max_queued_per_owner: args.max_queued_per_owner,
            max_stored_bytes_per_owner: (args.max_stored_mib_per_owner > 0.0)
                .then_some((args.max_stored_mib_per_owner * 1_048_576.0) as i64),
            budgets: api::limits::Budgets {
                guesses_per_hour: args.logins_per_hour,
                anonymous_registrations_per_hour: args.registrations_per_hour,
                invite_registrations_per_hour: args.invite_registrations_per_hour,
            },
            owner_quotas: crate::registry::owners::OwnerQuotas {
                versions_per_day: args.versions_per_day,
                pending_builds: args.pending_builds_per_owner,
                build_minutes_per_day: args.build_minutes_per_day,
            },
            secure_cookies: args.secure_cookies,
        }),
        metrics: metrics.clone(),
        wake: wake.clone(),
        ranker: Default::default(),
        shows: Default::default(),
        runtimes,
    };

    let listener = TcpListener::bind(&args.bind)
        .await
        .with_context(|| format!("cannot listen on {}", args.bind))?;
    let addr = listener.local_addr()?;
    if sandbox.is_none() {
        println!(
            "mazearena listening on http://{addr} (API only: no match workers, so no sandbox here; the workers report their own)"
        );
    } else {
        println!(
            "mazearena listening on http://{addr} ({}, sandbox {}, match limits by {}{})",
            super::count(jobs as i64, "match worker", "match workers"),
            state.settings.sandbox_level,
            state.settings.limits,
            if state.settings.limits == "watchdog" {
                ": no cgroup could be made here, so no CPU limit"
            } else {
                ""
            }
        );
    }
    if args.demo {
        match &demo {
            Some(d) => println!(
                "the demo, in {}: open http://{addr}/ ({} bots of the starter kits play the {} shipped mazes, tournament {}; \
                 competition {} is open: register at http://{addr}/register to take part)",
                args.demo_dir.display(),
                d.bots.len(),
                DEFAULT_MAZES.len(),
                d.tournament_id,
                d.competition,
            ),
            None => println!(
                "the demo, in {}: open http://{addr}/ (as it was left; remove the folder to start it afresh)",
                args.demo_dir.display()
            ),
        }
    }
    use std::io::Write;
    let _ = std::io::stdout().flush();

    let shutdown = Shutdown::default();
    let tracker = TaskTracker::new();
    let pool = if let Some(sandbox) = sandbox {
        Some(worker::spawn_workers(
            &tracker,
            storage.clone(),
            args.pool
                .config(jobs, sandbox, "serve", &state.settings.data_dir)?,
            Some(metrics),
            wake,
            shutdown.clone(),
            None,
        ))
    } else {
        None
    };
    tracker.close();

    {
        // Every hour: the budgets whose tries have all come back are removed, and the
        // traces of old practice matches when the server prunes them.
        let storage = storage.clone();
        let days = i64::from(args.prune_practice_after_days);
        tokio::spawn(async move {
            let mut hourly = tokio::time::interval(Duration::from_secs(3600));
            loop {
                hourly.tick().await;
                let now = crate::storage::now_ms();
                if let Err(e) = storage.prune_budgets(now).await {
                    tracing::warn!(error = %e, "cannot remove spent budgets");
                }
                if days == 0 {
                    continue;
                }
                let before = now - days * super::prune::DAY_MS;
                match storage.prune_practice_records(before).await {
                    Ok((0, _)) => {}
                    Ok((count, bytes)) => {
                        tracing::info!(count, bytes, "removed the traces of old practice matches")
                    }
                    Err(e) => tracing::warn!(error = %e, "cannot prune old practice matches"),
                }
            }
        });
    }
    {
        // The competitions' clock: ranks new versions, and closes competitions on time.
        // It runs every COMPETITION_TICK, and at once when an upload or a build wakes the
        // workers; it wakes them when it queued matches.
        let storage = storage.clone();
        tokio::spawn(async move {
            let mut wait = Duration::ZERO;
            loop {
                let woken = clock_wake.notified();
                tokio::select! {
                    _ = tokio::time::sleep(wait) => {}
                    _ = woken => tokio::time::sleep(Duration::from_millis(10)).await,
                }
                wait = COMPETITION_TICK;
                let now = crate::storage::now_ms();
                match crate::registry::competitions::tick(&storage, now).await {
                    Ok(r) => {
                        if r.closing > 0 {
                            // A close is under way: its last matches and final run are
                            // looked at often, so that the results follow them closely.
                            wait = CLOSING_TICK;
                        }
                        if r.ranked > 0 || r.selected > 0 {
                            clock_wake.notify_waiters();
                        }
                        if r.ranked > 0 || r.selected > 0 || r.finalized > 0 {
                            tracing::info!(
                                ranked = r.ranked,
                                selected = r.selected,
                                finalized = r.finalized,
                                "competitions moved on"
                            )
                        }
                    }
                    Err(e) => {
                        tracing::warn!(error = %e, "the competitions' clock failed; trying again")
                    }
                }
            }
        });
    }
    let stop = shutdown.stop_claiming.clone();
    tokio::spawn(async move {
        wait_for_signal().await;
        tracing::info!("shutting down: no new matches are started");
        stop.cancel();
    });
    let http_stop = shutdown.stop_claiming.clone();
    let limits = api::connections::ConnectionLimits {
        max_connections: args.max_connections as usize,
        max_per_address: args.max_connections_per_address as usize,
        head_timeout: Duration::from_secs(args.head_timeout_secs),
    }
    .fitted_to_descriptors();
    api::serve(listener, state, limits, trusted, async move {
        http_stop.cancelled().await
    })
    .await
    .context("the HTTP server failed")?;

    finish(
        &storage,
        &tracker,
        &shutdown,
        pool.as_ref(),
        args.pool.grace(),
    )
    .await;
    eprintln!("mazearena stopped");
    Ok(())
}

/// The paths a bot must never see: the data directory, and the database file if it is
/// SQLite.
pub(super) fn hidden_paths(data_dir: &std::path::Path, database: &str) -> Vec<PathBuf> {
    let mut hide = vec![data_dir.to_path_buf()];
    if let Some(file) = database.strip_prefix("sqlite://") {
        let file = file.split('?').next().unwrap_or(file);
        hide.push(std::path::absolute(file).unwrap_or_else(|_| file.into()));
    }
    hide
}

/// After a stop signal: gives the running matches `grace` to end, then stops and
/// re-queues the rest, reports the pool stopped and closes the database.
pub(super) async fn finish(
    storage: &Storage,
    tracker: &TaskTracker,
    shutdown: &Shutdown,
    pool: Option<&worker::PoolHandle>,
    grace: Duration,
) {
    if tokio::time::timeout(grace, tracker.wait()).await.is_err() {
        tracing::warn!("running matches did not finish in time: stopping them and re-queueing");
        shutdown.abort.cancel();
        tracker.wait().await;
    }
    if let Some(pool) = pool {
        worker::report_stopped(storage, pool).await;
    }
    storage.close().await;
}

/// Stores the shipped mazes as public mazes when the database has none (servers that
/// start together on one database may both try: a maze already stored is skipped).
/// The server's start-up work on the database: re-queue what an earlier server left
/// running, load the default mazes into an empty database, move an earlier release's
/// data folder in.
/// The shortest admin token accepted.
pub const MIN_ADMIN_TOKEN_CHARS: usize = 16;

/// The admin token: the one given (at least [`MIN_ADMIN_TOKEN_CHARS`] characters), or
/// the one kept in the data folder (`admin-token`, readable by its owner only), made and
/// printed on the first start.
fn admin_token(given: Option<&str>, data_dir: &std::path::Path) -> anyhow::Result<String> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    if let Some(t) = given.map(str::trim).filter(|t| !t.is_empty()) {
        anyhow::ensure!(
            t.chars().count() >= MIN_ADMIN_TOKEN_CHARS,
            "the admin token is too short ({} characters): use at least {MIN_ADMIN_TOKEN_CHARS}, \
             e.g. MAZEARENA_ADMIN_TOKEN=$(openssl rand -hex 32)",
            t.chars().count()
        );
        return Ok(t.to_string());
    }
    let file = data_dir.join("admin-token");
    if let Ok(kept) = std::fs::read_to_string(&file) {
        let kept = kept.trim().to_string();
        if kept.chars().count() >= MIN_ADMIN_TOKEN_CHARS {
            eprintln!("admin token: the one kept in {}", file.display());
            return Ok(kept);
        }
    }
    let t = auth::new_token().map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut out = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(&file)
        .with_context(|| format!("cannot write {}", file.display()))?;
    writeln!(out, "{t}").with_context(|| format!("cannot write {}", file.display()))?;
    eprintln!(
        "admin token (generated, kept in {} for the next start; set MAZEARENA_ADMIN_TOKEN to choose one): {t}",
        file.display()
    );
    Ok(t)
}

async fn prepare(storage: &Storage, data_dir: &std::path::Path) -> anyhow::Result<()> {
    let requeued = storage.requeue_expired().await?;
    if requeued > 0 {
        tracing::warn!(
            count = requeued,
            "re-queued matches left running by an earlier server"
        );
    }
    load_default_mazes(storage).await?;
    registry::migrate::migrate_data_folder(storage, data_dir).await?;
    Ok(())
}

async fn load_default_mazes(storage: &Storage) -> anyhow::Result<()> {
    if storage.count_mazes().await? > 0 {
        return Ok(());
    }
    for (name, text) in DEFAULT_MAZES {
        match registry::mazes::admit(storage, name, text.as_bytes(), false).await {
            // Another server sharing the database stored it first.
            Ok(_) | Err(RegistryError::Conflict(_)) => {}
            Err(e) => anyhow::bail!("cannot load the default maze {name}: {e}"),
        }
    }
    Ok(())
}

/// Resolves on SIGINT or SIGTERM.
pub(super) async fn wait_for_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {}
        _ = term => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_maze_is_embedded() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("mazes");
        let mut on_disk: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".txt"))
            .map(|n| n.trim_end_matches(".txt").to_string())
            .collect();
        on_disk.sort();
        let embedded: Vec<String> = DEFAULT_MAZES.iter().map(|(n, _)| n.to_string()).collect();
        assert_eq!(on_disk, embedded);
    }
}
