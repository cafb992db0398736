//! `mazearena tournament`: a tournament without a server. Bots come from `bot.toml`
//! manifests and run from their own folders; results go to the same database as the
//! server's, through the same queue and workers.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use tokio::sync::Notify;
use tokio_util::task::TaskTracker;

use crate::manifest::{self, BotManifest};
use crate::registry::{
    self,
    cache::{BundleCache, DEFAULT_CACHE_BYTES},
};
use crate::runner::{self, Limits};
use crate::storage::leaderboard::Scope;
use crate::work::worker::{self, Shutdown, WorkerConfig};

use super::report::{markdown, print_failures, print_table, results};

/// Arguments of `mazearena tournament`.
#[derive(Debug, Args)]
pub struct TournamentArgs {
    /// Bots: `bot.toml` files, folders holding one, or folders searched for them.
    #[arg(long, num_args = 1.., required = true)]
    bots: Vec<PathBuf>,
    /// Mazes: files (either format) or folders of `.txt` maze files.
    #[arg(long, num_args = 1.., required = true)]
    mazes: Vec<PathBuf>,
    /// How many times each bot plays each maze (seeds 0, 1, ...).
    #[arg(long, default_value_t = 1)]
    repeats: i64,
    /// Parallel matches, at most one per core (default: the number of cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// The database to write to (the server's, if you like).
    #[arg(
        long,
        env = "MAZEARENA_DATABASE",
        default_value = "sqlite://mazearena.db"
    )]
    database: String,
    /// The tournament's name.
    #[arg(long, default_value = "local tournament")]
    name: String,
    /// Print the result as JSON instead of a table (with every match).
    #[arg(long, conflicts_with = "markdown")]
    json: bool,
    /// Print the result as Markdown: every bot on every maze (run-0 steps, run-1 steps,
    /// score, the score the bot's manifest says its author claimed), then the standings.
    #[arg(long)]
    markdown: bool,
    /// An environment variable for every bot, KEY=VALUE (repeatable; over a manifest's
    /// `env` of the same name).
    #[arg(long = "bot-env", value_name = "KEY=VALUE", value_parser = super::run::parse_bot_env)]
    bot_env: Vec<(String, String)>,
    /// The protocol every bot speaks, over its manifest's `protocol`: `v1` or `mms` (mice
    /// written for the mms simulator: docs/PROTOCOL-mms.md).
    #[arg(long, value_parser = crate::runner::BotProtocol::parse)]
    protocol: Option<crate::runner::BotProtocol>,
    #[command(flatten)]
    sandbox: super::sandbox::SandboxArgs,
}

/// Runs `mazearena tournament`.
///
/// # Errors
/// Bad manifests or mazes, a failing build command, or the database.
pub fn run(args: TournamentArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=100).contains(&args.repeats),
        "--repeats must be 1 to 100"
    );
    let mut bots = Vec::new();
    for path in &args.bots {
        bots.extend(manifest::load(path)?);
    }
    for b in &mut bots {
        b.env.extend(args.bot_env.iter().cloned());
        if let Some(p) = args.protocol {
            b.protocol = p;
        }
        let env: Vec<(String, String)> = b.env.clone().into_iter().collect();
        runner::botenv::check(&env).with_context(|| format!("bot {}: env", b.name))?;
    }
    let mut names = std::collections::BTreeSet::new();
    for b in &bots {
        anyhow::ensure!(
            names.insert(b.name.clone()),
            "two bots are named {:?}",
            b.name
        );
    }
    let maze_files = maze_files(&args.mazes)?;
    let sandbox = args.sandbox.open(&[], true)?;
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    let mut built = std::collections::BTreeSet::new();
    for b in &bots {
        // Bots of one folder often share one build command: run it once.
        let Some(cmd) = &b.build else { continue };
        if built.insert((b.dir.clone(), cmd.clone())) {
            eprintln!("building {} ({cmd})", b.name);
            runtime
                .block_on(runner::build::build(
                    cmd,
                    &b.dir,
                    &sandbox,
                    b.runtime.as_deref(),
                ))
                .with_context(|| format!("{}: the build failed", b.name))?;
        }
    }
    runtime.block_on(play(args, bots, sandbox, maze_files))
}

fn maze_files(paths: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("cannot list {}", p.display()))?
                .flatten()
                .map(|e| e.path())
                .filter(|f| f.is_file() && f.extension().is_some_and(|e| e == "txt"))
                .collect();
            found.sort();
            anyhow::ensure!(!found.is_empty(), "no .txt maze files in {}", p.display());
            files.extend(found);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

