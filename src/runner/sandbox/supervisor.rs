//! The inside of a warm sandbox ([`super::warm`]): `mazearena sandbox-serve`, run by
//! bubblewrap once the namespaces and the filesystem view are in place, stays for many
//! matches of one worker slot. Its standard input is a `SOCK_SEQPACKET` socket to the
//! runner; nothing else reaches it.
//!
//! For each match the runner sends a [`Request`] with the bot's stdin, stdout and stderr,
//! its folder as a detached read-only mount (`open_tree`), and the files of the match's
//! own cgroup. The supervisor clones a fresh **match init** into new PID, mount and IPC
//! namespaces, which enters the network namespace made for it ahead
//! ([`super::fresh`]), mounts a fresh `/proc` (this match's processes only), a fresh
//! scratch tmpfs (`/sandbox`: `tmp/` and `work/`), attaches the bot's folder at
//! `/run/mazearena/bot` ([`super::mounts`]), moves itself into the match's cgroup and a
//! cgroup namespace of its own, then puts up the jail's walls on itself
//! ([`super::jail::walls`]: uid, limits, `no_new_privs`, Landlock, seccomp), links each
//! entry of the folder in `work/`, and only then starts the bot's program, which inherits
//! every wall. When the bot's process ends, the init ends, and the kernel kills whatever
//! is left in its PID namespace; once the supervisor has told the runner, it drops what
//! it kept of the match, and the mount, network and IPC namespaces, with the scratch area
//! and every IPC object, go. Nothing of a match is left for the next one: not a process,
//! a file, an IPC object, a namespace, a cgroup or a PID number.

use std::ffi::OsString;
use std::io::IoSlice;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, FromRawFd, OwnedFd, RawFd};
use std::path::Path;

use nix::sys::socket::{ControlMessage, ControlMessageOwned, MsgFlags, recvmsg, sendmsg};

use super::fresh::{Fresh, FreshPool, Leftovers};
use super::jail::{self, SCRATCH};
use super::view::BOT_FILES;

/// The largest message either side sends (a bot's command line and variables).
pub const MAX_MESSAGE: usize = 256 * 1024;

/// The descriptors every [`Request`] carries first, in order: the bot's stdin, stdout
/// and stderr, and its folder.
pub const REQUEST_FDS: usize = 4;

/// The most cgroup files a [`Request`] carries after them.
pub const MAX_CGROUP_FILES: usize = 8;

/// One match, as the runner asks for it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Request {
    /// The size of the match's scratch tmpfs, in bytes.
    pub scratch_bytes: u64,
    /// The jail step's arguments ([`jail::JailArgs::to_args`]).
    pub jail: Vec<String>,
    /// How many descriptors follow the first [`REQUEST_FDS`]: the match's own cgroup's
    /// files the init writes `0` to, to move itself in (opened for writing by the
    /// runner, whose rights the kernel checks), one per hierarchy.
    pub cgroup_files: usize,
}

/// What the supervisor answers.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Reply {
    /// Up and waiting for matches (sent once, first).
    Ready,
    /// The match's init is started; the message carries its pidfd.
    Started,
    /// The match could not be started, and why.
    Refused(String),
    /// The match's init ended with this code (the bot's exit code, or 128 + the signal
    /// that ended it, as bubblewrap reports it).
    Ended(i32),
}

/// Sends one message with `fds` attached.
///
/// # Errors
/// The socket's.
pub fn send(socket: BorrowedFd<'_>, message: &[u8], fds: &[RawFd]) -> std::io::Result<()> {
    let iov = [IoSlice::new(message)];
    let rights = [ControlMessage::ScmRights(fds)];
    let cmsgs: &[ControlMessage] = if fds.is_empty() { &[] } else { &rights };
    sendmsg::<()>(
        socket.as_raw_fd(),
        &iov,
        cmsgs,
        MsgFlags::MSG_NOSIGNAL,
        None,
    )
    .map(drop)
    .map_err(std::io::Error::from)
}

