//! One bot's side of a match: start it, exchange one sense message for one answer at a
//! time, end it. [`Session::exchange`] returns a [`Verdict`] per step, so the match loop
//! in [`super::run_match`] stays a short loop over verdicts.

mod limits;
mod mms;
mod waiting;

use std::pin::Pin;
use std::time::{Duration, Instant};

use tokio::io::AsyncWriteExt;
use tokio::time::timeout_at;

use super::framing;
use super::outcome::{Failure, LimitHit, MatchStatus};
use super::process::{self, BotOutput, BotProcess, BotStdin, LimitKind};
use super::{EXIT_GRACE, Limits, WALL_BACKSTOP_FACTOR};
use crate::engine::Action;
use crate::engine::game::Sense;
use crate::protocol::{EXCERPT_BYTES, ProtocolError, ServerMessage, excerpt};

/// The start of the reason for a bot that stopped answering (rewritten with its exit
/// status and last stderr line once it has ended).
/// How often the whole-match limits are looked at while the bot thinks.
/// The longest a match keeps its thread from the runtime's other tasks (a worker's
/// lease renewal, a shutdown) while every answer comes within [`NEAR_WAIT`].
pub(super) const TURN_EVERY: Duration = Duration::from_millis(10);
pub(super) const WATCHDOG_PERIOD: Duration = Duration::from_millis(25);

pub const CLOSED_STDOUT: &str = "the bot closed its stdout (or exited)";

/// Added to a timeout at step 1: the usual cause is an answer left in an output buffer.
pub const STARTUP_HINT: &str = " (if the bot did print an answer, it may still sit in its output buffer: \
     flush stdout after every line, e.g. fflush(stdout) in C or print(..., flush=True) in Python; \
     see docs/PROTOCOL.md \"Flush every answer\")";

/// What one step's exchange gave.
#[derive(Debug)]
pub enum Verdict {
    /// A valid answer, with its wall time and the CPU time all the bot's processes used.
    Answer {
        /// The decoded answer.
        action: Action,
        /// From the sense message (first step: the process start) to the answer, in µs.
        answer_us: u64,
        /// CPU time of every process of the bot over the step, in µs.
        cpu_us: Option<u64>,
        /// The answer's `debug` field, as sent.
        debug: Option<Box<serde_json::value::RawValue>>,
    },
    /// The bot failed: timeout, crash, protocol error or a limit.
    Fault(MatchStatus, Failure),
}

/// How the bot ended.
#[derive(Debug, Default)]
pub struct Ended {
    /// The outer process's exit status, if it ended in time.
    pub exit: Option<std::process::ExitStatus>,
    /// The end of its stderr.
    pub stderr_tail: String,
    /// CPU time of all its processes over the match, in ms, with what its floods of
    /// output were charged.
    pub cpu_ms: Option<u64>,
    /// What its floods of output were charged, in ms ([`super::flood`]).
    pub charged_ms: u64,
    /// Stderr lines not yet handed out by [`Session::take_stderr_lines`].
    pub late_stderr: Vec<String>,
}

/// A running bot and its pipes.
pub struct Session {
    process: BotProcess,
    stdin: BotStdin,
    replies: framing::ReplyReader<BotOutput>,
    stderr: framing::StderrReader<BotOutput>,
    started: Instant,
    limits: Limits,
    /// When the match passes its wall-clock ceiling ([`Limits::match_wall_clock`]).
    match_deadline: Option<Instant>,
    cpu_mark: Option<u64>,
    /// Whether the bot's CPU time can be read: the time limits count it, else they
    /// count wall-clock time.
    cpu_counted: bool,
    /// What is left of the match's time bank, in µs.
    bank_left_us: u64,
    /// While an answer is waited for: the CPU counter when it was asked and the CPU
    /// time it may use, in µs (looked at with the whole-match limits).
    cpu_cap: Option<(u64, u64)>,
    watchdog: tokio::time::Interval,
    /// The time limit of the step being asked, for a wait through the runtime: one
    /// timer for the whole match, moved to each step's deadline (a timer made per step
    /// costs its registration each time).
    step_limit: Pin<Box<tokio::time::Sleep>>,
    /// When the whole-match limits are next looked at by a wait on the match's thread.
    watch_at: Instant,
    /// When the runtime last had a turn.
    turned_at: Instant,
    /// The operator's runtime folders as the bot's stderr shows them, and the neutral
    /// name each is shown as instead (`/runtimes/NAME`): a traceback through a
    /// runtime's library names no folder of the server's.
    redact: Vec<(String, String)>,
}

