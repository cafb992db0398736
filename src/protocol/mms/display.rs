//! The mouse's display commands (colours, texts, walls it draws in the simulator), kept
//! within their budget and handed to the replay as the step's drawing.

use super::{MAX_CELL_TEXT_CHARS, MmsError, Mouse};

impl Mouse {
    /// Applies a display command to the drawing; false when its arguments are not
    /// ones mms takes (a cell outside the maze, an unknown colour or side).
    pub(super) fn draw(&mut self, command: &str, args: &[&str]) -> bool {
        let dim = self.dim;
        let cell = |args: &[&str]| -> Option<(i32, i32)> {
            let x: i32 = args.first()?.parse().ok()?;
            let y: i32 = args.get(1)?.parse().ok()?;
            (x >= 0 && y >= 0 && x < dim && y < dim).then_some((x, y))
        };
        let d = &mut self.display;
        match (command, args.len()) {
            ("setColor", 3) => {
                let (Some(c), Some(color)) = (cell(args), args[2].chars().next()) else {
                    return false;
                };
                let Some(hex) = COLORS.iter().find(|(k, _)| *k == color).map(|(_, h)| *h) else {
                    return false;
                };
                if args[2].chars().count() != 1 {
                    return false;
                }
                d.colors.insert(c, hex);
                d.changed[0] = true;
            }
            ("clearColor", 2) => {
                let Some(c) = cell(args) else { return false };
                d.changed[0] |= d.colors.remove(&c).is_some();
            }
            ("clearAllColor", 0) => {
                d.changed[0] |= !d.colors.is_empty();
                d.colors.clear();
            }
            ("setText", n) if n >= 2 => {
                let Some(c) = cell(args) else { return false };
                let text: String = args[2..]
                    .join(" ")
                    .chars()
                    .take(MAX_CELL_TEXT_CHARS)
                    .collect();
                d.texts.insert(c, text);
                d.changed[1] = true;
            }
            ("clearText", 2) => {
                let Some(c) = cell(args) else { return false };
                d.changed[1] |= d.texts.remove(&c).is_some();
            }
            ("clearAllText", 0) => {
                d.changed[1] |= !d.texts.is_empty();
                d.texts.clear();
            }
            ("setWall" | "clearWall", 3) => {
                let Some((x, y)) = cell(args) else {
                    return false;
                };
                let side = match args[2] {
                    "n" => 0,
                    "e" => 1,
                    "s" => 2,
                    "w" => 3,
                    _ => return false,
                };
                let changed = if command == "setWall" {
                    d.walls.insert((x, y, side))
                } else {
                    d.walls.remove(&(x, y, side))
                };
                d.changed[2] |= changed;
            }
            _ => return false,
        }
        true
    }

    /// The drawing's fields that changed since the last call, as the replay's debug
    /// object (docs/PROTOCOL.md, "Debug drawing": `colors`, `cells`, `walls`; each field
    /// whole, as the viewer keeps the latest of each); `None` when nothing changed.
    pub fn take_drawing(&mut self) -> Option<String> {
        let d = &mut self.display;
        if !d.changed.iter().any(|c| *c) {
            return None;
        }
        let mut object = serde_json::Map::new();
        if d.changed[0] {
            let colors: Vec<serde_json::Value> = d
                .colors
                .iter()
                .map(|((x, y), hex)| serde_json::json!([x, y, hex]))
                .collect();
            object.insert("colors".into(), colors.into());
        }
        if d.changed[1] {
            let cells: Vec<serde_json::Value> = d
                .texts
                .iter()
                .map(|((x, y), t)| serde_json::json!([x, y, t]))
                .collect();
            object.insert("cells".into(), cells.into());
        }
        if d.changed[2] {
            let walls: Vec<serde_json::Value> = d
                .walls
                .iter()
                .map(|(x, y, side)| {
                    let name = ["up", "right", "down", "left"][*side as usize];
                    serde_json::json!([x, y, name])
                })
                .collect();
            object.insert("walls".into(), walls.into());
        }
        d.changed = [false; 3];
        Some(serde_json::Value::Object(object).to_string())
    }

    pub(super) fn on_grid(&self, what: &str) -> Result<(), MmsError> {
        if self.mouse8 % 2 == 1 {
            return Err(MmsError(format!(
                "{what} while the mouse faces a diagonal (after a 45-degree turn): the task's \
                 robot faces and moves along the grid only"
            )));
        }
        Ok(())
    }
}

/// mms's colour letters and the colours the replay draws them with.
const COLORS: [(char, &str); 15] = [
    ('k', "#000000"),
    ('b', "#0000ff"),
    ('a', "#808080"),
    ('c', "#00ffff"),
    ('g', "#00ff00"),
    ('o', "#ffa500"),
    ('r', "#ff0000"),
    ('w', "#ffffff"),
    ('y', "#ffff00"),
    ('B', "#00008b"),
    ('C', "#008b8b"),
    ('A', "#a9a9a9"),
    ('G', "#006400"),
    ('R', "#8b0000"),
    ('Y', "#9b870c"),
];
