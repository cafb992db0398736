//! The time limits: the CPU time an answer used, the time bank, and the faults and
//! limit failures a late or failing answer ends the match with.

use std::time::Duration;

use super::{Ask, Session, Verdict, Waited, failure, limit_failure, with_time_limit};
use crate::runner::outcome::MatchStatus;
use crate::runner::process::LimitKind;

impl Session {
    /// CPU time the bot has used since the counter read `mark`, in µs.
    pub(super) fn cpu_used(&self, mark: u64) -> u64 {
        self.process
            .cpu_us()
            .map_or(0, |now| now.saturating_sub(mark))
            + self.stderr.meter.step_charge_us()
    }

    /// [`Waited::CpuOver`] if the step being waited for has used more CPU time than
    /// it may.
    pub(super) fn cpu_over(&self) -> Option<Waited> {
        let (mark, allowed) = self.cpu_cap?;
        let used = self.cpu_used(mark);
        (used > allowed).then_some(Waited::CpuOver(used, allowed))
    }

    /// The timeout of step `step`, which used `used` µs of CPU time where it might use
    /// `allowed` (its `limit` and what was left of the bank).
    pub(super) fn cpu_fault(
        &self,
        step: u32,
        used: u64,
        allowed: u64,
        limit: Option<Duration>,
    ) -> Verdict {
        let what = if step == 1 { "startup" } else { "move" };
        let ms = limit.map_or(0, |l| l.as_millis() as u64);
        let bank = if step == 1 {
            String::new()
        } else {
            format!(
                " and the {} ms left of the match's time bank",
                self.bank_left_us / 1000
            )
        };
        let reason = format!(
            "step {step} used more than {} ms of CPU time ({} ms when stopped): over the {what} limit of {ms} ms{bank}",
            allowed / 1000,
            used / 1000
        );
        let verdict = self.fault_or_limit(MatchStatus::Timeout, reason, step);
        with_time_limit(verdict, "cpu_time", allowed / 1000)
    }

    /// The step `ask` is answered now: its wall-clock and CPU time, its CPU time counted
    /// against its limit and the bank.
    pub(super) fn answered(&mut self, ask: &Ask) -> Result<(u64, Option<u64>), Box<Verdict>> {
        self.cpu_cap = None;
        let (since, step, limit, allowed_us) = (ask.since, ask.step, ask.limit, ask.allowed_us);
        let answer_us = since.elapsed().as_micros() as u64;
        let cpu_now = self.process.cpu_us();
        // The referee's time on a flood of the step's output is the bot's (`flood`).
        let charge = self.stderr.meter.end_step();
        let cpu_us = match (self.cpu_mark, cpu_now) {
            (Some(before), Some(now)) => Some(now.saturating_sub(before) + charge),
            _ => None,
        };
        // A counter that could not be read leaves the mark where it was: the next step
        // is measured from the last reading, never from zero.
        if cpu_now.is_some() {
            self.cpu_mark = cpu_now;
        }
        // An answer that came after its CPU time ran out is late, however it was
        // noticed: the same rule whenever the counter is read.
        if let (Some(used), Some(allowed), true) = (cpu_us, allowed_us, self.cpu_counted) {
            if used > allowed {
                return Err(Box::new(self.cpu_fault(step, used, allowed, limit)));
            }
            if step > 1 {
                let limit_us = limit.map_or(0, |l| l.as_micros() as u64);
                self.bank_left_us = self
                    .bank_left_us
                    .saturating_sub(used.saturating_sub(limit_us));
            }
        }
        Ok((answer_us, cpu_us))
    }

    /// The fault `status` at `step` because of `reason`, unless a limit hit explains it
    /// better.
    pub(super) fn fault_or_limit(&self, status: MatchStatus, reason: String, step: u32) -> Verdict {
        self.limit_or(Verdict::Fault(status, failure(reason, step)), step)
    }

    /// A limit hit explains a crash or a timeout better than the symptom does: the
    /// limit's verdict if one was hit, else `verdict`.
    pub(super) fn limit_or(&self, verdict: Verdict, step: u32) -> Verdict {
        match self.process.limit_hit() {
            Some(kind) => self.limit_fault(kind, step),
            None => verdict,
        }
    }

    /// The verdict for a limit the bot went over at `step`.
    pub fn limit_fault(&self, kind: LimitKind, step: u32) -> Verdict {
        let (status, failure) = limit_failure(kind, &self.limits, step);
        Verdict::Fault(status, failure)
    }

    /// The limit the bot has gone over, if any (for the check at the end of a match).
    pub fn limit_hit(&self) -> Option<LimitKind> {
        self.process.limit_hit()
    }
}