/// The operator's runtimes of `sandbox` as (their folder, `/runtimes/NAME`), longest
/// folder first (a folder inside another is replaced first).
fn runtime_redactions(sandbox: &super::Sandbox) -> Vec<(String, String)> {
    let super::Sandbox::Full(full) = sandbox else {
        return Vec::new();
    };
    let mut out: Vec<(String, String)> = full
        .runtimes
        .iter()
        .map(|r| {
            (
                r.prefix.to_string_lossy().into_owned(),
                format!("/runtimes/{}", super::runtimes::name_of(r)),
            )
        })
        .filter(|(from, _)| from.len() > 1)
        .collect();
    out.sort_by_key(|(from, _)| std::cmp::Reverse(from.len()));
    out
}

/// `line` with each runtime folder of `redact` replaced by its neutral name.
fn redacted(redact: &[(String, String)], line: String) -> String {
    if redact.iter().all(|(from, _)| !line.contains(from.as_str())) {
        return line;
    }
    let mut line = line;
    for (from, to) in redact {
        if line.contains(from.as_str()) {
            line = line.replace(from.as_str(), to);
        }
    }
    line
}

/// One step's answer being waited for: since when and under which limits.
pub(super) struct Ask {
    since: Instant,
    step: u32,
    limit: Option<Duration>,
    allowed_us: Option<u64>,
    /// The CPU counter when it was asked.
    mark: u64,
    /// The wall-clock backstop (moved out with the CPU time used).
    deadline: Option<Instant>,
    factor: u32,
}

/// How a wait for an answer ended.
pub(super) enum Waited {
    /// The reply pipe holds what is next (or could not be read).
    Got(std::io::Result<framing::Next>),
    /// The step's deadline passed.
    TimedOut,
    /// A whole-match limit was hit.
    Limit(LimitKind),
    /// The step used more CPU time than it may: (used, allowed), in µs.
    CpuOver(u64, u64),
    /// Nothing yet on the match's thread: wait through the runtime.
    Later,
}

impl Session {
    /// Starts the bot and sends it the start message.
    ///
    /// # Errors
    /// The failure to record when it cannot be started or refuses the start message.
    /// With `echo_stderr`, the bot's stderr lines are also printed on ours as they come.
    pub fn start(
        launch: &process::Launch<'_>,
        limits: Limits,
        echo_stderr: bool,
    ) -> Result<Session, Box<Failure>> {
        let started = Instant::now();
        let mut process = process::spawn(launch).map_err(|e| {
            Box::new(Failure {
                reason: e.to_string(),
                ..Failure::default()
            })
        })?;
        // The pipes were requested in `spawn`; their absence would be a bug there.
        let (stdin, stdout, stderr) = process
            .take_stdio()
            .expect("the pipes are made by process::spawn");
        let mut watchdog = tokio::time::interval(WATCHDOG_PERIOD);
        watchdog.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let cpu_counted = process.cpu_us().is_some();
        Ok(Session {
            stderr: framing::StderrReader::new(stderr, framing::STDERR_TAIL_BYTES, echo_stderr),
            replies: framing::ReplyReader::new(stdout),
            stdin,
            started,
            limits,
            match_deadline: limits.match_wall_clock().map(|c| started + c),
            cpu_mark: Some(0),
            cpu_counted,
            bank_left_us: limits.time_bank.as_micros() as u64,
            cpu_cap: None,
            watchdog,
            step_limit: Box::pin(tokio::time::sleep_until(started.into())),
            watch_at: started + WATCHDOG_PERIOD,
            turned_at: started,
            redact: runtime_redactions(launch.sandbox),
            process,
        })
    }

    /// The bot's pid (its process group id).
    pub fn pid(&self) -> Option<u32> {
        self.process.pid
    }

    /// The bot's stderr lines read since the last call (bounded in total by
    /// [`framing::STDERR_TRACE_BYTES`]). Stderr is read while the bot is waited for,
    /// each answer only after the stderr written before it, so a line written before
    /// an answer is never handed on after it.
    pub fn take_stderr_lines(&mut self) -> Vec<String> {
        let lines = self.stderr.take_lines();
        if self.redact.is_empty() {
            return lines;
        }
        lines
            .into_iter()
            .map(|l| redacted(&self.redact, l))
            .collect()
    }

