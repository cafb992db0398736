//! Running a bot's build command (`bot.toml`'s `build`), which is as untrusted as the bot:
//! in the sandbox, with the bot's folder writable so that what it builds stays, no
//! network, and the match limits; without the sandbox, directly in the folder.
//!
//! A server's build runs in a [`BuildArea`] of its own: as root, a tmpfs of bounded size
//! (`nosuid,nodev`, mode 0700) owned by the build's own unprivileged uid, which the build
//! runs as (never host uid 0); otherwise a 0700 folder whose use is watched. Each file is
//! bounded by RLIMIT_FSIZE, and a build that fills its area fails with the reason.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::sandbox::{Sandbox, UidLease, jail};

/// The default bound of a build's writable area (its folder, and its `/tmp` apart).
pub const DEFAULT_BUILD_WRITE_BYTES: u64 = 256 << 20;

/// How often a build's writable area is measured while it runs.
const AREA_POLL: Duration = Duration::from_millis(250);

/// Free space under which a mounted area counts as filled.
const FULL_MARGIN_BYTES: u64 = 64 * 1024;

/// The writable folder of one build.
#[derive(Debug)]
pub struct BuildArea {
    /// The temporary folder holding the area (removed when dropped); `None` in place.
    _holder: Option<tempfile::TempDir>,
    /// What is bounded: the tmpfs (or watched folder) holding `work`.
    area: PathBuf,
    /// The build's working folder.
    work: PathBuf,
    /// True when `work` is a tmpfs of ours (unmounted when dropped).
    mounted: bool,
    /// The bound, in bytes.
    limit: u64,
    /// True when the build runs as a uid of its own (a fresh area, as root).
    own_uid: bool,
}

impl BuildArea {
    /// A fresh area under `parent` bounded by `limit` bytes: as root a tmpfs of that size
    /// (`nosuid,nodev`, 0700) for a build that runs as a uid of its own; otherwise (or
    /// when the tmpfs cannot be mounted, logged) a 0700 folder whose use is watched.
    ///
    /// # Errors
    /// The folder cannot be made.
    pub fn new(parent: &Path, limit: u64) -> std::io::Result<BuildArea> {
        remove_stale(parent);
        let holder = tempfile::Builder::new()
            .prefix(&format!("build-{}-", std::process::id()))
            .tempdir_in(parent)?;
        // The tmpfs (or folder) holds the working folder, so that files can be put in
        // place by a rename from beside it.
        let area = holder.path().join("area");
        std::fs::create_dir(&area)?;
        let root = nix::unistd::geteuid().is_root();
        let mut mounted = false;
        if root {
            use nix::mount::{MsFlags, mount};
            match mount(
                Some("tmpfs"),
                &area,
                Some("tmpfs"),
                MsFlags::MS_NOSUID | MsFlags::MS_NODEV,
                Some(format!("size={limit},mode=0700").as_str()),
            ) {
                Ok(()) => mounted = true,
                Err(e) => tracing::warn!(
                    cause = %e,
                    "cannot mount a tmpfs for a build: its folder's size is watched instead"
                ),
            }
        }
        let work = area.join("work");
        std::fs::create_dir(&work)?;
        Ok(BuildArea {
            _holder: Some(holder),
            area,
            work,
            mounted,
            limit,
            own_uid: root,
        })
    }

    /// The folder `dir` itself as a build's area (a local bot's folder, built where it
    /// is, as the runner's own user): its use is watched against `limit`.
    pub fn in_place(dir: &Path, limit: u64) -> BuildArea {
        BuildArea {
            _holder: None,
            area: dir.to_path_buf(),
            work: dir.to_path_buf(),
            mounted: false,
            limit,
            own_uid: false,
        }
    }

    /// The build's working folder: put its files here before, read the result after.
    pub fn work(&self) -> &Path {
        &self.work
    }

    /// Whether the build has filled its area (a mounted area: less than 64 KiB free;
    /// a watched one: more than its bound in blocks on the disk).
    fn filled(&self) -> bool {
        if self.mounted {
            return nix::sys::statvfs::statvfs(&self.area)
                .is_ok_and(|s| s.blocks_available() * s.fragment_size() < FULL_MARGIN_BYTES);
        }
        disk_usage(&self.area) > self.limit
    }
}

