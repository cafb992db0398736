//! Protocol v1 for bots: read one JSON message per line from stdin, answer sense
//! messages with one line on stdout. Implement [`Bot`] and call [`run`].
//!
//! The server's messages are small and fixed, so a few lines of scanning read them; no
//! JSON library is needed. Print debug output with `eprintln!` (stderr is your log);
//! never `println!`, which would be taken as an answer.
//!
//! Debug drawing (docs/PROTOCOL.md, "Debug drawing"): override [`Bot::debug`] to attach a
//! [`DebugDraw`] to each answer; the replay viewer draws it as a layer over the maze.
//!
//! ```
//! use mazebot::protocol::DebugDraw;
//! let mut d = DebugDraw::new();
//! d.text("to the goal").path([(0, 0), (0, 1)]).wall(0, 1, 1).cell(0, 0, 7);
//! assert_eq!(
//!     d.to_json(),
//!     r#"{"text":"to the goal","walls":[[0,1,"right"]],"cells":[[0,0,7]],"path":[[0,0],[0,1]]}"#
//! );
//! ```

use std::fmt::Write as _;
use std::io::{BufRead, Write};

/// The server keeps at most this many bytes of one step's debug JSON.
pub const MAX_DEBUG_STEP_BYTES: usize = 16 * 1024;
/// The server keeps at most this many bytes of debug JSON per match.
pub const MAX_DEBUG_MATCH_BYTES: usize = 64 * 1024;

/// Wall sides, in the order of the direction numbers 0..3 (`map::UP`, `RIGHT`, `DOWN`,
/// `LEFT`).
pub const SIDES: [&str; 4] = ["up", "right", "down", "left"];

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
    /// Right after each `next_move` (by [`run`] only, so in-process studies that call
    /// `next_move` pay nothing): a debug object to send with that answer, for the
    /// replay viewer. `None` (the default) sends none.
    fn debug(&mut self) -> Option<DebugDraw> {
        None
    }
    /// Once, last: the end message's status (`finished`, `step_limit`, ...).
    fn end(&mut self, _status: &str) {}
}

/// A cell value of a debug drawing: a number, a short text, or nothing.
#[derive(Debug, Clone, PartialEq)]
pub enum DebugValue {
    /// `null`: nothing shown.
    Null,
    /// An integer.
    Int(i64),
    /// A number (NaN and infinities are sent as `null`).
    Float(f64),
    /// A short text.
    Text(String),
}

macro_rules! debug_value_from_int {
    ($($t:ty),*) => {$(
        impl From<$t> for DebugValue {
            fn from(v: $t) -> DebugValue {
                i64::try_from(v).map_or(DebugValue::Float(v as f64), DebugValue::Int)
            }
        }
    )*};
}
debug_value_from_int!(i8, i16, i32, i64, u8, u16, u32, u64, usize, isize);

impl From<f64> for DebugValue {
    fn from(v: f64) -> DebugValue {
        DebugValue::Float(v)
    }
}
impl From<f32> for DebugValue {
    fn from(v: f32) -> DebugValue {
        DebugValue::Float(f64::from(v))
    }
}
impl From<&str> for DebugValue {
    fn from(v: &str) -> DebugValue {
        DebugValue::Text(v.to_string())
    }
}
impl From<String> for DebugValue {
    fn from(v: String) -> DebugValue {
        DebugValue::Text(v)
    }
}
impl<T: Into<DebugValue>> From<Option<T>> for DebugValue {
    fn from(v: Option<T>) -> DebugValue {
        v.map_or(DebugValue::Null, Into::into)
    }
}

impl DebugValue {
    fn write_json(&self, out: &mut String) {
        match self {
            DebugValue::Null => out.push_str("null"),
            DebugValue::Int(i) => {
                if *i < 0 {
                    out.push('-');
                }
                push_uint(out, i.unsigned_abs());
            }
            DebugValue::Float(f) if f.is_finite() => {
                let _ = write!(out, "{f}");
            }
            DebugValue::Float(_) => out.push_str("null"),
            DebugValue::Text(t) => json_string(out, t),
        }
    }
}

/// Appends `v` in decimal (faster than `write!`, which matters for big grids).
fn push_uint(out: &mut String, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.push_str(std::str::from_utf8(&digits[i..]).unwrap_or("0"));
}

/// Appends `[x,y` (the start of a cell's item).
fn push_cell(out: &mut String, x: usize, y: usize) {
    out.push('[');
    push_uint(out, x as u64);
    out.push(',');
    push_uint(out, y as u64);
}

