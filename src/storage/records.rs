//! How a match's record is stored: compactly, apart from the match row.
//!
//! The match row keeps the score and step counts as columns and a small summary (what
//! lists and pages need besides: status, error, warnings, limits, timings, the referee's
//! version; see [`summary`]). The rest of the record, with its stderr tail, notices and
//! per-step trace, is one zstd-compressed value in `match_record`. Its usual encoding
//! ([`ENCODING_ANSWERS`]) keeps of each step only what the referee cannot work out
//! again: the bot's answer, its timings, its stderr lines and debug object. Everything
//! else (sensors, events, positions, headings, warnings) is replayed by the referee on
//! the maze when the record is read: the rules are a pure function of the answers. An
//! encoding is only used when reading it back gives the very same record (checked when
//! it is written, by replaying the answers); otherwise the whole record is kept as JSON
//! ([`ENCODING_JSON`]).

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::engine::{Action, Game, GameConfig, Maze, StepReport};
use crate::runner::outcome::{MatchSummary, Notice};
use crate::runner::{MatchRecord, TraceStep};

/// The whole record as JSON, compressed.
pub const ENCODING_JSON: i64 = 1;
/// As [`ENCODING_ANSWERS`], but with the rest of the record (all but its trace, stderr
/// tail and notices) in the row. Written by development builds before 0.2.0; still read.
pub const ENCODING_ANSWERS_WHOLE_ROW: i64 = 2;
/// What the row's [`summary`] leaves out, and per step only the answers and what the
/// bot showed, compressed; the rest of each step is replayed on the maze.
pub const ENCODING_ANSWERS: i64 = 3;

/// The zstd level: about 3 KB for a match of a few hundred steps, a few ms to write.
const LEVEL: i32 = 9;

/// The part of each step the referee cannot replay, by column. It borrows from the
/// record when written and owns its parts when read.
#[derive(Debug, Default, Serialize, Deserialize)]
struct Answers<'a> {
    /// Each answer as a small number (see [`action_code`]); 255: in `other_actions`.
    actions: Vec<u8>,
    /// The answers outside the rules (played leniently), by index in the trace.
    other_actions: BTreeMap<usize, Action>,
    answer_us: Vec<u64>,
    /// Each step's CPU time (written by [`ENCODING_ANSWERS_WHOLE_ROW`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    cpu_us: Vec<Option<u64>>,
    /// Each step's answer time less its CPU time: the bot's CPU time is most of its
    /// answer time, so these are small numbers, which compress better.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    cpu_lag_us: Vec<Option<i64>>,
    /// By index in the trace, the steps that have any.
    stderr: BTreeMap<usize, Cow<'a, [String]>>,
    debug: BTreeMap<usize, Cow<'a, serde_json::Value>>,
}

/// What the compact encoding stores besides the row's summary and columns. (The
/// fields before `stderr_tail` are absent from [`ENCODING_ANSWERS_WHOLE_ROW`].)
#[derive(Debug, Serialize, Deserialize)]
struct Stored<'a> {
    #[serde(default)]
    protocol: u32,
    #[serde(default)]
    seed: u64,
    #[serde(default)]
    score: Option<f64>,
    #[serde(default)]
    run0_steps: Option<u32>,
    #[serde(default)]
    run1_steps: Option<u32>,
    #[serde(default)]
    total_steps: u32,
    #[serde(default)]
    bot_pid: Option<u32>,
    #[serde(default)]
    core: Option<usize>,
    stderr_tail: Cow<'a, str>,
    notices: Cow<'a, [Notice]>,
    steps: Answers<'a>,
}

/// An answer within the rules as a number: 0-20 for a rotation of -90, 0 or 90 and a
/// movement of -3 to 3, 21 for a reset.
fn action_code(action: Action) -> Option<u8> {
    match action {
        Action::Reset { reset: true } => Some(21),
        Action::Move { rotation, movement } if (-3..=3).contains(&movement) => {
            let turn = match rotation {
                -90 => 0,
                0 => 1,
                90 => 2,
                _ => return None,
            };
            Some(turn * 7 + (movement + 3) as u8)
        }
        _ => None,
    }
}

