//! What a match's trace keeps of the bot's thinking besides its answers: the `debug`
//! objects of the debug-drawing extension (docs/PROTOCOL.md "Debug drawing") and the
//! stderr lines written during each step, both bounded, with a notice when cut.

use serde_json::value::RawValue;

use super::framing::STDERR_STEP_LINES;
use super::outcome::{Notice, TraceStep};
use crate::protocol::{MAX_DEBUG_MATCH_BYTES, MAX_DEBUG_STEP_BYTES};

/// Keeps the bot's debug objects within [`MAX_DEBUG_STEP_BYTES`] per step and
/// [`MAX_DEBUG_MATCH_BYTES`] per match.
#[derive(Debug, Default)]
pub struct DebugBudget {
    used: usize,
    warned_size: bool,
    warned_kind: bool,
    warned_full: bool,
}

impl DebugBudget {
    /// The debug value to keep for `step`, or `None` with a notice pushed (once per
    /// kind of cut) when it is not an object or is over a limit.
    pub fn admit(
        &mut self,
        debug: Option<Box<RawValue>>,
        step: u32,
        notices: &mut Vec<Notice>,
    ) -> Option<serde_json::Value> {
        let raw = debug?;
        let text = raw.get();
        let mut note = |flag: &mut bool, message: String| {
            if !std::mem::replace(flag, true) {
                notices.push(Notice { step, message });
            }
        };
        if !text.starts_with('{') {
            note(
                &mut self.warned_kind,
                format!("step {step}: the debug value is not a JSON object; it is not kept"),
            );
            return None;
        }
        if text.len() > MAX_DEBUG_STEP_BYTES {
            note(
                &mut self.warned_size,
                format!(
                    "step {step}: the debug object has {} bytes, over the limit of {MAX_DEBUG_STEP_BYTES} per step; \
                     it is not kept (nor any other over the limit)",
                    text.len()
                ),
            );
            return None;
        }
        if self.used + text.len() > MAX_DEBUG_MATCH_BYTES {
            note(
                &mut self.warned_full,
                format!(
                    "step {step}: the match's debug objects reached the limit of {MAX_DEBUG_MATCH_BYTES} bytes; \
                     no later debug object is kept"
                ),
            );
            return None;
        }
        self.used += text.len();
        serde_json::from_str(text).ok()
    }
}

/// Gives `step` the stderr `lines` written during it, at most [`STDERR_STEP_LINES`],
/// with a notice when some are left out.
pub fn attach_stderr(step: &mut TraceStep, mut lines: Vec<String>, notices: &mut Vec<Notice>) {
    if lines.len() > STDERR_STEP_LINES {
        let cut = lines.len() - STDERR_STEP_LINES;
        lines.truncate(STDERR_STEP_LINES);
        notices.push(Notice {
            step: step.report.step,
            message: format!(
                "step {}: {cut} more stderr lines than the {STDERR_STEP_LINES} a step keeps \
                 (the stderr tail has the end)",
                step.report.step
            ),
        });
    }
    step.stderr.extend(lines);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(s: &str) -> Option<Box<RawValue>> {
        Some(RawValue::from_string(s.to_string()).unwrap())
    }

    #[test]
    fn objects_within_the_limits_are_kept() {
        let mut b = DebugBudget::default();
        let mut notices = Vec::new();
        let v = b.admit(raw(r#"{"text":"hi"}"#), 1, &mut notices).unwrap();
        assert_eq!(v["text"], "hi");
        assert!(notices.is_empty());
        assert!(b.admit(None, 2, &mut notices).is_none());
    }

    #[test]
    fn non_objects_and_oversized_objects_are_dropped_with_one_notice_each() {
        let mut b = DebugBudget::default();
        let mut notices = Vec::new();
        assert!(b.admit(raw("[1,2]"), 1, &mut notices).is_none());
        assert!(b.admit(raw("\"x\""), 2, &mut notices).is_none());
        let big = format!(r#"{{"text":"{}"}}"#, "x".repeat(MAX_DEBUG_STEP_BYTES));
        assert!(b.admit(raw(&big), 3, &mut notices).is_none());
        assert!(b.admit(raw(&big), 4, &mut notices).is_none());
        assert_eq!(notices.len(), 2, "{notices:?}");
        assert_eq!(notices[0].step, 1);
        assert_eq!(notices[1].step, 3);
    }

    #[test]
    fn the_match_budget_stops_later_objects() {
        let mut b = DebugBudget::default();
        let mut notices = Vec::new();
        let obj = format!(r#"{{"text":"{}"}}"#, "x".repeat(MAX_DEBUG_STEP_BYTES - 20));
        let fits = MAX_DEBUG_MATCH_BYTES / obj.len();
        for step in 0..fits as u32 {
            assert!(b.admit(raw(&obj), step, &mut notices).is_some());
        }
        assert!(b.admit(raw(&obj), 999, &mut notices).is_none());
        assert_eq!(notices.len(), 1);
        assert!(notices[0].message.contains("no later debug object"));
    }
}
