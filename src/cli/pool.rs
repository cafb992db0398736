//! The match workers' settings (`--jobs`, the sandbox, the limits, the caches), shared by
//! `mazearena serve` and `mazearena worker`.

use std::time::Duration;

use anyhow::Context;
use clap::Args;

use crate::registry::cache::{BundleCache, DEFAULT_CACHE_BYTES};
use crate::runner::Limits;
use crate::storage::Storage;
use crate::work::worker::{self, WorkerConfig};

/// The match workers' settings, shared by `serve` and `worker`.
#[derive(Debug, Args)]
pub(super) struct PoolArgs {
    /// Do not play a new version's validation match: every version that builds is
    /// `ready`, even one that crashes at its first step (for testing the server with
    /// misbehaving bots; an open server should validate).
    #[arg(long, env = "MAZEARENA_NO_VALIDATION")]
    no_validation: bool,
    /// Matches played at once, at most one per core (default: the number of cores).
    /// `serve --jobs 0` plays none: it serves the API only, leaving the matches to
    /// `mazearena worker` processes.
    #[arg(long, env = "MAZEARENA_JOBS")]
    jobs: Option<usize>,
    /// Lease on a running match, in seconds: a match whose worker died is re-queued
    /// this long after its last renewal.
    #[arg(long, env = "MAZEARENA_LEASE_SECS", default_value_t = worker::DEFAULT_LEASE.as_secs())]
    lease_secs: u64,
    /// On SIGINT/SIGTERM, how long running matches may take to finish before they are
    /// stopped and re-queued, in seconds.
    #[arg(long, env = "MAZEARENA_SHUTDOWN_GRACE_SECS", default_value_t = 10)]
    shutdown_grace_secs: u64,
    /// How many times a match whose worker died while it ran is put back in the queue;
    /// the next time it is recorded as `aborted` (a bot that brings its worker down is
    /// not re-run forever). Raise it where workers are often stopped without a graceful
    /// shutdown.
    #[arg(long, env = "MAZEARENA_MAX_RETRIES", default_value_t = crate::storage::retries::MAX_MATCH_RETRIES)]
    max_retries: i64,
    /// Size of the local cache of bots' files (unpacked from the database into
    /// `DATA_DIR/cache`), in MiB; the least recently used bots beyond it are removed.
    #[arg(long, env = "MAZEARENA_CACHE_MIB", default_value_t = DEFAULT_CACHE_BYTES >> 20)]
    cache_mib: u64,
    /// The most a bot's build may write, in MiB: its folder (a tmpfs of this size when
    /// the server runs as root) and, apart, its /tmp; over it the build fails.
    #[arg(long, env = "MAZEARENA_BUILD_WRITE_MIB", default_value_t = crate::runner::build::DEFAULT_BUILD_WRITE_BYTES >> 20,
          value_parser = clap::value_parser!(u64).range(1..=65536))]
    build_write_mib: u64,
}

impl PoolArgs {
    /// `storage` with this pool's retry budget.
    pub(super) fn storage(&self, storage: Storage) -> Storage {
        storage.with_max_retries(self.max_retries)
    }

    /// The workers to run on this machine: `--jobs` (default: the number of cores), at
    /// least `least`, at most one per core (said on stderr when lowered).
    pub(super) fn jobs(&self, least: usize) -> usize {
        let cores = crate::runner::affinity::cores();
        if self.jobs.is_some_and(|j| j > cores) {
            eprintln!(
                "--jobs {} lowered to {cores}: one bot process per core keeps timing fair",
                self.jobs.unwrap_or(0)
            );
        }
        self.jobs.unwrap_or(cores).clamp(least, cores)
    }

    /// The configuration of `jobs` workers that play every queued match in `sandbox`
    /// and build the versions waiting for their build, reported in the worker table as
    /// `role`, with their cache and build folders in `data_dir`.
    ///
    /// # Errors
    /// When the cache cannot be created.
    pub(super) fn config(
        &self,
        jobs: usize,
        sandbox: crate::runner::Sandbox,
        role: &'static str,
        data_dir: &std::path::Path,
    ) -> anyhow::Result<WorkerConfig> {
        let cache = BundleCache::new(&data_dir.join("cache"), self.cache_mib << 20)?;
        let builds = data_dir.join("builds");
        std::fs::create_dir_all(&builds)
            .with_context(|| format!("cannot create {}", builds.display()))?;
        Ok(WorkerConfig {
            jobs,
            lease: Duration::from_secs(self.lease_secs.max(1)),
            limits: Limits::default(),
            sandbox,
            only_tournament: None,
            exit_when_idle: false,
            report_as: Some(role),
            cache,
            builds: Some(builds),
            build_write_bytes: self.build_write_mib << 20,
            validate: !self.no_validation,
        })
    }

    /// The grace period of a graceful stop.
    pub(super) fn grace(&self) -> Duration {
        Duration::from_secs(self.shutdown_grace_secs)
    }
}
