//! The bot runner: plays one match between one bot process and one maze.
//!
//! [`run_match`] starts the bot (see [`process`], in the [`sandbox`] unless told
//! otherwise), speaks protocol v1 with it one step at a time ([`session`]), drives the
//! pure [`Game`], and always returns a [`MatchRecord`]: a misbehaving bot is an outcome
//! recorded with its reason, never an error or a panic. Matches are plain futures, so
//! many can run at once in one process, each best on a thread of its own (as a worker's
//! and `mazearena run`'s are): a match waits for each answer on its thread for up to
//! 2 ms before it lets the runtime wait ([`session`]), so matches that share a thread
//! hold each other up by as much a step (their answer times count it). This module is
//! the only code that starts processes.

pub mod affinity;
pub mod botenv;
pub mod build;
pub mod flood;
pub mod framing;
pub mod outcome;
pub mod process;
pub mod runtimes;
pub mod sandbox;
pub mod session;
pub mod trace;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::engine::{Game, GameConfig, GameEnd, Maze};
use crate::protocol::{PROTOCOL_VERSION, ServerMessage};
pub use outcome::{
    Failure, LimitHit, LimitsRecord, MatchRecord, MatchState, MatchStatus, Timings, TraceStep,
};
pub use sandbox::Sandbox;
use session::{Session, Verdict};

/// The version of the referee, recorded with every match.
pub const ENGINE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Default time for the first answer, which includes the interpreter's start.
pub const DEFAULT_STARTUP_TIMEOUT: Duration = Duration::from_secs(10);

/// Default time for every later answer.
pub const DEFAULT_MOVE_TIMEOUT: Duration = Duration::from_millis(1000);

/// Default time bank: CPU time the moves of a match may use beyond their limits, all
/// together, so that a few slow moves do not end a match: a robot that needs 5 s of CPU
/// on each of six moves under a 1 s limit finishes (an overage budget, as hosted
/// simulation competitions give).
pub const DEFAULT_TIME_BANK: Duration = Duration::from_secs(30);

/// The wall-clock backstop of an answer, as a multiple of its CPU time: an answer is
/// given up on once the wall-clock time since it was asked passes this many times (the
/// step's limit + the CPU time the bot has used on it). A bot that waits instead of
/// thinking is stopped after 4x its limit; one that thinks is never stopped by the
/// clock while it gets at least a quarter of a core, however busy the machine.
pub const WALL_BACKSTOP_FACTOR: u32 = 4;

/// A match's wall-clock ceiling, as a multiple of the most CPU time its limits let the
/// bot use ([`Limits::match_wall_clock`]): a bot that thinks to its limits all match
/// long is never stopped by it while it gets half a core, and one that waits holds a
/// worker no longer than the ceiling says.
pub const MATCH_WALL_FACTOR: u32 = 2;

/// Added to every match's wall-clock ceiling: the bot's start and end, the referee's own
/// time.
pub const MATCH_WALL_SLACK: Duration = Duration::from_secs(10);

/// Default memory limit: 1 GiB of resident memory for all the bot's processes together
/// (in the sandbox). Without the sandbox each process gets twice this as address space
/// (JavaScript runtimes reserve a lot of virtual memory up front).
pub const DEFAULT_MEMORY_LIMIT_MB: u64 = 1024;

/// Default limit on the bot's processes and threads at once (in the sandbox).
pub const DEFAULT_PROCESS_LIMIT: u32 = 64;

/// Default size of the bot's writable scratch area (working directory and `/tmp`).
pub const DEFAULT_SCRATCH_MB: u64 = 64;

/// How long a bot may live after the end message before all its processes are killed.
pub const EXIT_GRACE: Duration = Duration::from_secs(1);

