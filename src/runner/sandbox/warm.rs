//! Warm sandboxes: a sandbox kept for many matches of a worker slot, so that a match does
//! not pay for bubblewrap, the view's mounts and a cgroup of its own
//! (docs/PERFORMANCE.md).
//!
//! A warm sandbox is bubblewrap with a match's view, minus the bot's folder and scratch
//! area, running the supervisor ([`super::supervisor`]) in a cgroup of its own. Each
//! match gets, from the supervisor, fresh PID, mount, IPC and network namespaces (so no
//! counter, table or socket name of one match reaches the next) with a fresh `/proc`
//! and scratch tmpfs, the bot's folder attached read-only, and the same jail step
//! as a one-shot sandbox; and, from the runner, a cgroup of its own with the match's
//! limits, which its init joins before anything of the bot runs. Network namespaces
//! and cgroups are made before the matches that take them ([`super::fresh::FreshPool`],
//! [`super::ahead`]) and removed after; none is handed to two matches. Between matches
//! the runner checks that nothing of the last one is left: its init has ended and been
//! reaped, and the sandbox's cgroup holds only the sandbox's own processes. A sandbox
//! that fails a check is thrown away, never reused.
//!
//! Used where it is proven: a server running as root with cgroups (the limits of a match
//! must hold for every process together), a bot folder shown as one mount with links, no
//! runtime under `/tmp`, and a runner that plays many matches (servers, workers,
//! tournaments). Everything else gets a one-shot sandbox per match.

use std::os::fd::{AsFd, AsRawFd, OwnedFd, RawFd};
use std::path::Path;
use std::process::Stdio;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::ahead::CgroupsAhead;
use super::cgroup::{CgroupLimits, MatchCgroup};
use super::supervisor::{self, Reply, Request};
use super::view::{self, Work};
use super::{FullSandbox, SERVE_SUBCOMMAND};
use crate::runner::runtimes::Runtime;

/// Idle warm sandboxes kept at most: two per core, and at least 8; the oldest goes
/// first.
pub fn idle_max() -> usize {
    std::thread::available_parallelism().map_or(8, |n| (2 * n.get()).max(8))
}

/// A warm sandbox's own processes, its cgroup's process limit: bubblewrap's two, the
/// supervisor, and a match's init until it moves to its match's cgroup.
pub const WARM_PROCESSES: u64 = 4;

/// The processes of a match's cgroup that are not the bot's: its init.
pub const MATCH_PROCESSES: u64 = 1;

/// The view's placeholder scratch area, covered by each match's own.
const PLACEHOLDER_SCRATCH: u64 = 64 * 1024;

/// How long the supervisor may take to start, or to answer.
const ANSWER_WAIT: Duration = Duration::from_secs(10);

/// How long the processes of a match that was killed may take to leave its cgroup.
const LEAVE_WAIT: Duration = Duration::from_secs(2);

/// What makes warm sandboxes interchangeable: the match's core and the runtimes in the
/// view, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WarmKey {
    /// The core the cgroup holds the match to.
    pub core: Option<usize>,
    /// The runtimes mounted in the view.
    pub runtimes: Vec<Runtime>,
}

/// The idle warm sandboxes of a runner, and the cgroups made for their next matches.
#[derive(Debug, Default)]
pub struct WarmPool {
    idle: Mutex<Vec<(WarmKey, WarmSandbox)>>,
    /// Matches started in warm sandboxes so far.
    started: std::sync::atomic::AtomicU64,
    /// Each match's own cgroup, made ahead and removed after.
    cgroups: CgroupsAhead,
}

