//! A match's cgroup: made with its limits, joined, held to one core, read (CPU time,
//! memory and fork refusals, members) and emptied.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::{
    CPU_PERIOD_US, CgroupHit, CgroupRoot, Marks, MatchCgroup, copy_file, counter, read_counter,
    remove_stale, write, write_text,
};

impl MatchCgroup {
    pub(super) fn make(&mut self, dir: &Path) -> std::io::Result<PathBuf> {
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
    pub(super) fn hold_to_one_core(
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

    pub(super) fn oom_kills(&self) -> u64 {
        let file = match self.version {
            CgroupRoot::V1 { .. } => "memory.oom_control",
            CgroupRoot::V2 { .. } => "memory.events",
        };
        read_counter(&self.memory.join(file), "oom_kill").unwrap_or(0)
    }

    pub(super) fn refused_forks(&self) -> u64 {
        read_counter(&self.pids.join("pids.events"), "max").unwrap_or(0)
    }

    /// CPU time used by every process that ran in the cgroup in this match, in µs.
    pub fn cpu_us(&self) -> Option<u64> {
        Some(self.cpu_total_us()?.saturating_sub(self.marks.cpu_us))
    }

    /// CPU time used by every process that ever ran in the cgroup, in µs.
    pub(super) fn cpu_total_us(&self) -> Option<u64> {
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
