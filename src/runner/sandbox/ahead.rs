//! Cgroups made before the warm matches that take them, and removed after: a warm
//! match's start does not wait for the kernel to make its cgroup, nor its end for the
//! removal. Each match gets a cgroup no other match had ([`super::warm`]); one thread of
//! the runner makes the next ones and removes the used ones, on whatever core the
//! scheduler finds free (it is not held to the matches' cores).
//!
//! A cgroup is handed out once: [`CgroupsAhead::take`] removes it from the pool, and a
//! used one given back ([`CgroupsAhead::retire`]) is emptied and removed, never handed
//! out again.

use std::sync::{Arc, Condvar, Mutex};

use super::cgroup::{CgroupLimits, CgroupRoot, MatchCgroup};

/// How many cgroups are kept made for each core.
const PER_CORE: usize = 1;

/// The pool and its worker thread (started with the first match).
#[derive(Debug, Default)]
pub struct CgroupsAhead {
    shared: Arc<Shared>,
}

#[derive(Debug, Default)]
struct Shared {
    state: Mutex<State>,
    wake: Condvar,
}

#[derive(Debug, Default)]
struct State {
    /// Made and not handed out, with the core each is held to.
    fresh: Vec<(Option<usize>, MatchCgroup)>,
    /// Cores to make one more for, and the hierarchy to make it in.
    wanted: Vec<(CgroupRoot, Option<usize>)>,
    /// Used, to empty and remove.
    used: Vec<MatchCgroup>,
    /// The worker thread runs.
    running: bool,
    /// The pool is dropped: the worker ends.
    stop: bool,
}

impl CgroupsAhead {
    /// A fresh cgroup held to `core` in `root`: one made ahead when there is one, else
    /// one made now; either way the next one for `core` is made ahead.
    ///
    /// # Errors
    /// None was made ahead and one could not be made now.
    pub fn take(&self, root: &CgroupRoot, core: Option<usize>) -> std::io::Result<MatchCgroup> {
        let found = {
            let mut state = self.lock();
            let found = state
                .fresh
                .iter()
                .position(|(c, _)| *c == core)
                .map(|at| state.fresh.remove(at).1);
            state.wanted.push((root.clone(), core));
            self.start_worker(&mut state);
            found
        };
        self.shared.wake.notify_one();
        match found {
            Some(group) => Ok(group),
            None => root.create(bare(core)),
        }
    }

    /// Gives back a used cgroup: the worker kills whatever is left in it and removes it.
    pub fn retire(&self, group: MatchCgroup) {
        let mut state = self.lock();
        if state.running {
            state.used.push(group);
            drop(state);
            self.shared.wake.notify_one();
        } else {
            drop(state);
            drop(group);
        }
    }

    /// How many cgroups are made and waiting.
    pub fn fresh(&self) -> usize {
        self.lock().fresh.len()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn start_worker(&self, state: &mut State) {
        if state.running {
            return;
        }
        let shared = self.shared.clone();
        let started = std::thread::Builder::new()
            .name("cgroups-ahead".into())
            .spawn(move || work(&shared));
        state.running = started.is_ok();
    }
}

impl Drop for CgroupsAhead {
    fn drop(&mut self) {
        let (fresh, used) = {
            let mut state = self.lock();
            state.stop = true;
            (
                std::mem::take(&mut state.fresh),
                std::mem::take(&mut state.used),
            )
        };
        self.shared.wake.notify_all();
        // Removed here, not left to a thread that may not run again before the
        // process ends.
        drop((fresh, used));
    }
}

/// A match cgroup's limits before its match sets them: held to `core`, nothing else.
fn bare(core: Option<usize>) -> CgroupLimits {
    CgroupLimits {
        memory_bytes: None,
        pids: None,
        core,
    }
}

/// The worker: removes used cgroups first (they hold nothing anyone waits for, but the
/// kernel's memory), then makes the wanted ones, until the pool is dropped.
fn work(shared: &Shared) {
    widen_to_the_process_cores();
    loop {
        let job = {
            let mut state = shared
                .state
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            loop {
                if state.stop {
                    state.running = false;
                    let used = std::mem::take(&mut state.used);
                    drop(state);
                    drop(used);
                    return;
                }
                if let Some(used) = state.used.pop() {
                    break Job::Remove(used);
                }
                if let Some((root, core)) = state.wanted.pop() {
                    let made = state.fresh.iter().filter(|(c, _)| *c == core).count();
                    if made < PER_CORE {
                        break Job::Make(root, core);
                    }
                    continue;
                }
                state = shared
                    .wake
                    .wait(state)
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
            }
        };
        match job {
            Job::Remove(group) => drop(group),
            Job::Make(root, core) => {
                if let Ok(group) = root.create(bare(core)) {
                    let mut state = shared
                        .state
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner);
                    if state.stop {
                        drop(state);
                        drop(group);
                    } else {
                        state.fresh.push((core, group));
                    }
                }
            }
        }
    }
}

enum Job {
    Remove(MatchCgroup),
    Make(CgroupRoot, Option<usize>),
}

/// Lets this thread run on every core the process may use: it is started from a match
/// thread, whose pinning it would otherwise inherit.
fn widen_to_the_process_cores() {
    use nix::sched::{sched_getaffinity, sched_setaffinity};
    use nix::unistd::Pid;
    let process = Pid::from_raw(std::process::id() as i32);
    if let Ok(set) = sched_getaffinity(process) {
        let _ = sched_setaffinity(Pid::from_raw(0), &set);
    }
}
