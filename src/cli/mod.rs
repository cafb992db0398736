//! The `mazearena` command line: one file per subcommand, each a thin layer over the
//! engine and the runner.

mod client;
mod competition;
mod matches;
mod maze;
mod migrate;
mod pool;
mod prune;
mod replay;
mod report;
mod run;
mod sandbox;
mod serve;
mod tournament;
mod worker;

use std::path::Path;

use anyhow::Context;
use clap::{Parser, Subcommand};

use crate::engine::{Maze, mazefile};

/// mazearena: referee, bot runner and tools for the micromouse maze task.
#[derive(Debug, Parser)]
#[command(name = "mazearena", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Referee one match: run a bot on a maze, both runs, and print the score.
    Run(run::RunArgs),
    /// Maze tools: validate, solve, convert, render, generate.
    #[command(subcommand)]
    Maze(maze::MazeCommand),
    /// Run the match server: HTTP API, storage (SQLite or PostgreSQL), match workers.
    Serve(serve::ServeArgs),
    /// Only play matches, from the database the servers use (scale-out on PostgreSQL).
    Worker(worker::WorkerArgs),
    /// Bring the database's schema up to date and print its version (servers and workers
    /// also do it on start; a rollout runs it once first).
    Migrate(migrate::MigrateArgs),
    /// Run a tournament locally (no server): every bot on every maze, into the database.
    Tournament(tournament::TournamentArgs),
    /// Show each isolation mechanism of the sandbox and whether it works here.
    Doctor(sandbox::DoctorArgs),
    /// Write a replay file (from `run --replay`) as a self-contained HTML viewer.
    Replay(replay::ReplayArgs),
    /// Stored matches: `match show ID` prints one, with its reason and stderr tail.
    #[command(subcommand)]
    Match(matches::MatchCommand),
    /// Remove the stored traces of old practice matches (their results stay).
    Prune(prune::PruneArgs),
    /// Competitions: create from a file, export, edit, list, results, organiser keys.
    #[command(subcommand)]
    Competition(competition::CompetitionCommand),
    /// Log in to a server: check your key there, and keep the server and the key.
    Login(client::LoginArgs),
    /// Forget the server, the key and the tokens of bots registered from here.
    Logout,
    /// Upload a bot's folder (its bot.toml) as a new bot or a new version, and follow
    /// its build.
    Submit(client::SubmitArgs),
    /// Your bots on the server: versions, builds, ranks, and your competitions' quotas.
    Status(client::StatusArgs),
    /// Your bots' latest matches on the server.
    Matches(client::MatchesArgs),
    /// A match's log from the server: status, reason, the bot's stderr.
    Logs(client::LogsArgs),
    /// Play your bot's latest version on every practice maze and print the results.
    Practice(client::PracticeArgs),
}

/// A step of the sandbox, when this process was started as `mazearena sandbox-exec ...`
/// (the jail inside it: `sandbox::sandbox_exec`) or `mazearena sandbox-enter ...` (the
/// cgroup join before it: `sandbox::sandbox_enter`). Neither returns, unless it failed;
/// `None` for every other command line.
pub fn sandbox_exec_if_asked() -> Option<std::process::ExitCode> {
    use crate::runner::sandbox::{ENTER_SUBCOMMAND, JAIL_SUBCOMMAND, SERVE_SUBCOMMAND};
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let step = args.get(1)?;
    if step == JAIL_SUBCOMMAND {
        Some(sandbox::sandbox_exec(&args[2..]))
    } else if step == ENTER_SUBCOMMAND {
        Some(sandbox::sandbox_enter(&args[2..]))
    } else if step == SERVE_SUBCOMMAND {
        Some(sandbox::sandbox_serve(&args[2..]))
    } else {
        None
    }
}