impl Drop for BuildArea {
    fn drop(&mut self) {
        if self.mounted {
            let _ = nix::mount::umount2(&self.area, nix::mount::MntFlags::MNT_DETACH);
        }
    }
}

/// Removes the build areas under `parent` left by runner processes that are gone (a
/// server killed while it built): their tmpfs is unmounted and their folder removed.
fn remove_stale(parent: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix("build-")
            .and_then(|rest| rest.split('-').next())
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists() {
            continue;
        }
        let area = e.path().join("area");
        let _ = nix::mount::umount2(&area, nix::mount::MntFlags::MNT_DETACH);
        if let Err(err) = std::fs::remove_dir_all(e.path()) {
            tracing::warn!(cause = %err, dir = %e.path().display(), "cannot remove a stale build folder");
        }
    }
}

/// Bytes of disk blocks held by the files below `dir` (links not followed).
fn disk_usage(dir: &Path) -> u64 {
    use std::os::unix::fs::MetadataExt;
    let mut total = 0u64;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let Ok(meta) = e.metadata() else { continue };
            total += meta.blocks() * 512;
            if meta.is_dir() {
                stack.push(e.path());
            }
        }
    }
    total
}

/// Gives the files below `dir` (which the runner made) to `uid`, links not followed.
fn chown_tree(dir: &Path, uid: u32) -> std::io::Result<()> {
    let mut stack = vec![dir.to_path_buf()];
    std::os::unix::fs::lchown(dir, Some(uid), Some(uid))?;
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d)? {
            let e = e?;
            std::os::unix::fs::lchown(e.path(), Some(uid), Some(uid))?;
            if e.file_type()?.is_dir() {
                stack.push(e.path());
            }
        }
    }
    Ok(())
}

/// The longest a build may take.
pub const BUILD_TIMEOUT: Duration = Duration::from_secs(600);

/// Processes and threads a build may have at once.
const BUILD_PROCESS_LIMIT: u64 = 256;

/// Why a build failed.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The command is empty or has unbalanced quotes.
    #[error("the build command {0:?} cannot be split into words")]
    BadCommand(String),
    /// It could not be started.
    #[error("cannot run the build command {command:?}: {source}")]
    Spawn {
        /// The command.
        command: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// It ran and failed.
    #[error("the build command {command:?} failed ({status}){stderr}")]
    Failed {
        /// The command.
        command: String,
        /// How it ended.
        status: String,
        /// The end of its stderr, prefixed with a newline when not empty.
        stderr: String,
    },
}

/// The most memory a build's processes may hold together (in the sandbox, with a
/// cgroup): compilers need more than bots.
pub const BUILD_MEMORY_BYTES: u64 = 2 << 30;

/// How much of a build's output (stdout and stderr, interleaved) is kept.
pub const BUILD_LOG_BYTES: usize = 64 * 1024;

/// How a build ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BuildOutcome {
    /// Whether it exited with status 0 in time.
    pub ok: bool,
    /// How it ended, for people ("exit status: 2", "took more than 600 s").
    pub status: String,
    /// The end of its output ([`BUILD_LOG_BYTES`]).
    pub log: String,
}

/// Runs `command` in `dir` (in place, as the runner's user) under `sandbox`, waiting at
/// most [`BUILD_TIMEOUT`], its writes bounded by [`DEFAULT_BUILD_WRITE_BYTES`]; the
/// runtime named `runtime` first on its `PATH`.
///
/// # Errors
/// [`BuildError`] when it cannot run, fails or takes too long.
pub async fn build(
    command: &str,
    dir: &Path,
    sandbox: &Sandbox,
    runtime: Option<&str>,
) -> Result<(), BuildError> {
    let area = BuildArea::in_place(dir, DEFAULT_BUILD_WRITE_BYTES);
    let outcome = build_logged(command, &area, sandbox, runtime).await?;
    if outcome.ok {
        return Ok(());
    }
    let tail: String = outcome
        .log
        .chars()
        .rev()
        .take(2000)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    Err(BuildError::Failed {
        command: command.to_string(),
        status: outcome.status,
        stderr: if tail.trim().is_empty() {
            String::new()
        } else {
            format!("\n{}", tail.trim_end())
        },
    })
}