/// A bot to run: a command, the directory it runs in, and the environment variables
/// declared for it.
#[derive(Debug, Clone, Default)]
pub struct BotSpec {
    /// The command line, split like a shell (no shell is run), e.g. `python3 bot.py`.
    pub command: String,
    /// The bot's folder.
    pub dir: PathBuf,
    /// Variables declared for the bot ([`botenv`]); it gets no other of ours.
    pub env: Vec<(String, String)>,
    /// Print the bot's stderr lines on ours as they come (`mazearena run --verbose`).
    pub echo_stderr: bool,
    /// The runtime to put first on the bot's `PATH`, by name (one of the sandbox's).
    pub runtime: Option<String>,
    /// The protocol it speaks.
    pub protocol: BotProtocol,
}

/// The protocol a bot speaks: protocol v1 (line-delimited JSON, docs/PROTOCOL.md), or
/// the text commands of a mouse written for the mms simulator, translated by the referee
/// (docs/PROTOCOL-mms.md).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BotProtocol {
    /// Protocol v1.
    #[default]
    V1,
    /// An mms mouse.
    Mms,
}

impl BotProtocol {
    /// Its name in `bot.toml`, the API and the command line (`v1` or `mms`).
    pub fn as_str(self) -> &'static str {
        match self {
            BotProtocol::V1 => "v1",
            BotProtocol::Mms => "mms",
        }
    }

    /// The protocol named `name`.
    ///
    /// # Errors
    /// An unknown name, said with the known ones.
    pub fn parse(name: &str) -> Result<BotProtocol, String> {
        match name {
            "v1" => Ok(BotProtocol::V1),
            "mms" => Ok(BotProtocol::Mms),
            other => Err(format!(
                "unknown protocol {other:?}: `v1` (JSON lines) or `mms` (a mouse of the mms simulator)"
            )),
        }
    }
}

impl BotProtocol {
    /// The protocol a stored version names (`None`: protocol v1; an unknown name,
    /// written by a later release, also v1).
    pub fn of_stored(name: Option<&str>) -> BotProtocol {
        name.and_then(|n| BotProtocol::parse(n).ok())
            .unwrap_or_default()
    }

    /// What a stored version keeps: `None` for protocol v1.
    pub fn stored(self) -> Option<&'static str> {
        (self != BotProtocol::V1).then(|| self.as_str())
    }
}

impl std::str::FromStr for BotProtocol {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        BotProtocol::parse(s)
    }
}

impl BotSpec {
    /// A bot with no declared variables.
    pub fn new(command: impl Into<String>, dir: impl Into<PathBuf>) -> BotSpec {
        BotSpec {
            command: command.into(),
            dir: dir.into(),
            ..BotSpec::default()
        }
    }
}

/// The limits a match is played under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The shared step budget.
    pub max_steps: u32,
    /// CPU time for the first answer, from the process start; `None`: no limit.
    pub startup_timeout: Option<Duration>,
    /// CPU time for every later answer; `None`: no limit. CPU time of every process of
    /// the bot (its cgroup, or its process tree), the same on an idle or a busy
    /// machine; where no CPU counter can be read, wall-clock time.
    pub move_timeout: Option<Duration>,
    /// CPU time the moves may use beyond `move_timeout`, all together over the match.
    pub time_bank: Duration,
    /// Memory limit in MiB (see [`DEFAULT_MEMORY_LIMIT_MB`]); `None`: no limit.
    pub memory_limit_mb: Option<u64>,
    /// Processes and threads at once (sandbox only); `None`: no limit.
    pub process_limit: Option<u32>,
    /// Scratch area size in MiB (sandbox only).
    pub scratch_mb: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_steps: GameConfig::default().max_steps,
            startup_timeout: Some(DEFAULT_STARTUP_TIMEOUT),
            move_timeout: Some(DEFAULT_MOVE_TIMEOUT),
            time_bank: DEFAULT_TIME_BANK,
            memory_limit_mb: Some(DEFAULT_MEMORY_LIMIT_MB),
            process_limit: Some(DEFAULT_PROCESS_LIMIT),
            scratch_mb: DEFAULT_SCRATCH_MB,
        }
    }
}