/// Appends `s` as a JSON string (quotes, backslashes and control characters escaped).
pub fn json_string(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if u32::from(c) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04x}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// A debug object for the replay viewer (docs/PROTOCOL.md, "Debug drawing"): what the
/// bot believes, drawn over the maze at each step. Every method returns the builder, so
/// calls chain. (0, 0) is the bottom-left cell, x to the right, y up. Fields are sticky
/// in the viewer (each shows the latest one sent), so send big ones only when they
/// change.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DebugDraw {
    text: Option<String>,
    walls: Option<String>,
    cells: Option<String>,
    grid: Option<String>,
    colors: Option<String>,
    path: Option<String>,
}

/// Appends one item to a list field's JSON (the items, comma-separated, no brackets).
fn push_item(field: &mut Option<String>, item: impl FnOnce(&mut String)) {
    let list = field.get_or_insert_with(String::new);
    if !list.is_empty() {
        list.push(',');
    }
    item(list);
}

impl DebugDraw {
    /// An empty debug object.
    pub fn new() -> DebugDraw {
        DebugDraw::default()
    }

    /// A line of text shown with the step (replaces an earlier one).
    pub fn text(&mut self, text: impl AsRef<str>) -> &mut Self {
        let mut out = String::new();
        json_string(&mut out, text.as_ref());
        self.text = Some(out);
        self
    }

    /// A wall the bot believes in, on `side` (0..3: up, right, down, left, as in
    /// [`crate::map`]) of cell (x, y). Another side is ignored.
    pub fn wall(&mut self, x: usize, y: usize, side: usize) -> &mut Self {
        if let Some(name) = SIDES.get(side) {
            push_item(&mut self.walls, |o| {
                push_cell(o, x, y);
                o.push_str(",\"");
                o.push_str(name);
                o.push_str("\"]");
            });
        }
        self
    }

    /// Several walls, `(x, y, side)` each. `walls([])` sends an empty list (clears).
    pub fn walls(&mut self, walls: impl IntoIterator<Item = (usize, usize, usize)>) -> &mut Self {
        self.walls.get_or_insert_with(String::new);
        for (x, y, side) in walls {
            self.wall(x, y, side);
        }
        self
    }

    /// A number or short text written in cell (x, y).
    pub fn cell(&mut self, x: usize, y: usize, value: impl Into<DebugValue>) -> &mut Self {
        let value = value.into();
        push_item(&mut self.cells, |o| {
            push_cell(o, x, y);
            o.push(',');
            value.write_json(o);
            o.push(']');
        });
        self
    }

    /// Values for the whole maze, `columns[x][y]` (one sequence per column, like the maze
    /// file): numbers, short texts or `None`. Replaces an earlier grid.
    pub fn grid<C, V>(&mut self, columns: impl IntoIterator<Item = C>) -> &mut Self
    where
        C: IntoIterator<Item = V>,
        V: Into<DebugValue>,
    {
        let mut out = String::from("[");
        for (i, column) in columns.into_iter().enumerate() {
            out.push_str(if i == 0 { "[" } else { ",[" });
            for (j, v) in column.into_iter().enumerate() {
                if j > 0 {
                    out.push(',');
                }
                v.into().write_json(&mut out);
            }
            out.push(']');
        }
        out.push(']');
        self.grid = Some(out);
        self
    }

    /// A cell colour, `#rgb` or `#rrggbb`; anything else is ignored.
    pub fn color(&mut self, x: usize, y: usize, color: &str) -> &mut Self {
        let hex = color.strip_prefix('#').unwrap_or("");
        if (hex.len() == 3 || hex.len() == 6) && hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            push_item(&mut self.colors, |o| {
                push_cell(o, x, y);
                o.push_str(",\"");
                o.push_str(color);
                o.push_str("\"]");
            });
        }
        self
    }

    /// No colours: an empty list, which clears the colours sent before.
    pub fn no_colors(&mut self) -> &mut Self {
        self.colors = Some(String::new());
        self
    }

    /// A planned path through the cells `(x, y)`, in order (replaces an earlier one).
    pub fn path(&mut self, cells: impl IntoIterator<Item = (usize, usize)>) -> &mut Self {
        let mut out = String::from("[");
        for (i, (x, y)) in cells.into_iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            push_cell(&mut out, x, y);
            out.push(']');
        }
        out.push(']');
        self.path = Some(out);
        self
    }

    /// Whether no field is set.
    pub fn is_empty(&self) -> bool {
        *self == DebugDraw::default()
    }

    /// The object as compact JSON.
    pub fn to_json(&self) -> String {
        let mut out = String::from("{");
        let lists = [
            ("walls", &self.walls),
            ("cells", &self.cells),
            ("colors", &self.colors),
        ];
        let mut add = |key: &str, raw: &str, list: bool| {
            if out.len() > 1 {
                out.push(',');
            }
            out.push('"');
            out.push_str(key);
            out.push_str("\":");
            if list {
                out.push('[');
            }
            out.push_str(raw);
            if list {
                out.push(']');
            }
        };
        if let Some(t) = &self.text {
            add("text", t, false);
        }
        for (key, field) in lists {
            if let Some(items) = field {
                add(key, items, true);
            }
        }
        if let Some(g) = &self.grid {
            add("grid", g, false);
        }
        if let Some(p) = &self.path {
            add("path", p, false);
        }
        out.push('}');
        out
    }
}

