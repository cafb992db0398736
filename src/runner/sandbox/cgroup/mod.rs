//! Whole-match limits with control groups (v1 or v2): one cgroup per match that holds
//! every process of the bot, with a memory limit (resident, all processes together), a
//! process/thread limit, one core of CPU (so a bot's helpers cannot slow another match)
//! and a CPU-time counter.
//!
//! One core is the match's own core where the match has one and the cpuset controller is
//! there (the bot's processes cannot run anywhere else, whatever affinity they ask
//! for), else a CPU quota of one core. The cpuset costs nothing per step, while a cpu
//! controller group puts the bot in a scheduling group of its own, and each switch
//! between the referee and the bot then crosses groups: about 0.7 µs more per exchange
//! on the project's machine (BENCHMARKS.md).
//!
//! The bot's outer process (`mazearena sandbox-enter`) joins the cgroup before it
//! `exec`s bubblewrap, so no process of the bot is ever outside it.
//!
//! Match cgroups are made under this server's own cgroup (read from `/proc/self/cgroup`),
//! in a folder `mazearena`, so an operator's limits on the server also bound its bots.

mod detect;

mod match_cgroup;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use nix::fcntl::{Flock, FlockArg};

/// The CPU quota period, in microseconds; the quota is one period (one core).
pub(super) const CPU_PERIOD_US: u64 = 100_000;

/// Which cgroup version is in use, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CgroupRoot {
    /// Separate hierarchies per controller; each path is this server's `mazearena` folder.
    V1 {
        /// The memory controller's folder.
        memory: PathBuf,
        /// The pids controller's folder.
        pids: PathBuf,
        /// The cpuacct controller's folder (CPU time).
        cpuacct: PathBuf,
        /// The cpu controller's folder (the quota), when mounted.
        cpu: Option<PathBuf>,
        /// The cpuset controller's folder (the match's core), when mounted and usable.
        cpuset: Option<PathBuf>,
    },
    /// The unified hierarchy: one folder with memory, pids and cpu enabled below it.
    V2 {
        /// This server's `mazearena` folder.
        base: PathBuf,
    },
}

/// The limits one match cgroup enforces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CgroupLimits {
    /// Resident memory of all processes together, in bytes.
    pub memory_bytes: Option<u64>,
    /// Processes and threads at once.
    pub pids: Option<u64>,
    /// The one core every process may run on (the match's), held by a cpuset where
    /// there is one; without it (or without a cpuset) a CPU quota of one core.
    pub core: Option<usize>,
}

/// A limit that a match cgroup saw being hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CgroupHit {
    /// The kernel's OOM killer ended a process of the bot.
    Memory,
    /// A fork or thread creation was refused.
    Pids,
}

static NEXT: AtomicU64 = AtomicU64::new(0);

impl CgroupRoot {
    /// The folders match cgroups are made in (one per controller with v1).
    fn folders(&self) -> Vec<&Path> {
        match self {
            CgroupRoot::V1 {
                memory,
                pids,
                cpuacct,
                cpu,
                cpuset,
            } => [
                Some(memory),
                Some(pids),
                Some(cpuacct),
                cpu.as_ref(),
                cpuset.as_ref(),
            ]
            .into_iter()
            .flatten()
            .map(PathBuf::as_path)
            .collect(),
            CgroupRoot::V2 { base } => vec![base.as_path()],
        }
    }

    /// Removes the match cgroups left by processes that are gone (a server killed with
    /// SIGKILL cannot remove its own), killing anything still in them.
    pub fn sweep_stale(&self) {
        for folder in self.folders() {
            let Ok(entries) = std::fs::read_dir(folder) else {
                continue;
            };
            for entry in entries.flatten() {
                let name = entry.file_name();
                let Some(pid) = name
                    .to_str()
                    .and_then(|n| n.strip_prefix("m-"))
                    .and_then(|n| n.split('-').next())
                    .and_then(|p| p.parse::<u32>().ok())
                else {
                    continue;
                };
                if !Path::new(&format!("/proc/{pid}")).exists() {
                    remove_stale(&entry.path());
                }
            }
        }
    }

