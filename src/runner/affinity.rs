//! One core per match. The referee is idle while the bot thinks and the bot is idle
//! while the referee works, so both belong on one core: a wake-up across cores costs
//! some 30 µs a step, on one core a few. A match worker runs on its own thread pinned
//! to a core, and the bot's processes, started from that thread, inherit the pinning
//! (in the sandbox too: bubblewrap and the jail keep the affinity they are given).

use nix::sched::{CpuSet, sched_getaffinity, sched_getcpu, sched_setaffinity};
use nix::unistd::Pid;

/// The cores the calling thread may run on, in order.
pub fn allowed_cores() -> Vec<usize> {
    let Ok(set) = sched_getaffinity(Pid::from_raw(0)) else {
        return Vec::new();
    };
    (0..CpuSet::count())
        .filter(|&c| set.is_set(c).unwrap_or(false))
        .collect()
}

/// Pins the calling thread (and what it starts from now on) to `core`.
///
/// # Errors
/// The core is not one this process may use.
pub fn pin_current_thread(core: usize) -> nix::Result<()> {
    let mut set = CpuSet::new();
    set.set(core)?;
    sched_setaffinity(Pid::from_raw(0), &set)
}

/// Pins the calling thread to the core it is running on now (the one the scheduler
/// chose for it), and returns that core.
pub fn pin_to_this_core() -> Option<usize> {
    let core = sched_getcpu().ok()?;
    pin_current_thread(core).ok()?;
    Some(core)
}

/// The core the calling thread is pinned to, if it may run on exactly one.
pub fn pinned_core() -> Option<usize> {
    match allowed_cores()[..] {
        [core] => Some(core),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pinned_thread_reports_its_core_and_its_children_inherit_it() {
        let cores = allowed_cores();
        assert!(!cores.is_empty());
        let core = *cores.last().unwrap();
        std::thread::spawn(move || {
            assert_eq!(pinned_core(), (cores.len() == 1).then_some(core));
            pin_current_thread(core).unwrap();
            assert_eq!(pinned_core(), Some(core));
            // A process started from this thread runs on the same core.
            let out = std::process::Command::new("grep")
                .args(["Cpus_allowed_list", "/proc/self/status"])
                .output()
                .unwrap();
            let text = String::from_utf8_lossy(&out.stdout);
            assert_eq!(
                text.split_whitespace().last(),
                Some(core.to_string().as_str())
            );
        })
        .join()
        .unwrap();
    }
}