/// Receives one message into `buf` with the descriptors attached to it (close-on-exec).
/// `None` when the other side has closed the socket.
///
/// # Errors
/// The socket's; a message that did not fit `buf` (`InvalidData`).
pub fn recv(
    socket: BorrowedFd<'_>,
    buf: &mut [u8],
) -> std::io::Result<Option<(usize, Vec<OwnedFd>)>> {
    let mut space = nix::cmsg_space!([RawFd; REQUEST_FDS + MAX_CGROUP_FILES]);
    let mut iov = [std::io::IoSliceMut::new(buf)];
    let msg = recvmsg::<()>(
        socket.as_raw_fd(),
        &mut iov,
        Some(&mut space),
        MsgFlags::MSG_CMSG_CLOEXEC,
    )
    .map_err(std::io::Error::from)?;
    let mut fds = Vec::new();
    for cmsg in msg.cmsgs().map_err(std::io::Error::from)? {
        if let ControlMessageOwned::ScmRights(received) = cmsg {
            // SAFETY: the kernel just installed these descriptors in this process.
            fds.extend(
                received
                    .into_iter()
                    .map(|fd| unsafe { OwnedFd::from_raw_fd(fd) }),
            );
        }
    }
    let truncated = msg
        .flags
        .intersects(MsgFlags::MSG_TRUNC | MsgFlags::MSG_CTRUNC);
    let n = msg.bytes;
    if truncated {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "a message too long for the other side",
        ));
    }
    if n == 0 && fds.is_empty() {
        return Ok(None);
    }
    Ok(Some((n, fds)))
}

fn reply(socket: BorrowedFd<'_>, reply: &Reply, fds: &[RawFd]) -> std::io::Result<()> {
    let bytes = serde_json::to_vec(reply).map_err(std::io::Error::other)?;
    send(socket, &bytes, fds)
}

/// Serves matches on standard input until the runner closes it, with `ahead` matches'
/// network namespaces and empty layers made before the matches that take them
/// ([`FreshPool`]; with 0, each match's init makes its own). Returns only on a failure,
/// with the reason (when the runner has gone: `Ok`).
///
/// # Errors
/// The reason it stopped.
pub fn serve(ahead: usize) -> Result<(), String> {
    // SAFETY: descriptor 0 is the control socket for this process's whole life.
    let control = unsafe { BorrowedFd::borrow_raw(0) };
    if std::fs::read_dir("/proc/self/task").map_or(0, Iterator::count) != 1 {
        return Err("the supervisor must have one thread (it clones)".into());
    }
    // The part of the seccomp deny list that nothing here needs goes on this process
    // now, before any request: every match's init, and its bot, inherits it. The rest
    // (mounts, namespaces), compiled once, goes on each init behind its other walls.
    let own = super::seccomp::helper_filter().map_err(|e| format!("seccomp: {e}"))?;
    seccompiler::apply_filter(&own).map_err(|e| format!("seccomp: {e}"))?;
    let filters = super::seccomp::match_filters().map_err(|e| format!("seccomp: {e}"))?;
    // The runner's program is no match's: gone from this mount namespace, it is in no
    // match's copy of it (and its host path in no match's mount table).
    nix::mount::umount2(super::HELPER_IN_SANDBOX, nix::mount::MntFlags::MNT_DETACH)
        .map_err(|e| format!("leaving out the runner's program: {e}"))?;
    // The runner's thread is held to its match's core, and so was this process from
    // its start: it may run on any core (each match's init joins its match's cgroup,
    // which holds it to the match's core), so what it makes between matches need not
    // wait for that core.
    widen_to_every_core();
    let mut pool = FreshPool::new(ahead)?;
    pool.fill()?;
    reply(control, &Reply::Ready, &[]).map_err(|e| format!("cannot answer: {e}"))?;
    let mut buf = vec![0u8; MAX_MESSAGE];
    loop {
        let (n, fds) = match recv(control, &mut buf) {
            Ok(Some(m)) => m,
            Ok(None) => return Ok(()),
            Err(e) => return Err(format!("cannot read the runner's request: {e}")),
        };
        let request = serde_json::from_slice::<Request>(&buf[..n])
            .map_err(|e| format!("a bad request: {e}"))
            .and_then(|r| {
                let args: Vec<OsString> = r.jail.iter().map(OsString::from).collect();
                let jail = jail::JailArgs::parse(&args)?;
                let mut fds = fds;
                if fds.len() != REQUEST_FDS + r.cgroup_files {
                    return Err(format!(
                        "a request needs {} descriptors",
                        REQUEST_FDS + r.cgroup_files
                    ));
                }
                let cgroup = fds.split_off(REQUEST_FDS);
                let fds: [OwnedFd; REQUEST_FDS] = fds
                    .try_into()
                    .map_err(|_| format!("a request needs {REQUEST_FDS} descriptors"))?;
                Ok((r, jail, (fds, cgroup)))
            });
        let (request, jail, fds) = match request {
            Ok(r) => r,
            Err(e) => {
                reply(control, &Reply::Refused(e), &[]).map_err(|e| e.to_string())?;
                continue;
            }
        };
        match start(&request, &jail, &filters, fds, &mut pool) {
            Err(e) => reply(control, &Reply::Refused(e), &[]).map_err(|e| e.to_string())?,
            Ok((pidfd, pid, leftovers)) => {
                reply(control, &Reply::Started, &[pidfd.as_raw_fd()]).map_err(|e| e.to_string())?;
                let code = wait_match(control, &pidfd, pid)?;
                reply(control, &Reply::Ended(code), &[]).map_err(|e| e.to_string())?;
                // Torn down now that the match's end is told, while the runner records
                // its result.
                drop(leftovers);
            }
        }
        // The next match's parts are made now, not when it asks.
        pool.fill()?;
    }
}

