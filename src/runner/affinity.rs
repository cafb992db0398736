//! One core per match. The referee is idle while the bot thinks and the bot is idle
//! while the referee works, so both belong on one core: a wake-up across cores costs
//! some 30 µs a step, on one core a few. A match worker runs on its own thread pinned
//! to a core, and the bot's processes, started from that thread, inherit the pinning
//! (in the sandbox too: bubblewrap and the jail keep the affinity they are given).
//!
//! Several processes on one machine (a server and `mazearena worker`s, or a local
//! tournament beside a server) share its cores: each claims its cores with a lock file
//! per core (see [`claim_cores`]), so that their matches do not all land on the first.

use nix::sched::{CpuSet, sched_getaffinity, sched_getcpu, sched_setaffinity};
use nix::unistd::Pid;

/// The number of cores: the default and the maximum number of workers, so that each
/// bot has a core to itself and timing is fair.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The cores the calling thread may run on, in order.
pub fn allowed_cores() -> Vec<usize> {
    let Ok(set) = sched_getaffinity(Pid::from_raw(0)) else {
        return Vec::new();
    };
    (0..CpuSet::count())
        .filter(|&c| set.is_set(c).unwrap_or(false))
        .collect()
}

/// A core this process holds for one match worker: other mazearena processes on the
/// machine leave it alone while the claim lives (the lock goes with the process, even
/// when it is killed).
#[derive(Debug)]
pub struct CoreClaim {
    /// The core.
    pub core: usize,
    /// The lock on it; `None` when every core was taken and this one is shared.
    _lock: Option<nix::fcntl::Flock<std::fs::File>>,
}

/// Claims `n` of the allowed cores for match workers: first the cores no other
/// mazearena process on this machine holds (an exclusive lock on
/// `mazearena-core-N.lock` in `lock_dir`), then, if there are not enough, shared ones
/// in turn. Empty if the allowed cores cannot be read.
pub fn claim_cores(n: usize, lock_dir: &std::path::Path) -> Vec<CoreClaim> {
    let cores = allowed_cores();
    let mut claims: Vec<CoreClaim> = Vec::new();
    for &core in &cores {
        if claims.len() == n {
            break;
        }
        let path = lock_dir.join(format!("mazearena-core-{core}.lock"));
        let Ok(file) = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
        else {
            continue;
        };
        if let Ok(lock) = nix::fcntl::Flock::lock(file, nix::fcntl::FlockArg::LockExclusiveNonblock)
        {
            claims.push(CoreClaim {
                core,
                _lock: Some(lock),
            });
        }
    }
    let mut shared = cores.iter().cycle();
    while claims.len() < n && !cores.is_empty() {
        let core = *shared.next().expect("a cycle over a non-empty list");
        claims.push(CoreClaim { core, _lock: None });
    }
    claims
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
    fn a_second_process_claims_the_cores_the_first_left_free() {
        let dir = tempfile::tempdir().unwrap();
        let cores = allowed_cores();
        let first = claim_cores(1, dir.path());
        assert_eq!(first.len(), 1);
        // Locks are per open file: a second claim (as another process would make) gets
        // another core while one is free, and shares one after that.
        let second = claim_cores(cores.len(), dir.path());
        assert_eq!(second.len(), cores.len());
        if cores.len() > 1 {
            assert_ne!(second[0].core, first[0].core);
        }
        let locked = second.iter().filter(|c| c._lock.is_some()).count();
        assert_eq!(locked, cores.len() - 1);
        drop(first);
        let third = claim_cores(1, dir.path());
        assert!(third[0]._lock.is_some(), "a released core is free again");
    }

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