/// Runs `command` in `area` under `sandbox` with the build limits (time
/// [`BUILD_TIMEOUT`], memory [`BUILD_MEMORY_BYTES`] where a cgroup can be made, the
/// area's bound on what it writes, output kept to its last [`BUILD_LOG_BYTES`]), the
/// runtime named `runtime` first on its `PATH`, and returns how it ended with its
/// output.
///
/// # Errors
/// [`BuildError`] only when it cannot be started at all.
pub async fn build_logged(
    command: &str,
    area: &BuildArea,
    sandbox: &Sandbox,
    runtime: Option<&str>,
) -> Result<BuildOutcome, BuildError> {
    let dir = area.work();
    let words = shlex::split(command)
        .filter(|w| !w.is_empty())
        .ok_or_else(|| BuildError::BadCommand(command.to_string()))?;
    let spawn_err = |source| BuildError::Spawn {
        command: command.to_string(),
        source,
    };
    let mut cgroup = None;
    let mut uid = None;
    let mut cmd = match sandbox {
        Sandbox::None => {
            let mut cmd = tokio::process::Command::new(&words[0]);
            cmd.args(&words[1..]).current_dir(dir);
            cmd
        }
        Sandbox::Full(full) => {
            let sandbox_err = |e: String| spawn_err(std::io::Error::other(e));
            if full.as_root && area.own_uid {
                let lease = UidLease::take().map_err(sandbox_err)?;
                chown_tree(dir, lease.uid()).map_err(spawn_err)?;
                uid = Some(lease);
            }
            let runtimes = full
                .runtimes_for(&words[0], dir, runtime)
                .map_err(sandbox_err)?;
            let args = super::sandbox::bwrap_args(
                full,
                Some(dir),
                area.limit,
                super::sandbox::Work::Build {
                    own_uid: uid.is_some(),
                },
                &runtimes,
            )
            .map_err(spawn_err)?;
            if let Ok(root) = &full.cgroups {
                cgroup = Some(
                    root.create(super::sandbox::cgroup::CgroupLimits {
                        memory_bytes: Some(BUILD_MEMORY_BYTES),
                        pids: Some(BUILD_PROCESS_LIMIT),
                        core: None,
                    })
                    .map_err(spawn_err)?,
                );
            }
            let jail = jail::JailArgs {
                uid: uid.as_ref().map(UidLease::uid),
                nproc: (!full.as_root || uid.is_some()).then_some(BUILD_PROCESS_LIMIT),
                fsize: Some(area.limit),
                command: words.iter().map(Into::into).collect(),
                ..jail::JailArgs::default()
            };
            tokio::process::Command::from(full.command(args, &jail, cgroup.as_ref()))
        }
    };
    // One pipe for stdout and stderr, so the log keeps their order.
    let (reader, writer) = std::io::pipe().map_err(spawn_err)?;
    let writer2 = writer.try_clone().map_err(spawn_err)?;
    cmd.stdin(std::process::Stdio::null())
        .stdout(writer)
        .stderr(writer2)
        .process_group(0)
        .kill_on_drop(true);
    let mut child = cmd.spawn().map_err(spawn_err)?;
    // Our copies of the pipe's write end went with `cmd`: drop it so the read ends.
    drop(cmd);
    let log = tokio::task::spawn_blocking(move || read_tail_blocking(reader, BUILD_LOG_BYTES));
    let pid = child.id();
    let mut filled = false;
    let watched = async {
        let mut poll = tokio::time::interval(AREA_POLL);
        loop {
            tokio::select! {
                status = child.wait() => return status,
                _ = poll.tick() => {
                    if !filled && area.filled() {
                        filled = true;
                        if let Some(pid) = pid {
                            super::sandbox::proctree::kill_tree(pid);
                            super::process::kill_group(pid);
                        }
                    }
                }
            }
        }
    };
    let waited = tokio::time::timeout(BUILD_TIMEOUT, watched).await;
    filled = filled || area.filled();
    if let Some(pid) = pid {
        super::sandbox::proctree::kill_tree(pid);
        super::process::kill_group(pid);
    }
    let status = match &waited {
        Ok(Ok(s)) => s.to_string(),
        Ok(Err(e)) => format!("could not be waited for: {e}"),
        Err(_) => {
            let _ = child.kill().await;
            format!("took more than {} s", BUILD_TIMEOUT.as_secs())
        }
    };
    let ok = matches!(&waited, Ok(Ok(s)) if s.success());
    let oom = cgroup
        .as_ref()
        .and_then(|c| c.limit_hit())
        .is_some_and(|k| k == super::sandbox::cgroup::CgroupHit::Memory);
    let mut log = tokio::time::timeout(std::time::Duration::from_secs(5), log)
        .await
        .ok()
        .and_then(Result::ok)
        .unwrap_or_else(|| "[the build's output could not be read to its end]".into());
    if oom {
        log.push_str(&format!(
            "\n[the build went over its memory limit of {} MiB]",
            BUILD_MEMORY_BYTES >> 20
        ));
    }
    if filled {
        log.push_str(&format!(
            "\n[the build wrote more than {} MiB]",
            area.limit >> 20
        ));
    }
    drop(uid);
    Ok(BuildOutcome {
        ok: ok && !oom && !filled,
        status: if filled {
            format!("the build wrote more than {} MiB", area.limit >> 20)
        } else {
            status
        },
        log,
    })
}

