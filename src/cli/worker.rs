//! `mazearena worker`: a process that only plays matches. It claims queued matches from
//! the database the servers use, plays them in the sandbox, writes their records, and
//! reports itself in the worker table; any number of them, on any machines, share one
//! PostgreSQL database (or, on the server's own machine, its SQLite file).

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Context;
use clap::Args;
use tokio::sync::Notify;
use tokio_util::task::TaskTracker;

use super::pool::PoolArgs;
use super::serve::{finish, hidden_paths, wait_for_signal};
use crate::work::worker::{self, Shutdown};

/// Settings of `mazearena worker`; every flag can also come from its `MAZEARENA_*` variable.
#[derive(Debug, Args)]
pub struct WorkerArgs {
    /// The servers' database: `postgres://USER:PASSWORD@HOST/DB`, or `sqlite://FILE` on
    /// the server's own machine.
    #[arg(long, env = "MAZEARENA_DATABASE")]
    database: String,
    /// A local folder for the cache of bots' files and for builds (the files themselves
    /// come from the database: no shared disk is needed).
    #[arg(long, env = "MAZEARENA_DATA_DIR", default_value = "mazearena-data")]
    data_dir: PathBuf,
    #[command(flatten)]
    pool: PoolArgs,
    #[command(flatten)]
    sandbox: super::sandbox::SandboxArgs,
}

/// Plays matches until SIGINT or SIGTERM.
///
/// # Errors
/// When the database or the data directory cannot be used, or the sandbox cannot be had.
pub fn run(args: WorkerArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(work(args))
}

async fn work(args: WorkerArgs) -> anyhow::Result<()> {
    let data_dir = std::path::absolute(&args.data_dir)
        .with_context(|| format!("cannot resolve {}", args.data_dir.display()))?;
    let sandbox = args
        .sandbox
        .open(&hidden_paths(&data_dir, &args.database), false)
        .context("refusing to play matches without the sandbox")?;
    let storage = args
        .pool
        .storage(super::open_database(&args.database).await?);
    let jobs = args.pool.jobs(1);
    let level = sandbox.level();
    let shutdown = Shutdown::default();
    let tracker = TaskTracker::new();
    let pool = worker::spawn_workers(
        &tracker,
        storage.clone(),
        args.pool.config(jobs, sandbox, "worker", &data_dir)?,
        None,
        Arc::new(Notify::new()),
        shutdown.clone(),
        None,
    );
    tracker.close();
    eprintln!("mazearena worker playing matches ({jobs} at once, sandbox {level})");
    wait_for_signal().await;
    tracing::info!("shutting down: no new matches are started");
    shutdown.stop_claiming.cancel();
    finish(
        &storage,
        &tracker,
        &shutdown,
        Some(&pool),
        args.pool.grace(),
    )
    .await;
    eprintln!("mazearena worker stopped");
    Ok(())
}