impl Limits {
    /// The most CPU time these limits let a bot use over a whole match: the startup
    /// limit, the move limit for each later step, and the time bank; `None` without
    /// time limits.
    pub fn most_cpu_time(&self) -> Option<Duration> {
        let startup = self.startup_timeout?;
        let each = self.move_timeout?;
        Some(startup + each * self.max_steps.saturating_sub(1) + self.time_bank)
    }

    /// The most wall-clock time a match may last under these limits, published with
    /// them: [`MATCH_WALL_FACTOR`] x [`Limits::most_cpu_time`] + [`MATCH_WALL_SLACK`].
    /// Past it the match ends as `timeout` (limit `match_wall_clock`). `None` without
    /// time limits (`--no-timeout`).
    pub fn match_wall_clock(&self) -> Option<Duration> {
        Some(self.most_cpu_time()? * MATCH_WALL_FACTOR + MATCH_WALL_SLACK)
    }

    fn record(&self, sandbox: &Sandbox) -> LimitsRecord {
        let sandboxed = matches!(sandbox, Sandbox::Full(_));
        LimitsRecord {
            max_steps: self.max_steps,
            startup_timeout_ms: self.startup_timeout.map(|d| d.as_millis() as u64),
            move_timeout_ms: self.move_timeout.map(|d| d.as_millis() as u64),
            time_bank_ms: self.move_timeout.map(|_| self.time_bank.as_millis() as u64),
            match_wall_clock_ms: self.match_wall_clock().map(|d| d.as_millis() as u64),
            memory_limit_mb: self.memory_limit_mb,
            process_limit: self.process_limit.filter(|_| sandboxed),
            scratch_mb: sandboxed.then_some(self.scratch_mb),
            sandbox: sandbox.level().to_string(),
        }
    }
}