/// Lets this process run on every core its cgroup allows.
fn widen_to_every_core() {
    use nix::sched::{CpuSet, sched_setaffinity};
    let mut every = CpuSet::new();
    for core in 0..CpuSet::count() {
        let _ = every.set(core);
    }
    let _ = sched_setaffinity(nix::unistd::Pid::from_raw(0), &every);
}

/// Waits for the match's init to end; when the runner closes the socket meanwhile (it
/// has gone), kills the match and stops.
fn wait_match(control: BorrowedFd<'_>, pidfd: &OwnedFd, pid: libc::pid_t) -> Result<i32, String> {
    use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
    loop {
        let mut fds = [
            PollFd::new(pidfd.as_fd(), PollFlags::POLLIN),
            PollFd::new(control, PollFlags::POLLIN),
        ];
        match poll(&mut fds, PollTimeout::NONE) {
            Err(nix::errno::Errno::EINTR) => continue,
            Err(e) => return Err(format!("poll: {e}")),
            Ok(_) => {}
        }
        let ended = fds[0].any().unwrap_or(false);
        let runner = fds[1].revents().unwrap_or(PollFlags::empty());
        if ended {
            let mut status = 0;
            // SAFETY: waits for our own child.
            let got = unsafe { libc::waitpid(pid, &mut status, 0) };
            if got != pid {
                return Err(format!("waitpid: {}", std::io::Error::last_os_error()));
            }
            return Ok(exit_code(status));
        }
        if runner.intersects(PollFlags::POLLHUP | PollFlags::POLLERR | PollFlags::POLLIN) {
            // Nothing is asked during a match: the runner has gone.
            kill_pidfd(pidfd);
            return Err("the runner has gone".into());
        }
    }
}

/// Sends SIGKILL through a pidfd: to a match's init, which takes its PID namespace with
/// it. A process that has ended already is not an error.
pub fn kill_pidfd(pidfd: &OwnedFd) {
    // SAFETY: pidfd_send_signal(2) with no siginfo.
    unsafe {
        libc::syscall(
            libc::SYS_pidfd_send_signal,
            pidfd.as_raw_fd(),
            libc::SIGKILL,
            std::ptr::null::<libc::siginfo_t>(),
            0u32,
        )
    };
}

/// The code a process's wait status stands for: its exit code, or 128 + its signal.
fn exit_code(status: libc::c_int) -> i32 {
    if libc::WIFEXITED(status) {
        libc::WEXITSTATUS(status)
    } else if libc::WIFSIGNALED(status) {
        128 + libc::WTERMSIG(status)
    } else {
        jail::SETUP_FAILED
    }
}

