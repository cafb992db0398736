//! Match workers: a pool of threads, each pinned to a core of its own (claimed from
//! the other mazearena processes on the machine: see [`runner::affinity`]), that claim
//! queued matches from the database with a lease, play
//! them with the runner, and write each record in one transaction.
//!
//! Used by the server and by `mazearena tournament`. A worker keeps its lease alive while
//! a match runs; a match whose worker died goes back to the queue when its lease expires
//! (the reaper), so nothing accepted is ever lost, and the lease check on writing makes
//! sure nothing is recorded twice. A match whose lease keeps expiring is retried at most
//! [`crate::storage::retries::MAX_MATCH_RETRIES`] times, then recorded as `aborted`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicI64, Ordering};
use std::time::{Duration, Instant};

use tokio::sync::Notify;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use crate::engine::mazefile;
use crate::metrics::Metrics;
use crate::registry::cache::{BundleCache, CachedBundle};
use crate::runner::{self, BotSpec, Limits, MatchStatus};
use crate::storage::Storage;
use crate::storage::matches::queue::ClaimedMatch;
use crate::storage::workers::NewWorker;

/// Default lease on a running match; renewed every third of it.
pub const DEFAULT_LEASE: Duration = Duration::from_secs(30);

/// How often an idle worker looks at the queue even without being woken.
pub const IDLE_POLL: Duration = Duration::from_millis(500);

/// How the workers run.
#[derive(Debug, Clone)]
pub struct WorkerConfig {
    /// Number of workers (at most one bot process per core).
    pub jobs: usize,
    /// Lease length on a running match.
    pub lease: Duration,
    /// Limits for every match.
    pub limits: Limits,
    /// How every bot is isolated.
    pub sandbox: runner::Sandbox,
    /// Only claim this tournament's matches.
    pub only_tournament: Option<i64>,
    /// Stop when the queue is empty instead of waiting for more.
    pub exit_when_idle: bool,
    /// Report the workers in the database's worker table under this role (`serve` or
    /// `worker`), so that every server shows them; `None`: not reported (a local
    /// tournament).
    pub report_as: Option<&'static str>,
    /// Where the bots' stored files are unpacked for their matches.
    pub cache: BundleCache,
    /// Build the versions waiting for their build, in this local folder; `None`: this
    /// pool builds nothing (a local tournament, whose bots are built by the caller).
    pub builds: Option<PathBuf>,
    /// The bound of each build's writable area, in bytes.
    pub build_write_bytes: u64,
    /// Play each new version's validation match after its build ([`crate::work::builder`]).
    pub validate: bool,
}

/// How often a reported worker refreshes its row (and looks for expired leases).
pub fn report_interval(lease: Duration) -> Duration {
    (lease / 2).clamp(Duration::from_millis(200), Duration::from_secs(5))
}

/// Signals that stop the workers.
#[derive(Debug, Clone, Default)]
pub struct Shutdown {
    /// Stop claiming new matches; running ones go on.
    pub stop_claiming: CancellationToken,
    /// Abandon running matches now (their bots are killed and the matches re-queued).
    pub abort: CancellationToken,
}

/// A unique name for this process's leases.
pub fn lease_owner_name() -> String {
    let mut bytes = [0u8; 6];
    let _ = getrandom::fill(&mut bytes);
    let suffix: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    format!("{}-{}", std::process::id(), suffix)
}

