//! What a match produces: its status, the failure details and the match record that a
//! replay viewer reads and a user can re-run to the exact step.

use serde::{Deserialize, Serialize};

use crate::engine::game::{StepReport, Warning};

/// How a match ended (the `status` of PROTOCOL-v1's end message).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchStatus {
    /// Run 1 reached the goal room: the match has a score.
    Finished,
    /// The 1000-step budget ran out.
    StepLimit,
    /// The bot did not answer within its time limit.
    Timeout,
    /// The bot could not be started, exited, or closed its pipes before the end.
    Crashed,
    /// The bot sent something that is not a valid answer.
    ProtocolError,
    /// The bot's processes together held more resident memory than the match allows.
    MemoryLimit,
    /// The bot tried to run more processes or threads at once than the match allows.
    ProcessLimit,
    /// The bot filled its scratch area.
    ScratchLimit,
    /// The match was running each time the server died, more often than it is retried.
    Aborted,
}

impl MatchStatus {
    /// The wire name, e.g. `step_limit`.
    pub fn as_str(self) -> &'static str {
        match self {
            MatchStatus::Finished => "finished",
            MatchStatus::StepLimit => "step_limit",
            MatchStatus::Timeout => "timeout",
            MatchStatus::Crashed => "crashed",
            MatchStatus::ProtocolError => "protocol_error",
            MatchStatus::MemoryLimit => "memory_limit",
            MatchStatus::ProcessLimit => "process_limit",
            MatchStatus::ScratchLimit => "scratch_limit",
            MatchStatus::Aborted => "aborted",
        }
    }
}

impl std::fmt::Display for MatchStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Where a match is: waiting in the queue, being played, or ended with a final status.
/// Its wire and database name is [`MatchState::as_str`] (`queued`, `running`, or the
/// status's name).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchState {
    /// Waiting for a worker.
    Queued,
    /// A worker holds it and plays it.
    Running,
    /// Ended with this status.
    #[serde(untagged)]
    Ended(MatchStatus),
}

impl MatchState {
    /// Every state, the queue's first.
    pub const ALL: [MatchState; 11] = [
        MatchState::Queued,
        MatchState::Running,
        MatchState::Ended(MatchStatus::Finished),
        MatchState::Ended(MatchStatus::StepLimit),
        MatchState::Ended(MatchStatus::Timeout),
        MatchState::Ended(MatchStatus::Crashed),
        MatchState::Ended(MatchStatus::ProtocolError),
        MatchState::Ended(MatchStatus::MemoryLimit),
        MatchState::Ended(MatchStatus::ProcessLimit),
        MatchState::Ended(MatchStatus::ScratchLimit),
        MatchState::Ended(MatchStatus::Aborted),
    ];

    /// The wire and database name, e.g. `queued` or `step_limit`.
    pub fn as_str(self) -> &'static str {
        match self {
            MatchState::Queued => "queued",
            MatchState::Running => "running",
            MatchState::Ended(status) => status.as_str(),
        }
    }

    /// The final status, once the match has ended.
    pub fn ended(self) -> Option<MatchStatus> {
        match self {
            MatchState::Ended(status) => Some(status),
            _ => None,
        }
    }
}

impl From<MatchStatus> for MatchState {
    fn from(status: MatchStatus) -> Self {
        MatchState::Ended(status)
    }
}

impl std::str::FromStr for MatchState {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        MatchState::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = MatchState::ALL.iter().map(|m| m.as_str()).collect();
                format!("unknown status {s:?}: use one of {}", names.join(", "))
            })
    }
}

impl TryFrom<String> for MatchState {
    type Error = String;

    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl std::fmt::Display for MatchState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for MatchState {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// Why a bot's match ended early: kept with the record so the bot's author can see it.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failure {
    /// A sentence saying what went wrong.
    pub reason: String,
    /// The offending line, cut to 200 bytes (protocol errors).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<String>,
    /// The bot's exit code, if it exited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exit_code: Option<i32>,
    /// The signal that ended the bot, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<i32>,
    /// The step the failure happened at (the step that was asked and not answered).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<u32>,
    /// The limit that was hit, for the limit statuses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<LimitHit>,
}

/// A match limit that a bot went over: which one and its value.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LimitHit {
    /// `memory`, `processes` or `scratch`.
    pub name: String,
    /// The limit's value, in `unit`.
    pub value: u64,
    /// `MiB` or `processes`.
    pub unit: String,
}

