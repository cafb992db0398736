//! Protocol v1 for bots: read one JSON message per line from stdin, answer sense
//! messages with one line on stdout. Implement [`Bot`] and call [`run`].
//!
//! The server's messages are small and fixed, so a few lines of scanning read them; no
//! JSON library is needed. Print debug output with `eprintln!` (stderr is your log);
//! never `println!`, which would be taken as an answer.

use std::io::{BufRead, Write};

/// The start message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Start {
    /// The side of the maze.
    pub maze_dim: u32,
    /// The shared step budget.
    pub max_steps: u32,
    /// Seed for any randomness.
    pub seed: u64,
    /// Time per answer, in ms.
    pub move_timeout_ms: u64,
}

/// An answer for one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Answer {
    /// Rotate (-90, 0, 90), then move (-3..=3 cells).
    Move {
        /// -90, 0 or 90.
        rotation: i32,
        /// -3..=3.
        movement: i32,
    },
    /// End run 0 (allowed once the robot has been in the goal room).
    Reset,
}

/// A bot: the server calls these in order.
pub trait Bot {
    /// Once, first.
    fn start(&mut self, start: &Start);
    /// At every step: `sensors` = open cells to the wall `[left, front, right]`.
    fn next_move(&mut self, sensors: [u32; 3], run: u8, step: u32) -> Answer;
    /// Once, last: the end message's status (`finished`, `step_limit`, ...).
    fn end(&mut self, _status: &str) {}
}

/// Runs `bot` until the end message or the end of stdin.
pub fn run<B: Bot>(mut bot: B) {
    let stdin = std::io::stdin();
    let mut out = std::io::stdout().lock();
    for line in stdin.lock().lines() {
        let Ok(line) = line else { break };
        match field(&line, "type").as_deref() {
            Some("\"start\"") => bot.start(&Start {
                maze_dim: number(&line, "maze_dim").unwrap_or(0) as u32,
                max_steps: number(&line, "max_steps").unwrap_or(1000) as u32,
                seed: number(&line, "seed").unwrap_or(0),
                move_timeout_ms: number(&line, "move_timeout_ms").unwrap_or(1000),
            }),
            Some("\"sense\"") => {
                let sensors = sensors(&line);
                let run = number(&line, "run").unwrap_or(0) as u8;
                let step = number(&line, "step").unwrap_or(0) as u32;
                let text = match bot.next_move(sensors, run, step) {
                    Answer::Move { rotation, movement } => {
                        format!("{{\"rotation\":{rotation},\"movement\":{movement}}}\n")
                    }
                    Answer::Reset => "{\"reset\":true}\n".to_string(),
                };
                if out
                    .write_all(text.as_bytes())
                    .and_then(|_| out.flush())
                    .is_err()
                {
                    break;
                }
            }
            Some("\"end\"") => {
                let status = field(&line, "status").unwrap_or_default();
                bot.end(status.trim_matches('"'));
                break;
            }
            _ => {}
        }
    }
}

/// The raw text of a top-level field's value (up to the next `,` or `}` outside brackets).
fn field(line: &str, key: &str) -> Option<String> {
    let pattern = format!("\"{key}\"");
    let at = line.find(&pattern)? + pattern.len();
    let rest = line[at..].trim_start().strip_prefix(':')?.trim_start();
    let mut depth = 0;
    let mut end = rest.len();
    for (i, c) in rest.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            ',' | '}' if depth == 0 => {
                end = i;
                break;
            }
            _ => {}
        }
    }
    Some(rest[..end].trim().to_string())
}

fn number(line: &str, key: &str) -> Option<u64> {
    field(line, key)?.parse().ok()
}

fn sensors(line: &str) -> [u32; 3] {
    let raw = field(line, "sensors").unwrap_or_default();
    let mut out = [0; 3];
    let inner = raw.trim_start_matches('[').trim_end_matches(']');
    for (slot, part) in out.iter_mut().zip(inner.split(',')) {
        *slot = part.trim().parse().unwrap_or(0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_server_messages() {
        let sense = r#"{"type":"sense","run":1,"step":35,"sensors":[0,11,0]}"#;
        assert_eq!(field(sense, "type").as_deref(), Some("\"sense\""));
        assert_eq!(sensors(sense), [0, 11, 0]);
        assert_eq!(number(sense, "step"), Some(35));
        let start = r#"{"type":"start","protocol":1,"maze_dim":12,"max_steps":1000,"seed":7,"move_timeout_ms":1000}"#;
        assert_eq!(number(start, "maze_dim"), Some(12));
        assert_eq!(number(start, "seed"), Some(7));
        let spaced = r#"{ "sensors" : [ 1 , 2 , 3 ] , "type" : "sense" }"#;
        assert_eq!(sensors(spaced), [1, 2, 3]);
    }
}
