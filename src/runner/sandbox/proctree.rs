//! A bot's processes seen through `/proc`, for where no cgroup can be made: the tree
//! under the bot's outer process (in a PID namespace every orphan is adopted inside it,
//! so nothing escapes the tree), with its total resident memory, thread count and CPU
//! time. The watchdog compares them with the limits. And the orphans a one-match runner
//! adopts from bubblewrap and reaps.

use std::collections::BTreeSet;

/// One reading of a process tree.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TreeUsage {
    /// Processes in the tree.
    pub processes: u64,
    /// Threads of all of them (a process counts at least one).
    pub threads: u64,
    /// Resident memory of all of them, in bytes.
    pub rss_bytes: u64,
    /// CPU time (user + system, with waited-for children) of all of them, in µs.
    pub cpu_us: u64,
}

/// Every process in the tree rooted at `root`, the root first.
pub fn members(root: u32) -> Vec<u32> {
    let mut seen = BTreeSet::new();
    let mut order = Vec::new();
    let mut stack = vec![root];
    while let Some(pid) = stack.pop() {
        if !seen.insert(pid) {
            continue;
        }
        let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
            continue;
        };
        order.push(pid);
        for task in tasks.flatten() {
            let path = task.path().join("children");
            if let Ok(text) = std::fs::read_to_string(path) {
                stack.extend(
                    text.split_whitespace()
                        .filter_map(|c| c.parse::<u32>().ok()),
                );
            }
        }
    }
    order
}

fn clock_ticks() -> u64 {
    nix::unistd::sysconf(nix::unistd::SysconfVar::CLK_TCK)
        .ok()
        .flatten()
        .filter(|&h| h > 0)
        .map_or(100, |h| h as u64)
}

/// Fields of `/proc/<pid>/stat` after the command name (field 3 of stat(5) is index 0).
fn stat_fields(pid: u32) -> Option<Vec<u64>> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    Some(
        rest.split_whitespace()
            .skip(1)
            .map(|f| f.parse::<u64>().unwrap_or(0))
            .collect(),
    )
}

/// Reads the usage of the tree rooted at `root`.
pub fn usage(root: u32) -> TreeUsage {
    let hz = clock_ticks();
    let page = 4096;
    let mut total = TreeUsage::default();
    for pid in members(root) {
        let Some(f) = stat_fields(pid) else { continue };
        // stat(5): utime 14, stime 15, cutime 16, cstime 17, num_threads 20, rss 24;
        // index = field - 4 (state, field 3, was skipped).
        let ticks: u64 = f.get(10..14).map_or(0, |t| t.iter().sum());
        total.processes += 1;
        total.threads += f.get(16).copied().unwrap_or(1).max(1);
        total.rss_bytes += f.get(20).copied().unwrap_or(0) * page;
        total.cpu_us += ticks * 1_000_000 / hz;
    }
    total
}

/// A small kernel file (a counter) read again and again through one open handle: a
/// read from offset 0 each time, without opening the file per read (which costs more
/// than the rest of a step), into a buffer on the stack.
#[derive(Debug)]
pub struct OpenCounter {
    file: std::fs::File,
}

/// The most bytes of a counter file [`OpenCounter::read_with`] reads: `cpuacct.usage`
/// holds one number, a v2 `cpu.stat` six to nine lines (150-250 bytes, `usage_usec`
/// first).
const COUNTER_BYTES: usize = 512;

impl OpenCounter {
    /// Opens `path`, if it exists and may be read.
    pub fn open(path: &std::path::Path) -> Option<OpenCounter> {
        std::fs::File::open(path)
            .ok()
            .map(|file| OpenCounter { file })
    }

    /// Reads the file's text now (at most 512 bytes) and hands it to `parse`, without
    /// allocating: it is read at every step of a match.
    pub fn read_with<T>(&self, parse: impl FnOnce(&str) -> Option<T>) -> Option<T> {
        use std::os::unix::fs::FileExt;
        let mut buf = [0u8; COUNTER_BYTES];
        let n = self.file.read_at(&mut buf, 0).ok()?;
        parse(std::str::from_utf8(&buf[..n]).ok()?)
    }
}

/// Sends SIGKILL to every process of the tree, leaves first, until none is left (at
/// most 50 rounds: a process may fork while the tree is walked).
pub fn kill_tree(root: u32) {
    use nix::sys::signal::{Signal, kill};
    use nix::unistd::Pid;
    for _ in 0..50 {
        let pids = members(root);
        if pids.is_empty() {
            return;
        }
        for pid in pids.iter().rev() {
            let _ = kill(Pid::from_raw(*pid as i32), Signal::SIGKILL);
        }
        if pids.len() == 1 {
            return;
        }
    }
}

/// Makes this process the reaper of the orphans among its descendants
/// (`PR_SET_CHILD_SUBREAPER`), for a runner of one match (`mazearena run`): bubblewrap
/// exits without reaping its init, which would otherwise wait for the host's init,
/// still counted by the match's cgroup. Call [`reap_orphans`] when the match is over.
///
/// # Errors
/// The kernel refused it.
pub fn adopt_orphans() -> nix::Result<()> {
    nix::sys::prctl::set_child_subreaper(true)
}

/// Reaps every child of this process that has ended: for a process whose runtime waits
/// for no child any more (`mazearena run` once its match is over), after
/// [`adopt_orphans`].
pub fn reap_orphans() {
    use nix::sys::wait::{WaitPidFlag, WaitStatus, waitpid};
    while let Ok(status) = waitpid(None, Some(WaitPidFlag::WNOHANG)) {
        if status == WaitStatus::StillAlive {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_is_a_tree_of_one_or_more_with_memory_and_threads() {
        let u = usage(std::process::id());
        assert!(u.processes >= 1);
        assert!(u.threads >= 1);
        assert!(u.rss_bytes > 0);
    }
}
