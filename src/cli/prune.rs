//! `mazearena prune`: removes the stored traces of old practice matches.

use anyhow::Context;
use clap::Args;

/// Arguments of `mazearena prune`.
#[derive(Debug, Args)]
pub struct PruneArgs {
    /// The database.
    #[arg(
        long,
        env = "MAZEARENA_DATABASE",
        default_value = "sqlite://mazearena.db"
    )]
    database: String,
    /// Remove the traces of practice matches that ended more than this many days ago.
    #[arg(long, value_name = "DAYS")]
    older_than_days: u32,
}

/// Milliseconds in a day.
pub const DAY_MS: i64 = 24 * 60 * 60 * 1000;

/// Removes the per-step traces, stderr and debug drawings of practice matches (single
/// matches, not in a tournament) that ended more than `--older-than-days` ago. Their
/// status, score, steps and summary stay, and every standing is unchanged.
///
/// # Errors
/// The database cannot be opened or written.
pub fn run(args: PruneArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(async {
        let storage = super::open_existing(&args.database).await?;
        let before = crate::storage::now_ms() - i64::from(args.older_than_days) * DAY_MS;
        let (count, bytes) = storage.prune_practice_records(before).await?;
        println!(
            "removed the traces of {count} practice match{} ({} KiB stored); their results stay",
            if count == 1 { "" } else { "es" },
            bytes / 1024
        );
        Ok(())
    })
}
