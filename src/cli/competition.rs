//! `mazearena competition`: competitions from the server's machine, on its database:
//! create one from a competition file (TOML naming maze files), export one back to a
//! folder (the file and its mazes), edit its settings, list them, print the results,
//! and give an organiser a key.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use crate::competition::{MazeText, Rule, Spec, Timestamp};
use crate::registry::competitions::{self as ops, Patch};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;

/// The database of the server.
#[derive(Debug, Args)]
pub struct DatabaseArg {
    /// The database.
    #[arg(
        long,
        env = "MAZEARENA_DATABASE",
        default_value = "sqlite://mazearena.db"
    )]
    database: String,
}

/// `mazearena competition ...`.
#[derive(Debug, Subcommand)]
pub enum CompetitionCommand {
    /// Create a competition from a competition file (TOML; maze paths are relative to it).
    Create {
        /// The competition file.
        file: PathBuf,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Write a competition to a folder: `competition.toml` and its mazes, ready for
    /// `competition create` on another server (the name can be changed in the file).
    Export {
        /// The competition's name.
        name: String,
        /// The folder to write (created; must be empty if it exists).
        #[arg(long, short = 'o')]
        out: PathBuf,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// List the competitions with their phase.
    List {
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// List a competition's entrants: their bot, versions and quotas ("2 of 5 versions
    /// used in the last 24 hours; the next one at ...").
    Entrants {
        /// The competition's name.
        name: String,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Change a competition's settings (times as RFC 3339, or `now`).
    Edit(EditArgs),
    /// Print the final results (a table, `--csv` or `--json`) and whether they equal a
    /// recount from the match records.
    Results {
        /// The competition's name.
        name: String,
        /// As CSV, one row per entrant.
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// As JSON, with each row's manifest.
        #[arg(long)]
        json: bool,
        /// Wait up to this many seconds for the results (a server playing the final run
        /// writes them), printing the final run's progress as it moves.
        #[arg(long, value_name = "SECS")]
        wait: Option<u64>,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Play again a version's or a maze's ranking matches (a rejudge, after an
    /// infrastructure failure or a referee fix): the earlier records are kept, marked
    /// superseded; the boards and results are counted again as the matches are played
    /// by the server's workers.
    Rejudge {
        /// The competition's name.
        name: String,
        /// The bot version's id (`bot_version_id`) whose matches are played again.
        #[arg(long, conflicts_with = "maze", required_unless_present = "maze")]
        version_id: Option<i64>,
        /// The maze's id whose matches are played again.
        #[arg(long)]
        maze: Option<i64>,
        /// Why (kept with the rejudge).
        #[arg(long)]
        reason: String,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Publish results held for the reveal (`hold_results`): from now on everyone sees
    /// them.
    Publish {
        /// The competition's name.
        name: String,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Write the reveal of the final results (last place to first, each entrant's best
    /// and worst private match inside) as one HTML file that plays without the server:
    /// the organisers' copy (hidden private mazes are drawn, and it says so).
    Reveal {
        /// The competition's name.
        name: String,
        /// The file to write.
        #[arg(long, short = 'o')]
        out: PathBuf,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Write the race of every entrant on one maze and seed (the final run's on a private
    /// maze, the public set's on a public one) as one HTML file that plays without the
    /// server.
    Race {
        /// The competition's name.
        name: String,
        /// The maze's name in the competition (or its id).
        #[arg(long)]
        maze: String,
        /// Which of the set's seeds, from 0.
        #[arg(long, default_value_t = 0)]
        repeat: i64,
        /// The file to write.
        #[arg(long, short = 'o')]
        out: PathBuf,
        #[command(flatten)]
        db: DatabaseArg,
    },
    /// Register an organiser and print its key (shown once): it makes competitions
    /// through the API, and manages and sees what seals the ones it made (or was handed
    /// with `edit --organiser`), nothing else.
    Organiser {
        /// The organiser's name.
        name: String,
        #[command(flatten)]
        db: DatabaseArg,
    },
}

/// Arguments of `competition edit`.
#[derive(Debug, Args)]
pub struct EditArgs {
    /// The competition's name.
    name: String,
    /// New opening (before it opens).
    #[arg(long)]
    opens_at: Option<String>,
    /// New close (`now` closes it now).
    #[arg(long)]
    closes_at: Option<String>,
    /// Freeze the public board this many hours before the close (negative: no freeze).
    #[arg(long, allow_hyphen_values = true)]
    freeze_hours: Option<f64>,
    /// Versions per entrant per 24 hours.
    #[arg(long)]
    versions_per_day: Option<u32>,
    /// Practice matches per entrant per 24 hours.
    #[arg(long)]
    practice_per_day: Option<u32>,
    /// The final run's repeats (0: as many as `repeats`).
    #[arg(long)]
    final_repeats: Option<u32>,
    /// Hold the results for the reveal (`true`) or publish them once written (`false`).
    #[arg(long)]
    hold_results: Option<bool>,
    /// Hand the competition to this organiser (registered with `competition organiser`).
    #[arg(long)]
    organiser: Option<String>,
    /// The final selection: latest, best_public or choice.
    #[arg(long)]
    selection: Option<String>,
    /// Title.
    #[arg(long)]
    title: Option<String>,
    /// How new versions are checked: `start` (invalid only for a failure that no maze
    /// causes), `match` (invalid for any failure in the validation match) or `off`.
    #[arg(long, value_parser = ["start", "match", "off"])]
    validation: Option<String>,
    /// Add a practice maze (a maze file; its file name, without the extension, names
    /// it). May be given several times.
    #[arg(long, value_name = "FILE")]
    add_practice: Vec<std::path::PathBuf>,
    /// Remove a practice maze, by its name in the competition. May be given several
    /// times.
    #[arg(long, value_name = "NAME")]
    remove_practice: Vec<String>,
    #[command(flatten)]
    db: DatabaseArg,
}

/// Runs a `competition` command.
///
/// # Errors
/// A bad file or argument, said with its cause; the database.
pub fn run(cmd: CompetitionCommand) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new().context("cannot start the async runtime")?;
    runtime.block_on(async move {
        match cmd {
            CompetitionCommand::Create { file, db } => {
                let spec = read_file(&file)?;
                let storage = open(&db, true).await?;
                let c = ops::create(&storage, spec, None).await?;
                print_line(&storage, &c).await?;
                Ok(())
            }
            CompetitionCommand::Export { name, out, db } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                export(&storage, &c, &out).await?;
                println!(
                    "wrote {} and its mazes",
                    out.join("competition.toml").display()
                );
                Ok(())
            }
            CompetitionCommand::List { db } => {
                let storage = open(&db, false).await?;
                for c in storage.list_competitions().await? {
                    print_line(&storage, &c).await?;
                }
                Ok(())
            }
            CompetitionCommand::Edit(args) => edit(args).await,
            CompetitionCommand::Entrants { name, db } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                let now = crate::storage::now_ms();
                for e in storage.competition_entries(c.competition_id).await? {
                    let versions = storage.submissions(&c, e.entrant_id).await?;
                    let ranked = versions.iter().filter(|v| v.ranked).count();
                    let versions_quota =
                        ops::version_quota(&storage, &c, e.entrant_id, now).await?;
                    let practice = ops::practice_quota(&storage, &c, e.entrant_id, now).await?;
                    println!(
                        "{}: bot {} ({}), {} versions ({ranked} ranked); {}; {}",
                        e.entrant_name,
                        e.bot_name,
                        e.bot_id,
                        versions.len(),
                        versions_quota.message,
                        practice.message
                    );
                }
                Ok(())
            }
            CompetitionCommand::Results {
                name,
                csv,
                json,
                wait,
                db,
            } => {
                let storage = open(&db, false).await?;
                let c = wait_for_results(&storage, &name, wait.unwrap_or(0)).await?;
                let rows = ops::results(&storage, &c).await?;
                let differ = ops::recount_differences(&storage, &c).await?;
                if csv {
                    print!("{}", ops::results_csv(&rows));
                } else if json {
                    println!(
                        "{}",
                        serde_json::to_string_pretty(&serde_json::json!({
                            "competition": c.name,
                            "recount_equal": differ.is_empty(),
                            "results": rows,
                        }))?
                    );
                } else {
                    println!(
                        "{:>4}  {:<24} {:<24} {:>7} {:>10} {:>8}",
                        "rank", "entrant", "bot", "version", "mean", "finished"
                    );
                    for r in &rows {
                        println!(
                            "{:>4}  {:<24} {:<24} {:>7} {:>10.3} {:>5}/{}",
                            r.rank,
                            r.entrant_name,
                            r.bot_name,
                            r.version,
                            r.mean_score,
                            r.finished,
                            r.played
                        );
                    }
                    if differ.is_empty() {
                        println!("recount: every row equals a recount from the match records");
                    } else {
                        println!(
                            "recount: these rows differ from the match records: {}",
                            differ.join(", ")
                        );
                    }
                }
                anyhow::ensure!(differ.is_empty(), "the results differ from a recount");
                Ok(())
            }
            CompetitionCommand::Rejudge {
                name,
                version_id,
                maze,
                reason,
                db,
            } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                let request = ops::RejudgeRequest {
                    bot_version_id: version_id,
                    maze_id: maze,
                    reason,
                };
                let r = ops::rejudge(&storage, &c, &request, "admin").await?;
                println!(
                    "rejudge {}: {} matches of {} queued again (their earlier records are kept, superseded)",
                    r.rejudge_id, r.matches, c.name
                );
                Ok(())
            }
            CompetitionCommand::Publish { name, db } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                ops::publish(&storage, &c).await?;
                println!("the results of {} are published", c.name);
                Ok(())
            }
            CompetitionCommand::Reveal { name, out, db } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                let reveal = crate::registry::finale::reveal(&storage, &c, true).await?;
                std::fs::write(&out, crate::web::finale::reveal_file(&reveal))
                    .with_context(|| format!("cannot write {}", out.display()))?;
                println!(
                    "wrote {}: the reveal of {} entrants{}",
                    out.display(),
                    reveal.lines.len(),
                    if reveal.organiser_copy {
                        " (it draws hidden private mazes: an organiser's copy)"
                    } else {
                        ""
                    }
                );
                Ok(())
            }
            CompetitionCommand::Race {
                name,
                maze,
                repeat,
                out,
                db,
            } => {
                let storage = open(&db, false).await?;
                let c = find(&storage, &name).await?;
                let race = crate::registry::finale::race(&storage, &c, true, &maze, repeat).await?;
                std::fs::write(&out, crate::web::finale::race_file(&race))
                    .with_context(|| format!("cannot write {}", out.display()))?;
                println!(
                    "wrote {}: {} robots on {} (seed {}){}",
                    out.display(),
                    race.runners.len(),
                    race.maze,
                    repeat + 1,
                    if race.organiser_copy {
                        "; the maze is hidden: an organiser's copy"
                    } else {
                        ""
                    }
                );
                Ok(())
            }
            CompetitionCommand::Organiser { name, db } => {
                let storage = open(&db, false).await?;
                let key = crate::registry::tokens::new_token()?;
                storage
                    .create_organiser(name.trim(), &crate::registry::tokens::hash_token(&key))
                    .await?;
                println!("organiser {name}: key {key}");
                println!("(shown once; it goes in `Authorization: Bearer KEY`)");
                Ok(())
            }
        }
    })
}

async fn open(db: &DatabaseArg, create: bool) -> anyhow::Result<Storage> {
    if create {
        super::open_database(&db.database).await
    } else {
        super::open_existing(&db.database).await
    }
}

async fn find(storage: &Storage, name: &str) -> anyhow::Result<CompetitionRow> {
    storage
        .get_competition(name)
        .await?
        .with_context(|| format!("no competition {name:?}"))
}

async fn print_line(storage: &Storage, c: &CompetitionRow) -> anyhow::Result<()> {
    let phase = ops::phase(c, crate::storage::now_ms());
    let mazes = storage.competition_mazes(c.competition_id).await?;
    let count = |set: &str| mazes.iter().filter(|m| m.maze_set == set).count();
    let when = |t: Option<i64>| t.map_or("-".to_string(), |t| Timestamp(t).words());
    println!(
        "{}: {:?}{} \"{}\"; opens {}, closes {}; mazes: {} practice, {} public, {} private",
        c.name,
        phase,
        c.state
            .as_deref()
            .map(|s| format!(" ({s})"))
            .unwrap_or_default(),
        c.title,
        when(c.opens_at),
        when(c.closes_at),
        count("practice"),
        count("public"),
        count("private"),
    );
    Ok(())
}

/// Reads a competition file and the maze files it names (relative to its folder).
///
/// # Errors
/// The file or a maze file cannot be read, or the file is not a competition.
pub fn read_file(file: &Path) -> anyhow::Result<Spec<MazeText>> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("cannot read {}", file.display()))?;
    let base = file.parent().unwrap_or(Path::new("."));
    crate::competition::read_competition_file(&text, |p| {
        let path = base.join(p);
        let bytes = super::read_capped(&path, crate::engine::mazefile::MAX_FILE_BYTES)
            .map_err(|e| format!("{e:#}"))?;
        String::from_utf8(bytes).map_err(|_| format!("{} is not text", path.display()))
    })
    .map_err(|e| anyhow::anyhow!("{}: {}", file.display(), e.0))
}

/// Writes competition `c` to folder `out`: `competition.toml` naming `mazes/SET/NAME.txt`.
async fn export(storage: &Storage, c: &CompetitionRow, out: &Path) -> anyhow::Result<()> {
    let files = ops::export_files(storage, c).await?;
    if out.exists() && std::fs::read_dir(out)?.next().is_some() {
        bail!("{} is not empty", out.display());
    }
    for (rel, text) in files {
        let path = out.join(&rel);
        if let Some(folder) = path.parent() {
            std::fs::create_dir_all(folder)
                .with_context(|| format!("cannot create {}", folder.display()))?;
        }
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

async fn edit(args: EditArgs) -> anyhow::Result<()> {
    let storage = open(&args.db, false).await?;
    let c = find(&storage, &args.name).await?;
    let now = crate::storage::now_ms();
    let time = |t: &Option<String>| -> anyhow::Result<Option<Timestamp>> {
        t.as_deref()
            .map(|t| {
                if t == "now" {
                    Ok(Timestamp(now))
                } else {
                    Timestamp::parse(t).map_err(anyhow::Error::msg)
                }
            })
            .transpose()
    };
    let selection = match args.selection.as_deref() {
        Some(word) => Some(Rule::parse(word).with_context(|| {
            format!("unknown selection {word:?}: use latest, best_public or choice")
        })?),
        None => None,
    };
    let patch = Patch {
        title: args.title,
        opens_at: time(&args.opens_at)?,
        closes_at: time(&args.closes_at)?,
        freeze_hours: args.freeze_hours,
        versions_per_day: args.versions_per_day,
        practice_per_day: args.practice_per_day,
        final_repeats: args.final_repeats,
        selection,
        hold_results: args.hold_results,
        organiser: args.organiser,
        validation: args
            .validation
            .as_deref()
            .map(crate::competition::Validation::parse),
        ..Patch::default()
    };
    let c = ops::edit(&storage, c, patch, now).await?;
    for path in &args.add_practice {
        let layout = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the maze {}", path.display()))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "practice".into());
        let id = ops::add_practice_maze(&storage, &c, &MazeText { name, layout }, now).await?;
        println!("practice maze {} added (maze {id})", path.display());
    }
    for name in &args.remove_practice {
        let mazes = storage.competition_mazes(c.competition_id).await?;
        let m = mazes
            .iter()
            .find(|m| m.maze_set == "practice" && &m.name == name)
            .with_context(|| {
                format!("competition {} has no practice maze named {name:?}", c.name)
            })?;
        ops::remove_practice_maze(&storage, &c, m.maze_id, now).await?;
        println!("practice maze {name} removed");
    }
    print_line(&storage, &c).await
}

/// Competition `name` once its results are written, waiting up to `wait_secs` for them
/// and printing the final run's progress (to stderr) each time it moves.
async fn wait_for_results(
    storage: &crate::storage::Storage,
    name: &str,
    wait_secs: u64,
) -> anyhow::Result<crate::storage::competitions::CompetitionRow> {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(wait_secs);
    let mut shown = None;
    loop {
        let c = find(storage, name).await?;
        if c.state.as_deref() == Some("final") {
            return Ok(c);
        }
        let progress = ops::final_progress(storage, &c).await?;
        if progress.is_some() && progress != shown {
            if let Some(p) = progress {
                eprintln!(
                    "final run of {name}: {} of {} matches played",
                    p.played, p.total
                );
            }
            shown = progress;
        }
        if std::time::Instant::now() >= deadline {
            match progress {
                Some(p) => bail!(
                    "competition {name} has no results yet: its final run has played {} of {} matches (the server writes the results once it has played)",
                    p.played,
                    p.total
                ),
                None => bail!(
                    "competition {name} has no results yet (they come after its close, {}, and its final run)",
                    c.closes_at.map_or("never".into(), |t| Timestamp(t).words())
                ),
            }
        }
        tokio::time::sleep(std::time::Duration::from_millis(500)).await;
    }
}
