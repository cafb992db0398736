//! Tests of the module's operations.

use std::path::{Path, PathBuf};

use super::detect::{cgroup_mounts, own_path};
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
