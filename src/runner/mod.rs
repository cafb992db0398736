//! The bot runner: plays one match between one bot process and one maze.
//!
//! [`run_match`] starts the bot (see [`process`]), speaks protocol v1 with it under the
//! time limits, drives the pure [`Game`], and always returns a
//! [`MatchRecord`]: a misbehaving bot is an outcome recorded with its reason, never an
//! error or a panic. Matches are plain futures, so many can run at once in one process.

pub mod framing;
pub mod outcome;
pub mod process;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use futures_util::StreamExt;
use tokio::io::AsyncWriteExt;
use tokio::process::{Child, ChildStdin};
use tokio::time::timeout_at;
use tokio_util::codec::AnyDelimiterCodecError;

use crate::engine::game::StepReport;
use crate::engine::{Game, GameConfig, GameEnd, Maze};
use crate::protocol::{EXCERPT_BYTES, PROTOCOL_VERSION, ProtocolError, ServerMessage, excerpt};
pub use outcome::{Failure, LimitsRecord, MatchRecord, MatchStatus, Timings, TraceStep};

/// The version of the referee, recorded with every match.
pub const ENGINE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Default time for the first answer, which includes the interpreter's start.
pub const DEFAULT_STARTUP_TIMEOUT: Duration = Duration::from_secs(10);

/// Default time for every later answer.
pub const DEFAULT_MOVE_TIMEOUT: Duration = Duration::from_millis(1000);

/// Default address-space limit for a bot: 2 GiB (JavaScript runtimes reserve a lot of
/// virtual memory up front; less than this stops Node from starting).
pub const DEFAULT_MEMORY_LIMIT_MB: u64 = 2048;

/// How long a bot may live after the end message before its process group is killed.
pub const EXIT_GRACE: Duration = Duration::from_secs(1);

/// A bot to run: a command and the directory it runs in.
#[derive(Debug, Clone)]
pub struct BotSpec {
    /// The command line, split like a shell (no shell is run), e.g. `python3 bot.py`.
    pub command: String,
    /// The working directory of the bot.
    pub dir: PathBuf,
}

/// The limits a match is played under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The shared step budget.
    pub max_steps: u32,
    /// Time for the first answer, from the process start; `None`: no limit.
    pub startup_timeout: Option<Duration>,
    /// Time for every later answer; `None`: no limit.
    pub move_timeout: Option<Duration>,
    /// Address-space limit in MiB; `None`: no limit.
    pub memory_limit_mb: Option<u64>,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_steps: GameConfig::default().max_steps,
            startup_timeout: Some(DEFAULT_STARTUP_TIMEOUT),
            move_timeout: Some(DEFAULT_MOVE_TIMEOUT),
            memory_limit_mb: Some(DEFAULT_MEMORY_LIMIT_MB),
        }
    }
}

impl Limits {
    fn record(&self) -> LimitsRecord {
        LimitsRecord {
            max_steps: self.max_steps,
            startup_timeout_ms: self.startup_timeout.map(|d| d.as_millis() as u64),
            move_timeout_ms: self.move_timeout.map(|d| d.as_millis() as u64),
            memory_limit_mb: self.memory_limit_mb,
            process_limit: None,
            scratch_mb: None,
            sandbox: "none".to_string(),
        }
    }
}