/// Plays one match of `bot` on `maze` under `limits`, isolated by `sandbox`, and returns
/// its record.
///
/// `observe` is called after every step (for live progress output); pass `|_| {}` when
/// not needed.
pub async fn run_match(
    bot: &BotSpec,
    maze: &Maze,
    seed: u64,
    limits: Limits,
    sandbox: &Sandbox,
    mut observe: impl FnMut(&TraceStep) + Send,
) -> MatchRecord {
    let started = Instant::now();
    let mut game = Game::new(
        maze.clone(),
        GameConfig {
            max_steps: limits.max_steps,
        },
    );
    let mut record = new_record(maze, seed, &limits, sandbox);
    let launch = process::Launch {
        command: &bot.command,
        dir: &bot.dir,
        memory_limit_bytes: limits.memory_limit_mb.map(|mb| mb << 20),
        process_limit: limits.process_limit.map(u64::from),
        scratch_bytes: limits.scratch_mb << 20,
        sandbox,
        env: &bot.env,
        runtime: bot.runtime.as_deref(),
    };
    let mut session = match Session::start(&launch, limits, bot.echo_stderr) {
        Ok(s) => s,
        Err(failure) => {
            record.error = Some(*failure);
            record.timings.wall_ms = started.elapsed().as_millis() as u64;
            return record;
        }
    };
    record.bot_pid = session.pid();

    let start = ServerMessage::Start {
        protocol: PROTOCOL_VERSION,
        maze_dim: maze.dim(),
        max_steps: limits.max_steps,
        seed,
        move_timeout_ms: limits.move_timeout.map_or(0, |d| d.as_millis() as u64),
    };
    // An mms mouse gets no start message: it asks what it wants to know.
    let mut mouse = (bot.protocol == BotProtocol::Mms).then(|| {
        record.bot_protocol = Some(BotProtocol::Mms.as_str().to_string());
        crate::protocol::mms::Mouse::new(maze.dim())
    });
    let mut failure = match mouse {
        Some(_) => None,
        None => session.greet(&start).await.err(),
    };
    let mut debug_budget = trace::DebugBudget::default();
    while failure.is_none() {
        let Some(sense) = game.begin_step() else {
            break;
        };
        if !record.trace.is_empty() {
            stderr_to_last_step(&mut record, session.take_stderr_lines());
        }
        let verdict = match mouse.as_mut() {
            Some(m) => match session.exchange_mms(&sense, m).await {
                // What the mouse drew (setColor, setText, setWall) up to its action is
                // the step's debug drawing, within the same budget as v1's.
                Verdict::Answer {
                    action,
                    answer_us,
                    cpu_us,
                    ..
                } => Verdict::Answer {
                    action,
                    answer_us,
                    cpu_us,
                    debug: m
                        .take_drawing()
                        .and_then(|json| serde_json::value::RawValue::from_string(json).ok()),
                },
                fault => fault,
            },
            None => session.exchange(&sense).await,
        };
        match verdict {
            Verdict::Answer {
                action,
                answer_us,
                cpu_us,
                debug,
            } => {
                let step = TraceStep {
                    report: game.apply(action),
                    answer_us,
                    cpu_us,
                    stderr: Vec::new(),
                    debug: debug_budget.admit(debug, sense.step, &mut record.notices),
                };
                observe(&step);
                record.trace.push(step);
            }
            Verdict::Fault(status, f) => failure = Some((status, f)),
        }
    }
    // A limit hit at any time ends the match with its status, even if the bot went on.
    if let Some(kind) = session.limit_hit() {
        failure = Some(session::limit_failure(kind, &limits, game.t()));
    }

    record.total_steps = game.t();
    record.run0_steps = game.run0_steps();
    record.warnings = game.warnings().to_vec();
    record.status = match (&failure, game.end()) {
        (Some((status, _)), _) => *status,
        (None, Some(GameEnd::Finished)) => MatchStatus::Finished,
        (None, _) => MatchStatus::StepLimit,
    };
    if record.status == MatchStatus::Finished {
        record.run1_steps = game.run1_steps();
        record.score = game.score().map(|s| s.value());
    }
    let end = ServerMessage::End {
        status: record.status.to_string(),
        score: record.score,
        run0_steps: record.run0_steps,
        run1_steps: record.run1_steps,
    };
    if let Some(m) = &mouse {
        let (kept, count) = m.warnings();
        if count > 0 {
            let mut message = format!("{count} unknown mms commands were not answered");
            if let Some(first) = kept.first() {
                message.push_str(&format!(", the first: {first}"));
            }
            record.notices.push(crate::runner::outcome::Notice {
                step: record.total_steps,
                message,
            });
        }
    }
    let mut ended = session.finish(mouse.is_none().then_some(&end)).await;
    if ended.charged_ms > 0 {
        record.notices.push(crate::runner::outcome::Notice {
            step: record.total_steps,
            message: format!(
                "{} ms of the referee's CPU time, spent taking in the bot's output past each \
                 step's free {} KiB, counted as the bot's CPU time (a flood of stderr or of \
                 mms commands costs its bot, not the server)",
                ended.charged_ms,
                flood::FREE_BYTES_PER_STEP / 1024
            ),
        });
    }
    stderr_to_last_step(&mut record, std::mem::take(&mut ended.late_stderr));
    if let Some((_, mut f)) = failure {
        (f.exit_code, f.signal) = exit_of(ended.exit, sandbox);
        if record.status == MatchStatus::Crashed && f.reason.starts_with(session::CLOSED_STDOUT) {
            f.reason = ended_reason(&f);
            if mouse.as_ref().is_some_and(|m| m.waits_for_run_1()) {
                f.reason.push_str(
                    " after reaching the goal in run 0: an mms mouse gets its second run by \
                     asking wasReset, calling ackReset, or coming back to the start \
                     (docs/PROTOCOL-mms.md, \"Runs\")",
                );
            }
        }
        if let Some(reason) = setup_failure(&ended, sandbox) {
            // The jail could not start the bot's program: it never ran.
            f.reason = format!("could not start the bot: {reason}");
            f.step = None;
            record.total_steps = 0;
        }
        record.error = Some(f);
    }
    record.stderr_tail = ended.stderr_tail;
    record.timings = timings(&record.trace, ended.cpu_ms, started);
    record
}

