//! `mazearena match show`: a stored match, as its bot's author wants to see it: the
//! result, why it failed, the end of the bot's stderr, and its HTML replay.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};

use crate::engine::mazefile;
use crate::runner::MatchRecord;

/// `mazearena match ...`.
#[derive(Debug, Subcommand)]
pub enum MatchCommand {
    /// Print a stored match: result, reason, stderr tail; optionally its HTML replay.
    Show(ShowArgs),
}

/// Arguments of `mazearena match show`.
#[derive(Debug, Args)]
pub struct ShowArgs {
    /// The match id (as `mazearena tournament` and the server print it).
    id: i64,
    /// The database.
    #[arg(
        long,
        env = "MAZEARENA_DATABASE",
        default_value = "sqlite://mazearena.db"
    )]
    database: String,
    /// Print the stored record's summary as JSON, and nothing else.
    #[arg(long)]
    json: bool,
    /// With --json: the whole record, with its per-step trace and the maze.
    #[arg(long, requires = "json")]
    trace: bool,
    /// Write the match's HTML replay viewer to this file.
    #[arg(long)]
    html: Option<PathBuf>,
    /// Write the replay (record, trace and maze, JSON) to this file.
    #[arg(long)]
    replay: Option<PathBuf>,
}

/// Runs `mazearena match ...`.
///
/// # Errors
/// The database, an unknown match, or files that cannot be written.
pub fn run(cmd: MatchCommand) -> anyhow::Result<()> {
    let MatchCommand::Show(args) = cmd;
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(show(args))
}

async fn show(args: ShowArgs) -> anyhow::Result<()> {
    let storage = super::open_existing(&args.database).await?;
    let row = storage.get_match(args.id).await?.with_context(|| {
        format!(
            "no match {} in {}",
            args.id,
            crate::storage::redacted_url(&args.database)
        )
    })?;
    let maze_row = storage.get_maze(row.maze_id).await?;
    let (bot_name, maze_name) = (row.bot_name.clone(), row.maze_name.clone());
    if row.record.is_none() && args.json {
        println!(
            "{}",
            serde_json::json!({"match_id": row.match_id, "status": row.status.to_string()})
        );
        return Ok(());
    }
    if !args.json {
        println!(
            "match {}: {bot_name} v{} on {maze_name}, seed {}{}",
            row.match_id,
            row.version,
            row.seed,
            row.tournament_id
                .map_or_else(String::new, |t| format!(", tournament {t}"))
        );
    }
    if row.record.is_none() {
        println!("status: {} (not played yet)", row.status);
        return Ok(());
    }
    let mut record: MatchRecord = storage
        .get_record(row.match_id)
        .await?
        .with_context(|| format!("match {}: the stored record cannot be read", row.match_id))?;
    let maze = maze_row
        .as_ref()
        .and_then(|m| mazefile::parse(m.layout.as_bytes()).ok());
    record.maze_layout = maze_row.map(|m| m.layout);
    if args.json && args.trace {
        println!("{}", serde_json::to_string(&record)?);
    } else if args.json {
        println!("{}", serde_json::to_string(&record.summary())?);
    } else {
        print_record(&record);
    }
    if let Some(path) = &args.replay {
        std::fs::write(path, serde_json::to_string(&record)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(path) = &args.html {
        let title = format!("match {}: {bot_name} on {maze_name}", row.match_id);
        super::replay::write_html(&record, maze.as_ref(), title, path)?;
        eprintln!("wrote {}", path.display());
    }
    storage.close().await;
    Ok(())
}

fn print_record(r: &MatchRecord) {
    let steps = |s: Option<u32>| s.map_or("-".to_string(), |n| n.to_string());
    println!(
        "status: {}   score: {}   run 0: {} steps   run 1: {} steps   total: {}",
        r.status,
        r.score.map_or("-".to_string(), |s| format!("{s:.3}")),
        steps(r.run0_steps),
        steps(r.run1_steps),
        r.total_steps
    );
    for w in &r.warnings {
        println!("warning at step {}: {}", w.step, w.message);
    }
    for n in &r.notices {
        println!("note: {}", n.message);
    }
    if let Some(e) = &r.error {
        let at = e.step.map_or_else(String::new, |s| format!(" (step {s})"));
        println!("reason{at}: {}", e.reason);
        if let Some(line) = &e.line {
            println!("offending line: {line}");
        }
    }
    let tail: Vec<&str> = r.stderr_tail.lines().rev().take(20).collect();
    if !tail.is_empty() {
        println!("last lines of the bot's stderr:");
        for line in tail.into_iter().rev() {
            println!("  | {line}");
        }
    }
}