impl WarmPool {
    /// How many matches were started in warm sandboxes of this pool.
    pub fn matches_started(&self) -> u64 {
        self.started.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// How many cgroups are made and waiting for matches.
    pub fn cgroups_ahead(&self) -> usize {
        self.cgroups.fresh()
    }

    /// The outer process (bubblewrap's) of each idle sandbox, oldest first.
    pub fn idle_pids(&self) -> Vec<u32> {
        self.idle
            .lock()
            .map(|i| i.iter().map(|(_, s)| s.child.id()).collect())
            .unwrap_or_default()
    }

    /// An idle sandbox for `key` that passes its checks, if there is one.
    fn take(&self, key: &WarmKey) -> Option<WarmSandbox> {
        loop {
            let found = {
                let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
                let at = idle.iter().rposition(|(k, _)| k == key)?;
                idle.remove(at).1
            };
            let mut sandbox = found;
            if sandbox.ready() {
                return Some(sandbox);
            }
            // Dropped: killed and removed.
        }
    }

    /// Keeps `sandbox` for the next match of `key`.
    fn put(&self, key: WarmKey, sandbox: WarmSandbox) {
        let evicted = {
            let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
            idle.push((key, sandbox));
            (idle.len() > idle_max()).then(|| idle.remove(0))
        };
        drop(evicted);
    }
}

/// One warm sandbox: bubblewrap running the supervisor, its socket and its cgroup.
/// Dropping it kills every process in it and removes its cgroup.
#[derive(Debug)]
pub struct WarmSandbox {
    child: std::process::Child,
    /// The runner's end of the supervisor's socket (non-blocking).
    control: OwnedFd,
    cgroup: MatchCgroup,
    /// The threads in the cgroup with no match (the sandbox's own), sorted.
    own_threads: Vec<i32>,
    /// The last match's end was not read yet.
    awaiting_end: bool,
}

impl WarmSandbox {
    /// Starts one, in a cgroup of its own (its matches' processes are not in it).
    fn start(full: &FullSandbox, key: &WarmKey) -> Result<WarmSandbox, String> {
        use nix::sys::socket::{AddressFamily, SockFlag, SockType, socketpair};
        let root = full.cgroups.as_ref().map_err(Clone::clone)?;
        // Its own processes run on any core (the making of the next match's parts is
        // not held to this match's core); each match's cgroup holds the match to its own.
        let cgroup = root
            .create_unheld(CgroupLimits {
                memory_bytes: None,
                pids: Some(WARM_PROCESSES),
                core: None,
            })
            .map_err(|e| e.to_string())?;
        let (ours, theirs) = socketpair(
            AddressFamily::Unix,
            SockType::SeqPacket,
            None,
            SockFlag::SOCK_CLOEXEC | SockFlag::SOCK_NONBLOCK,
        )
        .map_err(|e| format!("socketpair: {e}"))?;
        // The supervisor's end blocks; ours does not.
        set_blocking(&theirs).map_err(|e| format!("fcntl: {e}"))?;
        let args = view::bwrap_args(full, None, PLACEHOLDER_SCRATCH, Work::Warm, &key.runtimes)
            .map_err(|e| e.to_string())?;
        let step = vec![
            SERVE_SUBCOMMAND.into(),
            "--ahead".into(),
            full.ahead.to_string().into(),
        ];
        let mut cmd = full.command_step(args, step, Some(&cgroup));
        use std::os::unix::process::CommandExt;
        cmd.stdin(Stdio::from(theirs))
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .process_group(0);
        let child = cmd
            .spawn()
            .map_err(|e| format!("cannot run {}: {e}", full.bwrap.display()))?;
        let mut sandbox = WarmSandbox {
            child,
            control: ours,
            cgroup,
            own_threads: Vec::new(),
            awaiting_end: false,
        };
        match sandbox.answer() {
            Ok((Reply::Ready, _)) => {}
            Ok((other, _)) => return Err(format!("the supervisor said {other:?}")),
            Err(e) => {
                let status = sandbox.child.try_wait().ok().flatten();
                return Err(format!("the warm sandbox did not start ({status:?}): {e}"));
            }
        }
        sandbox.own_threads = sandbox.cgroup.threads();
        sandbox.own_threads.sort_unstable();
        Ok(sandbox)
    }

