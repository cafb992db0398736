//! The ASCII-art maze format: any bytes give a maze or an error, never a panic; a maze
//! read is written back to the same maze, in both formats.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mazearena::engine::mazefile::{ascii, numeric};

fuzz_target!(|data: &[u8]| {
    if let Ok(maze) = ascii::parse(data) {
        let again = ascii::parse(ascii::write(&maze).as_bytes()).expect("ascii round trip");
        assert_eq!(again, maze);
        let numbers = numeric::parse(numeric::write(&maze).as_bytes()).expect("numeric round trip");
        assert_eq!(numbers, maze);
    }
});