/// Starts `config.jobs` workers and the lease reaper on `tracker`. `wake` is notified by
/// whoever queues matches.
pub fn spawn_workers(
    tracker: &TaskTracker,
    storage: Storage,
    config: WorkerConfig,
    metrics: Option<Metrics>,
    wake: Arc<Notify>,
    shutdown: Shutdown,
    on_done: Option<Arc<dyn Fn(MatchStatus) + Send + Sync>>,
) -> PoolHandle {
    let owner: Arc<str> = lease_owner_name().into();
    let done_count = Arc::new(AtomicI64::new(0));
    let mut cores = runner::affinity::claim_cores(config.jobs.max(1), &std::env::temp_dir())
        .into_iter()
        .map(Some)
        .collect::<Vec<_>>();
    for k in 0..config.jobs.max(1) {
        let worker = Worker {
            storage: storage.clone(),
            config: config.clone(),
            metrics: metrics.clone(),
            wake: wake.clone(),
            shutdown: shutdown.clone(),
            owner: owner.clone(),
            on_done: on_done.clone(),
            done_count: done_count.clone(),
        };
        // The worker's thread holds its core's claim as long as it runs.
        let claim = cores.get_mut(k).and_then(Option::take);
        let (done, finished) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name(format!("match-worker-{k}"))
            .spawn(move || {
                worker.run_on_core(claim.as_ref().map(|c| c.core));
                drop(claim);
                let _ = done.send(());
            });
        match thread {
            // The tracker waits for the worker's thread to end its last match.
            Ok(_) => {
                tracker.spawn(async move {
                    let _ = finished.await;
                });
            }
            Err(e) => tracing::error!(cause = %e, "could not start a match worker's thread"),
        }
    }
    let handle = PoolHandle {
        owner: owner.clone(),
        done_count: done_count.clone(),
        reported: config.report_as.is_some(),
    };
    let reporter = Reporter {
        storage,
        owner: owner.clone(),
        done_count,
        role: config.report_as,
        jobs: config.jobs.max(1),
        sandbox: config.sandbox.level(),
    };
    if let Some(scratch) = &config.builds {
        let builder = crate::work::builder::Builder {
            storage: reporter.storage.clone(),
            sandbox: config.sandbox.clone(),
            scratch: scratch.clone(),
            write_limit: config.build_write_bytes,
            owner: owner.clone(),
            lease: config.lease,
            validate: config.validate,
        };
        tracker.spawn(builder.run(wake.clone(), shutdown.stop_claiming.clone()));
    }
    let lease = config.lease;
    let stop = shutdown.stop_claiming.clone();
    tracker.spawn(async move {
        reporter.register().await;
        let mut tick = tokio::time::interval(report_interval(lease));
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => {}
            }
            reporter.seen().await;
            if reap(&reporter.storage).await {
                wake.notify_waiters();
            }
        }
    });
    handle
}

/// What a started pool leaves its caller: its name in the worker table and its count.
#[derive(Debug, Clone)]
pub struct PoolHandle {
    owner: Arc<str>,
    done_count: Arc<AtomicI64>,
    reported: bool,
}

/// Re-queues (or aborts) the matches whose lease expired; whether there were any.
async fn reap(storage: &Storage) -> bool {
    match storage.reap_expired().await {
        Ok(r) if r.requeued.is_empty() && r.aborted.is_empty() => false,
        Ok(r) => {
            if !r.requeued.is_empty() {
                tracing::warn!(matches = ?r.requeued, "re-queued matches whose worker stopped");
            }
            if !r.aborted.is_empty() {
                tracing::warn!(matches = ?r.aborted, "aborted matches that were running each time their worker stopped");
            }
            if !r.paused_bots.is_empty() {
                tracing::warn!(bots = ?r.paused_bots, "paused bots whose matches keep aborting");
            }
            true
        }
        Err(e) => {
            tracing::error!(cause = %e, "could not re-queue expired leases");
            false
        }
    }
}

/// The pool's row in the worker table (when it reports itself).
struct Reporter {
    storage: Storage,
    owner: Arc<str>,
    done_count: Arc<AtomicI64>,
    role: Option<&'static str>,
    jobs: usize,
    sandbox: &'static str,
}

impl Reporter {
    async fn register(&self) {
        let Some(role) = self.role else { return };
        let host = nix::unistd::gethostname()
            .map(|h| h.to_string_lossy().into_owned())
            .unwrap_or_else(|_| "unknown".into());
        let row = NewWorker {
            worker_id: &self.owner,
            role,
            host: &host,
            pid: i64::from(std::process::id()),
            jobs: self.jobs as i64,
            sandbox: self.sandbox,
        };
        if let Err(e) = self.storage.register_worker(&row).await {
            tracing::error!(cause = %e, "could not report this worker in the database");
        }
    }