    /// The supervisor's next answer, waited for up to [`ANSWER_WAIT`].
    fn answer(&self) -> Result<(Reply, Vec<OwnedFd>), String> {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        let until = Instant::now() + ANSWER_WAIT;
        loop {
            match try_answer(&self.control) {
                Ok(Some(answer)) => return Ok(answer),
                Ok(None) => {}
                Err(e) => return Err(e),
            }
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err("no answer from the supervisor".into());
            }
            let mut fds = [PollFd::new(self.control.as_fd(), PollFlags::POLLIN)];
            let ms = u16::try_from(left.as_millis()).unwrap_or(u16::MAX);
            let _ = poll(&mut fds, PollTimeout::from(ms));
        }
    }

    /// Whether the sandbox may take the next match: the last one's end is read, the
    /// sandbox is alive, and its cgroup holds its own threads and nothing else.
    fn ready(&mut self) -> bool {
        if self.awaiting_end {
            match self.answer() {
                Ok((Reply::Ended(_), _)) => self.awaiting_end = false,
                _ => return false,
            }
        }
        if !matches!(self.child.try_wait(), Ok(None)) {
            return false;
        }
        let until = Instant::now() + LEAVE_WAIT;
        loop {
            let mut now = self.cgroup.threads();
            now.sort_unstable();
            if now == self.own_threads {
                return true;
            }
            if Instant::now() > until {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

impl Drop for WarmSandbox {
    fn drop(&mut self) {
        self.cgroup.kill_all();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The supervisor's answer if one is there: `Ok(None)` when none is yet.
fn try_answer(control: &OwnedFd) -> Result<Option<(Reply, Vec<OwnedFd>)>, String> {
    let mut buf = [0u8; 4096];
    match supervisor::recv(control.as_fd(), &mut buf) {
        Ok(Some((n, fds))) => serde_json::from_slice(&buf[..n])
            .map(|r| Some((r, fds)))
            .map_err(|e| format!("a bad answer from the supervisor: {e}")),
        Ok(None) => Err("the supervisor has ended".into()),
        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => Ok(None),
        Err(e) => Err(format!("the supervisor's socket: {e}")),
    }
}

fn set_blocking(fd: &OwnedFd) -> nix::Result<()> {
    use nix::fcntl::{FcntlArg, OFlag, fcntl};
    let flags = OFlag::from_bits_truncate(fcntl(fd, FcntlArg::F_GETFL)?);
    fcntl(fd, FcntlArg::F_SETFL(flags - OFlag::O_NONBLOCK)).map(drop)
}

/// The bot's side of a match's pipes, as the supervisor gets them: stdin's read end,
/// stdout's and stderr's write ends.
pub struct MatchStdio {
    /// The bot's stdin (read end).
    pub stdin: OwnedFd,
    /// The bot's stdout (write end).
    pub stdout: OwnedFd,
    /// The bot's stderr (write end).
    pub stderr: OwnedFd,
}

/// A match running in a warm sandbox. Dropping it kills the match and gives the sandbox
/// back to the pool, which checks it before its next match.
#[derive(Debug)]
pub struct WarmMatch {
    full: Arc<FullSandbox>,
    key: WarmKey,
    sandbox: Option<WarmSandbox>,
    pidfd: OwnedFd,
    /// The match's own cgroup.
    cgroup: Option<MatchCgroup>,
    /// The match's init, as this runner sees it.
    pub init_pid: u32,
    ended: Option<i32>,
}

/// Starts a match in a warm sandbox of `full` for `key` (an idle one, or a new one), in
/// a cgroup of its own with the match's limits (`pids`: the bot's processes and the
/// match's init).
///
/// # Errors
/// The sandbox could not be started or refused the match, and why.
pub fn start_match(
    full: &Arc<FullSandbox>,
    key: WarmKey,
    memory: Option<u64>,
    pids: Option<u64>,
    request: &Request,
    bot_dir: &Path,
    stdio: MatchStdio,
) -> Result<WarmMatch, String> {
    let tree = detached_read_only(bot_dir)
        .map_err(|e| format!("cannot mount the bot's folder {}: {e}", bot_dir.display()))?;
    let root = full.cgroups.as_ref().map_err(Clone::clone)?;
    let cgroup = full
        .warm
        .cgroups
        .take(root, key.core)
        .map_err(|e| format!("the match's cgroup: {e}"))?;
    let retire = |e: String, cgroup: MatchCgroup| {
        full.warm.cgroups.retire(cgroup);
        e
    };
    if let Err(e) = cgroup.limit(memory, pids) {
        return Err(retire(format!("the match's cgroup: {e}"), cgroup));
    }
    let join: Vec<OwnedFd> = match cgroup
        .join_files()
        .iter()
        .map(|f| {
            std::fs::OpenOptions::new()
                .write(true)
                .open(f)
                .map(OwnedFd::from)
        })
        .collect::<std::io::Result<_>>()
    {
        Ok(files) => files,
        Err(e) => return Err(retire(format!("the match's cgroup: {e}"), cgroup)),
    };
    let request = Request {
        cgroup_files: join.len(),
        ..request.clone()
    };
    let message = serde_json::to_vec(&request).map_err(|e| e.to_string())?;
    if message.len() > supervisor::MAX_MESSAGE {
        return Err(retire(
            "the bot's command line and variables are too long".into(),
            cgroup,
        ));
    }
    let fds: Vec<RawFd> = [
        stdio.stdin.as_raw_fd(),
        stdio.stdout.as_raw_fd(),
        stdio.stderr.as_raw_fd(),
        tree.as_raw_fd(),
    ]
    .into_iter()
    .chain(join.iter().map(AsRawFd::as_raw_fd))
    .collect();
    // An idle sandbox that passed its checks may still be gone by the time the request
    // is sent (its supervisor ended), or may not take the match's limits: then a new one
    // is started, once. A request that was sent is never sent again.
    let mut idle = full.warm.take(&key);
    let sandbox = loop {
        let reused = idle.is_some();
        let sandbox = match idle.take() {
            Some(s) => s,
            None => match WarmSandbox::start(full, &key) {
                Ok(s) => s,
                Err(e) => return Err(retire(e, cgroup)),
            },
        };
        match supervisor::send(sandbox.control.as_fd(), &message, &fds) {
            Ok(()) => break sandbox,
            Err(_) if reused => continue,
            Err(e) => {
                return Err(retire(
                    format!("the warm sandbox's supervisor: {e}"),
                    cgroup,
                ));
            }
        }
    };
    drop((stdio, tree, join));
    let answer = match sandbox.answer() {
        Ok(answer) => answer,
        Err(e) => return Err(retire(e, cgroup)),
    };
    match answer {
        (Reply::Started, mut fds) if fds.len() == 1 => {
            let pidfd = fds.remove(0);
            let mut warm = WarmMatch {
                full: full.clone(),
                key,
                sandbox: Some(sandbox),
                pidfd,
                cgroup: Some(cgroup),
                init_pid: 0,
                ended: None,
            };
            // Dropped on an error: the match is killed, its cgroup removed.
            warm.init_pid = pid_of(&warm.pidfd).ok_or("the match's init is not found")?;
            full.warm
                .started
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Ok(warm)
        }
        (Reply::Refused(reason), _) => {
            full.warm.put(key, sandbox);
            Err(retire(reason, cgroup))
        }
        (other, _) => Err(retire(format!("the supervisor said {other:?}"), cgroup)),
    }
}

impl WarmMatch {
    /// The match's own cgroup.
    pub fn cgroup(&self) -> Option<&MatchCgroup> {
        self.cgroup.as_ref()
    }

    /// Kills the match: its init, and with it its whole PID namespace.
    pub fn kill(&self) {
        supervisor::kill_pidfd(&self.pidfd);
    }

    /// Waits until the match's init has ended: the bot's exit status, as bubblewrap
    /// would report it.
    ///
    /// # Errors
    /// The supervisor's socket failed, or the supervisor ended.
    pub async fn wait(&mut self) -> std::io::Result<std::process::ExitStatus> {
        use std::os::unix::process::ExitStatusExt;
        if self.ended.is_none() {
            let code = self.read_end().await?;
            self.ended = Some(code);
        }
        let code = self.ended.unwrap_or(super::jail::SETUP_FAILED);
        Ok(std::process::ExitStatus::from_raw(code << 8))
    }

    /// Reads the supervisor's report of the match's end.
    async fn read_end(&self) -> std::io::Result<i32> {
        let sandbox = self
            .sandbox
            .as_ref()
            .ok_or_else(|| std::io::Error::other("no sandbox"))?;
        let copy = sandbox.control.try_clone()?;
        // SAFETY: the descriptor is owned by the AsyncFd for its whole life.
        let events = unsafe { tokio::io::unix::AsyncFd::register(copy) }?;
        loop {
            let mut ready = events.readable().await?;
            match try_answer(&sandbox.control) {
                Ok(Some((Reply::Ended(code), _))) => return Ok(code),
                Ok(Some((other, _))) => {
                    return Err(std::io::Error::other(format!(
                        "the supervisor said {other:?}"
                    )));
                }
                Ok(None) => ready.clear_ready(),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
    }
}

impl Drop for WarmMatch {
    fn drop(&mut self) {
        self.kill();
        // Emptied and removed by the pool's thread, off the match's path.
        if let Some(cgroup) = self.cgroup.take() {
            self.full.warm.cgroups.retire(cgroup);
        }
        if let Some(mut sandbox) = self.sandbox.take() {
            sandbox.awaiting_end = self.ended.is_none();
            self.full.warm.put(self.key.clone(), sandbox);
        }
    }
}

/// The pid of the process behind `pidfd`, in this runner's PID namespace.
fn pid_of(pidfd: &OwnedFd) -> Option<u32> {
    let info = std::fs::read_to_string(format!("/proc/self/fdinfo/{}", pidfd.as_raw_fd())).ok()?;
    info.lines()
        .find_map(|l| l.strip_prefix("Pid:"))
        .and_then(|p| p.trim().parse::<i64>().ok())
        .and_then(|p| u32::try_from(p).ok())
}

/// `open_tree(2)` flag: a detached copy of the mount.
const OPEN_TREE_CLONE: libc::c_uint = 1;
/// `mount_setattr(2)` attributes: read-only, no set-uid, no devices.
const MOUNT_ATTR_RDONLY: u64 = 0x1;
const MOUNT_ATTR_NOSUID: u64 = 0x2;
const MOUNT_ATTR_NODEV: u64 = 0x4;

/// `struct mount_attr` of `mount_setattr(2)`.
#[repr(C)]
struct MountAttr {
    attr_set: u64,
    attr_clr: u64,
    propagation: u64,
    userns_fd: u64,
}

/// A detached, read-only, no-set-uid, no-devices copy of the mount of folder `dir`,
/// for the supervisor to attach in a match's namespace.
fn detached_read_only(dir: &Path) -> std::io::Result<OwnedFd> {
    use std::os::fd::FromRawFd;
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::CString::new(dir.as_os_str().as_bytes())?;
    // SAFETY: open_tree(2) with a NUL-terminated path; returns a new descriptor.
    let fd = unsafe {
        libc::syscall(
            libc::SYS_open_tree,
            libc::AT_FDCWD,
            path.as_ptr(),
            OPEN_TREE_CLONE | libc::O_CLOEXEC as libc::c_uint,
        )
    };
    if fd < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: the descriptor was just made for this process.
    let tree = unsafe { OwnedFd::from_raw_fd(fd as RawFd) };
    let attr = MountAttr {
        attr_set: MOUNT_ATTR_RDONLY | MOUNT_ATTR_NOSUID | MOUNT_ATTR_NODEV,
        attr_clr: 0,
        propagation: 0,
        userns_fd: 0,
    };
    // SAFETY: mount_setattr(2) on our descriptor with a live `struct mount_attr`.
    let r = unsafe {
        libc::syscall(
            libc::SYS_mount_setattr,
            tree.as_raw_fd(),
            c"".as_ptr(),
            libc::AT_EMPTY_PATH as libc::c_uint,
            &attr as *const MountAttr,
            std::mem::size_of::<MountAttr>(),
        )
    };
    if r != 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(tree)
}

/// Why this machine's runners cannot keep warm sandboxes, if they cannot: each match
/// needs a uid of its own (`as_root`) and a cgroup (`cgroups`) for its limits.
pub fn unavailable(as_root: bool, cgroups: bool) -> Option<&'static str> {
    if !as_root {
        Some("not root (each match needs a uid of its own)")
    } else if !cgroups {
        Some("no cgroups (limits must hold for the match alone)")
    } else {
        None
    }
}

/// Whether a match may use a warm sandbox of `full` (see the module's documentation).
///
/// # Errors
/// The bot's folder cannot be read.
pub fn plan(full: &FullSandbox, bot_dir: &Path, runtimes: &[Runtime]) -> std::io::Result<bool> {
    if !full.reuse
        || unavailable(full.as_root, full.cgroups.is_ok()).is_some()
        || runtimes.iter().any(view::in_scratch)
    {
        return Ok(false);
    }
    view::linkable(bot_dir, true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    fn sandbox(reuse: bool, as_root: bool, cgroups: bool) -> FullSandbox {
        FullSandbox {
            bwrap: "/usr/bin/bwrap".into(),
            helper: "/usr/bin/true".into(),
            as_root,
            cgroups: if cgroups {
                Ok(super::super::cgroup::CgroupRoot::V2 {
                    base: "/sys/fs/cgroup/x".into(),
                })
            } else {
                Err("none in this test".into())
            },
            runtimes: Vec::new(),
            detect: false,
            hide: Vec::new(),
            reuse,
            ahead: 1,
            warm: WarmPool::default(),
            detected: Default::default(),
        }
    }

    #[test]
    fn a_match_is_warm_only_as_root_with_cgroups_a_linkable_folder_and_no_runtime_in_tmp() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("bot");
        std::fs::create_dir(&dir).unwrap();
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        std::fs::write(dir.join("b.py"), "").unwrap();
        std::fs::write(dir.join("a.py"), "").unwrap();
        let plan_of =
            |full: &FullSandbox, runtimes: &[Runtime]| plan(full, &dir, runtimes).unwrap();
        assert!(plan_of(&sandbox(true, true, true), &[]));
        // A runner of one match, not root, or without cgroups: a one-shot sandbox.
        assert!(!plan_of(&sandbox(false, true, true), &[]));
        assert!(!plan_of(&sandbox(true, false, true), &[]));
        assert!(!plan_of(&sandbox(true, true, false), &[]));
        // A runtime under /tmp lives in the scratch area, made anew for each match.
        let in_tmp = Runtime::offered("/tmp/venv".into(), "test");
        assert!(!plan_of(&sandbox(true, true, true), &[in_tmp]));
        // An entry that is a link, and a folder the match's uid cannot pass through.
        std::os::unix::fs::symlink("a.py", dir.join("c.py")).unwrap();
        assert!(!plan_of(&sandbox(true, true, true), &[]));
        std::fs::remove_file(dir.join("c.py")).unwrap();
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).unwrap();
        assert!(!plan_of(&sandbox(true, true, true), &[]));
    }
}
