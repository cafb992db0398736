//! Text from a server, made safe to print on the participant's terminal.
//!
//! Everything a server sends (names of bots, mazes, entrants and competitions, statuses,
//! error messages, build logs, a bot's stderr) is someone else's text: a maze name or a
//! bot's stderr holding `ESC ] 52 ; c ; ... BEL` would write to the participant's
//! clipboard, `ESC [ 2 J` would clear their screen, and a carriage return would print
//! over what the client itself wrote. So the client prints no control character it did
//! not make: every server-derived text goes through [`escape`] (or one of its short
//! forms [`text`], [`log`], [`value`]) where it is printed, and JSON output through
//! [`json`].
//!
//! What is escaped: the C0 controls U+0000..U+001F (`\n`, `\r` and `\t` by name, the
//! others as `\x1b`), DEL as `\x7f`, and the C1 controls U+0080..U+009F as `\u{9b}`
//! (a terminal may take U+009B as CSI with no ESC in sight). Everything else, non-ASCII
//! letters included, is printed as it is. A backslash is not escaped: the escapes are
//! for a person to read, not to be parsed back.

use std::borrow::Cow;
use std::fmt::Write as _;

use serde_json::Value;

/// Whether a text's own line breaks are printed as line breaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lines {
    /// One line of a table or a message: a newline and a tab are escaped too.
    Escape,
    /// A log printed as a block of lines: its newlines and tabs are kept (a tab moves
    /// the cursor right and nothing else); every other control is escaped.
    Keep,
}

/// Whether `c` is escaped in `lines` mode.
fn escaped(c: char, lines: Lines) -> bool {
    match c {
        '\n' | '\t' => lines == Lines::Escape,
        '\u{0}'..='\u{1f}' | '\u{7f}'..='\u{9f}' => true,
        _ => false,
    }
}

/// `text` with its control characters shown as escapes (see the module's doc): the
/// text itself when it has none.
pub fn escape(text: &str, lines: Lines) -> Cow<'_, str> {
    if !text.chars().any(|c| escaped(c, lines)) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if !escaped(c, lines) {
            out.push(c);
            continue;
        }
        // Writing to a String cannot fail.
        let _ = match c {
            '\n' => write!(out, "\\n"),
            '\r' => write!(out, "\\r"),
            '\t' => write!(out, "\\t"),
            '\u{0}'..='\u{7f}' => write!(out, "\\x{:02x}", u32::from(c)),
            _ => write!(out, "\\u{{{:x}}}", u32::from(c)),
        };
    }
    Cow::Owned(out)
}

/// One line's worth of server text: [`escape`] with [`Lines::Escape`].
pub fn text(text: &str) -> Cow<'_, str> {
    escape(text, Lines::Escape)
}

/// A log printed as lines: [`escape`] with [`Lines::Keep`].
pub fn log(text: &str) -> Cow<'_, str> {
    escape(text, Lines::Keep)
}

/// A JSON value of a server's answer shown in a line, as JSON (`12`, `null`,
/// `"a name"`), escaped: a server that sends a string where a number belongs gets its
/// text shown, not obeyed.
pub fn value(v: &Value) -> String {
    text(&v.to_string()).into_owned()
}

/// `v` as pretty-printed JSON that is still valid JSON and holds no control character
/// outside its layout: serde_json writes the C0 controls in strings as `\u001b` and the
/// like, and here DEL and the C1 controls become `\u007f`..`\u009f` too (they can only
/// stand inside strings, where JSON allows that form).
///
/// # Errors
/// A value serde_json cannot write (none that came from parsing JSON).
pub fn json(v: &Value) -> serde_json::Result<String> {
    let pretty = serde_json::to_string_pretty(v)?;
    if !pretty.chars().any(|c| ('\u{7f}'..='\u{9f}').contains(&c)) {
        return Ok(pretty);
    }
    let mut out = String::with_capacity(pretty.len() + 16);
    for c in pretty.chars() {
        if ('\u{7f}'..='\u{9f}').contains(&c) {
            let _ = write!(out, "\\u{:04x}", u32::from(c));
        } else {
            out.push(c);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No byte that a terminal acts on: C0 but for `keep`, DEL, and C1 as UTF-8.
    fn inert(s: &str, keep: &[char]) -> bool {
        s.chars()
            .all(|c| keep.contains(&c) || !(c < ' ' || ('\u{7f}'..='\u{9f}').contains(&c)))
    }

    #[test]
    fn plain_text_and_other_scripts_are_printed_as_they_are() {
        for s in ["gen-12-s1", "équipe ß 迷路 🐭", "a\\x1b b", ""] {
            assert!(matches!(text(s), Cow::Borrowed(_)), "{s}");
            assert_eq!(text(s), s);
            assert_eq!(log(s), s);
        }
    }

    #[test]
    fn escape_sequences_are_shown_not_obeyed() {
        // OSC 52 (clipboard), a title, erase and CSI by C1, a carriage return.
        let hostile =
            "a\u{1b}]52;c;ZXZpbA==\u{7}b\u{1b}]0;title\u{1b}\\\u{1b}[2J\u{9b}31mc\rd\u{8}\u{7f}";
        let shown = text(hostile);
        assert_eq!(
            shown,
            "a\\x1b]52;c;ZXZpbA==\\x07b\\x1b]0;title\\x1b\\\\x1b[2J\\u{9b}31mc\\rd\\x08\\x7f"
        );
        assert!(inert(&shown, &[]), "{shown:?}");
        assert_eq!(text("\u{0}\u{80}\u{9f}\u{a0}"), "\\x00\\u{80}\\u{9f}\u{a0}");
    }

    #[test]
    fn a_log_keeps_its_lines_and_tabs_and_nothing_else() {
        let log_text = "line 1\n\tline 2\r\n\u{1b}[1Aover\u{85}";
        let shown = log(log_text);
        assert_eq!(shown, "line 1\n\tline 2\\r\n\\x1b[1Aover\\u{85}");
        assert!(inert(&shown, &['\n', '\t']), "{shown:?}");
        // In one line, the same breaks are escaped.
        assert_eq!(text("a\nb\tc"), "a\\nb\\tc");
    }

    #[test]
    fn escaping_twice_changes_nothing_more() {
        let once = text("x\u{1b}[2J\u{9b}\r").into_owned();
        assert_eq!(text(&once), once);
    }

    #[test]
    fn a_value_is_shown_as_json_with_its_controls_escaped() {
        assert_eq!(value(&Value::from(12)), "12");
        assert_eq!(value(&Value::Null), "null");
        let v = Value::from("m\u{1b}]52;c;x\u{7}\u{9b}");
        let shown = value(&v);
        assert!(inert(&shown, &[]), "{shown:?}");
        assert!(shown.contains("\\u{9b}"), "{shown}");
    }

    #[test]
    fn json_output_stays_valid_json_and_inert() {
        let v = serde_json::json!({
            "name": "m\u{1b}[2J\u{9b}\u{7f}\r\n",
            "list": ["\u{85}", 1, null],
        });
        let out = json(&v).unwrap();
        assert!(inert(&out, &['\n']), "{out:?}");
        assert!(out.contains("\\u009b") && out.contains("\\u001b"), "{out}");
        let back: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(back, v);
        // Nothing to escape: serde_json's own text.
        let plain = serde_json::json!({"a": "b"});
        assert_eq!(
            json(&plain).unwrap(),
            serde_json::to_string_pretty(&plain).unwrap()
        );
    }
}