    /// Reports that the pool is alive; registers it again when its row is missing (its
    /// first registration failed, e.g. while the database restarted), so a worker that
    /// started during an outage still shows up once the database is back.
    async fn seen(&self) {
        if self.role.is_none() {
            return;
        }
        match self
            .storage
            .worker_seen(&self.owner, self.done_count.load(Ordering::Relaxed))
            .await
        {
            Ok(true) => {}
            Ok(false) => self.register().await,
            Err(e) => {
                tracing::error!(cause = %e, "could not report this worker in the database");
            }
        }
    }
}

/// Records in the worker table that `pool` stopped (after its tasks ended).
pub async fn report_stopped(storage: &Storage, pool: &PoolHandle) {
    if pool.reported
        && let Err(e) = storage
            .worker_stopped(&pool.owner, pool.done_count.load(Ordering::Relaxed))
            .await
    {
        tracing::error!(cause = %e, "could not report this worker's stop in the database");
    }
}

struct Worker {
    storage: Storage,
    config: WorkerConfig,
    metrics: Option<Metrics>,
    wake: Arc<Notify>,
    shutdown: Shutdown,
    owner: Arc<str>,
    on_done: Option<Arc<dyn Fn(MatchStatus) + Send + Sync>>,
    done_count: Arc<AtomicI64>,
}

impl Worker {
    /// Runs the worker on the calling thread, pinned to `core`, in a runtime of its own:
    /// the referee's side of each match and the bot's processes share that core.
    fn run_on_core(self, core: Option<usize>) {
        if let Some(core) = core
            && let Err(e) = runner::affinity::pin_current_thread(core)
        {
            tracing::warn!(core, cause = %e, "could not pin a match worker to its core");
        }
        match tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
        {
            Ok(runtime) => runtime.block_on(self.run()),
            Err(e) => tracing::error!(cause = %e, "could not start a match worker's runtime"),
        }
    }

    async fn run(mut self) {
        // The worker's database work on its own core too.
        self.storage = self.storage.for_this_thread();
        let lease_ms = self.config.lease.as_millis() as i64;
        while !self.shutdown.stop_claiming.is_cancelled() {
            // Register for a wake-up before looking, so a notification is not missed.
            let woken = self.wake.notified();
            match self
                .storage
                .claim_next(&self.owner, lease_ms, self.config.only_tournament)
                .await
            {
                Ok(Some(job)) => self.play(job).await,
                Ok(None) if self.config.exit_when_idle => break,
                Ok(None) => {
                    tokio::select! {
                        _ = woken => {}
                        _ = tokio::time::sleep(IDLE_POLL) => {}
                        _ = self.shutdown.stop_claiming.cancelled() => {}
                    }
                }
                Err(e) => {
                    tracing::error!(cause = %e, "could not claim a match");
                    tokio::time::sleep(Duration::from_secs(1)).await;
                }
            }
        }
    }

    /// Writes a played match's record; whether it was written. A database that does not
    /// answer (restarting, unreachable) is tried again for about half a minute, so that
    /// a played match is not lost to a short outage; if the lease expires meanwhile,
    /// another worker has the match and this record is dropped (never written twice).
    async fn write_record(
        &self,
        match_id: i64,
        record: &runner::MatchRecord,
        maze: &crate::engine::Maze,
    ) -> bool {
        const TRIES: u32 = 10;
        for attempt in 1..=TRIES {
            match self
                .storage
                .complete_match(match_id, &self.owner, record, maze)
                .await
            {
                Ok(true) => return true,
                Ok(false) => {
                    tracing::warn!(
                        "lease lost before the record was written; another worker has the match"
                    );
                    return false;
                }
                Err(e) if attempt < TRIES => {
                    tracing::warn!(cause = %e, attempt, "could not write the match record; trying again");
                    tokio::time::sleep(Duration::from_millis(500) * attempt).await;
                }
                Err(e) => {
                    tracing::error!(cause = %e, "could not write the match record; it will be re-queued");
                }
            }
        }
        false
    }

    /// The bot's files from the cache: its built bundle, else its bundle; `None` for a
    /// bot that plays from a local folder.
    async fn files(&self, job: &ClaimedMatch) -> crate::registry::Result<Option<CachedBundle>> {
        match job.built_sha256.as_ref().or(job.bundle_sha256.as_ref()) {
            Some(sha) => Ok(Some(self.config.cache.get(&self.storage, sha).await?)),
            None => Ok(None),
        }
    }

