//! `mazearena migrate`: brings a database's schema up to date and says where it stands,
//! then exits. Servers and workers migrate on start too (one at a time: the migrations
//! take a lock), so this is for a rollout that migrates once before the new servers
//! start (the Kubernetes manifests' Job) and for checking a database by hand.

use anyhow::Context;
use clap::Args;

/// Settings of `mazearena migrate`.
#[derive(Debug, Args)]
pub struct MigrateArgs {
    /// The database: `postgres://USER:PASSWORD@HOST/DB` or `sqlite://FILE`.
    #[arg(long, env = "MAZEARENA_DATABASE")]
    database: String,
}

/// Applies the migrations the database lacks and prints the schema's version.
///
/// # Errors
/// When the database cannot be reached or a migration fails (nothing is half applied:
/// each migration runs in its own transaction).
pub fn run(args: MigrateArgs) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(async {
        let storage = super::open_database(&args.database).await?;
        let (version, count) = storage.schema_version().await?;
        storage.close().await;
        println!(
            "database schema at migration {version} ({count} applied): ready for mazearena {}",
            env!("CARGO_PKG_VERSION")
        );
        Ok(())
    })
}