fn code_action(code: u8) -> Option<Action> {
    match code {
        21 => Some(Action::RESET),
        0..=20 => Some(Action::turn_move(
            (i64::from(code) / 7 - 1) * 90,
            i64::from(code) % 7 - 3,
        )),
        _ => None,
    }
}

/// The summary the match row keeps: what lists and pages show of a match besides the
/// row's columns (score and step counts) and its maze (hash and side).
pub fn summary(record: &MatchRecord) -> MatchSummary {
    MatchSummary {
        engine_version: Some(record.engine_version.clone()),
        limits: Some(record.limits.clone()),
        status: Some(record.status),
        warnings: record.warnings.clone(),
        error: record.error.clone(),
        timings: Some(record.timings),
    }
}

/// Encodes `record` of a match on `maze`: its encoding and bytes. With
/// [`ENCODING_ANSWERS`], the bytes complete the row's [`summary`] of the record.
///
/// # Errors
/// The record cannot be serialised or compressed.
pub fn encode(record: &MatchRecord, maze: &Maze) -> Result<(i64, Vec<u8>), String> {
    let mut steps = Answers::default();
    for (i, s) in record.trace.iter().enumerate() {
        let code = action_code(s.report.action);
        steps.actions.push(code.unwrap_or(255));
        if code.is_none() {
            steps.other_actions.insert(i, s.report.action);
        }
        steps.answer_us.push(s.answer_us);
        steps
            .cpu_lag_us
            .push(s.cpu_us.map(|cpu| s.answer_us as i64 - cpu as i64));
        if !s.stderr.is_empty() {
            steps.stderr.insert(i, Cow::Borrowed(&s.stderr));
        }
        if let Some(d) = &s.debug {
            steps.debug.insert(i, Cow::Borrowed(d));
        }
    }
    let stored = Stored {
        protocol: record.protocol,
        seed: record.seed,
        score: record.score,
        run0_steps: record.run0_steps,
        run1_steps: record.run1_steps,
        total_steps: record.total_steps,
        bot_pid: record.bot_pid,
        core: record.core,
        stderr_tail: Cow::Borrowed(&record.stderr_tail),
        notices: Cow::Borrowed(&record.notices),
        steps,
    };
    let encode_err = |e: serde_json::Error| format!("cannot encode the match record: {e}");
    let (encoding, json) = if replays_the_same(&stored.steps, record, maze) {
        (
            ENCODING_ANSWERS,
            serde_json::to_vec(&stored).map_err(encode_err)?,
        )
    } else {
        let whole = MatchRecord {
            maze_layout: None,
            title: None,
            ..record.clone()
        };
        (
            ENCODING_JSON,
            serde_json::to_vec(&whole).map_err(encode_err)?,
        )
    };
    let data = compress(&json).map_err(|e| format!("cannot compress the match record: {e}"))?;
    Ok((encoding, data))
}

/// Whether reading `steps` back on `maze` gives `record`'s trace and maze. The rest of
/// the compact encoding is `record`'s own fields (and the row's [`summary`]) as they
/// are, so this is the part of the read-back that can differ: the replayed steps.
fn replays_the_same(steps: &Answers, record: &MatchRecord, maze: &Maze) -> bool {
    record.maze_hash == maze.hash()
        && record.maze_dim == maze.dim()
        && steps.actions.len() == record.trace.len()
        && replay_reports(steps, maze, record.limits.max_steps, |i, report| {
            (report == record.trace[i].report)
                .then_some(())
                .ok_or_else(|| format!("step {} replays otherwise", i + 1))
        })
        .is_ok()
}

