//! `mazearena replay`: turn a replay file (a match record with its trace, from
//! `mazearena run --replay` or the viewer's "download replay") into a self-contained HTML
//! viewer that opens from disk.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use crate::engine::{Maze, mazefile};
use crate::runner::MatchRecord;
use crate::web::viewer::{ViewerData, standalone};

/// The largest replay file read: a 1000-step trace with every debug object allowed is
/// well under this.
const MAX_REPLAY_BYTES: usize = 64 * 1024 * 1024;

/// Arguments of `mazearena replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The replay file (JSON), or the id of a match on the server you are logged in to
    /// (`mazearena login`), or `last` for your newest match there on a public maze.
    replay: PathBuf,
    /// Where to write the HTML (default: the replay's name with `.html`).
    #[arg(long, short = 'o')]
    output: Option<PathBuf>,
    /// The maze file, for a replay that does not carry its maze.
    #[arg(long)]
    maze: Option<PathBuf>,
}

/// Runs `mazearena replay`.
///
/// # Errors
/// An unreadable or invalid replay or maze, a replay whose maze is not the one given,
/// or an output that cannot be written.
pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    // A match id or `last` (and no file of that name): the server's replay.
    let server_match = args
        .replay
        .to_str()
        .filter(|s| !args.replay.exists() && super::client::is_match_spec(s));
    if let Some(spec) = server_match {
        anyhow::ensure!(
            args.maze.is_none(),
            "--maze is for a replay file, not a match"
        );
        return super::client::replay(spec, args.output);
    }
    let bytes = super::read_capped(&args.replay, MAX_REPLAY_BYTES)?;
    anyhow::ensure!(
        bytes.len() <= MAX_REPLAY_BYTES,
        "{} is larger than {} MiB",
        args.replay.display(),
        MAX_REPLAY_BYTES >> 20
    );
    let record: MatchRecord = serde_json::from_slice(&bytes).with_context(|| {
        format!(
            "{} is not a mazearena replay (a match record with its trace)",
            args.replay.display()
        )
    })?;
    let maze = match (&args.maze, &record.maze_layout) {
        (Some(path), _) => super::load_maze(path)?,
        (None, Some(layout)) => mazefile::parse(layout.as_bytes())
            .with_context(|| format!("the maze in {} is invalid", args.replay.display()))?,
        (None, None) => anyhow::bail!(
            "{} does not carry its maze: give the maze file with --maze",
            args.replay.display()
        ),
    };
    anyhow::ensure!(
        maze.hash() == record.maze_hash,
        "the maze does not match the replay (the replay was played on maze {})",
        record.maze_hash
    );
    let output = args
        .output
        .unwrap_or_else(|| args.replay.with_extension("html"));
    // The title `run` wrote (the bot, the maze, the seed), else the file's name.
    let title = record.title.clone().unwrap_or_else(|| {
        args.replay
            .file_stem()
            .map_or_else(|| "replay".into(), |s| s.to_string_lossy().into_owned())
    });
    write_html(&record, Some(&maze), title, &output)?;
    eprintln!("wrote {}", output.display());
    Ok(())
}

/// Writes the standalone viewer of `record` on `maze` to `path`.
///
/// # Errors
/// When the file cannot be written.
pub(super) fn write_html(
    record: &MatchRecord,
    maze: Option<&Maze>,
    title: String,
    path: &Path,
) -> anyhow::Result<()> {
    let name = path
        .file_stem()
        .map_or_else(|| "replay".into(), |s| s.to_string_lossy().into_owned());
    let data = ViewerData::new(title, record, maze, format!("{name}.json"));
    std::fs::write(path, standalone(&data))
        .with_context(|| format!("cannot write {}", path.display()))
}
