//! A bot pays for a flood of output: the referee's own CPU time spent on a step's output
//! past a small free share (its stderr bytes, an mms mouse's command lines) counts as
//! the bot's CPU time for that step, under the same limits as the bot's own.
//!
//! A bot can make output far more cheaply than the referee can take it in: one write of
//! a buffer it made once puts thousands of stderr lines or display commands in a pipe,
//! and each must be read, cut and looked at. Without this, a flood would cost the
//! server many times the CPU time the bot is charged. The share is well above what
//! bots show of their thinking (a few stderr lines, an mms mouse redrawing its maze),
//! so they are never charged; past it the charge is measured, not estimated: the
//! match's thread's CPU clock (each match has a thread of its own) from the moment the
//! step's output passed the share to the step's answer.

/// The output a step may have for free, in bytes: a step's stderr bytes, plus, for an mms
/// mouse, each command line's bytes and [`MMS_LINE_WEIGHT`].
pub const FREE_BYTES_PER_STEP: u64 = 32 * 1024;

/// What each command line of an mms mouse weighs besides its bytes: taking in a line
/// costs the referee more than its bytes do (about 200 free lines a step, where a
/// mouse that redraws every cell of its maze needs about as many).
pub const MMS_LINE_WEIGHT: u64 = 128;

/// The charge of one match's steps.
#[derive(Debug, Default, Clone)]
pub struct FloodMeter {
    /// The output of the step being asked, in bytes (weighted).
    step_volume: u64,
    /// The thread's CPU clock (µs) when the step's output passed its free share.
    charging_since: Option<u64>,
    /// What the steps answered so far were charged, in µs.
    charged_us: u64,
}

/// The CPU time of the calling thread, in µs (`None` where it cannot be read).
pub fn thread_cpu_us() -> Option<u64> {
    let t = nix::time::clock_gettime(nix::time::ClockId::CLOCK_THREAD_CPUTIME_ID).ok()?;
    Some(t.tv_sec() as u64 * 1_000_000 + t.tv_nsec() as u64 / 1_000)
}

impl FloodMeter {
    /// A new step is asked: its output starts from nothing.
    pub fn begin_step(&mut self) {
        self.step_volume = 0;
        self.charging_since = None;
    }

    /// The step's output grew by `bytes` (weighted); past the free share, the thread's
    /// CPU time from now on is the bot's.
    pub fn add(&mut self, bytes: u64) {
        self.step_volume = self.step_volume.saturating_add(bytes);
        if self.charging_since.is_none() && self.step_volume > FREE_BYTES_PER_STEP {
            self.charging_since = thread_cpu_us();
        }
    }

    /// What the step being asked has been charged so far, in µs.
    pub fn step_charge_us(&self) -> u64 {
        // The clock is read only while the step is being charged: a quiet step costs
        // no system call.
        let Some(since) = self.charging_since else {
            return 0;
        };
        thread_cpu_us().map_or(0, |now| now.saturating_sub(since))
    }

    /// The step was answered: its charge (µs), added to the match's.
    pub fn end_step(&mut self) -> u64 {
        let charge = self.step_charge_us();
        self.charged_us += charge;
        self.begin_step();
        charge
    }

    /// What the match's answered steps were charged, in µs.
    pub fn charged_us(&self) -> u64 {
        self.charged_us
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_work_past_the_free_share_is_charged() {
        let mut m = FloodMeter::default();
        m.begin_step();
        m.add(FREE_BYTES_PER_STEP);
        let spin = |ms: u64| {
            let until = thread_cpu_us().unwrap() + ms * 1000;
            while thread_cpu_us().unwrap() < until {}
        };
        spin(20);
        assert_eq!(m.step_charge_us(), 0, "within the share");
        m.add(1);
        spin(20);
        let charged = m.end_step();
        assert!((20_000..40_000).contains(&charged), "{charged}");
        // A new step starts free again.
        m.add(10);
        spin(5);
        assert_eq!(m.end_step(), 0);
        assert_eq!(m.charged_us(), charged);
    }
}