    /// Sends `message` within the startup limit (the start message).
    pub async fn greet(&mut self, message: &ServerMessage) -> Result<(), (MatchStatus, Failure)> {
        let deadline = self
            .limits
            .startup_timeout
            .map(|l| (self.started + l).into());
        send(&mut self.stdin, message, deadline)
            .await
            .map_err(|e| write_failure(e, 0))
    }

    /// Asks the bot for one step and waits for its answer under the time limit, looking
    /// at the whole-match limits meanwhile.
    ///
    /// The sense is written and the answer waited for on the match's thread first
    /// (`waiting::NEAR_WAIT`), then through the runtime; either way every stderr byte the bot
    /// wrote before its answer is read before the answer.
    pub async fn exchange(&mut self, sense: &Sense) -> Verdict {
        let mut ask = self.ask(sense).await;
        let line = ServerMessage::sense(sense).to_line();
        if let Err(e) = self.send_sense(line.as_bytes(), ask.deadline).await {
            let (status, failure) = write_failure(e, sense.step);
            return self.limit_or(Verdict::Fault(status, failure), sense.step);
        }
        if let Err(verdict) = self.wait_line(&mut ask).await {
            return *verdict;
        }
        let (answer_us, cpu_us) = match self.answered(&ask) {
            Ok(times) => times,
            Err(verdict) => return *verdict,
        };
        let line = self.replies.line();
        match crate::protocol::decode_answer(line) {
            Ok(answer) => Verdict::Answer {
                action: answer.action,
                answer_us,
                cpu_us,
                debug: answer.debug,
            },
            Err(e) => protocol_fault(e, line, sense.step),
        }
    }

    /// Starts timing the answer to `sense`: its limit, the CPU time it may use, and the
    /// wall-clock backstop.
    async fn ask(&mut self, sense: &Sense) -> Ask {
        if self.turned_at.elapsed() >= TURN_EVERY {
            tokio::task::yield_now().await;
            self.turned_at = Instant::now();
        }
        let sent_at = Instant::now();
        self.stderr.meter.begin_step();
        // PROTOCOL-v1: the first answer is timed from the process start.
        let (since, limit) = if sense.step == 1 {
            (self.started, self.limits.startup_timeout)
        } else {
            (sent_at, self.limits.move_timeout)
        };
        // The CPU time this answer may use: its limit, and for a move what is left of
        // the bank. Without a CPU counter, the limit is wall-clock time.
        let allowed_us = limit.map(|l| {
            let bank = if sense.step == 1 {
                0
            } else {
                self.bank_left_us
            };
            l.as_micros() as u64 + bank
        });
        let mark = self.cpu_mark.unwrap_or(0);
        self.cpu_cap = allowed_us.filter(|_| self.cpu_counted).map(|a| (mark, a));
        let factor = if self.cpu_counted {
            WALL_BACKSTOP_FACTOR
        } else {
            1
        };
        Ask {
            since,
            step: sense.step,
            limit,
            allowed_us,
            mark,
            deadline: self.within_match(limit.map(|l| since + l * factor)),
            factor,
        }
    }

    /// `deadline`, or the match's wall-clock ceiling if that comes first.
    fn within_match(&self, deadline: Option<Instant>) -> Option<Instant> {
        match (deadline, self.match_deadline) {
            (Some(d), Some(m)) => Some(d.min(m)),
            (d, m) => d.or(m),
        }
    }

    /// Whether the match has passed its wall-clock ceiling.
    fn past_ceiling(&self) -> bool {
        self.match_deadline.is_some_and(|m| Instant::now() >= m)
    }