    /// How a match is held to one core, for reports.
    pub fn cpu_limit(&self) -> &'static str {
        match self {
            CgroupRoot::V1 {
                cpuset: Some(_), ..
            } => "a cpuset of the match's core",
            CgroupRoot::V1 { cpu: None, .. } => "no CPU limit (no cpu or cpuset controller)",
            CgroupRoot::V1 { .. } => "a one-core CPU quota",
            CgroupRoot::V2 { base } if base.join("cpuset.cpus").exists() => {
                "a cpuset of the match's core"
            }
            CgroupRoot::V2 { .. } => "a one-core CPU quota",
        }
    }

    /// The version, for reports: `v1` or `v2`.
    pub fn version(&self) -> &'static str {
        match self {
            CgroupRoot::V1 { .. } => "v1",
            CgroupRoot::V2 { .. } => "v2",
        }
    }

    /// Makes the cgroup of one match with `limits` (removed when the match is over).
    ///
    /// # Errors
    /// The file system errors of making or configuring it.
    pub fn create(&self, limits: CgroupLimits) -> std::io::Result<MatchCgroup> {
        self.build(&own_name(), limits, false, true)
    }

    /// Makes a cgroup as [`CgroupRoot::create`] does, but with no hold on the CPU
    /// (`limits.core` is not read): a warm sandbox's own, for its supervisor, whose
    /// matches each have a cgroup of their own held to their core.
    ///
    /// # Errors
    /// The file system errors of making or configuring it.
    pub fn create_unheld(&self, limits: CgroupLimits) -> std::io::Result<MatchCgroup> {
        self.build(&own_name(), limits, false, false)
    }

    /// The cgroup of a one-shot match (`mazearena run`, or a match that cannot be
    /// played warm): one of the cgroups kept between such matches (`run-K`, made by the
    /// first runner that needed it) that no other process holds, emptied and set for
    /// this match; else, when none can be taken up, one of its own as
    /// [`CgroupRoot::create`] makes. A kept cgroup spares a match the making of its
    /// cgroups and their removal (docs/PERFORMANCE.md); its counters are read as
    /// differences from the match's start. (A warm match has a cgroup of its own,
    /// [`super::ahead`].)
    ///
    /// A kept cgroup is held by an exclusive `flock` on its own folder in the pids
    /// hierarchy for as long as its match lasts: every runner that shares the hierarchy
    /// sees the same lock, whatever its `/run`.
    ///
    /// # Errors
    /// The file system errors of making or configuring a cgroup of its own.
    pub fn kept(&self, limits: CgroupLimits) -> std::io::Result<MatchCgroup> {
        for slot in 0..KEPT {
            let name = format!("run-{slot}");
            let Some(lock) = self.lock_kept(&name) else {
                continue;
            };
            if let Ok(mut group) = self.build(&name, limits, true, true) {
                group.kept = Some(lock);
                return Ok(group);
            }
            // A cgroup that could not be taken up was removed (as ours, under the lock).
        }
        self.create(limits)
    }

    /// The lock of kept cgroup `name` (its folder in the pids hierarchy, made if
    /// needed), if no other process holds it.
    fn lock_kept(&self, name: &str) -> Option<Flock<std::fs::File>> {
        use std::os::unix::fs::OpenOptionsExt;
        let dir = match self {
            CgroupRoot::V1 { pids, .. } => pids.join(name),
            CgroupRoot::V2 { base } => base.join(name),
        };
        match std::fs::create_dir(&dir) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
            Err(_) => return None,
        }
        let folder = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_DIRECTORY | libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&dir)
            .ok()?;
        Flock::lock(folder, FlockArg::LockExclusiveNonblock).ok()
    }

    /// Makes the cgroup `name` with `limits`; with `reuse`, takes up the folders of a
    /// kept cgroup that stand (emptied first, and refused while it still counts a
    /// process), else replaces a stale one; with `hold`, holds it to one core. On an
    /// error, what was made is removed.
    fn build(
        &self,
        name: &str,
        limits: CgroupLimits,
        reuse: bool,
        hold: bool,
    ) -> std::io::Result<MatchCgroup> {
        let mut group = MatchCgroup {
            dirs: Vec::new(),
            version: self.clone(),
            memory: PathBuf::new(),
            pids: PathBuf::new(),
            cpu_usage: PathBuf::new(),
            cpu_counter: None,
            marks: Marks::default(),
            reuse,
            kept: None,
        };
        // The folders first, every limit after: a kept cgroup is emptied in between, so
        // that no process left in it meets this match's limits.
        let (pin, quota) = match self {
            CgroupRoot::V1 {
                memory,
                pids,
                cpuacct,
                cpu,
                cpuset,
            } => {
                // The pids folder first, so that it is removed last: a kept cgroup's
                // lock is on it ([`CgroupRoot::kept`]).
                group.pids = group.make(&pids.join(name))?;
                group.memory = group.make(&memory.join(name))?;
                let acct = group.make(&cpuacct.join(name))?;
                group.cpu_usage = acct.join("cpuacct.usage");
                let pin = match (limits.core, cpuset) {
                    (Some(core), Some(cpuset)) if hold => {
                        Some((group.make(&cpuset.join(name))?, core))
                    }
                    _ => None,
                };
                // Unpinned, a quota of one core: in the cpu controller's own folder, or
                // in cpuacct's where the two are mounted together.
                let quota = match (&pin, cpu) {
                    _ if !hold => None,
                    (None, Some(cpu)) if cpu != cpuacct => Some(group.make(&cpu.join(name))?),
                    (None, Some(_)) => Some(acct),
                    _ => None,
                };
                (pin, quota)
            }
            CgroupRoot::V2 { base } => {
                let dir = group.make(&base.join(name))?;
                group.memory = dir.clone();
                group.pids = dir.clone();
                group.cpu_usage = dir.join("cpu.stat");
                (limits.core.filter(|_| hold).map(|core| (dir, core)), None)
            }
        };
        if reuse {
            // Whatever a runner killed before it could empty the cgroup left behind.
            group.kill_all();
            // A process that ended but was not yet reaped (bubblewrap's init, orphaned
            // when bubblewrap exits first, waits for the host's init) still counts
            // against the process limit: such a cgroup waits for a later match.
            if !group.members().is_empty()
                || read_counter_file(&group.pids.join("pids.current")).unwrap_or(0) > 0
            {
                return Err(std::io::Error::other(
                    "a kept cgroup still counts processes",
                ));
            }
        }
        group.limit(limits.memory_bytes, limits.pids)?;
        if hold {
            group.hold_to_one_core(pin, quota)?;
        }
        group.cpu_counter = super::proctree::OpenCounter::open(&group.cpu_usage);
        if reuse {
            group.mark();
        }
        Ok(group)
    }
}

