//! What a warm match needs new, made by the supervisor ([`super::supervisor`]) before
//! the match that takes it, and what it keeps of a match until the match's end is told.
//!
//! Making a network namespace costs the kernel about half a millisecond (its tables,
//! counters and loopback), and tearing a mount or a namespace down waits for an RCU
//! grace period. None of that needs to lie between a match's request and its bot's
//! first step, or between the bot's exit and the runner learning of it: the supervisor
//! makes the next match's network namespace (loopback up) and the empty layer under its
//! bot's folder while the runner records the last result, and drops what a match used
//! only after it has told the runner the match ended.
//!
//! Each part is handed to exactly one match: [`FreshPool::take`] removes it from the
//! pool, and once the match has ended the supervisor drops its own copies, so the
//! kernel tears the parts down. Nothing is kept for a second match.

use std::collections::VecDeque;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};

/// One match's parts, made ahead.
#[derive(Debug)]
pub struct Fresh {
    /// A new network namespace with its loopback up.
    net: OwnedFd,
    /// A detached, read-only, empty tmpfs: the lower layer under the bot's folder.
    pub empty: OwnedFd,
}

impl Fresh {
    /// Moves the calling process (the match's init) into this match's network
    /// namespace.
    ///
    /// # Errors
    /// The kernel refused it.
    pub fn enter(&self) -> Result<(), String> {
        // SAFETY: setns(2) with a namespace descriptor this value owns.
        if unsafe { libc::setns(self.net.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
            return Err(format!(
                "cannot enter the match's network namespace: {}",
                std::io::Error::last_os_error()
            ));
        }
        Ok(())
    }
}

/// The parts made ahead, for the supervisor's next matches.
#[derive(Debug)]
pub struct FreshPool {
    /// The supervisor's own network namespace, come back to after making each one.
    home: OwnedFd,
    /// Made and not yet handed out, oldest first.
    made: VecDeque<Fresh>,
    /// How many to keep made; 0: none (each match's init makes its own).
    ahead: usize,
}

impl FreshPool {
    /// A pool keeping `ahead` matches' parts made (none are made yet).
    ///
    /// # Errors
    /// This process's own network namespace cannot be opened.
    pub fn new(ahead: usize) -> Result<FreshPool, String> {
        Ok(FreshPool {
            home: open_ns("net").map_err(|e| format!("the supervisor's network namespace: {e}"))?,
            made: VecDeque::new(),
            ahead,
        })
    }

    /// Makes parts until `ahead` matches' are ready.
    ///
    /// # Errors
    /// They could not be made, or this process could not come back to its own
    /// network namespace.
    pub fn fill(&mut self) -> Result<(), String> {
        while self.made.len() < self.ahead {
            let made = self.make()?;
            self.made.push_back(made);
        }
        Ok(())
    }

    /// The next match's parts: made ahead, or made now when none were left; `None` when
    /// the pool keeps none.
    ///
    /// # Errors
    /// None were ready and they could not be made.
    pub fn take(&mut self) -> Result<Option<Fresh>, String> {
        if self.ahead == 0 {
            return Ok(None);
        }
        match self.made.pop_front() {
            Some(fresh) => Ok(Some(fresh)),
            None => self.make().map(Some),
        }
    }

    /// The descriptors this pool holds, which a match's init closes first.
    pub fn held(&self) -> impl Iterator<Item = RawFd> + '_ {
        std::iter::once(self.home.as_raw_fd()).chain(
            self.made
                .iter()
                .flat_map(|f| [f.net.as_raw_fd(), f.empty.as_raw_fd()]),
        )
    }

    /// One match's parts: this process enters a new network namespace, brings its
    /// loopback up, opens it, and comes back to its own.
    fn make(&self) -> Result<Fresh, String> {
        let empty = super::mounts::empty_layer()
            .map_err(|e| format!("the bot's folder's empty layer: {e}"))?;
        // SAFETY: unshare(2) of this (single-threaded) process's network namespace.
        if unsafe { libc::unshare(libc::CLONE_NEWNET) } != 0 {
            return Err(format!(
                "cannot make a network namespace: {}",
                std::io::Error::last_os_error()
            ));
        }
        let net = loopback_up()
            .map_err(|e| format!("bringing up a match's loopback: {e}"))
            .and_then(|()| open_ns("net").map_err(|e| format!("a new network namespace: {e}")));
        // SAFETY: setns(2) with a namespace descriptor this pool owns.
        if unsafe { libc::setns(self.home.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
            return Err(format!(
                "cannot come back to the supervisor's network namespace: {}",
                std::io::Error::last_os_error()
            ));
        }
        Ok(Fresh { net: net?, empty })
    }
}

/// What the supervisor keeps of a match while it plays: its network and mount
/// namespaces and its bot's folder's tree (and empty layer). Each is the last
/// reference, or one of the last, to something the kernel tears down when it goes
/// (waiting out an RCU grace period for the mounts): dropped after the match's end is
/// told, that waiting is not between the bot's exit and the runner learning of it.
#[derive(Debug)]
pub struct Leftovers {
    _fresh: Option<Fresh>,
    _tree: OwnedFd,
    _net: Option<OwnedFd>,
    _mounts: Option<OwnedFd>,
}

impl Leftovers {
    /// Keeps what match init `pid` was given (`fresh`, `tree`) and its namespaces.
    pub fn keep(pid: libc::pid_t, fresh: Option<Fresh>, tree: OwnedFd) -> Leftovers {
        let of_pid = |kind: &str| {
            std::fs::File::open(format!("/proc/{pid}/ns/{kind}"))
                .ok()
                .map(OwnedFd::from)
        };
        Leftovers {
            // Made ahead, the network namespace is held by `fresh` already.
            _net: if fresh.is_none() { of_pid("net") } else { None },
            _mounts: of_pid("mnt"),
            _fresh: fresh,
            _tree: tree,
        }
    }
}

/// Brings up the loopback of the match's own network namespace, as bubblewrap does for
/// a one-shot sandbox's: a bot may listen on and talk to itself, never beyond.
pub fn loopback_up() -> std::io::Result<()> {
    // SAFETY: socket(2) with constant arguments; the descriptor is owned below.
    let fd = unsafe { libc::socket(libc::AF_INET, libc::SOCK_DGRAM | libc::SOCK_CLOEXEC, 0) };
    if fd < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: a descriptor just made and owned by nothing else.
    let socket = unsafe { OwnedFd::from_raw_fd(fd) };
    // SAFETY: ifreq is plain data; zeroed is a valid value.
    let mut req: libc::ifreq = unsafe { std::mem::zeroed() };
    for (to, from) in req.ifr_name.iter_mut().zip(b"lo\0") {
        *to = *from as libc::c_char;
    }
    // SAFETY: SIOCGIFFLAGS and SIOCSIFFLAGS read and write the ifreq given.
    unsafe {
        if libc::ioctl(socket.as_raw_fd(), libc::SIOCGIFFLAGS, &mut req) < 0 {
            return Err(std::io::Error::last_os_error());
        }
        req.ifr_ifru.ifru_flags |= libc::IFF_UP as libc::c_short;
        if libc::ioctl(socket.as_raw_fd(), libc::SIOCSIFFLAGS, &req) < 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// This thread's namespace of `kind`, opened.
fn open_ns(kind: &str) -> std::io::Result<OwnedFd> {
    std::fs::File::open(format!("/proc/thread-self/ns/{kind}")).map(OwnedFd::from)
}