/// Reads `reader` to its end, keeping its last `cap` bytes as text.
fn read_tail_blocking(mut reader: impl std::io::Read, cap: usize) -> String {
    let mut tail: std::collections::VecDeque<u8> = std::collections::VecDeque::new();
    let mut total = 0u64;
    let mut buf = [0u8; 8192];
    loop {
        match reader.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                total += n as u64;
                tail.extend(&buf[..n]);
                if tail.len() > cap {
                    let extra = tail.len() - cap;
                    tail.drain(..extra);
                }
            }
        }
    }
    let text = String::from_utf8_lossy(tail.make_contiguous()).into_owned();
    if total > tail.len() as u64 {
        format!(
            "[... {} earlier bytes not kept]\n{text}",
            total - tail.len() as u64
        )
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn areas_of_gone_processes_are_removed_and_live_ones_kept() {
        let parent = tempfile::tempdir().unwrap();
        let live = BuildArea::new(parent.path(), 1 << 20).unwrap();
        std::fs::write(live.work().join("f"), "x").unwrap();
        // pid 0 is never a process's: a runner that is gone.
        let stale = parent.path().join("build-0-abc");
        std::fs::create_dir_all(stale.join("area/work")).unwrap();
        let other = parent.path().join("notes");
        std::fs::create_dir(&other).unwrap();
        let again = BuildArea::new(parent.path(), 1 << 20).unwrap();
        assert!(!stale.exists());
        assert!(live.work().join("f").exists() && other.exists());
        let holders = || std::fs::read_dir(parent.path()).unwrap().count();
        assert_eq!(holders(), 3);
        drop((live, again));
        assert_eq!(holders(), 1, "an area is removed when dropped");
    }

    #[test]
    fn an_area_is_bounded() {
        let parent = tempfile::tempdir().unwrap();
        let area = BuildArea::new(parent.path(), 4 << 20).unwrap();
        assert!(!area.filled());
        let big = vec![7u8; 1 << 20];
        let mut wrote = 0;
        for i in 0..8 {
            if std::fs::write(area.work().join(format!("f{i}")), &big).is_err() {
                break;
            }
            wrote += 1;
        }
        assert!(area.filled(), "wrote {wrote} MiB into a 4 MiB area");
        if area.mounted {
            assert!(
                wrote <= 4,
                "a mounted area holds at most its bound: {wrote} MiB"
            );
        }
    }
}