/// Clones the match's init into new PID, mount and IPC namespaces and a fresh network
/// namespace (one made ahead by `pool`, which the init enters first, or a new one): its
/// pidfd and pid, and what the supervisor keeps of the match until its end is told
/// ([`Leftovers`]). A network namespace of its own holds every counter and table a bot
/// can move (`/proc/net/*`, abstract sockets, the loopback's counters): nothing of one
/// match reaches the next.
fn start(
    request: &Request,
    jail: &jail::JailArgs,
    filters: &[seccompiler::BpfProgram],
    (fds, cgroup): ([OwnedFd; REQUEST_FDS], Vec<OwnedFd>),
    pool: &mut FreshPool,
) -> Result<(OwnedFd, libc::pid_t, Leftovers), String> {
    let fresh = pool.take()?;
    let mut pidfd: libc::c_int = -1;
    let new_net = if fresh.is_some() {
        0
    } else {
        libc::CLONE_NEWNET
    };
    let flags = libc::CLONE_NEWPID
        | libc::CLONE_NEWNS
        | libc::CLONE_NEWIPC
        | new_net
        | libc::CLONE_PIDFD
        | libc::SIGCHLD;
    // SAFETY: a clone without a new stack, like fork(2): this process has one thread
    // (checked at start), so the child's copy of its memory is consistent.
    let pid = unsafe {
        libc::syscall(
            libc::SYS_clone,
            flags as libc::c_ulong,
            0usize,
            &mut pidfd as *mut libc::c_int,
            0usize,
            0usize,
        )
    };
    match pid {
        -1 => Err(format!(
            "cannot make the match's namespaces: {}",
            std::io::Error::last_os_error()
        )),
        0 => {
            // What was made for later matches is not this one's.
            for fd in pool.held() {
                // SAFETY: closes, in this child only, descriptors the pool owns.
                unsafe { libc::close(fd) };
            }
            let code = match_init(request, jail, filters, fds, fresh.as_ref(), cgroup);
            // SAFETY: ends the child without running anything of the parent's.
            unsafe { libc::_exit(code) }
        }
        pid => {
            let [_, _, _, tree] = fds;
            let leftovers = Leftovers::keep(pid as libc::pid_t, fresh, tree);
            drop(cgroup);
            // SAFETY: CLONE_PIDFD stored a new descriptor that this process owns.
            let pidfd = unsafe { OwnedFd::from_raw_fd(pidfd) };
            Ok((pidfd, pid as libc::pid_t, leftovers))
        }
    }
}

/// The match's init (PID 1 of the match's namespace): prepares the match's world as
/// root, then puts up the jail's walls on itself (the match's uid, limits,
/// `no_new_privs`, Landlock, seccomp) and only then starts the bot's program, which
/// inherits every wall: from then on the init is one of the match's processes, with no
/// more rights than the bot's. It reaps every orphan of the match and ends with the
/// bot's process. Returns its exit code.
fn match_init(
    request: &Request,
    jail: &jail::JailArgs,
    filters: &[seccompiler::BpfProgram],
    fds: [OwnedFd; REQUEST_FDS],
    fresh: Option<&Fresh>,
    cgroup: Vec<OwnedFd>,
) -> i32 {
    let [stdin, stdout, stderr, tree] = fds;
    // The runner's socket is not the match's.
    // SAFETY: closes descriptor 0 (the control socket) in this process only.
    unsafe { libc::close(0) };
    // SAFETY: prctl(2) with a signal number.
    unsafe { libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) };
    let fail = |e: String| {
        say(&stderr, &format!("mazearena sandbox: {e}\n"));
        jail::SETUP_FAILED
    };
    if let Some(fresh) = fresh
        && let Err(e) = fresh.enter()
    {
        return fail(e);
    }
    if let Err(e) = prepare(request, &tree, fresh) {
        return fail(e);
    }
    if let Err(e) = join_cgroup(&cgroup) {
        return fail(e);
    }
    drop(cgroup);
    // The match sees its init as `init`, not as the runner's helper.
    name_this_process(b"init");
    drop(tree);
    // Nothing but the bot's stdio passes to it.
    // SAFETY: marks every descriptor from 3 up close-on-exec in this process.
    if unsafe {
        libc::syscall(
            libc::SYS_close_range,
            3u32,
            u32::MAX,
            libc::CLOSE_RANGE_CLOEXEC,
        )
    } != 0
    {
        return fail(format!("close_range: {}", std::io::Error::last_os_error()));
    }
    if let Err(e) = std::env::set_current_dir(Path::new(SCRATCH).join("work")) {
        return fail(format!("cannot enter the working directory: {e}"));
    }
    if let Err(e) = jail::walls(jail, filters) {
        return fail(e);
    }
    // The bot's file names are read, and linked, only behind the walls.
    if let Err(e) = link_bot_files() {
        return fail(e);
    }
    let dup = |fd: &OwnedFd| fd.try_clone().map(std::process::Stdio::from);
    let stdio = (dup(&stdin), dup(&stdout), dup(&stderr));
    let (Ok(i), Ok(o), Ok(e)) = stdio else {
        return fail("cannot pass the bot its pipes".into());
    };
    // The owner's variables reach the bot's own program alone, at its exec, after every
    // wall: started with posix_spawn, nothing runs between fork and exec.
    use std::os::unix::process::CommandExt;
    let spawned = std::process::Command::new(&jail.command[0])
        .args(&jail.command[1..])
        .envs(jail.env.iter().map(|(k, v)| (k, v)))
        .stdin(i)
        .stdout(o)
        .stderr(e)
        .process_group(0)
        .spawn();
    let bot = match spawned {
        Ok(child) => child.id() as libc::pid_t,
        Err(e) => return fail(format!("could not start {:?}: {e}", jail.command[0])),
    };
    drop((stdin, stdout, stderr));
    loop {
        let mut status = 0;
        // SAFETY: reaps any child (orphans of the match are adopted here).
        let got = unsafe { libc::waitpid(-1, &mut status, 0) };
        if got == bot {
            return exit_code(status);
        }
        if got < 0 && std::io::Error::last_os_error().raw_os_error() != Some(libc::EINTR) {
            return jail::SETUP_FAILED;
        }
    }
}

