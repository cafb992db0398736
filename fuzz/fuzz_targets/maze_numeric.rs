//! The numeric maze format: any bytes give a maze or an error, never a panic; a maze
//! read is written back to the same maze, in the numeric format and (when its start
//! cell opens upwards, as a drawing's start must: the ASCII reader turns a drawing to
//! bring the start's opening up) in the ASCII format.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mazearena::engine::mazefile::{ascii, numeric};
use mazearena::engine::{Heading, Position};

fuzz_target!(|data: &[u8]| {
    if let Ok(maze) = numeric::parse(data) {
        let again = numeric::parse(numeric::write(&maze).as_bytes()).expect("numeric round trip");
        assert_eq!(again, maze);
        if maze.is_open(Position { x: 0, y: 0 }, Heading::Up) {
            let drawn = ascii::parse(ascii::write(&maze).as_bytes()).expect("ascii round trip");
            assert_eq!(drawn, maze);
        }
    }
});
