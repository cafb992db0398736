//! champion_study: plays the champion in-process on many mazes, fast, for tuning and for
//! asking how much of its score is luck.
//!
//! ```sh
//! cargo run --release --example champion_study -- [options] MAZE.txt...
//! ```
//!
//! Mazes are in the task's numeric format (`mazearena maze convert` turns an ASCII maze
//! into one). The study carries its own small referee with the game's rules (sensors,
//! moves stopped by walls, reset after the goal room, 1000 steps); official numbers come
//! from `mazearena run` and `mazearena tournament`, which agree with it on the classic
//! mazes (19.800 / 25.667 / 30.933).
//!
//! Options:
//! - `--verbose`: one line per maze.
//! - `--tie-seeds N`: also play N variants per maze that break ties between equally short
//!   plans at random before the goal (seeds 1..=N), and report the best and median score,
//!   the fastest first arrival, and how many variants beat the maze's `--targets` score.
//! - `--targets A,B,C`: a target score per maze, in the order given.
//! - `--target-ratio R`: for mazes without a `--targets` score, the target is R times the
//!   maze's optimum; the summary counts the mazes whose score beats their target.
//! - `--likely-weight W`, `--gain-weight W`: override the champion's weights.

use mazebot::champion::{Champion, Params};
use mazebot::map::{turn_and_direction, Edge, Map, Mode, Pose};
use mazebot::protocol::{Answer, Bot, Start};

/// What one game came to.
struct Game {
    finished: bool,
    run0: u32,
    run1: u32,
    arrival: Option<u32>,
    /// The first run-0 step count after which the champion had been in the goal room and
    /// had proven a fewest-step route: the least run 0 that any stopping rule could have
    /// had with this exploration.
    proven_optimum_at: Option<u32>,
}

impl Game {
    fn score(&self) -> f64 {
        f64::from(self.run1) + f64::from(self.run0) / 30.0
    }

    /// The score had the robot reset at the best moment: as soon as it had been in the
    /// goal room and had proven a fewest-step route (plus the reset step).
    fn best_stop(&self, optimum: u32) -> Option<f64> {
        self.proven_optimum_at
            .map(|s| f64::from(optimum) + f64::from(s + 1) / 30.0)
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let verbose = args.iter().any(|a| a == "--verbose");
    let tie_seeds: u64 = value("--tie-seeds").map_or(0, |v| v.parse().expect("--tie-seeds N"));
    let targets: Vec<f64> = value("--targets").map_or_else(Vec::new, |v| {
        v.split(',')
            .map(|t| t.parse().expect("--targets A,B,C"))
            .collect()
    });
    let target_ratio: Option<f64> =
        value("--target-ratio").map(|v| v.parse().expect("--target-ratio R"));
    let mut params = Params::default();
    if let Some(w) = value("--likely-weight") {
        params.likely_weight = w.parse().expect("--likely-weight W");
    }
    if let Some(w) = value("--gain-weight") {
        params.gain_weight = w.parse().expect("--gain-weight W");
    }
    let option_values: Vec<&String> = [
        "--tie-seeds",
        "--targets",
        "--target-ratio",
        "--likely-weight",
        "--gain-weight",
    ]
    .iter()
    .filter_map(|name| args.iter().position(|a| a == name).map(|i| &args[i + 1]))
    .collect();
    let files: Vec<&String> = args
        .iter()
        .filter(|a| !a.starts_with("--") && !option_values.contains(a))
        .collect();
    if files.is_empty() {
        eprintln!(
            "usage: champion_study [--verbose] [--tie-seeds N] [--targets A,B,C] MAZE.txt..."
        );
        std::process::exit(2);
    }

    let (mut played, mut finished, mut score_sum, mut ratio_sum) = (0, 0, 0.0, 0.0);
    let (mut targeted, mut beat, mut could_beat) = (0, 0, 0);
    for (i, file) in files.iter().enumerate() {
        let maze = match load(file) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{file}: {e}");
                std::process::exit(2);
            }
        };
        let Some(optimum) = maze
            .plan(Pose::START, |x, y| maze.is_goal(x, y), Mode::Known, false)
            .map(|p| p.steps)
        else {
            println!("{file}: the goal room cannot be reached; skipped");
            continue;
        };
        let game = play(&maze, optimum, params);
        played += 1;
        let target = targets
            .get(i)
            .copied()
            .or(target_ratio.map(|r| r * f64::from(optimum)));
        if let Some(t) = target {
            targeted += 1;
            beat += u32::from(game.finished && game.score() < t);
            could_beat += u32::from(game.best_stop(optimum).is_some_and(|s| s < t));
        }
        if game.finished {
            finished += 1;
            score_sum += game.score();
            ratio_sum += game.score() / f64::from(optimum);
        }
        if verbose || tie_seeds > 0 {
            println!(
                "{file}: optimum {optimum}, first arrival {}, run 0 {}, run 1 {}, score {:.3}{}",
                show(game.arrival),
                game.run0,
                game.run1,
                game.score(),
                if game.finished { "" } else { " (not finished)" }
            );
        }
        if tie_seeds > 0 {
            study_ties(&maze, params, optimum, tie_seeds, target);
        }
    }
    println!(
        "{played} mazes: {finished} finished, mean score {:.3}, mean score / optimum {:.4}",
        score_sum / f64::from(finished.max(1)),
        ratio_sum / f64::from(finished.max(1))
    );
    if targeted > 0 {
        println!(
            "{targeted} mazes with a target: {beat} beaten (with the best possible stopping rule: {could_beat})"
        );
    }
}