/// Gives the last played step the stderr lines written since it was asked (lines
/// written before the first answer go to step 1; a match without steps keeps only the
/// tail).
fn stderr_to_last_step(record: &mut MatchRecord, lines: Vec<String>) {
    if lines.is_empty() {
        return;
    }
    if let Some(step) = record.trace.last_mut() {
        trace::attach_stderr(step, lines, &mut record.notices);
    }
}

/// Why a bot that stopped answering crashed: its exit status or the signal that killed
/// it. (Not its stderr, which is its owner's: the reason is public. The owner's log
/// view ends with its last stderr lines, a Python exception among them.)
fn ended_reason(f: &Failure) -> String {
    let how = match (f.exit_code, f.signal) {
        (Some(code), _) => format!("exited with status {code}"),
        (None, Some(signal)) => format!("was killed by signal {signal}"),
        (None, None) => "closed its stdout".to_string(),
    };
    let step = f
        .step
        .map_or_else(String::new, |s| format!(" before answering step {s}"));
    format!("the bot {how}{step}")
}

/// The bot's exit code or signal. In the sandbox the process is bubblewrap, which exits
/// with the bot's code, or 128 + the signal that killed it.
fn exit_of(
    exit: Option<std::process::ExitStatus>,
    sandbox: &Sandbox,
) -> (Option<i32>, Option<i32>) {
    use std::os::unix::process::ExitStatusExt;
    let Some(status) = exit else {
        return (None, None);
    };
    match (sandbox, status.code()) {
        (Sandbox::Full(_), Some(code)) if (129..=159).contains(&code) => (None, Some(code - 128)),
        _ => (status.code(), status.signal()),
    }
}

/// The jail's own message when it could not start the bot's program.
fn setup_failure(ended: &session::Ended, sandbox: &Sandbox) -> Option<String> {
    if !matches!(sandbox, Sandbox::Full(_))
        || ended.exit.and_then(|e| e.code()) != Some(sandbox::jail::SETUP_FAILED)
    {
        return None;
    }
    ended
        .stderr_tail
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("mazearena sandbox: "))
        .map(str::to_string)
}

fn new_record(maze: &Maze, seed: u64, limits: &Limits, sandbox: &Sandbox) -> MatchRecord {
    MatchRecord {
        engine_version: ENGINE_VERSION.to_string(),
        protocol: PROTOCOL_VERSION,
        bot_protocol: None,
        maze_hash: maze.hash(),
        maze_dim: maze.dim(),
        seed,
        limits: limits.record(sandbox),
        status: MatchStatus::Crashed,
        score: None,
        run0_steps: None,
        run1_steps: None,
        total_steps: 0,
        warnings: Vec::new(),
        error: None,
        stderr_tail: String::new(),
        timings: Timings::default(),
        bot_pid: None,
        core: affinity::pinned_core(),
        notices: Vec::new(),
        maze_layout: None,
        title: None,
        trace: Vec::new(),
    }
}

fn timings(trace: &[TraceStep], cpu_ms: Option<u64>, started: Instant) -> Timings {
    let total: u64 = trace.iter().map(|s| s.answer_us).sum();
    Timings {
        wall_ms: started.elapsed().as_millis() as u64,
        bot_cpu_ms: cpu_ms,
        max_answer_us: trace.iter().map(|s| s.answer_us).max().unwrap_or(0),
        mean_answer_us: if trace.is_empty() {
            0
        } else {
            total / trace.len() as u64
        },
    }
}
