//! Unprivileged uids for matches and builds when the runner runs as root: each running
//! match or build gets a uid that no other running match or build **on this host** has,
//! whatever the number of runner processes (a server, its workers, `run` and
//! `tournament` side by side), so its processes can be counted (RLIMIT_NPROC) and can
//! touch nothing of anyone else's.
//!
//! A runner process reserves a block of [`SLOTS`] uids the first time it needs one: it
//! takes an exclusive `flock` on the block's lock file in [`LOCK_DIR`] and keeps it open
//! until it exits. The kernel releases the lock when the process ends, however it ends,
//! so a crashed runner gives its block back without any clean-up.

use std::collections::BTreeSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use nix::fcntl::{Flock, FlockArg};

/// The first uid used: far above any account's.
pub const UID_BASE: u32 = 2_000_000_000;

/// How many matches and builds one runner process can run at once.
const SLOTS: u32 = 256;

/// How many runner processes can hold uids on one host at once.
const BLOCKS: u32 = 4096;

/// Where the block lock files live (root only: uids are used only as root).
pub const LOCK_DIR: &str = "/run/mazearena/uids";

/// This process's block, once reserved: its number and the held lock.
static BLOCK: OnceLock<Result<(u32, Flock<File>), String>> = OnceLock::new();

static TAKEN: Mutex<BTreeSet<u32>> = Mutex::new(BTreeSet::new());

/// A uid held by one running match or build; given back when dropped.
#[derive(Debug)]
pub struct UidLease {
    uid: u32,
    slot: u32,
}

/// Reserves the first free block under `dir`: returns its number and the held lock.
fn reserve_block(dir: &Path) -> Result<(u32, Flock<File>), String> {
    use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt};
    std::fs::DirBuilder::new()
        .recursive(true)
        .mode(0o700)
        .create(dir)
        .map_err(|e| format!("cannot make {}: {e}", dir.display()))?;
    for block in 0..BLOCKS {
        let path: PathBuf = dir.join(format!("{block}.lock"));
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .mode(0o600)
            .custom_flags(libc::O_CLOEXEC | libc::O_NOFOLLOW)
            .open(&path)
            .map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        match Flock::lock(file, FlockArg::LockExclusiveNonblock) {
            Ok(lock) => return Ok((block, lock)),
            Err((_, nix::errno::Errno::EWOULDBLOCK)) => continue,
            Err((_, e)) => return Err(format!("cannot lock {}: {e}", path.display())),
        }
    }
    Err(format!(
        "all {BLOCKS} uid blocks in {} are held by running processes",
        dir.display()
    ))
}

/// This process's block of uids, reserved on first use.
///
/// # Errors
/// The lock directory cannot be made, or every block is held.
fn block() -> Result<u32, String> {
    match BLOCK.get_or_init(|| reserve_block(Path::new(LOCK_DIR))) {
        Ok((block, _)) => Ok(*block),
        Err(e) => Err(e.clone()),
    }
}

impl UidLease {
    /// Takes the lowest free uid of this process's block.
    ///
    /// # Errors
    /// No block can be reserved, or all `SLOTS` uids of it are in use.
    pub fn take() -> Result<UidLease, String> {
        let block = block()?;
        let mut taken = TAKEN.lock().unwrap_or_else(|p| p.into_inner());
        let slot = (0..SLOTS)
            .find(|s| !taken.contains(s))
            .ok_or_else(|| format!("all {SLOTS} uids of this process are in use"))?;
        taken.insert(slot);
        Ok(UidLease {
            uid: UID_BASE + block * SLOTS + slot,
            slot,
        })
    }

    /// The uid (and gid) of the match or build.
    pub fn uid(&self) -> u32 {
        self.uid
    }
}

impl Drop for UidLease {
    fn drop(&mut self) {
        let mut taken = TAKEN.lock().unwrap_or_else(|p| p.into_inner());
        taken.remove(&self.slot);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_exclusive_while_held_and_free_once_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let (a, lock_a) = reserve_block(dir.path()).unwrap();
        let (b, lock_b) = reserve_block(dir.path()).unwrap();
        assert_eq!((a, b), (0, 1));
        drop(lock_a);
        let (c, _lock_c) = reserve_block(dir.path()).unwrap();
        assert_eq!(c, 0, "a released block is taken again");
        drop(lock_b);
    }

    #[test]
    fn running_matches_get_different_uids_and_give_them_back() {
        if !nix::unistd::geteuid().is_root() {
            eprintln!("SKIPPED uid leases: only used as root");
            return;
        }
        let a = UidLease::take().unwrap();
        let b = UidLease::take().unwrap();
        assert_ne!(a.uid(), b.uid());
        assert!(a.uid() >= UID_BASE);
        let freed = a.uid();
        drop(a);
        let c = UidLease::take().unwrap();
        assert_eq!(c.uid(), freed);
        drop(b);
    }
}
