//! Bot protocol v1 (docs/PROTOCOL.md): the messages the server sends, and the strict
//! decoding of a bot's reply line into an [`Action`].
//!
//! Pure: bytes in, values out. The runner owns the pipes and the clocks.

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::value::RawValue;

use crate::engine::{Action, Sense};

pub mod mms;
mod plain;

/// The protocol version this server speaks.
pub const PROTOCOL_VERSION: u32 = 1;

/// A reply line may hold at most this many bytes before its "\n" (PROTOCOL-v1: a line
/// longer than 64 KiB is a protocol error).
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// How much of an offending line a match record keeps.
pub const EXCERPT_BYTES: usize = 200;

/// The most JSON bytes of one step's `debug` object that a trace keeps (docs/PROTOCOL.md
/// "Debug drawing"): enough for a 32x32 grid of values, small enough that a match's
/// trace stays cheap to store and to draw.
pub const MAX_DEBUG_STEP_BYTES: usize = 16 * 1024;

/// The most `debug` bytes a whole match keeps; later steps' debug objects are dropped.
pub const MAX_DEBUG_MATCH_BYTES: usize = 64 * 1024;

/// A message from the server to the bot, one JSON object per line.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// Sent once, first. The bot does not answer it.
    Start {
        /// Always [`PROTOCOL_VERSION`].
        protocol: u32,
        /// The side of the maze.
        maze_dim: u32,
        /// The shared step budget.
        max_steps: u32,
        /// A seed for randomized bots.
        seed: u64,
        /// The per-answer time limit after the first answer.
        move_timeout_ms: u64,
    },
    /// Sent at every step; the bot answers with one line.
    Sense {
        /// 0 or 1.
        run: u8,
        /// The shared counter `t`, 1-based.
        step: u32,
        /// `[left, front, right]`.
        sensors: [u32; 3],
    },
    /// Sent once, last; then stdin is closed.
    End {
        /// finished, step_limit, timeout, crashed or protocol_error.
        status: String,
        /// Null unless finished.
        score: Option<f64>,
        /// Null until a reset was accepted.
        run0_steps: Option<u32>,
        /// Null unless finished.
        run1_steps: Option<u32>,
    },
}

impl ServerMessage {
    /// The sense message for a step the referee opened.
    pub fn sense(sense: &Sense) -> ServerMessage {
        ServerMessage::Sense {
            run: sense.run,
            step: sense.step,
            sensors: sense.sensors,
        }
    }

    /// The message as one line, "\n" included.
    pub fn to_line(&self) -> String {
        if let ServerMessage::Sense { run, step, sensors } = self {
            return plain::sense_line(*run, *step, sensors);
        }
        // Serializing these plain structs cannot fail.
        let mut s = serde_json::to_string(self).expect("server messages always serialize");
        s.push('\n');
        s
    }
}

/// Why a bot's reply line is not a valid answer (PROTOCOL-v1 "What the bot may send").
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// The bytes are not UTF-8.
    #[error("the line is not valid UTF-8")]
    InvalidUtf8,
    /// The line is not a JSON value.
    #[error("the line is not JSON: {0}")]
    NotJson(String),
    /// A JSON value, but not an object.
    #[error("the line is JSON but not an object")]
    NotAnObject,
    /// Neither a reset nor both integer fields.
    #[error(
        "the object has no \"{0}\" field (an answer is {{\"rotation\":R,\"movement\":M}} or {{\"reset\":true}})"
    )]
    MissingField(&'static str),
    /// A field that must be an integer holds something else.
    #[error("\"{field}\" must be a JSON integer, found {found}")]
    NotAnInteger {
        /// rotation or movement.
        field: &'static str,
        /// The value as sent (cut).
        found: String,
    },
    /// More than [`MAX_LINE_BYTES`] before the newline.
    #[error("the line is longer than {MAX_LINE_BYTES} bytes")]
    LineTooLong,
}

/// A decoded reply: the action the referee plays, and the bot's optional `debug`
/// object (the debug-drawing extension), kept as sent and never read by the referee.
#[derive(Debug, Clone)]
pub struct Answer {
    /// What the referee plays.
    pub action: Action,
    /// The `debug` field as sent, if any (any JSON value; the runner keeps objects only).
    pub debug: Option<Box<RawValue>>,
}