/// `json` compressed at [`LEVEL`] with a compression context kept by the thread (a
/// fresh context costs about as much as compressing a record).
fn compress(json: &[u8]) -> std::io::Result<Vec<u8>> {
    thread_local! {
        static COMPRESSOR: RefCell<Option<zstd::bulk::Compressor<'static>>> =
            const { RefCell::new(None) };
    }
    COMPRESSOR.with_borrow_mut(|slot| {
        let compressor = match slot {
            Some(c) => c,
            None => slot.insert(zstd::bulk::Compressor::new(LEVEL)?),
        };
        compressor.compress(json)
    })
}

/// Decodes a stored record of a match on `maze`, whose row keeps `row_summary` (JSON).
///
/// # Errors
/// The bytes are not a record in that encoding, the row's summary is not one, or the
/// answers do not replay on the maze.
pub fn decode(
    encoding: i64,
    data: &[u8],
    row_summary: &str,
    maze: &Maze,
) -> Result<MatchRecord, String> {
    let json = zstd::stream::decode_all(data)
        .map_err(|e| format!("the stored match record cannot be decompressed: {e}"))?;
    let invalid = |e: serde_json::Error| format!("the stored match record is not valid: {e}");
    let invalid_row = |e: serde_json::Error| format!("the match's summary is not valid: {e}");
    match encoding {
        ENCODING_JSON => serde_json::from_slice(&json).map_err(invalid),
        ENCODING_ANSWERS => {
            let stored: Stored = serde_json::from_slice(&json).map_err(invalid)?;
            let summary = serde_json::from_str(row_summary).map_err(invalid_row)?;
            complete(stored, summary, maze)
        }
        ENCODING_ANSWERS_WHOLE_ROW => {
            let stored: Stored = serde_json::from_slice(&json).map_err(invalid)?;
            let head: MatchRecord = serde_json::from_str(row_summary).map_err(invalid_row)?;
            let trace = replay(stored.steps, maze, head.limits.max_steps)?;
            Ok(MatchRecord {
                stderr_tail: stored.stderr_tail.into_owned(),
                notices: stored.notices.into_owned(),
                trace,
                ..head
            })
        }
        other => Err(format!("unknown match record encoding {other}")),
    }
}

/// The whole record from its [`ENCODING_ANSWERS`] part, the row's summary and the maze.
fn complete(stored: Stored, summary: MatchSummary, maze: &Maze) -> Result<MatchRecord, String> {
    let missing = |what: &str| format!("the match's summary has no {what}");
    let limits = summary.limits.ok_or_else(|| missing("limits"))?;
    let trace = replay(stored.steps, maze, limits.max_steps)?;
    Ok(MatchRecord {
        engine_version: summary
            .engine_version
            .ok_or_else(|| missing("engine version"))?,
        protocol: stored.protocol,
        // Records of this encoding come from before mms mice.
        bot_protocol: None,
        maze_hash: maze.hash(),
        maze_dim: maze.dim(),
        seed: stored.seed,
        limits,
        status: summary.status.ok_or_else(|| missing("status"))?,
        score: stored.score,
        run0_steps: stored.run0_steps,
        run1_steps: stored.run1_steps,
        total_steps: stored.total_steps,
        warnings: summary.warnings,
        error: summary.error,
        stderr_tail: stored.stderr_tail.into_owned(),
        timings: summary.timings.ok_or_else(|| missing("timings"))?,
        bot_pid: stored.bot_pid,
        core: stored.core,
        notices: stored.notices.into_owned(),
        maze_layout: None,
        title: None,
        trace,
    })
}

/// Plays the stored answers again on `maze`.
fn replay(steps: Answers, maze: &Maze, max_steps: u32) -> Result<Vec<TraceStep>, String> {
    let mut reports = Vec::with_capacity(steps.actions.len());
    replay_reports(&steps, maze, max_steps, |_, report| {
        reports.push(report);
        Ok(())
    })?;
    let Answers {
        answer_us,
        cpu_us,
        cpu_lag_us,
        mut stderr,
        mut debug,
        ..
    } = steps;
    let by_lag = cpu_us.is_empty();
    Ok(reports
        .into_iter()
        .enumerate()
        .map(|(i, report)| TraceStep {
            report,
            answer_us: answer_us[i],
            cpu_us: if by_lag {
                cpu_lag_us[i].map(|lag| (answer_us[i] as i64 - lag) as u64)
            } else {
                cpu_us[i]
            },
            stderr: stderr.remove(&i).map(Cow::into_owned).unwrap_or_default(),
            debug: debug.remove(&i).map(Cow::into_owned),
        })
        .collect())
}

