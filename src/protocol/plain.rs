//! The messages of every step without a JSON library: the sense line written directly,
//! and the answers almost every bot sends read by a small scanner.
//!
//! A step's referee work is mostly these two (PERFORMANCE.md "A step"): through
//! `serde_json`, the sense line and the answer took some 4,000 instructions a step,
//! the parse twice (the line checked as JSON, then its fields gathered into a map).
//! The scanner takes only the plain answers (`{"rotation":R,"movement":M}` with the
//! two fields in either order, or `{"reset":true}`, with JSON whitespace anywhere between
//! tokens and integers that fit in 64 bits); any other line (a `debug` field, an escape
//! in a key, a duplicate field, a large or malformed number, anything wrong) is left to
//! the whole parse, which decides it as before. So the scanner changes no answer's
//! meaning: the tests below hold it to the whole parse.

use crate::engine::Action;

/// The action of a plain answer line (without its "\n"); `None` for any other line.
pub(super) fn decode(line: &[u8]) -> Option<Action> {
    let mut s = Scanner { bytes: line, at: 0 };
    s.byte(b'{')?;
    match s.key()? {
        Key::Reset => {
            s.literal(b"true")?;
            s.byte(b'}')?;
            s.end()?;
            Some(Action::RESET)
        }
        first => {
            let a = s.integer()?;
            s.byte(b',')?;
            let second = s.key()?;
            let b = s.integer()?;
            s.byte(b'}')?;
            s.end()?;
            match (first, second) {
                (Key::Rotation, Key::Movement) => Some(Action::Move {
                    rotation: a,
                    movement: b,
                }),
                (Key::Movement, Key::Rotation) => Some(Action::Move {
                    rotation: b,
                    movement: a,
                }),
                _ => None,
            }
        }
    }
}