/// Runs `bot` until the end message or the end of stdin.
///
/// Each answer is one line, flushed at once, with the bot's [`Bot::debug`] object if it
/// has one. A debug object over [`MAX_DEBUG_STEP_BYTES`], or past
/// [`MAX_DEBUG_MATCH_BYTES`] in the match, is not sent (the server would drop it); a
/// line on stderr says so, once.
pub fn run<B: Bot>(mut bot: B) {
    let stdin = std::io::stdin();
    let mut out = std::io::stdout().lock();
    let (mut debug_used, mut warned_step, mut warned_match) = (0usize, false, false);
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
                let mut text = match bot.next_move(sensors, run, step) {
                    Answer::Move { rotation, movement } => {
                        format!("{{\"rotation\":{rotation},\"movement\":{movement}")
                    }
                    Answer::Reset => "{\"reset\":true".to_string(),
                };
                if let Some(debug) = bot.debug().filter(|d| !d.is_empty()) {
                    let json = debug.to_json();
                    if json.len() > MAX_DEBUG_STEP_BYTES {
                        if !std::mem::replace(&mut warned_step, true) {
                            eprintln!(
                                "mazebot: step {step}: debug object of {} bytes, over {MAX_DEBUG_STEP_BYTES}: not sent",
                                json.len()
                            );
                        }
                    } else if debug_used + json.len() > MAX_DEBUG_MATCH_BYTES {
                        if !std::mem::replace(&mut warned_match, true) {
                            eprintln!(
                                "mazebot: step {step}: the match's debug objects reached {MAX_DEBUG_MATCH_BYTES} bytes: no more are sent"
                            );
                        }
                    } else {
                        debug_used += json.len();
                        text.push_str(",\"debug\":");
                        text.push_str(&json);
                    }
                }
                text.push_str("}\n");
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

    #[test]
    fn debug_objects_are_valid_compact_json() {
        assert_eq!(DebugDraw::new().to_json(), "{}");
        assert!(DebugDraw::new().is_empty());
        let mut d = DebugDraw::new();
        d.text("a\"b\\c\nd\u{1}é")
            .walls([(0, 0, 1), (1, 1, 3), (2, 2, 9)])
            .cell(1, 2, f64::NAN)
            .cell(0, 0, "x")
            .cell(0, 1, 2.5)
            .color(1, 1, "#abc")
            .color(1, 1, "red")
            .color(0, 0, "#00ff7F")
            .grid(vec![vec![Some(1u32), None], vec![Some(2), Some(3)]])
            .path([(0, 0), (0, 1)]);
        assert_eq!(
            d.to_json(),
            concat!(
                r#"{"text":"a\"b\\c\nd\u0001é","#,
                r#""walls":[[0,0,"right"],[1,1,"left"]],"#,
                r#""cells":[[1,2,null],[0,0,"x"],[0,1,2.5]],"#,
                r##""colors":[[1,1,"#abc"],[0,0,"#00ff7F"]],"##,
                r#""grid":[[1,null],[2,3]],"path":[[0,0],[0,1]]}"#
            )
        );
        let mut clear = DebugDraw::new();
        clear.walls([]).no_colors().path([]);
        assert_eq!(clear.to_json(), r#"{"walls":[],"colors":[],"path":[]}"#);
        let mut text_grid = DebugDraw::new();
        text_grid.grid([["a", "b"]]);
        assert_eq!(text_grid.to_json(), r#"{"grid":[["a","b"]]}"#);
    }
}
