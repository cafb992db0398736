//! The work that plays and builds, apart from the web face: the match workers
//! ([`worker`]: a pool of threads that claim queued matches with a lease, play them with
//! the runner and record them) and the build worker of each pool ([`builder`]: builds
//! and validates uploaded versions). The order in which they take work (the fair queue's
//! lanes, one owner's matches after another's) is the queue's claim in
//! [`crate::storage::matches::queue`]; the limits on what may wait are
//! [`crate::registry::owners`].
//!
//! Used by `mazearena serve` (its own pool), `mazearena worker` (pools on other machines)
//! and `mazearena tournament` (a pool for one local tournament); the API never calls in:
//! it queues, and the workers find the work in the database.

pub mod builder;
pub mod worker;