/// A name no other cgroup of this process had: `m-PID-N` (the sweep of stale cgroups
/// reads the pid back).
fn own_name() -> String {
    format!(
        "m-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    )
}

/// How many cgroups are kept for one-shot matches, in each hierarchy.
const KEPT: usize = 16;

/// Kills whatever is left in a match cgroup of a process that is gone, and removes it.
pub(super) fn remove_stale(dir: &Path) {
    let deadline = Instant::now() + Duration::from_secs(1);
    loop {
        let procs = std::fs::read_to_string(dir.join("cgroup.procs")).unwrap_or_default();
        for pid in procs.lines().filter_map(|l| l.trim().parse::<i32>().ok()) {
            let _ = nix::sys::signal::kill(
                nix::unistd::Pid::from_raw(pid),
                nix::sys::signal::Signal::SIGKILL,
            );
        }
        if std::fs::remove_dir(dir).is_ok() || !dir.exists() || Instant::now() > deadline {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Copies the value of `file` in folder `from` to the same file in `to`.
pub(super) fn copy_file(from: &Path, to: &Path, file: &str) -> std::io::Result<()> {
    let value = std::fs::read_to_string(from.join(file))?;
    write_text(to, file, value.trim())
}

pub(super) fn write(dir: &Path, file: &str, value: u64) -> std::io::Result<()> {
    write_text(dir, file, &value.to_string())
}

/// Writes `text` to `file` in `dir`; an error names the file.
pub(super) fn write_text(dir: &Path, file: &str, text: &str) -> std::io::Result<()> {
    std::fs::write(dir.join(file), text)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", dir.join(file).display())))
}

/// The cgroup of one running match. Dropping it kills every process left in it and
/// removes it (a kept one, [`CgroupRoot::kept`], stays for the next match).
#[derive(Debug)]
pub struct MatchCgroup {
    dirs: Vec<PathBuf>,
    version: CgroupRoot,
    memory: PathBuf,
    pids: PathBuf,
    cpu_usage: PathBuf,
    /// `cpu_usage`, kept open: it is read at every step.
    cpu_counter: Option<super::proctree::OpenCounter>,
    /// The counters when the current match began (all zero for a cgroup of one match).
    marks: Marks,
    /// Whether folders that stand are taken up (a kept cgroup's) rather than replaced.
    reuse: bool,
    /// For a kept cgroup ([`CgroupRoot::kept`]), the lock that makes it this match's:
    /// it is emptied, not removed, when dropped.
    kept: Option<Flock<std::fs::File>>,
}

/// A reused cgroup's counters at the start of a match: the match's own are the
/// differences.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Marks {
    cpu_us: u64,
    oom_kills: u64,
    refused_forks: u64,
}

/// The number a one-number file such as `pids.current` holds.
fn read_counter_file(path: &Path) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

pub(super) fn read_counter(path: &Path, key: &str) -> Option<u64> {
    counter(&std::fs::read_to_string(path).ok()?, key)
}

/// The value of `key` in a `key value` per line file such as `memory.events`.
pub(super) fn counter(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|l| {
        let mut words = l.split_whitespace();
        (words.next() == Some(key))
            .then(|| words.next()?.parse().ok())
            .flatten()
    })
}

#[cfg(test)]
mod tests;