/// The sense line, exactly as `serde_json` writes [`super::ServerMessage::Sense`]
/// (tested below), "\n" included.
pub(super) fn sense_line(run: u8, step: u32, sensors: &[u32; 3]) -> String {
    let mut numbers = itoa::Buffer::new();
    let mut line = String::with_capacity(72);
    line.push_str("{\"type\":\"sense\",\"run\":");
    line.push_str(numbers.format(run));
    line.push_str(",\"step\":");
    line.push_str(numbers.format(step));
    line.push_str(",\"sensors\":[");
    line.push_str(numbers.format(sensors[0]));
    line.push(',');
    line.push_str(numbers.format(sensors[1]));
    line.push(',');
    line.push_str(numbers.format(sensors[2]));
    line.push_str("]}\n");
    line
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Key {
    Rotation,
    Movement,
    Reset,
}

/// Reads a line token by token; every method skips the JSON whitespace before its token.
struct Scanner<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Scanner<'_> {
    fn skip_whitespace(&mut self) {
        while let Some(b' ' | b'\t' | b'\r' | b'\n') = self.bytes.get(self.at) {
            self.at += 1;
        }
    }

    fn byte(&mut self, want: u8) -> Option<()> {
        self.skip_whitespace();
        (self.bytes.get(self.at) == Some(&want)).then(|| self.at += 1)
    }

    fn literal(&mut self, want: &[u8]) -> Option<()> {
        self.skip_whitespace();
        let end = self.at.checked_add(want.len())?;
        (self.bytes.get(self.at..end) == Some(want)).then(|| self.at = end)
    }

    /// A quoted key without escapes, and the colon after it.
    fn key(&mut self) -> Option<Key> {
        let key = if self.literal(b"\"rotation\"").is_some() {
            Key::Rotation
        } else if self.literal(b"\"movement\"").is_some() {
            Key::Movement
        } else if self.literal(b"\"reset\"").is_some() {
            Key::Reset
        } else {
            return None;
        };
        self.byte(b':')?;
        Some(key)
    }

    /// A JSON integer of at most 18 digits (so it fits in 64 bits): `-`, then `0` or a
    /// digit from 1 to 9 and more digits. (A fraction or an exponent after it is not
    /// taken: the next token must be a comma or the closing brace.)
    fn integer(&mut self) -> Option<i64> {
        self.skip_whitespace();
        let negative = self.bytes.get(self.at) == Some(&b'-');
        if negative {
            self.at += 1;
        }
        let start = self.at;
        let mut value: i64 = 0;
        while let Some(&d) = self.bytes.get(self.at)
            && d.is_ascii_digit()
        {
            if self.at - start == 18 {
                return None;
            }
            value = value * 10 + i64::from(d - b'0');
            self.at += 1;
        }
        let digits = self.at - start;
        if digits == 0 || (digits > 1 && self.bytes[start] == b'0') {
            return None;
        }
        Some(if negative { -value } else { value })
    }

    /// Nothing but whitespace is left.
    fn end(&mut self) -> Option<()> {
        self.skip_whitespace();
        (self.at == self.bytes.len()).then_some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The whole parse's action for a line, when it takes the line without a `debug`.
    fn whole(line: &[u8]) -> Option<Action> {
        match super::super::decode_any(line) {
            Ok(a) if a.debug.is_none() => Some(a.action),
            _ => None,
        }
    }

    #[test]
    fn plain_answers_are_taken() {
        for (line, action) in [
            (r#"{"rotation":90,"movement":1}"#, Action::turn_move(90, 1)),
            (
                r#"{"movement":-3,"rotation":-90}"#,
                Action::turn_move(-90, -3),
            ),
            (
                " { \"rotation\" : 0 , \"movement\" : 2 } \r",
                Action::turn_move(0, 2),
            ),
            (
                r#"{"rotation": 0, "movement": -0}"#,
                Action::turn_move(0, 0),
            ),
            (r#"{"reset":true}"#, Action::RESET),
            ("{ \"reset\" :\ttrue }", Action::RESET),
            (
                r#"{"rotation":999999999999999999,"movement":-999999999999999999}"#,
                Action::turn_move(999_999_999_999_999_999, -999_999_999_999_999_999),
            ),
        ] {
            assert_eq!(decode(line.as_bytes()), Some(action), "{line}");
            assert_eq!(whole(line.as_bytes()), Some(action), "{line}");
        }
    }

    #[test]
    fn every_other_line_is_left_to_the_whole_parse() {
        for line in [
            r#"{"rotation":0,"movement":1,"debug":{}}"#,
            r#"{"reset":true,"rotation":1}"#,
            r#"{"reset":false,"rotation":0,"movement":1}"#,
            r#"{"rotation":1,"rotation":2}"#,
            r#"{"rotation":1,"movement":2,"movement":3}"#,
            r#"{"rotation":01,"movement":1}"#,
            r#"{"rotation":1.0,"movement":1}"#,
            r#"{"rotation":1e2,"movement":1}"#,
            r#"{"rotation":-,"movement":1}"#,
            r#"{"rotation":1234567890123456789,"movement":1}"#,
            r#"{"rot\u0061tion":1,"movement":1}"#,
            r#"{"rotation":1,"movement":1}x"#,
            r#"{"rotation":1,"movement":1"#,
            r#"{"rotation":1 "movement":1}"#,
            "\u{feff}{\"reset\":true}",
            "{\"reset\":true}\u{a0}",
            r#"{"reset":True}"#,
            "",
        ] {
            assert_eq!(decode(line.as_bytes()), None, "{line}");
        }
    }

    #[test]
    fn the_sense_line_is_serde_json_s() {
        for (run, step, sensors) in [
            (0, 1, [0, 11, 0]),
            (1, 1000, [15, 0, 3]),
            (u8::MAX, u32::MAX, [u32::MAX, 0, 10]),
        ] {
            let message = super::super::ServerMessage::Sense { run, step, sensors };
            let mut serde = serde_json::to_string(&message).unwrap();
            serde.push('\n');
            assert_eq!(sense_line(run, step, &sensors), serde);
        }
    }

    fn whitespace() -> impl Strategy<Value = &'static str> {
        prop::sample::select(vec!["", "", "", " ", "\t", "\r", "\n", " \r\n"])
    }

    fn key() -> impl Strategy<Value = &'static str> {
        prop::sample::select(vec![
            "\"rotation\"",
            "\"rotation\"",
            "\"rotation\"",
            "\"movement\"",
            "\"movement\"",
            "\"movement\"",
            "\"reset\"",
            "\"reset\"",
            "\"debug\"",
            "\"rot\\u0061tion\"",
            "\"Rotation\"",
            "rotation",
            "\"x\"",
        ])
    }

    fn value() -> impl Strategy<Value = &'static str> {
        prop::sample::select(vec![
            "true",
            "true",
            "0",
            "0",
            "-0",
            "7",
            "-90",
            "90",
            "-3",
            "3",
            "false",
            "null",
            "00",
            "01",
            "-",
            "--1",
            "1.5",
            "1e3",
            "2E1",
            "-0.0",
            "123456789012345678",
            "-123456789012345678",
            "1234567890123456789",
            "99999999999999999999",
            "\"x\"",
            "[1]",
            "{}",
            "True",
            "1x",
        ])
    }

    /// Answer lines, plain and not: objects of up to four fields of every kind of key
    /// and value, with whitespace between any tokens, and sometimes a stray byte.
    fn line() -> impl Strategy<Value = String> {
        let field = (
            whitespace(),
            key(),
            whitespace(),
            whitespace(),
            value(),
            whitespace(),
        );
        let stray = prop::sample::select(vec![
            "", "", "", "", "", "", "", "", "", "", "x", ",", "}", "{", "\u{feff}",
        ]);
        (
            whitespace(),
            prop::collection::vec(field, 0..4),
            whitespace(),
            stray.clone(),
            stray,
        )
            .prop_map(|(before, fields, after, head, tail)| {
                let fields: Vec<String> = fields
                    .into_iter()
                    .map(|(a, k, b, c, v, d)| format!("{a}{k}{b}:{c}{v}{d}"))
                    .collect();
                format!("{head}{before}{{{}}}{after}{tail}", fields.join(","))
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        #[test]
        fn the_scanner_agrees_with_the_whole_parse(line in line()) {
            let plain = decode(line.as_bytes());
            let whole = whole(line.as_bytes());
            if plain.is_some() {
                prop_assert_eq!(whole, plain, "{}", line);
            }
        }

        #[test]
        fn plain_answers_of_any_values_are_taken(
            rotation in -999_999_999_999_999_999i64..=999_999_999_999_999_999,
            movement in -999_999_999_999_999_999i64..=999_999_999_999_999_999,
            swap in any::<bool>(),
            gap in prop::sample::select(vec!["", " ", "\t", " \r\n "]),
        ) {
            let (r, m) = (format!("\"rotation\"{gap}:{gap}{rotation}"), format!("\"movement\"{gap}:{gap}{movement}"));
            let (a, b) = if swap { (m, r) } else { (r, m) };
            let line = format!("{gap}{{{gap}{a}{gap},{gap}{b}{gap}}}{gap}");
            let action = Action::turn_move(rotation, movement);
            prop_assert_eq!(decode(line.as_bytes()), Some(action));
            prop_assert_eq!(whole(line.as_bytes()), Some(action));
        }

        #[test]
        fn sense_lines_of_any_values_are_serde_json_s(run in any::<u8>(), step in any::<u32>(), sensors in any::<[u32; 3]>()) {
            let mut serde = serde_json::to_string(&super::super::ServerMessage::Sense { run, step, sensors }).unwrap();
            serde.push('\n');
            prop_assert_eq!(sense_line(run, step, &sensors), serde);
        }
    }
}