/// Moves this process into the match's own cgroup (`0` written to each of its files,
/// which the runner opened), then makes a cgroup namespace rooted there: the match sees
/// its cgroup as `/`, and no name of the runner's.
fn join_cgroup(files: &[OwnedFd]) -> Result<(), String> {
    if files.is_empty() {
        return Ok(());
    }
    for file in files {
        // SAFETY: write(2) of a live two-byte buffer to a descriptor we own.
        if unsafe { libc::write(file.as_raw_fd(), b"0\n".as_ptr().cast(), 2) } != 2 {
            return Err(format!(
                "cannot join the match's cgroup: {}",
                std::io::Error::last_os_error()
            ));
        }
    }
    // SAFETY: unshare(2) of this (single-threaded) process's cgroup namespace.
    if unsafe { libc::unshare(libc::CLONE_NEWCGROUP) } != 0 {
        return Err(format!(
            "cannot make the match's cgroup namespace: {}",
            std::io::Error::last_os_error()
        ));
    }
    Ok(())
}

/// Renames this process as its match sees it in `/proc` (`cmdline` and `comm`):
/// the command line's memory is overwritten in place, as `setproctitle` does.
fn name_this_process(name: &[u8]) {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return;
    };
    // Fields 48 and 49 of stat(5): where the command line lies in memory.
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(Vec::new(), |(_, rest)| rest.split_whitespace().collect());
    let at = |n: usize| fields.get(n - 3).and_then(|f| f.parse::<usize>().ok());
    let (Some(start), Some(end)) = (at(48), at(49)) else {
        return;
    };
    if end <= start || name.len() >= end - start {
        return;
    }
    // SAFETY: [start, end) is this process's own command line, which nothing reads
    // from now on; it is zeroed, then the name written at its start.
    unsafe {
        std::ptr::write_bytes(start as *mut u8, 0, end - start);
        std::ptr::copy_nonoverlapping(name.as_ptr(), start as *mut u8, name.len());
    }
    if let Ok(comm) = std::ffi::CString::new(name) {
        // SAFETY: prctl(2) with a NUL-terminated name.
        unsafe { libc::prctl(libc::PR_SET_NAME, comm.as_ptr()) };
    }
}

/// Writes `text` to a descriptor, ignoring failures (a message on the bot's stderr).
fn say(fd: &OwnedFd, text: &str) {
    // SAFETY: write(2) of a live buffer.
    unsafe { libc::write(fd.as_raw_fd(), text.as_ptr().cast(), text.len()) };
}

