//! `mazearena competition`: competitions from the server's machine, on its database:
//! create one from a competition file (TOML naming maze files), export one back to a
//! folder (the file and its mazes), edit its settings, list them, print the results,
//! and give an organiser a key.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use crate::competition::{MazeSets, MazeText, Rule, Spec, Timestamp};
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
    /// Hand the competition to this organiser (registered with `competition organiser`).
    #[arg(long)]
    organiser: Option<String>,
    /// The final selection: latest, best_public or choice.
    #[arg(long)]
    selection: Option<String>,
    /// Title.
    #[arg(long)]
    title: Option<String>,
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
        Storage::open(&db.database)
            .await
            .with_context(|| format!("cannot open the database {}", db.database))
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
    let spec: Spec<String> = toml::from_str(&text)
        .with_context(|| format!("{} is not a competition file", file.display()))?;
    let base = file.parent().unwrap_or(Path::new("."));
    let load = |paths: &Vec<String>| -> anyhow::Result<Vec<MazeText>> {
        paths
            .iter()
            .map(|p| {
                let path = base.join(p);
                let bytes = super::read_capped(&path, crate::engine::mazefile::MAX_FILE_BYTES)?;
                let layout = String::from_utf8(bytes)
                    .with_context(|| format!("{} is not text", path.display()))?;
                let name = path
                    .file_stem()
                    .map_or_else(|| p.clone(), |s| s.to_string_lossy().into_owned());
                Ok(MazeText { name, layout })
            })
            .collect()
    };
    let mazes = MazeSets {
        practice: load(&spec.mazes.practice)?,
        public: load(&spec.mazes.public)?,
        private: load(&spec.mazes.private)?,
    };
    Ok(spec.with_mazes(mazes))
}

/// Writes competition `c` to folder `out`: `competition.toml` naming `mazes/SET/NAME.txt`.
async fn export(storage: &Storage, c: &CompetitionRow, out: &Path) -> anyhow::Result<()> {
    let (Some(opens), Some(closes)) = (c.opens_at, c.closes_at) else {
        bail!("the default competition is the server's ranking: there is nothing to export");
    };
    if out.exists() && std::fs::read_dir(out)?.next().is_some() {
        bail!("{} is not empty", out.display());
    }
    let mut sets: MazeSets<String> = MazeSets {
        practice: Vec::new(),
        public: Vec::new(),
        private: Vec::new(),
    };
    for m in storage.competition_mazes(c.competition_id).await? {
        let layout = storage
            .get_maze(m.maze_id)
            .await?
            .with_context(|| format!("maze {} is gone", m.maze_id))?
            .layout;
        let folder = out.join("mazes").join(&m.maze_set);
        std::fs::create_dir_all(&folder)
            .with_context(|| format!("cannot create {}", folder.display()))?;
        let stem: String = m
            .name
            .chars()
            .map(|ch| {
                if ch.is_ascii_alphanumeric() || "-_.".contains(ch) {
                    ch
                } else {
                    '_'
                }
            })
            .collect();
        let stem = stem.trim_start_matches('.').to_string();
        let mut file = format!("{stem}.txt");
        let mut n = 2;
        while folder.join(&file).exists() {
            file = format!("{stem}-{n}.txt");
            n += 1;
        }
        std::fs::write(folder.join(&file), layout)?;
        let rel = format!("mazes/{}/{file}", m.maze_set);
        match m.maze_set.as_str() {
            "practice" => sets.practice.push(rel),
            "public" => sets.public.push(rel),
            _ => sets.private.push(rel),
        }
    }
    let spec = Spec {
        name: c.name.clone(),
        title: c.title.clone(),
        description: c.description.clone(),
        rules: c.rules.clone(),
        opens_at: Timestamp(opens),
        closes_at: Timestamp(closes),
        freeze_hours: c.freeze_ms.map(|ms| ms as f64 / 3_600_000.0),
        repeats: c.repeats as u32,
        final_repeats: c.final_repeats as u32,
        versions_per_day: c.versions_per_day as u32,
        practice_per_day: c.practice_per_day as u32,
        selection: Rule::parse(&c.selection).unwrap_or_default(),
        max_selected: c.max_selected as u32,
        reveal_private_mazes: c.reveal_private_mazes,
        limits: c.limit_set(),
        mazes: sets,
    };
    let text = toml::to_string(&spec).context("cannot write the competition as TOML")?;
    std::fs::create_dir_all(out)?;
    std::fs::write(
        out.join("competition.toml"),
        format!(
            "# Exported by mazearena {}\n{text}",
            crate::runner::ENGINE_VERSION
        ),
    )?;
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
        organiser: args.organiser,
        ..Patch::default()
    };
    let c = ops::edit(&storage, c, patch, now).await?;
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
