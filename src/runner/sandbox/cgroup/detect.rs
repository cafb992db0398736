//! Finding the machine's cgroups: v1 or v2, where this process's are, which
//! controllers it may use.

use std::path::{Path, PathBuf};

use super::{CgroupLimits, CgroupRoot, copy_file};

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
                core: crate::runner::affinity::allowed_cores().first().copied(),
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
}

/// Mount points of cgroup file systems from `/proc/self/mountinfo`: (mount point, fs
/// type, super options).
pub(super) fn cgroup_mounts(mountinfo: &str) -> Vec<(PathBuf, String, String)> {
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
pub(super) fn own_path(own: &str, controller: &str) -> Option<String> {
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
