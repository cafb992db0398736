//! A bot's reply line: any bytes give an answer or a protocol error, never a panic; an
//! action read, written as JSON, reads back as the same action; the error's excerpt of
//! a line stays short.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mazearena::protocol::{decode_answer, excerpt};

fuzz_target!(|data: &[u8]| {
    if let Ok(answer) = decode_answer(data) {
        let line = serde_json::to_vec(&answer.action).expect("an action is JSON");
        let again = decode_answer(&line).expect("a written action reads back");
        assert_eq!(again.action, answer.action);
    }
    // At most 80 bytes shown, each at most one character, and the mark of a cut.
    let shown = excerpt(data, 80);
    assert!(shown.chars().count() <= 81, "{shown:?}");
});
