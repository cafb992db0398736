//! Waiting for the bot's answer: its line read against its CPU time and the wall-clock
//! backstop, the runtime's start waited through, the next step's message sent.

use std::time::{Duration, Instant};

use std::os::fd::AsFd;

use super::{
    Ask, CLOSED_STDOUT, STARTUP_HINT, Session, Verdict, WATCHDOG_PERIOD, Waited, protocol_fault,
    send_bytes, with_time_limit,
};
use crate::protocol::ProtocolError;
use crate::runner::WALL_BACKSTOP_FACTOR;
use crate::runner::framing;
use crate::runner::outcome::MatchStatus;

impl Session {
    /// Waits for the bot's next line under `ask`'s limits: `Ok` when the replies hold
    /// it, else the verdict (a timeout, a crash, a line too long, a limit).
    pub(super) async fn wait_line(&mut self, ask: &mut Ask) -> Result<(), Box<Verdict>> {
        let (since, limit, mark, factor, step) =
            (ask.since, ask.limit, ask.mark, ask.factor, ask.step);
        let waited = loop {
            let waited = match self.wait_near(ask.deadline) {
                Waited::Later => self.wait_through_runtime(ask.deadline).await,
                waited => waited,
            };
            // The wall-clock backstop moves out with the CPU time the bot uses: a bot
            // that thinks on a busy machine is not stopped by the clock.
            if let (Waited::TimedOut, Some(l), true, false) =
                (&waited, limit, self.cpu_counted, self.past_ceiling())
            {
                let used = self.cpu_used(mark);
                let backstop = since + (l + Duration::from_micros(used)) * factor;
                if Instant::now() < backstop {
                    ask.deadline = self.within_match(Some(backstop));
                    continue;
                }
            }
            break waited;
        };
        if let Waited::Got(Ok(framing::Next::Line)) = waited {
            return Ok(());
        }
        self.cpu_cap = None;
        Err(Box::new(match waited {
            Waited::Got(Ok(framing::Next::Line)) => unreachable!("returned above"),
            Waited::Got(Ok(framing::Next::End)) => {
                let reason = format!("{CLOSED_STDOUT} before answering step {step}");
                self.fault_or_limit(MatchStatus::Crashed, reason, step)
            }
            Waited::Got(Ok(framing::Next::TooLong)) => {
                protocol_fault(ProtocolError::LineTooLong, self.replies.partial(), step)
            }
            Waited::Got(Err(e)) => {
                let reason = format!("reading the bot's stdout failed: {e}");
                self.fault_or_limit(MatchStatus::Crashed, reason, step)
            }
            Waited::TimedOut | Waited::Later if self.past_ceiling() => {
                let ceiling = self.limits.match_wall_clock().unwrap_or_default();
                let used = self.process.cpu_us().map_or(0, |us| us / 1000);
                let reason = format!(
                    "the match lasted {} s of wall-clock time, its ceiling ({} x the {} s of \
                     CPU time its limits allow + {} s), in which the bot used {} ms of CPU \
                     time: it was waiting, not thinking (step {step} was being asked)",
                    self.started.elapsed().as_secs(),
                    crate::runner::MATCH_WALL_FACTOR,
                    self.limits.most_cpu_time().unwrap_or_default().as_secs(),
                    crate::runner::MATCH_WALL_SLACK.as_secs(),
                    used
                );
                let verdict = self.fault_or_limit(MatchStatus::Timeout, reason, step);
                with_time_limit(verdict, "match_wall_clock", ceiling.as_millis() as u64)
            }
            Waited::TimedOut | Waited::Later => {
                let what = if step == 1 { "startup" } else { "move" };
                let ms = limit.map_or(0, |l| l.as_millis());
                let mut reason = if self.cpu_counted {
                    let used = self.cpu_used(mark) / 1000;
                    format!(
                        "no answer to step {step} within {} ms of wall-clock time, in which the bot \
                         used {used} ms of CPU time: it was waiting, not thinking (an answer is \
                         given up on after {WALL_BACKSTOP_FACTOR} x (the {what} limit of {ms} ms \
                         + the CPU time used))",
                        since.elapsed().as_millis()
                    )
                } else {
                    format!("no answer to step {step} within the {what} limit of {ms} ms")
                };
                if step == 1 {
                    reason.push_str(STARTUP_HINT);
                }
                let verdict = self.fault_or_limit(MatchStatus::Timeout, reason, step);
                with_time_limit(verdict, "wall_clock", since.elapsed().as_millis() as u64)
            }
            Waited::CpuOver(used, allowed) => self.cpu_fault(step, used, allowed, limit),
            Waited::Limit(kind) => self.limit_fault(kind, step),
        }))
    }