/// Plays the stored answers again on `maze`, handing each step's report to `each`
/// (with its index), after checking that the columns agree in length.
fn replay_reports(
    steps: &Answers,
    maze: &Maze,
    max_steps: u32,
    mut each: impl FnMut(usize, StepReport) -> Result<(), String>,
) -> Result<(), String> {
    let n = steps.actions.len();
    let cpu_len = if steps.cpu_us.is_empty() {
        steps.cpu_lag_us.len()
    } else {
        steps.cpu_us.len()
    };
    if steps.answer_us.len() != n || cpu_len != n {
        return Err("the stored steps' columns differ in length".into());
    }
    let mut game = Game::new(maze.clone(), GameConfig { max_steps });
    for i in 0..n {
        if game.begin_step().is_none() {
            return Err(format!(
                "the stored answers go on after the match ended (step {})",
                i + 1
            ));
        }
        let action = match steps.other_actions.get(&i) {
            Some(a) => *a,
            None => code_action(steps.actions[i])
                .ok_or_else(|| format!("step {}: no such stored answer", i + 1))?,
        };
        each(i, game.apply(action))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{generator, solver};
    use crate::runner::{LimitsRecord, MatchStatus, Timings};

    /// A record as the runner makes it: `actions` played on `maze`, with timings,
    /// stderr lines and debug objects on some steps.
    fn played(maze: &Maze, actions: &[Action]) -> MatchRecord {
        let mut game = Game::new(maze.clone(), GameConfig { max_steps: 1000 });
        let mut trace = Vec::new();
        for (i, a) in actions.iter().enumerate() {
            game.begin_step().unwrap();
            trace.push(TraceStep {
                report: game.apply(*a),
                answer_us: 100 + i as u64 * 7,
                cpu_us: (i % 2 == 0).then_some(40),
                stderr: if i % 3 == 0 {
                    vec![format!("step {i}")]
                } else {
                    Vec::new()
                },
                debug: (i % 4 == 0).then(|| serde_json::json!({"text": format!("at {i}")})),
            });
        }
        MatchRecord {
            engine_version: "t".into(),
            bot_protocol: None,
            protocol: 1,
            maze_hash: maze.hash(),
            maze_dim: maze.dim(),
            seed: 3,
            limits: LimitsRecord {
                max_steps: 1000,
                startup_timeout_ms: None,
                move_timeout_ms: None,
                time_bank_ms: None,
                match_wall_clock_ms: None,
                memory_limit_mb: None,
                process_limit: None,
                scratch_mb: None,
                sandbox: "none".into(),
            },
            status: MatchStatus::StepLimit,
            score: None,
            run0_steps: None,
            run1_steps: None,
            total_steps: game.t(),
            warnings: game.warnings().to_vec(),
            error: None,
            stderr_tail: "the tail\n".into(),
            timings: Timings::default(),
            bot_pid: Some(9),
            core: Some(1),
            notices: Vec::new(),
            maze_layout: None,
            title: None,
            trace,
        }
    }

    #[test]
    fn a_record_keeps_only_the_answers_and_reads_back_the_same() {
        let maze = generator::generate(12, 4).unwrap();
        let mut actions = solver::solve(&maze).unwrap().actions;
        // Lenient answers (warned, clamped) and a reset replay the same too.
        actions.insert(2, Action::turn_move(45, 7));
        actions.push(Action::RESET);
        actions.extend(solver::solve(&maze).unwrap().actions);
        let record = played(&maze, &actions);
        assert!(!record.warnings.is_empty());
        let (encoding, data) = encode(&record, &maze).unwrap();
        assert_eq!(encoding, ENCODING_ANSWERS);
        let row = serde_json::to_string(&summary(&record)).unwrap();
        let back = decode(encoding, &data, &row, &maze).unwrap();
        assert_eq!(back, record);
        for code in 0..=21 {
            assert_eq!(action_code(code_action(code).unwrap()), Some(code));
        }
        let json = serde_json::to_vec(&record).unwrap();
        assert!(
            data.len() * 5 < json.len(),
            "{} of {}",
            data.len(),
            json.len()
        );
    }

    #[test]
    fn a_trace_that_does_not_replay_is_kept_whole() {
        let maze = generator::generate(12, 4).unwrap();
        let mut record = played(&maze, &solver::solve(&maze).unwrap().actions);
        record.trace[1].report.sensors = [9, 9, 9];
        let (encoding, data) = encode(&record, &maze).unwrap();
        assert_eq!(encoding, ENCODING_JSON);
        let row = serde_json::to_string(&summary(&record)).unwrap();
        assert_eq!(decode(encoding, &data, &row, &maze).unwrap(), record);
        // Bytes that are not a record are an error, not a panic.
        assert!(decode(ENCODING_ANSWERS, b"nonsense", &row, &maze).is_err());
        assert!(decode(7, &data, &row, &maze).is_err());
        // Nor is a row without a summary.
        let (encoding, data) = encode(&played(&maze, &[Action::RESET]), &maze).unwrap();
        assert_eq!(encoding, ENCODING_ANSWERS);
        for row in ["", "{}", r#"{"status":"finished"}"#] {
            let err = decode(encoding, &data, row, &maze).unwrap_err();
            assert!(err.contains("summary"), "{err}");
        }
    }

    #[test]
    fn records_of_the_earlier_encoding_with_the_whole_row_still_read() {
        let maze = generator::generate(12, 4).unwrap();
        let record = played(&maze, &solver::solve(&maze).unwrap().actions);
        // As development builds wrote it: the record but its trace, stderr tail and
        // notices in the row; the answers and those in the bytes.
        let row = serde_json::to_string(&MatchRecord {
            trace: Vec::new(),
            stderr_tail: String::new(),
            ..record.clone()
        })
        .unwrap();
        let (_, data) = encode(&record, &maze).unwrap();
        let mut stored: serde_json::Value =
            serde_json::from_slice(&zstd::stream::decode_all(&data[..]).unwrap()).unwrap();
        stored
            .as_object_mut()
            .unwrap()
            .retain(|k, _| ["stderr_tail", "notices", "steps"].contains(&k.as_str()));
        let steps = stored["steps"].as_object_mut().unwrap();
        let lags = steps.remove("cpu_lag_us").unwrap();
        let cpu: Vec<Option<u64>> = record.trace.iter().map(|s| s.cpu_us).collect();
        assert_eq!(lags.as_array().unwrap().len(), cpu.len());
        steps.insert("cpu_us".into(), serde_json::to_value(cpu).unwrap());
        let old = zstd::bulk::compress(&serde_json::to_vec(&stored).unwrap(), LEVEL).unwrap();
        let back = decode(ENCODING_ANSWERS_WHOLE_ROW, &old, &row, &maze).unwrap();
        assert_eq!(back, record);
    }

    #[test]
    fn the_summary_leaves_out_the_bulky_parts() {
        let maze = generator::generate(12, 4).unwrap();
        let record = played(&maze, &solver::solve(&maze).unwrap().actions);
        let s = summary(&record);
        assert_eq!(
            (s.status, s.limits.as_ref(), s.timings),
            (
                Some(record.status),
                Some(&record.limits),
                Some(record.timings)
            )
        );
        // What the row's columns or the maze hold is not repeated.
        let row = serde_json::to_value(&s).unwrap();
        for key in [
            "seed",
            "score",
            "total_steps",
            "maze_hash",
            "stderr_tail",
            "trace",
        ] {
            assert!(row.get(key).is_none(), "{key} in {row}");
        }
    }
}