/// The match's own world, made in its fresh mount namespace: `/proc` of its PID
/// namespace (with the parts the one-shot view has read-only kept read-only), the
/// scratch tmpfs with `tmp/` (1777) and `work/` (0777), and the bot's folder attached
/// read-only (over the empty layer made ahead, or one made now); when the network
/// namespace was not made ahead, its loopback up.
fn prepare(request: &Request, tree: &OwnedFd, fresh: Option<&Fresh>) -> Result<(), String> {
    use nix::mount::{MsFlags, mount};
    let none = None::<&str>;
    let at = |what: &str, e: nix::Error| format!("{what}: {e}");
    mount(none, "/", none, MsFlags::MS_REC | MsFlags::MS_PRIVATE, none)
        .map_err(|e| at("making the mounts private", e))?;
    mount(
        Some("proc"),
        "/proc",
        Some("proc"),
        MsFlags::MS_NOSUID | MsFlags::MS_NODEV | MsFlags::MS_NOEXEC,
        none,
    )
    .map_err(|e| at("mounting /proc", e))?;
    for p in ["/proc/sys", "/proc/sysrq-trigger", "/proc/irq", "/proc/bus"] {
        if Path::new(p).exists() {
            super::mounts::read_only_bind(p).map_err(|e| at(p, e))?;
        }
    }
    let options = format!("size={},mode=0755", request.scratch_bytes);
    mount(
        Some("tmpfs"),
        SCRATCH,
        Some("tmpfs"),
        MsFlags::MS_NOSUID | MsFlags::MS_NODEV,
        Some(options.as_str()),
    )
    .map_err(|e| at("mounting the scratch area", e))?;
    let scratch = Path::new(SCRATCH);
    for (dir, mode) in [("tmp", 0o1777), ("work", 0o777)] {
        let path = scratch.join(dir);
        std::fs::create_dir(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let made;
    let empty = match fresh {
        Some(fresh) => &fresh.empty,
        None => {
            made = super::mounts::empty_layer()
                .map_err(|e| format!("the bot's folder's empty layer: {e}"))?;
            &made
        }
    };
    super::mounts::attach_unnamed(tree, empty, BOT_FILES)
        .map_err(|e| format!("attaching the bot's folder: {e}"))?;
    if fresh.is_none() {
        super::fresh::loopback_up()
            .map_err(|e| format!("bringing up the match's loopback: {e}"))?;
    }
    Ok(())
}

/// A link in the working directory to each entry of the bot's folder, made by the
/// match's init once its walls are up (as the match's uid, inside Landlock).
fn link_bot_files() -> Result<(), String> {
    let work = Path::new(SCRATCH).join("work");
    let entries = std::fs::read_dir(BOT_FILES).map_err(|e| format!("{BOT_FILES}: {e}"))?;
    for entry in entries {
        let name = entry.map_err(|e| format!("{BOT_FILES}: {e}"))?.file_name();
        std::os::unix::fs::symlink(Path::new(BOT_FILES).join(&name), work.join(&name))
            .map_err(|e| format!("a link to the bot's file {name:?}: {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_and_descriptors_cross_a_seqpacket_socket() {
        use nix::sys::socket::{AddressFamily, SockFlag, SockType, socketpair};
        let (a, b) = socketpair(
            AddressFamily::Unix,
            SockType::SeqPacket,
            None,
            SockFlag::SOCK_CLOEXEC,
        )
        .unwrap();
        let file = tempfile::tempfile().unwrap();
        send(a.as_fd(), b"hello", &[file.as_raw_fd()]).unwrap();
        send(a.as_fd(), b"again", &[]).unwrap();
        let mut buf = [0u8; 16];
        let (n, fds) = recv(b.as_fd(), &mut buf).unwrap().unwrap();
        assert_eq!((&buf[..n], fds.len()), (&b"hello"[..], 1));
        let (n, fds) = recv(b.as_fd(), &mut buf).unwrap().unwrap();
        assert_eq!((&buf[..n], fds.len()), (&b"again"[..], 0));
        send(a.as_fd(), &[7u8; 32], &[]).unwrap();
        assert!(
            recv(b.as_fd(), &mut buf).is_err(),
            "a message too long is an error"
        );
        drop(a);
        assert!(recv(b.as_fd(), &mut buf).unwrap().is_none());
    }
}