/// The limits a match was played under.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LimitsRecord {
    /// The shared step budget.
    pub max_steps: u32,
    /// CPU time for the first answer, from the process start; `None`: no limit.
    pub startup_timeout_ms: Option<u64>,
    /// CPU time for every later answer; `None`: no limit.
    pub move_timeout_ms: Option<u64>,
    /// CPU time the moves may use over their limits, over the whole match (absent in
    /// records made before there was a bank: they had none, and wall-clock limits).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_bank_ms: Option<u64>,
    /// The most wall-clock time the match could last (absent in records made before
    /// matches had a ceiling, and without time limits).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub match_wall_clock_ms: Option<u64>,
    /// The bot's memory limit in MiB; `None`: no limit. In the sandbox it counts the
    /// resident memory of all the bot's processes together; without it, it is each
    /// process's address space.
    pub memory_limit_mb: Option<u64>,
    /// The most processes and threads the bot may have at once (sandbox only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub process_limit: Option<u32>,
    /// The size of the bot's writable scratch area in MiB (sandbox only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scratch_mb: Option<u64>,
    /// The isolation the bot ran under: `full` or `none`.
    #[serde(default = "sandbox_none")]
    pub sandbox: String,
}

fn sandbox_none() -> String {
    "none".to_string()
}

/// How long things took.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Timings {
    /// Wall time of the whole match, start of the process to its end, in ms.
    pub wall_ms: u64,
    /// CPU time (user + system) of all the bot's processes together, in ms, when it
    /// can be measured (in the sandbox: every process the bot made; without it: the
    /// bot process and its waited-for children).
    pub bot_cpu_ms: Option<u64>,
    /// The slowest answer, in microseconds.
    pub max_answer_us: u64,
    /// The mean answer time, in microseconds.
    pub mean_answer_us: u64,
}

/// One step of the trace: the referee's report, the bot's answer time, and what the bot
/// showed of its thinking (stderr lines, debug drawing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceStep {
    /// What the step did.
    #[serde(flatten)]
    pub report: StepReport,
    /// Time from sending the sense message (first step: from the process start) to the
    /// answer line, in microseconds.
    pub answer_us: u64,
    /// CPU time all the bot's processes used from sending the sense message to the
    /// answer, in microseconds, when it can be measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_us: Option<u64>,
    /// The bot's stderr lines that arrived while this step was asked and answered
    /// (bounded: see [`crate::runner::framing::STDERR_STEP_LINES`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stderr: Vec<String>,
    /// The answer's `debug` object (docs/PROTOCOL.md "Debug drawing"), as sent; the
    /// referee never reads it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub debug: Option<serde_json::Value>,
}

/// A note from the runner about the record itself (not a rule warning), e.g. that the
/// bot's debug output was cut to its limit.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Notice {
    /// The step it concerns.
    pub step: u32,
    /// A sentence for people.
    pub message: String,
}