    /// Records a claimed match as crashed for a reason of the server's (it is never
    /// retried); a failure to record it leaves it to its lease.
    async fn give_up(&self, match_id: i64, reason: &str) {
        if let Err(e) = self.storage.fail_match(match_id, &self.owner, reason).await {
            tracing::error!(cause = %e, "could not record the match as crashed; its lease will expire");
        }
    }

    #[tracing::instrument(skip_all, fields(match_id = job.match_id))]
    async fn play(&self, job: ClaimedMatch) {
        let maze = match mazefile::numeric::parse(job.layout.as_bytes()) {
            Ok(m) => m,
            Err(e) => {
                tracing::error!(cause = %e, "stored maze layout is invalid; match marked crashed");
                self.give_up(job.match_id, &format!("stored maze is invalid: {e}"))
                    .await;
                return;
            }
        };
        let files = match self.files(&job).await {
            Ok(files) => files,
            Err(e) if e.is_permanent() => {
                // A bundle missing or damaged in the database: trying again cannot help.
                tracing::error!(cause = %e, "the bot's stored files cannot be used; match marked crashed");
                let reason = format!("the server could not use the bot's stored files: {e}");
                self.give_up(job.match_id, &reason).await;
                return;
            }
            Err(e) => {
                // The database or this machine's disk: not the bot's doing. The match goes
                // back to the queue (not counted against its retries) for this or another
                // worker, after a pause.
                tracing::error!(cause = %e, "cannot get the bot's files; the match goes back to the queue");
                if let Err(e) = self.storage.release_match(job.match_id, &self.owner).await {
                    tracing::error!(cause = %e, "could not re-queue the match; its lease will expire");
                }
                tokio::time::sleep(Duration::from_secs(1)).await;
                return;
            }
        };
        let dir = files
            .as_ref()
            .map_or_else(|| PathBuf::from(&job.dir), |f| f.dir.clone());
        let mut bot = BotSpec::new(job.command.clone(), dir);
        bot.env = crate::storage::bots::env_pairs(&job.env);
        bot.runtime.clone_from(&job.runtime);
        bot.protocol = crate::runner::BotProtocol::of_stored(job.protocol.as_deref());
        // A competition's matches play under its own limits.
        let job_limits = job
            .limits
            .as_deref()
            .and_then(|l| serde_json::from_str::<crate::competition::Limits>(l).ok())
            .map_or(self.config.limits, |l| l.apply(self.config.limits));
        let started = Instant::now();
        let lease_ms = self.config.lease.as_millis() as i64;
        // The first renewal a third of a lease from now. (An interval's first tick is
        // due at once, but awaiting it waits for the timer's next millisecond: up to
        // 1 ms lost before every match.)
        let period = self.config.lease / 3;
        let mut renew = tokio::time::interval_at(tokio::time::Instant::now() + period, period);
        let game = runner::run_match(
            &bot,
            &maze,
            job.seed as u64,
            job_limits,
            &self.config.sandbox,
            |_| {},
        );
        tokio::pin!(game);
        loop {
            tokio::select! {
                record = &mut game => {
                    if self.write_record(job.match_id, &record, &maze).await {
                        self.done_count.fetch_add(1, Ordering::Relaxed);
                        if let Some(m) = &self.metrics {
                            m.observe_match(started.elapsed());
                        }
                        if let Some(f) = &self.on_done {
                            f(record.status);
                        }
                    }
                    return;
                }
                _ = renew.tick() => {
                    match self.storage.renew_lease(job.match_id, &self.owner, lease_ms).await {
                        Ok(true) => {}
                        Ok(false) => {
                            tracing::warn!("lease lost while playing; abandoning the match");
                            return;
                        }
                        Err(e) => tracing::error!(cause = %e, "could not renew the lease"),
                    }
                }
                _ = self.shutdown.abort.cancelled() => {
                    // Dropping the match future kills the bot's process group. A graceful
                    // release does not count against the match's retries.
                    if let Err(e) = self.storage.release_match(job.match_id, &self.owner).await {
                        tracing::error!(cause = %e, "could not re-queue an interrupted match; its lease will expire");
                    }
                    return;
                }
            }
        }
    }
}
