//! `mazearena maze ...`: validate, solve, convert, render and generate maze files.

use std::path::PathBuf;

use anyhow::Context;
use clap::Subcommand;
use serde::Serialize;

use crate::engine::mazefile::numeric;
use crate::engine::{generator, render, solver};

/// The maze tools.
#[derive(Debug, Subcommand)]
pub enum MazeCommand {
    /// Check a maze file (either format); non-zero exit status if it is invalid.
    Validate {
        /// The maze file.
        file: PathBuf,
        /// Also check the task's own rules: 12 <= n <= 16, the start cell (wall on the
        /// right, open on top), a reachable goal room.
        #[arg(long)]
        strict: bool,
    },
    /// Print the fewest run-1 steps with full knowledge of the maze, and the actions.
    Solve {
        /// The maze file.
        file: PathBuf,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Convert a maze (e.g. an ASCII mazefile) to the task's numeric format.
    Convert {
        /// The input maze file.
        input: PathBuf,
        /// The numeric file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Draw a maze as SVG: walls, start, goal room, and optionally the optimal path.
    Render {
        /// The maze file.
        file: PathBuf,
        /// The SVG file to write.
        #[arg(short, long)]
        output: PathBuf,
        /// Draw the optimal run-1 path found by the solver.
        #[arg(long)]
        path: bool,
    },
    /// Generate a valid task maze from a seed (same seed, same maze).
    Generate {
        /// The side: an even number, 12 to 16 for task mazes.
        #[arg(long)]
        dim: u32,
        /// The seed. Without it, a random seed from the operating system is used and
        /// not shown, as a hidden (ranking) maze needs: whoever knows a seed can make
        /// the maze again.
        #[arg(long)]
        seed: Option<u64>,
        /// The numeric file to write (stdout if omitted).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

#[derive(Serialize)]
struct SolveJson {
    maze_dim: u32,
    steps: Option<u32>,
    actions: Vec<crate::engine::Action>,
}

/// Runs a maze subcommand.
///
/// # Errors
/// Unreadable or invalid mazes, unsolvable mazes where a path is needed, unwritable output.
pub fn run(cmd: MazeCommand) -> anyhow::Result<()> {
    match cmd {
        MazeCommand::Validate { file, strict } => {
            let maze = super::load_maze(&file)?;
            let problems = if strict {
                maze.strict_problems()
            } else {
                Vec::new()
            };
            if problems.is_empty() {
                println!(
                    "{}: valid {}x{} maze{} (sha256 {})",
                    file.display(),
                    maze.dim(),
                    maze.dim(),
                    if strict { ", task rules hold" } else { "" },
                    maze.hash()
                );
                Ok(())
            } else {
                anyhow::bail!(
                    "{} breaks the task's rules:\n  - {}",
                    file.display(),
                    problems.join("\n  - ")
                )
            }
        }
        MazeCommand::Solve { file, json } => {
            let maze = super::load_maze(&file)?;
            let solution = solver::solve(&maze);
            if json {
                let out = SolveJson {
                    maze_dim: maze.dim(),
                    steps: solution.as_ref().map(|s| s.steps),
                    actions: solution.map(|s| s.actions).unwrap_or_default(),
                };
                println!("{}", serde_json::to_string(&out)?);
                return Ok(());
            }
            let solution = solution.with_context(|| {
                format!(
                    "{}: the goal room cannot be reached from the start",
                    file.display()
                )
            })?;
            println!("Fewest run-1 steps: {}", solution.steps);
            for (i, (action, cells)) in solution
                .actions
                .iter()
                .zip(solution.path.windows(2))
                .enumerate()
            {
                if let crate::engine::Action::Move { rotation, movement } = action {
                    let (from, to) = (cells[0], cells[1]);
                    let moved = from.x.abs_diff(to.x) + from.y.abs_diff(to.y);
                    // A move asked longer than the way is open stops at the wall (the
                    // rules): say so, so that it does not read as a wrong count.
                    let stopped = if u64::from(moved) != movement.unsigned_abs() {
                        format!("  (a wall stops it after {moved})")
                    } else {
                        String::new()
                    };
                    println!(
                        "{:>3}: rotation {rotation:>3}, movement {movement:>2} -> {to}{stopped}",
                        i + 1
                    );
                }
            }
            Ok(())
        }
        MazeCommand::Convert { input, output } => {
            let maze = super::load_maze(&input)?;
            write(&output, &numeric::write(&maze))
        }
        MazeCommand::Render { file, output, path } => {
            let maze = super::load_maze(&file)?;
            let route = if path {
                Some(
                    solver::solve(&maze)
                        .with_context(|| {
                            format!("{}: the goal room cannot be reached", file.display())
                        })?
                        .path,
                )
            } else {
                None
            };
            write(&output, &render::svg(&maze, route.as_deref()))
        }
        MazeCommand::Generate { dim, seed, output } => {
            let seed = match seed {
                Some(s) => s,
                None => {
                    let mut b = [0u8; 8];
                    getrandom::fill(&mut b)
                        .map_err(|e| anyhow::anyhow!("no randomness for a secret seed: {e}"))?;
                    u64::from_le_bytes(b)
                }
            };
            let maze = generator::generate(dim, seed)?;
            let text = numeric::write(&maze);
            match output {
                Some(path) => write(&path, &text),
                None => {
                    print!("{text}");
                    Ok(())
                }
            }
        }
    }
}

fn write(path: &PathBuf, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}