/// Everything about one match: enough to show it, score it, and re-run it exactly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MatchRecord {
    /// The version of the referee that played it.
    pub engine_version: String,
    /// The bot protocol version.
    pub protocol: u32,
    /// `mms` when the bot was a mouse of the mms simulator, spoken to through the
    /// referee's translation (docs/PROTOCOL-mms.md); absent for protocol v1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bot_protocol: Option<String>,
    /// SHA-256 of the maze's canonical numeric text.
    pub maze_hash: String,
    /// The maze side.
    pub maze_dim: u32,
    /// The seed sent to the bot.
    pub seed: u64,
    /// The limits in force.
    pub limits: LimitsRecord,
    /// How the match ended.
    pub status: MatchStatus,
    /// The score, only when finished (3 decimals).
    pub score: Option<f64>,
    /// Steps of run 0, once a reset was accepted.
    pub run0_steps: Option<u32>,
    /// Steps of run 1, only when finished.
    pub run1_steps: Option<u32>,
    /// The counter `t` when the match ended (PROTOCOL-v1 "Counts in the result").
    pub total_steps: u32,
    /// Lenient-rule warnings.
    pub warnings: Vec<Warning>,
    /// Failure details when the bot misbehaved.
    pub error: Option<Failure>,
    /// The end of the bot's stderr (at most 64 KiB).
    pub stderr_tail: String,
    /// How long things took.
    pub timings: Timings,
    /// The bot's process id (also its process group id) while it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bot_pid: Option<u32>,
    /// The core the match ran on (referee and bot), when it was pinned to one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core: Option<usize>,
    /// Notes about the record: debug output or stderr lines that were cut.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notices: Vec<Notice>,
    /// The maze's canonical numeric text, so that a replay file alone is enough to
    /// watch the match (written by `mazearena run --replay`; the server keeps it apart).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maze_layout: Option<String>,
    /// What was played, for people: the bot, the maze and the seed (written by
    /// `mazearena run --replay`, shown by `mazearena replay`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub title: Option<String>,
    /// Every step, in order (left out of summaries).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub trace: Vec<TraceStep>,
}

impl MatchRecord {
    /// Removes what only the bot's owner (and the admin) may read: its stderr, per step
    /// and the tail. The debug drawing stays.
    pub fn without_stderr(mut self) -> MatchRecord {
        self.stderr_tail.clear();
        for step in &mut self.trace {
            step.stderr.clear();
        }
        self
    }

    /// The record without its trace, for summaries.
    pub fn summary(&self) -> MatchRecord {
        // Field by field: cloning the whole record would copy the trace only to drop it.
        MatchRecord {
            engine_version: self.engine_version.clone(),
            protocol: self.protocol,
            bot_protocol: self.bot_protocol.clone(),
            maze_hash: self.maze_hash.clone(),
            maze_dim: self.maze_dim,
            seed: self.seed,
            limits: self.limits.clone(),
            status: self.status,
            score: self.score,
            run0_steps: self.run0_steps,
            run1_steps: self.run1_steps,
            total_steps: self.total_steps,
            warnings: self.warnings.clone(),
            error: self.error.clone(),
            stderr_tail: self.stderr_tail.clone(),
            timings: self.timings,
            bot_pid: self.bot_pid,
            core: self.core,
            notices: self.notices.clone(),
            maze_layout: self.maze_layout.clone(),
            title: self.title.clone(),
            trace: Vec::new(),
        }
    }
}

/// What a match row keeps of its record for lists and pages, besides its columns (seed,
/// score, step counts) and its maze's (hash, side). Every field is optional: a match the
/// server ended without playing it (aborted, or its build failed) has only a status and
/// an error.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MatchSummary {
    /// The version of the referee that played it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub engine_version: Option<String>,
    /// The limits it was played under.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<LimitsRecord>,
    /// How it ended.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub status: Option<MatchStatus>,
    /// Lenient-rule warnings.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<Warning>,
    /// Why it did not finish, if it failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<Failure>,
    /// How long things took.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timings: Option<Timings>,
}

impl MatchSummary {
    /// The summary of a match the server ended with `status` without playing it.
    pub fn unplayed(status: MatchStatus, reason: &str) -> MatchSummary {
        MatchSummary {
            status: Some(status),
            error: Some(Failure {
                reason: reason.to_string(),
                ..Failure::default()
            }),
            ..MatchSummary::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_state_has_one_name_on_the_wire_and_in_the_database() {
        for state in MatchState::ALL {
            let name = state.as_str();
            assert_eq!(name.parse::<MatchState>(), Ok(state));
            assert_eq!(serde_json::to_value(state).unwrap(), name);
            assert_eq!(
                serde_json::from_value::<MatchState>(name.into()).unwrap(),
                state
            );
            if let Some(status) = state.ended() {
                assert_eq!(status.as_str(), name);
                assert_eq!(MatchState::from(status), state);
            }
        }
        let err = "done".parse::<MatchState>().unwrap_err();
        assert!(err.contains("queued") && err.contains("aborted"), "{err}");
    }
}
