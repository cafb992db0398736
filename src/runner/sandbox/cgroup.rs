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

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use nix::fcntl::{Flock, FlockArg};

/// The CPU quota period, in microseconds; the quota is one period (one core).
const CPU_PERIOD_US: u64 = 100_000;

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
    /// Finds a cgroup hierarchy this process may make match cgroups in, and proves it by
    /// making and removing one with limits. `Err` says why none can be used.
    ///
    /// # Errors
    /// A message for `mazearena doctor`.
    pub fn detect() -> Result<CgroupRoot, String> {
        let own = std::fs::read_to_string("/proc/self/cgroup")
            .map_err(|e| format!("/proc/self/cgroup: {e}"))?;
        let mounts = std::fs::read_to_string("/proc/self/mountinfo")
            .map_err(|e| format!("/proc/self/mountinfo: {e}"))?;
        let v1 = detect_v1(&own, &mounts);
        let mut root = match v1 {
            Ok(root) => root,
            Err(v1_err) => detect_v2(&own, &mounts)
                .map_err(|v2_err| format!("cgroup v1: {v1_err}; cgroup v2: {v2_err}"))?,
        };
        let probe = |root: &CgroupRoot| {
            root.create(CgroupLimits {
                memory_bytes: Some(64 << 20),
                pids: Some(8),
                core: super::super::affinity::allowed_cores().first().copied(),
            })
            .map(drop)
            .map_err(|e| format!("cannot make a match cgroup: {e}"))
        };
        if let Err(e) = probe(&root) {
            // A cpuset that cannot be set up leaves the CPU quota to hold the core.
            match &mut root {
                CgroupRoot::V1 { cpuset, .. } if cpuset.is_some() => *cpuset = None,
                _ => return Err(e),
            }
            probe(&root)?;
        }
        root.sweep_stale();
        Ok(root)
    }

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
fn remove_stale(dir: &Path) {
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
fn copy_file(from: &Path, to: &Path, file: &str) -> std::io::Result<()> {
    let value = std::fs::read_to_string(from.join(file))?;
    write_text(to, file, value.trim())
}

fn write(dir: &Path, file: &str, value: u64) -> std::io::Result<()> {
    write_text(dir, file, &value.to_string())
}

/// Writes `text` to `file` in `dir`; an error names the file.
fn write_text(dir: &Path, file: &str, text: &str) -> std::io::Result<()> {
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
struct Marks {
    cpu_us: u64,
    oom_kills: u64,
    refused_forks: u64,
}

impl MatchCgroup {
    fn make(&mut self, dir: &Path) -> std::io::Result<PathBuf> {
        let mut made = std::fs::create_dir(dir);
        let exists = made
            .as_ref()
            .is_err_and(|e| e.kind() == std::io::ErrorKind::AlreadyExists);
        if exists && self.reuse {
            // A kept cgroup, taken up again.
            made = Ok(());
        } else if exists {
            // Our names never repeat within a process: this one was left by a process
            // that had our pid before us and was killed.
            remove_stale(dir);
            made = std::fs::create_dir(dir);
        }
        made.map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", dir.display())))?;
        self.dirs.push(dir.to_path_buf());
        Ok(dir.to_path_buf())
    }

    /// The files `sandbox-enter` writes `0` to, one per hierarchy, to move itself in
    /// before it runs bubblewrap: with v1 each hierarchy's `tasks` (the writing thread:
    /// `sandbox-enter` has only the one), with v2 `cgroup.procs`.
    ///
    /// With v1, a write to `cgroup.procs` takes the kernel's global lock of every
    /// thread group, whose writer waits out an RCU grace period: 10-20 ms a match on the
    /// project's machine. Moving the writing thread alone through `tasks` skips that
    /// lock (0.06 ms), and a process of one thread is then wholly in the cgroup
    /// (docs/PERFORMANCE.md).
    pub fn join_files(&self) -> Vec<PathBuf> {
        let file = match self.version {
            CgroupRoot::V1 { .. } => "tasks",
            CgroupRoot::V2 { .. } => "cgroup.procs",
        };
        self.dirs.iter().map(|d| d.join(file)).collect()
    }

    /// Holds every process to one core: a cpuset of `pin`'s core (its folder, and the
    /// core) where there is one, else a CPU quota of one core (v1: in the `quota`
    /// folder, where there is a cpu controller). A kept cgroup also loses
    /// what its last match had and this one does not: the quota (v2, or v1's cpu
    /// controller mounted with cpuacct, whose folder this match joins) or the core (v2).
    ///
    /// # Errors
    /// The file system errors of writing them.
    fn hold_to_one_core(
        &self,
        pin: Option<(PathBuf, usize)>,
        quota: Option<PathBuf>,
    ) -> std::io::Result<()> {
        match &self.version {
            CgroupRoot::V1 {
                cpuset,
                cpu,
                cpuacct,
                ..
            } => {
                match pin {
                    Some((dir, core)) => {
                        // A v1 cpuset takes no process before it has memory nodes.
                        if let Some(cpuset) = cpuset {
                            copy_file(cpuset, &dir, "cpuset.mems")?;
                        }
                        write(&dir, "cpuset.cpus", core as u64)?;
                        // cpu mounted with cpuacct: this match's folder may hold the last
                        // one's quota.
                        if cpu.as_ref() == Some(cpuacct)
                            && self.reuse
                            && let Some(acct) = self.cpu_usage.parent()
                        {
                            write_text(acct, "cpu.cfs_quota_us", "-1")?;
                        }
                    }
                    None => {
                        if let Some(dir) = quota {
                            write(&dir, "cpu.cfs_period_us", CPU_PERIOD_US)?;
                            write(&dir, "cpu.cfs_quota_us", CPU_PERIOD_US)?;
                        }
                    }
                }
            }
            CgroupRoot::V2 { .. } => {
                let dir = &self.pids;
                let _ = std::fs::write(dir.join("memory.swap.max"), "0");
                // Without the cpuset controller the file is missing and the write fails.
                let pinned =
                    pin.is_some_and(|(_, core)| write(dir, "cpuset.cpus", core as u64).is_ok());
                if pinned {
                    if self.reuse {
                        let _ = std::fs::write(dir.join("cpu.max"), format!("max {CPU_PERIOD_US}"));
                    }
                } else {
                    let _ = std::fs::write(
                        dir.join("cpu.max"),
                        format!("{CPU_PERIOD_US} {CPU_PERIOD_US}"),
                    );
                    if self.reuse {
                        // The parent's cores.
                        let _ = std::fs::write(dir.join("cpuset.cpus"), "");
                    }
                }
            }
        }
        Ok(())
    }

    /// Sets the memory limit (resident, all processes; `None`: none) and the process
    /// limit, for a new cgroup or for the next match of a reused one.
    ///
    /// # Errors
    /// The file system errors of writing them.
    pub fn limit(&self, memory_bytes: Option<u64>, pids: Option<u64>) -> std::io::Result<()> {
        match self.version {
            CgroupRoot::V1 { .. } => {
                let mem = memory_bytes.map_or("-1".to_string(), |m| m.to_string());
                // Swap would let a bot hold more than the limit; refuse it where the
                // kernel accounts swap. The swap limit may never be below the memory
                // limit: going down, the memory limit is lowered first, going up last.
                let memsw = self.memory.join("memory.memsw.limit_in_bytes").exists();
                let first = write_text(&self.memory, "memory.limit_in_bytes", &mem);
                if memsw {
                    write_text(&self.memory, "memory.memsw.limit_in_bytes", &mem)?;
                }
                if first.is_err() {
                    write_text(&self.memory, "memory.limit_in_bytes", &mem)?;
                }
            }
            CgroupRoot::V2 { .. } => {
                let mem = memory_bytes.map_or("max".to_string(), |m| m.to_string());
                write_text(&self.memory, "memory.max", &mem)?;
            }
        }
        let pids = pids.map_or("max".to_string(), |n| n.to_string());
        write_text(&self.pids, "pids.max", &pids)
    }

    /// Starts a new match in this cgroup: from now on [`MatchCgroup::cpu_us`] and
    /// [`MatchCgroup::limit_hit`] count from here.
    pub fn mark(&mut self) {
        self.marks = Marks {
            cpu_us: self.cpu_total_us().unwrap_or(0),
            oom_kills: self.oom_kills(),
            refused_forks: self.refused_forks(),
        };
    }

    /// Every thread in the cgroup.
    pub fn threads(&self) -> Vec<i32> {
        let file = match self.version {
            CgroupRoot::V1 { .. } => "tasks",
            CgroupRoot::V2 { .. } => "cgroup.threads",
        };
        std::fs::read_to_string(self.pids.join(file))
            .unwrap_or_default()
            .lines()
            .filter_map(|l| l.trim().parse().ok())
            .collect()
    }

    fn oom_kills(&self) -> u64 {
        let file = match self.version {
            CgroupRoot::V1 { .. } => "memory.oom_control",
            CgroupRoot::V2 { .. } => "memory.events",
        };
        read_counter(&self.memory.join(file), "oom_kill").unwrap_or(0)
    }

    fn refused_forks(&self) -> u64 {
        read_counter(&self.pids.join("pids.events"), "max").unwrap_or(0)
    }

    /// CPU time used by every process that ran in the cgroup in this match, in µs.
    pub fn cpu_us(&self) -> Option<u64> {
        Some(self.cpu_total_us()?.saturating_sub(self.marks.cpu_us))
    }

    /// CPU time used by every process that ever ran in the cgroup, in µs.
    fn cpu_total_us(&self) -> Option<u64> {
        let parse = |text: &str| match self.version {
            CgroupRoot::V1 { .. } => text.trim().parse::<u64>().ok().map(|ns| ns / 1000),
            CgroupRoot::V2 { .. } => counter(text, "usage_usec"),
        };
        match &self.cpu_counter {
            Some(counter) => counter.read_with(parse),
            None => parse(&std::fs::read_to_string(&self.cpu_usage).ok()?),
        }
    }

    /// The first limit found hit, if any: an OOM kill, or a refused fork.
    pub fn limit_hit(&self) -> Option<CgroupHit> {
        if self.oom_kills() > self.marks.oom_kills {
            return Some(CgroupHit::Memory);
        }
        if self.refused_forks() > self.marks.refused_forks {
            return Some(CgroupHit::Pids);
        }
        None
    }

    /// Process ids still in the cgroup.
    pub fn members(&self) -> Vec<i32> {
        std::fs::read_to_string(self.pids.join("cgroup.procs"))
            .unwrap_or_default()
            .lines()
            .filter_map(|l| l.trim().parse().ok())
            .collect()
    }

    /// Kills every process in the cgroup and waits (up to 2 s) until it is empty.
    pub fn kill_all(&self) {
        if let CgroupRoot::V2 { .. } = self.version {
            let _ = std::fs::write(self.pids.join("cgroup.kill"), "1");
        }
        let until = Instant::now() + Duration::from_secs(2);
        loop {
            let members = self.members();
            if members.is_empty() || Instant::now() > until {
                break;
            }
            for pid in members {
                let _ = nix::sys::signal::kill(
                    nix::unistd::Pid::from_raw(pid),
                    nix::sys::signal::Signal::SIGKILL,
                );
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

impl Drop for MatchCgroup {
    fn drop(&mut self) {
        self.kill_all();
        if self.kept.is_some() {
            // Kept for the next one-shot match; its lock goes with it.
            return;
        }
        for dir in self.dirs.iter().rev() {
            // A dying process may hold the cgroup for a moment.
            for _ in 0..200 {
                if std::fs::remove_dir(dir).is_ok() || !dir.exists() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
}

/// The number a one-number file such as `pids.current` holds.
fn read_counter_file(path: &Path) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

fn read_counter(path: &Path, key: &str) -> Option<u64> {
    counter(&std::fs::read_to_string(path).ok()?, key)
}

/// The value of `key` in a `key value` per line file such as `memory.events`.
fn counter(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|l| {
        let mut words = l.split_whitespace();
        (words.next() == Some(key))
            .then(|| words.next()?.parse().ok())
            .flatten()
    })
}

/// Mount points of cgroup file systems from `/proc/self/mountinfo`: (mount point, fs
/// type, super options).
fn cgroup_mounts(mountinfo: &str) -> Vec<(PathBuf, String, String)> {
    mountinfo
        .lines()
        .filter_map(|line| {
            let (left, right) = line.split_once(" - ")?;
            let mount_point = left.split(' ').nth(4)?;
            let mut r = right.split(' ');
            let fstype = r.next()?;
            let _source = r.next()?;
            let options = r.next().unwrap_or("");
            (fstype == "cgroup" || fstype == "cgroup2").then(|| {
                (
                    PathBuf::from(mount_point),
                    fstype.to_string(),
                    options.to_string(),
                )
            })
        })
        .collect()
}

/// This process's path in the hierarchy whose controller list contains `controller`
/// (v1), or in the unified one (`controller` empty).
fn own_path(own: &str, controller: &str) -> Option<String> {
    own.lines().find_map(|l| {
        let mut parts = l.splitn(3, ':');
        let _id = parts.next()?;
        let controllers = parts.next()?;
        let path = parts.next()?;
        let hit = if controller.is_empty() {
            controllers.is_empty()
        } else {
            controllers.split(',').any(|c| c == controller)
        };
        hit.then(|| path.to_string())
    })
}

fn ensure_dir(dir: &Path) -> Result<(), String> {
    match std::fs::create_dir(dir) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(format!("cannot create {}: {e}", dir.display())),
    }
}

fn detect_v1(own: &str, mountinfo: &str) -> Result<CgroupRoot, String> {
    let mounts = cgroup_mounts(mountinfo);
    let folder = |controller: &str| -> Result<PathBuf, String> {
        let (mount, _, _) = mounts
            .iter()
            .find(|(_, t, o)| t == "cgroup" && o.split(',').any(|x| x == controller))
            .ok_or_else(|| format!("no {controller} hierarchy mounted"))?;
        let path = own_path(own, controller).unwrap_or_else(|| "/".into());
        let dir = mount.join(path.trim_start_matches('/')).join("mazearena");
        ensure_dir(&dir)?;
        Ok(dir)
    };
    Ok(CgroupRoot::V1 {
        memory: folder("memory")?,
        pids: folder("pids")?,
        cpuacct: folder("cpuacct")?,
        cpu: folder("cpu").ok(),
        cpuset: folder("cpuset")
            .ok()
            .filter(|dir| inherit_cpuset(dir).is_ok()),
    })
}

/// Gives a new v1 cpuset folder its parent's cores and memory nodes (it starts with
/// none, and its children could have none).
fn inherit_cpuset(dir: &Path) -> std::io::Result<()> {
    let parent = dir.parent().unwrap_or(dir);
    for file in ["cpuset.cpus", "cpuset.mems"] {
        if std::fs::read_to_string(dir.join(file))?.trim().is_empty() {
            copy_file(parent, dir, file)?;
        }
    }
    Ok(())
}

fn detect_v2(own: &str, mountinfo: &str) -> Result<CgroupRoot, String> {
    let mounts = cgroup_mounts(mountinfo);
    let (mount, _, _) = mounts
        .iter()
        .find(|(_, t, _)| t == "cgroup2")
        .ok_or("no cgroup2 hierarchy mounted")?;
    let path = own_path(own, "").ok_or("this process is in no cgroup2 group")?;
    let here = mount.join(path.trim_start_matches('/'));
    let controllers = std::fs::read_to_string(here.join("cgroup.controllers")).unwrap_or_default();
    for needed in ["memory", "pids"] {
        if !controllers.split_whitespace().any(|c| c == needed) {
            return Err(format!(
                "the {needed} controller is not available in {}",
                here.display()
            ));
        }
    }
    let enable = |dir: &Path| {
        let control = dir.join("cgroup.subtree_control");
        std::fs::write(&control, "+memory +pids +cpu +cpuset")
            .or_else(|_| std::fs::write(&control, "+memory +pids +cpu"))
            .or_else(|_| std::fs::write(&control, "+memory +pids"))
    };
    if enable(&here).is_err() {
        // "No internal processes": move this server into a leaf of its own first.
        let leaf = here.join("mazearena-server");
        ensure_dir(&leaf)?;
        std::fs::write(leaf.join("cgroup.procs"), std::process::id().to_string())
            .map_err(|e| format!("cannot move the server into {}: {e}", leaf.display()))?;
        enable(&here)
            .map_err(|e| format!("cannot enable controllers in {}: {e}", here.display()))?;
    }
    let base = here.join("mazearena");
    ensure_dir(&base)?;
    enable(&base).map_err(|e| format!("cannot enable controllers in {}: {e}", base.display()))?;
    Ok(CgroupRoot::V2 { base })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cgroup hierarchy stood in for by plain folders: what a match cgroup writes
    /// there can be read back.
    fn read(dir: &Path, file: &str) -> String {
        std::fs::read_to_string(dir.join(file)).unwrap_or_default()
    }

    fn limits(core: Option<usize>) -> CgroupLimits {
        CgroupLimits {
            memory_bytes: Some(64 << 20),
            pids: Some(8),
            core,
        }
    }

    #[test]
    fn a_kept_v2_cgroup_loses_its_last_matchs_core_or_quota() {
        let tmp = tempfile::tempdir().unwrap();
        let root = CgroupRoot::V2 {
            base: tmp.path().to_path_buf(),
        };
        let dir = tmp.path().join("run-0");
        // Unpinned first: a quota of one core. (Each is forgotten, not dropped: a
        // dropped one, not held as kept, would be removed.)
        std::mem::forget(root.build("run-0", limits(None), true, true).unwrap());
        assert_eq!(read(&dir, "cpu.max"), "100000 100000");
        // Then pinned: its core, and no quota left.
        std::mem::forget(root.build("run-0", limits(Some(1)), true, true).unwrap());
        assert_eq!(read(&dir, "cpuset.cpus"), "1");
        assert_eq!(read(&dir, "cpu.max"), "max 100000");
        assert_eq!(read(&dir, "pids.max"), "8");
        // Then unpinned again: the parent's cores, and the quota.
        std::mem::forget(root.build("run-0", limits(None), true, true).unwrap());
        assert_eq!(read(&dir, "cpuset.cpus"), "");
        assert_eq!(read(&dir, "cpu.max"), "100000 100000");
    }

    #[test]
    fn a_kept_v1_cgroup_with_cpu_and_cpuacct_together_loses_its_last_matchs_quota() {
        let tmp = tempfile::tempdir().unwrap();
        let folder = |name: &str| {
            let dir = tmp.path().join(name);
            std::fs::create_dir(&dir).unwrap();
            dir
        };
        let acct = folder("cpu,cpuacct");
        let cpuset = folder("cpuset");
        std::fs::write(cpuset.join("cpuset.mems"), "0\n").unwrap();
        let root = CgroupRoot::V1 {
            memory: folder("memory"),
            pids: folder("pids"),
            cpuacct: acct.clone(),
            cpu: Some(acct.clone()),
            cpuset: Some(cpuset.clone()),
        };
        let dir = acct.join("run-0");
        std::mem::forget(root.build("run-0", limits(None), true, true).unwrap());
        assert_eq!(read(&dir, "cpu.cfs_quota_us"), "100000");
        std::mem::forget(root.build("run-0", limits(Some(1)), true, true).unwrap());
        assert_eq!(read(&dir, "cpu.cfs_quota_us"), "-1");
        assert_eq!(read(&cpuset.join("run-0"), "cpuset.cpus"), "1");
        assert_eq!(read(&cpuset.join("run-0"), "cpuset.mems"), "0");
    }

    #[test]
    fn an_unpinned_v1_cgroup_has_its_quota_in_the_cpu_controllers_own_folder() {
        let tmp = tempfile::tempdir().unwrap();
        let folder = |name: &str| {
            let dir = tmp.path().join(name);
            std::fs::create_dir(&dir).unwrap();
            dir
        };
        let cpu = folder("cpu");
        let root = CgroupRoot::V1 {
            memory: folder("memory"),
            pids: folder("pids"),
            cpuacct: folder("cpuacct"),
            cpu: Some(cpu.clone()),
            cpuset: None,
        };
        std::mem::forget(root.build("run-0", limits(Some(1)), true, true).unwrap());
        assert_eq!(read(&cpu.join("run-0"), "cpu.cfs_period_us"), "100000");
        assert_eq!(read(&cpu.join("run-0"), "cpu.cfs_quota_us"), "100000");
        assert_eq!(
            read(&tmp.path().join("cpuacct/run-0"), "cpu.cfs_quota_us"),
            ""
        );
    }

    #[test]
    fn counters_are_read_by_key() {
        let events = "low 0\nhigh 0\nmax 3\noom 1\noom_kill 2\n";
        assert_eq!(counter(events, "oom_kill"), Some(2));
        assert_eq!(counter(events, "max"), Some(3));
        assert_eq!(counter(events, "missing"), None);
    }

    #[test]
    fn own_paths_are_found_per_controller() {
        let own = "9:name=systemd:/\n4:memory:/a/b\n2:cpu,cpuacct:/c\n0::/unified\n";
        assert_eq!(own_path(own, "memory").as_deref(), Some("/a/b"));
        assert_eq!(own_path(own, "cpuacct").as_deref(), Some("/c"));
        assert_eq!(own_path(own, "").as_deref(), Some("/unified"));
        assert_eq!(own_path(own, "pids"), None);
    }

    #[test]
    fn cgroup_mounts_are_parsed_from_mountinfo() {
        let info = "30 25 0:26 / /sys/fs/cgroup/memory rw,relatime shared:9 - cgroup cgroup rw,memory\n\
                    31 25 0:27 / /sys/fs/cgroup/unified rw - cgroup2 cgroup2 rw\n\
                    32 25 0:28 / /proc rw - proc proc rw\n";
        let mounts = cgroup_mounts(info);
        assert_eq!(mounts.len(), 2);
        assert_eq!(mounts[0].0, PathBuf::from("/sys/fs/cgroup/memory"));
        assert_eq!(mounts[0].2, "rw,memory");
        assert_eq!(mounts[1].1, "cgroup2");
    }
}