/// Decodes one reply line (without its "\n") into an [`Action`].
///
/// See [`decode_answer`], which also returns the `debug` field.
///
/// # Errors
/// A [`ProtocolError`] saying what is wrong.
pub fn decode_reply(line: &[u8]) -> Result<Action, ProtocolError> {
    decode_answer(line).map(|a| a.action)
}

/// Decodes one reply line (without its "\n") into an [`Answer`].
///
/// Follows PROTOCOL-v1's decided edge cases: `{"reset": true}` is a reset whatever else
/// the object holds; any other `reset` value is ignored; rotation and movement must be
/// JSON integers (of any size: they are saturated to 64 bits, then the referee's lenient
/// rules apply); surrounding whitespace, including a trailing "\r", is accepted; a
/// byte-order mark is not.
///
/// # Errors
/// A [`ProtocolError`] saying what is wrong.
pub fn decode_answer(line: &[u8]) -> Result<Answer, ProtocolError> {
    if line.len() > MAX_LINE_BYTES {
        return Err(ProtocolError::LineTooLong);
    }
    if let Some(action) = plain::decode(line) {
        return Ok(Answer {
            action,
            debug: None,
        });
    }
    decode_any(line)
}

/// [`decode_answer`] by a whole JSON parse: every line that [`plain::decode`] does not
/// take.
fn decode_any(line: &[u8]) -> Result<Answer, ProtocolError> {
    let text = std::str::from_utf8(line).map_err(|_| ProtocolError::InvalidUtf8)?;
    let raw: &RawValue =
        serde_json::from_str(text).map_err(|e| ProtocolError::NotJson(e.to_string()))?;
    if !raw.get().starts_with('{') {
        return Err(ProtocolError::NotAnObject);
    }
    let fields: BTreeMap<String, &RawValue> =
        serde_json::from_str(raw.get()).map_err(|e| ProtocolError::NotJson(e.to_string()))?;
    let debug = fields.get("debug").map(|v| (*v).to_owned());
    if fields.get("reset").is_some_and(|v| v.get() == "true") {
        return Ok(Answer {
            action: Action::RESET,
            debug,
        });
    }
    let rotation = integer_field(&fields, "rotation")?;
    let movement = integer_field(&fields, "movement")?;
    Ok(Answer {
        action: Action::Move { rotation, movement },
        debug,
    })
}

fn integer_field(
    fields: &BTreeMap<String, &RawValue>,
    name: &'static str,
) -> Result<i64, ProtocolError> {
    let raw = fields
        .get(name)
        .ok_or(ProtocolError::MissingField(name))?
        .get();
    let digits = raw.strip_prefix('-').unwrap_or(raw);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(ProtocolError::NotAnInteger {
            field: name,
            found: excerpt(raw.as_bytes(), 40),
        });
    }
    // An integer of any size is an integer: saturate, the referee clamps or warns.
    Ok(raw.parse::<i64>().unwrap_or(if raw.starts_with('-') {
        i64::MIN
    } else {
        i64::MAX
    }))
}