/// Plays one match of `bot` on `maze` and returns its record.
///
/// `observe` is called after every step (for live progress output); pass `|_| {}` when
/// not needed.
pub async fn run_match(
    bot: &BotSpec,
    maze: &Maze,
    seed: u64,
    limits: Limits,
    mut observe: impl FnMut(&TraceStep) + Send,
) -> MatchRecord {
    let started = Instant::now();
    let mut game = Game::new(
        maze.clone(),
        GameConfig {
            max_steps: limits.max_steps,
        },
    );
    let mut record = MatchRecord {
        engine_version: ENGINE_VERSION.to_string(),
        protocol: PROTOCOL_VERSION,
        maze_hash: maze.hash(),
        maze_dim: maze.dim(),
        seed,
        limits: limits.record(),
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
        trace: Vec::new(),
    };

    let launch = process::Launch {
        command: &bot.command,
        dir: &bot.dir,
        memory_limit_bytes: limits.memory_limit_mb.map(|mb| mb * 1024 * 1024),
    };
    let mut child = match process::spawn(&launch) {
        Ok(child) => child,
        Err(e) => {
            record.error = Some(Failure {
                reason: e.to_string(),
                ..Failure::default()
            });
            record.timings.wall_ms = started.elapsed().as_millis() as u64;
            return record;
        }
    };
    let pid = child.id();
    record.bot_pid = pid;
    let _guard = process::GroupGuard { pgid: pid };
    // The pipes were requested in `spawn`; their absence would be a bug there.
    let mut stdin = child
        .stdin
        .take()
        .expect("stdin is piped by process::spawn");
    let stdout = child
        .stdout
        .take()
        .expect("stdout is piped by process::spawn");
    let stderr = child
        .stderr
        .take()
        .expect("stderr is piped by process::spawn");
    let stderr_task = tokio::spawn(framing::read_tail(stderr, framing::STDERR_TAIL_BYTES));
    let mut replies = framing::reply_reader(stdout);

    let start = ServerMessage::Start {
        protocol: PROTOCOL_VERSION,
        maze_dim: maze.dim(),
        max_steps: limits.max_steps,
        seed,
        move_timeout_ms: limits.move_timeout.map_or(0, |d| d.as_millis() as u64),
    };
    let mut failure: Option<(MatchStatus, Failure)> = None;
    if let Err(e) = send(&mut stdin, &start, None).await {
        failure = Some(write_failure(e));
    }

    let mut answer_total_us: u64 = 0;
    while failure.is_none() {
        let Some(sense) = game.begin_step() else {
            break;
        };
        let sent_at = Instant::now();
        let (since, limit) = if sense.step == 1 {
            (started, limits.startup_timeout)
        } else {
            (sent_at, limits.move_timeout)
        };
        let deadline = limit.map(|l| tokio::time::Instant::from_std(since + l));
        if let Err(e) = send(&mut stdin, &ServerMessage::sense(&sense), deadline).await {
            failure = Some(write_failure(e));
            break;
        }
        let next = match deadline {
            Some(d) => timeout_at(d, replies.next()).await,
            None => Ok(replies.next().await),
        };
        let line = match next {
            Err(_) => {
                let what = if sense.step == 1 { "startup" } else { "move" };
                let ms = limit.map_or(0, |l| l.as_millis());
                failure = Some((
                    MatchStatus::Timeout,
                    Failure {
                        reason: format!(
                            "no answer to step {} within the {what} limit of {ms} ms",
                            sense.step
                        ),
                        ..Failure::default()
                    },
                ));
                break;
            }
            Ok(None) => {
                failure = Some((
                    MatchStatus::Crashed,
                    Failure {
                        reason: format!(
                            "the bot closed its stdout (or exited) before answering step {}",
                            sense.step
                        ),
                        ..Failure::default()
                    },
                ));
                break;
            }
            Ok(Some(Err(AnyDelimiterCodecError::MaxChunkLengthExceeded))) => {
                failure = Some(protocol_failure(
                    ProtocolError::LineTooLong,
                    replies.read_buffer(),
                ));
                break;
            }
            Ok(Some(Err(AnyDelimiterCodecError::Io(e)))) => {
                failure = Some((
                    MatchStatus::Crashed,
                    Failure {
                        reason: format!("reading the bot's stdout failed: {e}"),
                        ..Failure::default()
                    },
                ));
                break;
            }
            Ok(Some(Ok(line))) => line,
        };
        // PROTOCOL-v1: the first answer is timed from the process start.
        let answer_us = since.elapsed().as_micros() as u64;
        let action = match crate::protocol::decode_reply(&line) {
            Ok(action) => action,
            Err(e) => {
                failure = Some(protocol_failure(e, &line));
                break;
            }
        };
        answer_total_us += answer_us;
        let report: StepReport = game.apply(action);
        let step = TraceStep {
            report,
            answer_us,
            cpu_us: None,
        };
        observe(&step);
        record.timings.max_answer_us = record.timings.max_answer_us.max(answer_us);
        record.trace.push(step);
    }

    record.timings.bot_cpu_ms = pid.and_then(process::cpu_time_ms);
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
    if !record.trace.is_empty() {
        record.timings.mean_answer_us = answer_total_us / record.trace.len() as u64;
    }

    let end = ServerMessage::End {
        status: record.status.to_string(),
        score: record.score,
        run0_steps: record.run0_steps,
        run1_steps: record.run1_steps,
    };
    let exit = finish_process(&mut child, stdin, &end, pid).await;
    if let Some((_, mut f)) = failure {
        if let Some(status) = exit {
            use std::os::unix::process::ExitStatusExt;
            f.exit_code = status.code();
            f.signal = status.signal();
        }
        record.error = Some(f);
    }
    record.stderr_tail = match tokio::time::timeout(EXIT_GRACE, stderr_task).await {
        Ok(Ok(tail)) => tail,
        _ => String::from("[stderr could not be read to its end]"),
    };
    record.timings.wall_ms = started.elapsed().as_millis() as u64;
    record
}

/// Sends the end message, closes stdin, gives the bot [`EXIT_GRACE`] to exit, then kills
/// its whole process group and reaps it. Returns how the bot process ended, if known.
async fn finish_process(
    child: &mut Child,
    mut stdin: ChildStdin,
    end: &ServerMessage,
    pid: Option<u32>,
) -> Option<std::process::ExitStatus> {
    let grace = tokio::time::Instant::now() + EXIT_GRACE;
    let _ = send(&mut stdin, end, Some(grace)).await;
    drop(stdin);
    let status = timeout_at(grace, child.wait())
        .await
        .ok()
        .and_then(Result::ok);
    // Kill the whole group even when the leader exited: its children may linger.
    if let Some(pgid) = pid {
        process::kill_group(pgid);
    }
    match status {
        Some(s) => Some(s),
        None => child.wait().await.ok(),
    }
}

/// Writes one message line to the bot, within `deadline` if given.
async fn send(
    stdin: &mut ChildStdin,
    message: &ServerMessage,
    deadline: Option<tokio::time::Instant>,
) -> std::io::Result<()> {
    let line = message.to_line();
    let write = async {
        stdin.write_all(line.as_bytes()).await?;
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

fn write_failure(e: std::io::Error) -> (MatchStatus, Failure) {
    let status = if e.kind() == std::io::ErrorKind::TimedOut {
        MatchStatus::Timeout
    } else {
        MatchStatus::Crashed
    };
    (
        status,
        Failure {
            reason: format!("could not write to the bot's stdin: {e}"),
            ..Failure::default()
        },
    )
}

fn protocol_failure(e: ProtocolError, line: &[u8]) -> (MatchStatus, Failure) {
    (
        MatchStatus::ProtocolError,
        Failure {
            reason: e.to_string(),
            line: Some(excerpt(line, EXCERPT_BYTES)),
            ..Failure::default()
        },
    )
}
