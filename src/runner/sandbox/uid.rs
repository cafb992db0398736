//! Unprivileged uids for matches when the server runs as root: each running match gets
//! a uid no other running match of this server has, so its processes can be counted
//! (RLIMIT_NPROC) and can touch nothing of anyone else's.

use std::collections::BTreeSet;
use std::sync::Mutex;

/// The first uid used; the range is far above any account's, and per server process
/// (by pid) so two servers on one machine do not share uids.
pub const UID_BASE: u32 = 2_000_000_000;

/// How many matches one server process can run at once.
const SLOTS: u32 = 256;

static TAKEN: Mutex<BTreeSet<u32>> = Mutex::new(BTreeSet::new());

/// A uid held by one running match; given back when dropped.
#[derive(Debug)]
pub struct UidLease {
    slot: u32,
}

impl UidLease {
    /// Takes the lowest free slot (wrapping to share one if all 256 are in use).
    pub fn take() -> UidLease {
        let mut taken = TAKEN.lock().unwrap_or_else(|p| p.into_inner());
        let slot = (0..SLOTS).find(|s| !taken.contains(s)).unwrap_or(0);
        taken.insert(slot);
        UidLease { slot }
    }

    /// The uid (and gid) of the match.
    pub fn uid(&self) -> u32 {
        UID_BASE + (std::process::id() % 4096) * SLOTS + self.slot
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
    fn running_matches_get_different_uids_and_give_them_back() {
        let a = UidLease::take();
        let b = UidLease::take();
        assert_ne!(a.uid(), b.uid());
        assert!(a.uid() >= UID_BASE);
        let freed = a.uid();
        drop(a);
        let c = UidLease::take();
        assert_eq!(c.uid(), freed);
        drop(b);
    }
}