/// Plays `seeds` tie-break variants and prints what they came to.
fn study_ties(maze: &Map, params: Params, optimum: u32, seeds: u64, target: Option<f64>) {
    let mut scores = Vec::new();
    let (mut arrival_min, mut beat, mut could_beat) = (u32::MAX, 0, 0);
    for seed in 1..=seeds {
        let game = play(
            maze,
            optimum,
            Params {
                tie_jitter: Some(seed),
                ..params
            },
        );
        scores.push(game.score());
        arrival_min = arrival_min.min(game.arrival.unwrap_or(u32::MAX));
        if let Some(t) = target {
            beat += u32::from(game.finished && game.score() < t);
            could_beat += u32::from(game.best_stop(optimum).is_some_and(|s| s < t));
        }
    }
    scores.sort_by(f64::total_cmp);
    print!(
        "  {seeds} tie-break variants: best {:.3}, median {:.3}, fastest first arrival {}",
        scores[0],
        scores[scores.len() / 2],
        show((arrival_min != u32::MAX).then_some(arrival_min))
    );
    match target {
        Some(t) => {
            println!("; below {t}: {beat} (with the best possible stopping rule: {could_beat})")
        }
        None => println!(),
    }
}

fn show(n: Option<u32>) -> String {
    n.map_or_else(|| "-".to_string(), |n| n.to_string())
}

/// Plays one game of the champion on `maze` (whose fewest-step run is `optimum`) under
/// the task's rules.
fn play(maze: &Map, optimum: u32, params: Params) -> Game {
    const MAX_STEPS: u32 = 1000;
    let mut bot = Champion::new(params).quiet();
    bot.start(&Start {
        maze_dim: maze.n as u32,
        max_steps: MAX_STEPS,
        seed: 0,
        move_timeout_ms: 1000,
    });
    let mut game = Game {
        finished: false,
        run0: 0,
        run1: 0,
        arrival: None,
        proven_optimum_at: None,
    };
    let (mut pose, mut run, mut visited_goal) = (Pose::START, 0u8, false);
    for step in 1..=MAX_STEPS {
        let answer = bot.next_move(sensors(maze, pose), run, step);
        match answer {
            Answer::Reset if run == 0 && visited_goal => {
                game.run0 = step;
                run = 1;
                pose = Pose::START;
                continue;
            }
            Answer::Reset => {}
            Answer::Move { rotation, movement } => {
                pose = referee_move(maze, pose, rotation, movement)
            }
        }
        if run == 0 {
            if maze.is_goal(pose.x, pose.y) && !visited_goal {
                visited_goal = true;
                game.arrival = Some(step);
            }
            if visited_goal
                && game.proven_optimum_at.is_none()
                && bot.proven_plan().is_some_and(|p| p.steps <= optimum)
            {
                game.proven_optimum_at = Some(step);
            }
        } else if maze.is_goal(pose.x, pose.y) {
            game.finished = true;
            game.run1 = step - game.run0;
            return game;
        }
    }
    game
}

/// The sensors' reading at `pose`: open cells to the wall, `[left, front, right]`.
fn sensors(maze: &Map, pose: Pose) -> [u32; 3] {
    let mut out = [0; 3];
    for (i, slot) in out.iter_mut().enumerate() {
        let d = (pose.heading + 3 + i) % 4;
        let (mut x, mut y) = (pose.x, pose.y);
        while maze.edge(x, y, d) == Edge::Open {
            (x, y) = maze
                .neighbor(x, y, d)
                .expect("an open edge leads to a cell");
            *slot += 1;
        }
    }
    out
}

/// Rotate, then move cell by cell, stopping at a wall.
fn referee_move(maze: &Map, pose: Pose, rotation: i32, movement: i32) -> Pose {
    let (heading, dir) = turn_and_direction(pose.heading, rotation, movement);
    let (mut x, mut y) = (pose.x, pose.y);
    for _ in 0..movement.clamp(-3, 3).unsigned_abs() {
        if maze.edge(x, y, dir) != Edge::Open {
            break;
        }
        (x, y) = maze
            .neighbor(x, y, dir)
            .expect("an open edge leads to a cell");
    }
    Pose { x, y, heading }
}

/// Reads a maze in the task's numeric format: the side, then one line per column of
/// comma-separated 4-bit masks (1 up, 2 right, 4 down, 8 left; a bit set = open).
fn load(path: &str) -> Result<Map, String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let mut lines = text.lines();
    let n: usize = lines
        .next()
        .and_then(|l| l.trim().parse().ok())
        .filter(|n| *n >= 2)
        .ok_or("line 1: expected the maze side")?;
    let mut maze = Map::new(n);
    for x in 0..n {
        let line = lines.next().ok_or(format!("line {}: missing", x + 2))?;
        let masks: Vec<u32> = line
            .split(',')
            .map(|v| v.trim().parse())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("line {}: {e} (not the numeric format?)", x + 2))?;
        if masks.len() != n {
            return Err(format!(
                "line {}: {} values, expected {n}",
                x + 2,
                masks.len()
            ));
        }
        for (y, mask) in masks.iter().enumerate() {
            for d in 0..4 {
                if maze.neighbor(x, y, d).is_some() {
                    let edge = if mask & (1 << d) != 0 {
                        Edge::Open
                    } else {
                        Edge::Wall
                    };
                    maze.set(x, y, d, edge);
                }
            }
        }
    }
    Ok(maze)
}