async fn play(
    args: TournamentArgs,
    bots: Vec<BotManifest>,
    sandbox: runner::Sandbox,
    maze_files: Vec<PathBuf>,
) -> anyhow::Result<()> {
    let storage = super::open_database(&args.database).await?;
    storage.requeue_expired().await?;
    let mut version_ids = Vec::new();
    for b in &bots {
        version_ids.push(registry::bots::register_local(&storage, b).await?);
    }
    let mut maze_ids: Vec<i64> = Vec::new();
    let (mut duplicates, mut unplayable): (Vec<String>, Vec<String>) = (Vec::new(), Vec::new());
    let mut mazes = Vec::new();
    for f in &maze_files {
        let name = f
            .file_stem()
            .map_or_else(|| "maze".into(), |s| s.to_string_lossy().into_owned());
        mazes.push((name, crate::cli::load_maze(f)?));
    }
    let stored = registry::mazes::find_or_admit_all(&storage, mazes).await?;
    for (f, row) in maze_files.iter().zip(stored) {
        let name = f.display().to_string();
        match row.map(|r| r.maze_id) {
            None => unplayable.push(name),
            Some(id) if maze_ids.contains(&id) => duplicates.push(name),
            Some(id) => maze_ids.push(id),
        }
    }
    if !args.json {
        if !duplicates.is_empty() {
            eprintln!(
                "skipped {} maze file(s) with the same layout as an earlier one: {}",
                duplicates.len(),
                duplicates.join(", ")
            );
        }
        if !unplayable.is_empty() {
            eprintln!(
                "skipped {} maze(s) whose goal room cannot be reached: {}",
                unplayable.len(),
                unplayable.join(", ")
            );
        }
    }
    anyhow::ensure!(
        !maze_ids.is_empty(),
        "no playable maze among the files given"
    );
    let skipped = (duplicates, unplayable);
    let t = storage
        .create_tournament(&args.name, &version_ids, &maze_ids, args.repeats)
        .await?;
    let cores = crate::runner::affinity::cores();
    let jobs = args.jobs.unwrap_or(cores).clamp(1, cores);
    if !args.json {
        eprintln!(
            "tournament {}: {} x {} x {} = {}, {jobs} at a time",
            t.tournament_id,
            super::count(bots.len() as i64, "bot", "bots"),
            super::count(maze_ids.len() as i64, "maze", "mazes"),
            super::count(args.repeats, "repeat", "repeats"),
            super::count(t.total, "match", "matches"),
        );
    }
    let bar = if std::io::stderr().is_terminal() && !args.json {
        let bar = ProgressBar::new(t.total as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} matches  {elapsed_precise}  eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let started = Instant::now();
    let tracker = TaskTracker::new();
    let shutdown = Shutdown::default();
    let progress = bar.clone();
    // Each recorded match wakes the loop below, which ends the pool once all are done
    // (without it the pool's end waited for the loop's next look, up to 200 ms).
    let recorded = Arc::new(Notify::new());
    let on_record = recorded.clone();
    worker::spawn_workers(
        &tracker,
        storage.clone(),
        WorkerConfig {
            jobs,
            lease: worker::DEFAULT_LEASE,
            limits: Limits::default(),
            sandbox,
            only_tournament: Some(t.tournament_id),
            exit_when_idle: true,
            report_as: None,
            cache: BundleCache::new(
                &std::env::temp_dir().join("mazearena-cache"),
                DEFAULT_CACHE_BYTES,
            )?,
            builds: None,
            build_write_bytes: crate::runner::build::DEFAULT_BUILD_WRITE_BYTES,
            validate: false,
        },
        None,
        Arc::new(Notify::new()),
        shutdown.clone(),
        Some(Arc::new(move |_| {
            progress.inc(1);
            on_record.notify_one();
        })),
    );
    tracker.close();
    let abort = shutdown.clone();
    let interrupted = tokio::spawn(async move {
        let _ = tokio::signal::ctrl_c().await;
        abort.stop_claiming.cancel();
        abort.abort.cancel();
    });
    // The reaper exits with the workers: stop it once every worker has left.
    let workers_done = tracker.wait();
    tokio::pin!(workers_done);
    loop {
        tokio::select! {
            _ = &mut workers_done => break,
            () = recorded.notified() => {}
            _ = tokio::time::sleep(Duration::from_millis(200)) => {}
        }
        let done = storage
            .get_tournament(t.tournament_id)
            .await?
            .map_or(0, |t| t.done);
        if done >= t.total {
            shutdown.stop_claiming.cancel();
        }
    }
    interrupted.abort();
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let t = storage
        .get_tournament(t.tournament_id)
        .await?
        .context("the tournament vanished from the database")?;
    let standings = registry::rankings::Ranker::default()
        .leaderboard(&storage, Scope::Tournament(t.tournament_id))
        .await?;
    let results = results(&storage, t.tournament_id).await?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "tournament_id": t.tournament_id,
                "name": t.name,
                "total": t.total,
                "done": t.done,
                "elapsed_ms": elapsed.as_millis() as u64,
                "standings": standings,
                "matches": results,
                "skipped": {
                    "duplicate_layout": skipped.0,
                    "unreachable_goal": skipped.1,
                },
            })
        );
    } else if args.markdown {
        print!("{}", markdown(&bots, &results, &standings));
    } else {
        print_table(&standings);
        print_failures(&results, &args.database);
        let per_min = t.done as f64 / elapsed.as_secs_f64().max(1e-9) * 60.0;
        println!(
            "{}/{} matches in {:.1} s ({per_min:.0} matches per minute); tournament id {}",
            t.done,
            t.total,
            elapsed.as_secs_f64(),
            t.tournament_id
        );
    }
    storage.close().await;
    anyhow::ensure!(
        t.done == t.total,
        "interrupted: {} of {} matches played",
        t.done,
        t.total
    );
    Ok(())
}
