//! The referee's own speed, with no process around it (criterion):
//! - a 1000-step game on a 16x16 contest maze (All Japan 2015, expert final), beside the per-step protocol work the
//!   runner adds to each step (the sense encoded as a JSON line, the answer decoded);
//! - the solver (fewest run-1 steps) on the three classic mazes, beside reading the
//!   same maze file.
//!
//! `cargo bench --bench engine`; `bash benches/run.sh` puts the figures in
//! BENCHMARKS.md. Reads `../shared/mazes/` beside the checkout.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use mazearena::engine::{Action, Game, GameConfig, Maze, mazefile, solver};
use mazearena::protocol::{ServerMessage, decode_answer};

fn shared_maze(path: &str) -> (Vec<u8>, Maze) {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/mazes")
        .join(path);
    let text = std::fs::read(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let maze = mazefile::parse(&text).unwrap();
    (text, maze)
}

/// 1000 answers that turn and move about, bumping into walls (the game never ends
/// early: no reset, so run 0 lasts the whole budget).
fn answers() -> Vec<Action> {
    let cycle = [
        Action::turn_move(0, 3),
        Action::turn_move(90, 1),
        Action::turn_move(-90, 2),
        Action::turn_move(0, -1),
        Action::turn_move(90, 0),
    ];
    cycle.iter().copied().cycle().take(1000).collect()
}

fn play(maze: &Maze, answers: &[Action]) -> u32 {
    let mut game = Game::new(maze.clone(), GameConfig { max_steps: 1000 });
    for a in answers {
        if game.begin_step().is_none() {
            break;
        }
        game.apply(*a);
    }
    game.t()
}

fn protocol(maze: &Maze, answers: &[Action], lines: &[Vec<u8>]) -> usize {
    let mut game = Game::new(maze.clone(), GameConfig { max_steps: 1000 });
    let mut bytes = 0;
    for (a, line) in answers.iter().zip(lines) {
        let Some(sense) = game.begin_step() else {
            break;
        };
        bytes += ServerMessage::sense(&sense).to_line().len();
        bytes += usize::from(decode_answer(line).is_ok());
        game.apply(*a);
    }
    bytes
}

fn engine(c: &mut Criterion) {
    let (_, maze) = shared_maze("micromouseonline/classic/japan2015-ef.txt");
    let answers = answers();
    assert_eq!(play(&maze, &answers), 1000);
    let lines: Vec<Vec<u8>> = answers
        .iter()
        .map(|a| serde_json::to_vec(a).unwrap())
        .collect();
    let mut g = c.benchmark_group("game_1000_steps");
    g.bench_function("engine", |b| b.iter(|| play(black_box(&maze), &answers)));
    g.bench_function("engine_and_protocol", |b| {
        b.iter(|| protocol(black_box(&maze), &answers, &lines))
    });
    g.finish();
}

fn solver_time(c: &mut Criterion) {
    let mut g = c.benchmark_group("solver");
    for name in ["test_maze_01", "test_maze_02", "test_maze_03"] {
        let (text, maze) = shared_maze(&format!("classic/{name}.txt"));
        assert!(solver::solve(&maze).is_some());
        g.bench_function(format!("{name}/read"), |b| {
            b.iter(|| mazefile::parse(black_box(&text)).unwrap())
        });
        g.bench_function(format!("{name}/solve"), |b| {
            b.iter(|| solver::solve(black_box(&maze)).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, engine, solver_time);
criterion_main!(benches);