/// Parses the command line and runs it.
///
/// # Errors
/// Bad arguments, unreadable or invalid mazes, or output that cannot be written.
pub fn run() -> anyhow::Result<()> {
    let cli = Cli::parse();
    // Commands that only print what they read end quietly when their reader goes away
    // (`mazearena logs ID | head`), as other command-line tools do, instead of failing
    // on the broken pipe. Not the ones that run bots: a bot that closes its stdin must
    // not end the referee.
    if matches!(
        cli.command,
        Command::Maze(_)
            | Command::Replay(_)
            | Command::Match(_)
            | Command::Competition(_)
            | Command::Status(_)
            | Command::Matches(_)
            | Command::Logs(_)
            | Command::Practice(_)
    ) {
        // SAFETY: called at the start of the program, before any thread is made.
        unsafe {
            libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        }
    }
    match cli.command {
        Command::Run(args) => run::run(args),
        Command::Maze(cmd) => maze::run(cmd),
        Command::Serve(args) => serve::run(args),
        Command::Worker(args) => worker::run(args),
        Command::Migrate(args) => migrate::run(args),
        Command::Tournament(args) => tournament::run(args),
        Command::Doctor(args) => sandbox::doctor(args),
        Command::Replay(args) => replay::run(args),
        Command::Match(cmd) => matches::run(cmd),
        Command::Prune(args) => prune::run(args),
        Command::Competition(cmd) => competition::run(cmd),
        Command::Login(args) => client::login(args),
        Command::Logout => client::logout(),
        Command::Submit(args) => client::submit(args),
        Command::Status(args) => client::status(args),
        Command::Matches(args) => client::matches(args),
        Command::Logs(args) => client::logs(args),
        Command::Practice(args) => client::practice(args),
    }
}

/// `n` and the noun that goes with it: "1 match worker", "2 match workers".
pub(crate) fn count(n: impl Into<i64>, one: &str, many: &str) -> String {
    let n = n.into();
    format!("{n} {}", if n == 1 { one } else { many })
}

/// A failure that ends the program with its own exit status instead of the usual 2
/// (which says the command could not do its work): `doctor` exits 1 when the full
/// sandbox cannot run here.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct ExitWith {
    /// The exit status.
    pub code: u8,
    /// What to print.
    pub message: String,
}

/// Opens the database at `url` for a command that reads what a server or a tournament
/// stored: a SQLite file that does not exist is an error naming it (opening would
/// create an empty one in the current folder).
///
/// # Errors
/// As said, or the database cannot be opened.
pub(crate) async fn open_existing(url: &str) -> anyhow::Result<crate::storage::Storage> {
    if !url.starts_with("postgres") {
        let file = url.trim_start_matches("sqlite://");
        let file = file.split('?').next().unwrap_or(file);
        anyhow::ensure!(
            Path::new(file).exists(),
            "no database at {file} (give --database, or set MAZEARENA_DATABASE)"
        );
    }
    open_database(url).await
}

/// Opens the database at `url` (made and migrated if need be), saying which one when it
/// cannot, without its password.
pub(crate) async fn open_database(url: &str) -> anyhow::Result<crate::storage::Storage> {
    crate::storage::Storage::open(url).await.with_context(|| {
        format!(
            "cannot open the database {}",
            crate::storage::redacted_url(url)
        )
    })
}

/// Reads and parses a maze file of either format, with the file name in the error.
pub(crate) fn load_maze(path: &Path) -> anyhow::Result<Maze> {
    let bytes = read_capped(path, mazefile::MAX_FILE_BYTES)?;
    mazefile::parse(&bytes).with_context(|| format!("invalid maze {}", path.display()))
}

/// Reads at most `cap + 1` bytes of a file, so a huge file is refused without being
/// read whole.
fn read_capped(path: &Path, cap: usize) -> anyhow::Result<Vec<u8>> {
    use std::io::Read;
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let mut bytes = Vec::new();
    file.take(cap as u64 + 1)
        .read_to_end(&mut bytes)
        .with_context(|| format!("cannot read {}", path.display()))?;
    Ok(bytes)
}