    /// Waits for the answer through the runtime (a bot that thinks), under `deadline`,
    /// looking at the whole-match limits meanwhile. Never [`Waited::Later`].
    pub(super) async fn wait_through_runtime(&mut self, deadline: Option<Instant>) -> Waited {
        if let Some(d) = deadline {
            self.step_limit.as_mut().reset(d.into());
        }
        self.turned_at = Instant::now();
        loop {
            tokio::select! {
                biased;
                r = framing::next_reply(&mut self.replies, &mut self.stderr) => return Waited::Got(r),
                () = self.step_limit.as_mut(), if deadline.is_some() => return Waited::TimedOut,
                _ = self.watchdog.tick() => {
                    if let Some(kind) = self.process.limit_hit() {
                        return Waited::Limit(kind);
                    }
                    if let Some(over) = self.cpu_over() {
                        return over;
                    }
                }
            }
        }
    }

    /// Writes the sense line: at once while the pipe has room (it always has, but for a
    /// bot that does not read its stdin), else the rest through the runtime within the
    /// step's deadline.
    pub(super) async fn send_sense(
        &mut self,
        line: &[u8],
        deadline: Option<Instant>,
    ) -> std::io::Result<()> {
        let written = match nix::unistd::write(self.stdin.as_fd(), line) {
            Ok(n) => n,
            Err(nix::errno::Errno::EAGAIN | nix::errno::Errno::EINTR) => 0,
            Err(e) => return Err(e.into()),
        };
        if written == line.len() {
            return Ok(());
        }
        let rest = &line[written..];
        send_bytes(&mut self.stdin, rest, deadline.map(Into::into)).await
    }

    /// Waits for the answer on the match's own thread for at most [`NEAR_WAIT`] (and
    /// not past `deadline`): `ppoll` on the bot's stdout and stderr, each ready pipe
    /// read at once, stderr first, so what the bot wrote there before its answer goes
    /// with this step (the kernel reports the stderr pipe ready no later than the stdout
    /// pipe written after it; a bot writing stderr without end has it read 64 times in
    /// a row at most before its answer is taken, as through the runtime).
    pub(super) fn wait_near(&mut self, deadline: Option<Instant>) -> Waited {
        use nix::poll::{PollFd, PollFlags, ppoll};
        let start = Instant::now();
        let until = deadline.map_or(start + NEAR_WAIT, |d| d.min(start + NEAR_WAIT));
        let mut stderr_in_a_row = 0;
        loop {
            if let Some(next) = self.replies.look() {
                return Waited::Got(Ok(next));
            }
            let now = Instant::now();
            if now >= self.watch_at {
                self.watch_at = now + WATCHDOG_PERIOD;
                if let Some(kind) = self.process.limit_hit() {
                    return Waited::Limit(kind);
                }
                if let Some(over) = self.cpu_over() {
                    return over;
                }
            }
            if now >= until {
                return match deadline {
                    Some(d) if now >= d => Waited::TimedOut,
                    _ => Waited::Later,
                };
            }
            let wait = nix::sys::time::TimeSpec::from_duration(until - now);
            let stderr_open = self.stderr.is_open();
            let (stdout_ready, stderr_ready) = {
                let mut fds = [
                    PollFd::new(self.replies.pipe(), PollFlags::POLLIN),
                    PollFd::new(self.stderr.pipe(), PollFlags::POLLIN),
                ];
                let watched = if stderr_open { 2 } else { 1 };
                match ppoll(&mut fds[..watched], Some(wait), None) {
                    Ok(_) | Err(nix::errno::Errno::EINTR) => {}
                    Err(e) => return Waited::Got(Err(e.into())),
                }
                let ready = |fd: &PollFd| fd.any().unwrap_or(false);
                (ready(&fds[0]), stderr_open && ready(&fds[1]))
            };
            if stderr_ready && stderr_in_a_row < framing::STDERR_READS_BEFORE_REPLY {
                self.stderr.read_now();
                stderr_in_a_row += 1;
                continue;
            }
            stderr_in_a_row = 0;
            if stdout_ready && let Err(e) = self.replies.read_now() {
                return Waited::Got(Err(e));
            }
        }
    }
}

/// How long an answer is waited for on the match's own thread, in `ppoll` on the bot's
/// stdout and stderr, before the wait goes to the runtime. Most answers come within
/// it: a step then costs the referee its four system calls (the sense's `write`, the
/// wait, the answer's `read`, the CPU counter) and little else, where a wait through
/// the runtime's reactor costs some 4,000 instructions more (docs/PERFORMANCE.md).
/// Each match has a thread of its own ([`crate::work::worker`], `mazearena run`), so the
/// wait holds up nothing else for long.
const NEAR_WAIT: Duration = Duration::from_millis(2);
