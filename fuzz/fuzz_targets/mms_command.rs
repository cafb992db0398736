//! An mms mouse's command lines, as the referee reads them in a real game on a generated
//! maze: any lines give a step's answer, a line back, or a mouse fault (the match's
//! protocol error), never a panic, and the game stays within its step budget.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mazearena::engine::generator::generate;
use mazearena::engine::{Game, GameConfig};
use mazearena::protocol::mms::{Mouse, Next};

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let dim = [12, 14, 16][usize::from(first) % 3];
    let Ok(maze) = generate(dim, u64::from(first)) else {
        return;
    };
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