/// The first `max` bytes of `bytes` as text (lossy), for error records.
pub fn excerpt(bytes: &[u8], max: usize) -> String {
    let cut = &bytes[..bytes.len().min(max)];
    let mut s = String::from_utf8_lossy(cut).into_owned();
    if bytes.len() > max {
        s.push('…');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(line: &str) -> Action {
        decode_reply(line.as_bytes()).unwrap()
    }

    fn err(line: &[u8]) -> ProtocolError {
        decode_reply(line).unwrap_err()
    }

    #[test]
    fn valid_answers() {
        assert_eq!(
            ok(r#"{"rotation":90,"movement":1}"#),
            Action::turn_move(90, 1)
        );
        assert_eq!(ok(r#"{"reset":true}"#), Action::RESET);
        assert_eq!(
            ok("  {\"rotation\":-90,\"movement\":-3}\r"),
            Action::turn_move(-90, -3)
        );
        assert_eq!(
            ok(r#"{"rotation":0,"movement":2,"debug":{"x":[1,2]}}"#),
            Action::turn_move(0, 2)
        );
    }

    #[test]
    fn debug_is_kept_as_sent_beside_moves_and_resets() {
        let a =
            decode_answer(br#"{"rotation":0,"movement":1,"debug":{"text":"hi","path":[[0,1]]}}"#)
                .unwrap();
        assert_eq!(a.action, Action::turn_move(0, 1));
        assert_eq!(a.debug.unwrap().get(), r#"{"text":"hi","path":[[0,1]]}"#);
        let r = decode_answer(br#"{"reset":true,"debug":{"text":"back"}}"#).unwrap();
        assert_eq!(r.action, Action::RESET);
        assert!(r.debug.is_some());
        assert!(
            decode_answer(br#"{"rotation":0,"movement":1}"#)
                .unwrap()
                .debug
                .is_none()
        );
    }

    #[test]
    fn reset_true_wins_and_other_reset_values_are_ignored() {
        assert_eq!(ok(r#"{"reset":true,"rotation":"x"}"#), Action::RESET);
        assert_eq!(
            ok(r#"{"reset":false,"rotation":0,"movement":1}"#),
            Action::turn_move(0, 1)
        );
        assert_eq!(
            err(br#"{"reset":1}"#),
            ProtocolError::MissingField("rotation")
        );
        assert_eq!(
            err(br#"{"reset":"true"}"#),
            ProtocolError::MissingField("rotation")
        );
    }

    #[test]
    fn integers_of_any_size_are_integers() {
        assert_eq!(
            ok(r#"{"rotation":0,"movement":123456789012345678901234567890}"#),
            Action::turn_move(0, i64::MAX)
        );
        assert_eq!(
            ok(r#"{"rotation":-99999999999999999999999,"movement":0}"#),
            Action::turn_move(i64::MIN, 0)
        );
        assert_eq!(
            ok(r#"{"rotation":180,"movement":0}"#),
            Action::turn_move(180, 0)
        );
    }

    #[test]
    fn non_integers_are_protocol_errors() {
        for bad in ["1.0", "1e2", "true", "\"1\"", "null", "[1]", "-0.5", "1E2"] {
            let line = format!(r#"{{"rotation":0,"movement":{bad}}}"#);
            assert!(
                matches!(
                    err(line.as_bytes()),
                    ProtocolError::NotAnInteger {
                        field: "movement",
                        ..
                    }
                ),
                "{bad}"
            );
        }
        assert!(matches!(
            err(br#"{"rotation":NaN,"movement":0}"#),
            ProtocolError::NotJson(_)
        ));
        assert!(matches!(
            err(br#"{"rotation":Infinity,"movement":0}"#),
            ProtocolError::NotJson(_)
        ));
    }

    #[test]
    fn malformed_lines() {
        assert!(matches!(err(b"hello"), ProtocolError::NotJson(_)));
        assert!(matches!(err(b""), ProtocolError::NotJson(_)));
        assert_eq!(err(b"[1,2]"), ProtocolError::NotAnObject);
        assert_eq!(err(b"42"), ProtocolError::NotAnObject);
        assert_eq!(
            err(br#"{"rotation":0}"#),
            ProtocolError::MissingField("movement")
        );
        assert_eq!(
            err(b"{\"rotation\":0,\"movement\":\xff}"),
            ProtocolError::InvalidUtf8
        );
        assert!(matches!(
            err("\u{feff}{\"reset\":true}".as_bytes()),
            ProtocolError::NotJson(_)
        ));
        assert_eq!(
            err(&vec![b' '; MAX_LINE_BYTES + 1]),
            ProtocolError::LineTooLong
        );
    }

    #[test]
    fn server_messages_match_the_protocol_text() {
        let start = ServerMessage::Start {
            protocol: 1,
            maze_dim: 12,
            max_steps: 1000,
            seed: 42,
            move_timeout_ms: 1000,
        };
        assert_eq!(
            start.to_line(),
            "{\"type\":\"start\",\"protocol\":1,\"maze_dim\":12,\"max_steps\":1000,\"seed\":42,\"move_timeout_ms\":1000}\n"
        );
        let sense = ServerMessage::Sense {
            run: 0,
            step: 1,
            sensors: [0, 11, 0],
        };
        assert_eq!(
            sense.to_line(),
            "{\"type\":\"sense\",\"run\":0,\"step\":1,\"sensors\":[0,11,0]}\n"
        );
        let end = ServerMessage::End {
            status: "finished".into(),
            score: Some(18.133),
            run0_steps: Some(34),
            run1_steps: Some(17),
        };
        assert_eq!(
            end.to_line(),
            "{\"type\":\"end\",\"status\":\"finished\",\"score\":18.133,\"run0_steps\":34,\"run1_steps\":17}\n"
        );
    }

    #[test]
    fn excerpts_are_cut() {
        assert_eq!(excerpt(b"abc", 200), "abc");
        assert_eq!(excerpt(&[b'x'; 300], 200).len(), 200 + '…'.len_utf8());
    }
}