    /// Sends the end message (v1 bots), closes stdin, gives the bot [`EXIT_GRACE`] to exit, then
    /// kills every process it has left and reaps it.
    pub async fn finish(mut self, end: Option<&ServerMessage>) -> Ended {
        let grace = tokio::time::Instant::now() + EXIT_GRACE;
        // Without a cgroup the CPU time is read from live processes: read it now too.
        let cpu_before = self.process.cpu_us();
        if let Some(end) = end {
            let _ = send(&mut self.stdin, end, Some(grace)).await;
        }
        drop(self.stdin);
        // Its stderr is read meanwhile: a bot blocked on a full pipe could not exit.
        let exited = self.stderr.drain_while(self.process.wait());
        let status = timeout_at(grace, exited).await.ok().and_then(Result::ok);
        let charged_us = self.stderr.meter.charged_us() + self.stderr.meter.step_charge_us();
        let cpu_us = match (cpu_before, self.process.cpu_us()) {
            (Some(a), Some(b)) => Some(a.max(b) + charged_us),
            (a, b) => a.or(b).map(|us| us + charged_us),
        };
        // Kill everything even when the bot exited: its children may linger.
        self.process.kill_all();
        let exit = match status {
            Some(s) => Some(s),
            None => self.process.wait().await.ok(),
        };
        let (stderr_tail, late_stderr) = self.stderr.finish(EXIT_GRACE).await;
        let stderr_tail = redacted(&self.redact, stderr_tail);
        let late_stderr = late_stderr
            .into_iter()
            .map(|l| redacted(&self.redact, l))
            .collect();
        Ended {
            exit,
            stderr_tail,
            cpu_ms: cpu_us.map(|us| us / 1000),
            charged_ms: charged_us / 1000,
            late_stderr,
        }
    }
}

/// The status and failure for a limit the bot went over.
pub fn limit_failure(kind: LimitKind, limits: &Limits, step: u32) -> (MatchStatus, Failure) {
    let (status, name, value, unit, what) = match kind {
        LimitKind::Memory => (
            MatchStatus::MemoryLimit,
            "memory",
            limits.memory_limit_mb.unwrap_or(0),
            "MiB",
            "the bot's processes together held more memory than",
        ),
        LimitKind::Processes => (
            MatchStatus::ProcessLimit,
            "processes",
            u64::from(limits.process_limit.unwrap_or(0)),
            "processes",
            "the bot tried to run more processes and threads at once than",
        ),
        LimitKind::Scratch => (
            MatchStatus::ScratchLimit,
            "scratch",
            limits.scratch_mb,
            "MiB",
            "the bot filled its scratch area of",
        ),
    };
    let mut f = failure(format!("{what} the limit of {value} {unit}"), step);
    f.limit = Some(LimitHit {
        name: name.into(),
        value,
        unit: unit.into(),
    });
    (status, f)
}

/// `verdict` with the time limit that ended it named (`cpu_time` or `wall_clock`, in ms),
/// unless a whole-match limit explained it first.
pub(super) fn with_time_limit(verdict: Verdict, name: &str, value_ms: u64) -> Verdict {
    match verdict {
        Verdict::Fault(MatchStatus::Timeout, mut f) if f.limit.is_none() => {
            f.limit = Some(LimitHit {
                name: name.into(),
                value: value_ms,
                unit: "ms".into(),
            });
            Verdict::Fault(MatchStatus::Timeout, f)
        }
        v => v,
    }
}

pub(super) fn failure(reason: String, step: u32) -> Failure {
    Failure {
        reason,
        step: Some(step),
        ..Failure::default()
    }
}

pub(super) fn protocol_fault(e: ProtocolError, line: &[u8], step: u32) -> Verdict {
    let mut f = failure(e.to_string(), step);
    f.line = Some(excerpt(line, EXCERPT_BYTES));
    Verdict::Fault(MatchStatus::ProtocolError, f)
}

/// Writes one message line to the bot, within `deadline` if given.
async fn send(
    stdin: &mut BotStdin,
    message: &ServerMessage,
    deadline: Option<tokio::time::Instant>,
) -> std::io::Result<()> {
    send_bytes(stdin, message.to_line().as_bytes(), deadline).await
}

/// Writes `bytes` to the bot, within `deadline` if given.
pub(super) async fn send_bytes(
    stdin: &mut BotStdin,
    bytes: &[u8],
    deadline: Option<tokio::time::Instant>,
) -> std::io::Result<()> {
    let write = async {
        stdin.write_all(bytes).await?;
        stdin.flush().await
    };
    match deadline {
        Some(d) => timeout_at(d, write).await.unwrap_or_else(|_| {
            Err(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                "the bot did not read its stdin in time",
            ))
        }),
        None => write.await,
    }
}

pub(super) fn write_failure(e: std::io::Error, step: u32) -> (MatchStatus, Failure) {
    let status = if e.kind() == std::io::ErrorKind::TimedOut {
        MatchStatus::Timeout
    } else {
        MatchStatus::Crashed
    };
    let mut f = failure(format!("could not write to the bot's stdin: {e}"), step);
    if step == 0 {
        f.step = None;
    }
    (status, f)
}
