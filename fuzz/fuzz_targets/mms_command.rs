//! An mms mouse's command lines, as the referee reads them in a real game on a generated
//! maze: any lines give a step's answer, a line back, or a mouse fault (the match's
//! protocol error), never a panic, and the game stays within its step budget.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use mazearena::engine::generator::generate;
use mazearena::engine::{Game, GameConfig, Maze};
use mazearena::protocol::mms::{Mouse, Next};

/// Three generated mazes (12, 14 and 16 cells a side), made once: making one each run
/// would be most of the run's time.
fn mazes() -> &'static [Maze; 3] {
    static MAZES: OnceLock<[Maze; 3]> = OnceLock::new();
    MAZES.get_or_init(|| [12, 14, 16].map(|dim| generate(dim, u64::from(dim)).expect("a maze")))
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let maze = mazes()[usize::from(first) % 3].clone();
    let dim = maze.dim();
    let text = String::from_utf8_lossy(rest);
    let mut lines = text.split('\n');
    let mut game = Game::new(maze, GameConfig { max_steps: 200 });
    let mut mouse = Mouse::new(dim);
    while let Some(sense) = game.begin_step() {
        let mut next = match mouse.begin(&sense) {
            Ok(n) => n,
            Err(_) => return,
        };
        loop {
            match next {
                Next::Act(action) => {
                    game.apply(action);
                    break;
                }
                Next::Write(_) | Next::Read => {
                    let Some(line) = lines.next() else { return };
                    next = match mouse.line(line.trim_end_matches('\r')) {
                        Ok(n) => n,
                        Err(_) => return,
                    };
                }
            }
        }
        let _ = mouse.take_drawing();
        assert!(game.t() <= 200);
    }
});
