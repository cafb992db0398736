//! A version's build status.

/// Plays.
pub const READY: &str = "ready";
/// Waits for, or is in, its build.
pub const BUILDING: &str = "building";
/// Its build failed: it never plays.
pub const FAILED: &str = "build_failed";
/// Its validation match (after the build) failed: it crashed, timed out or broke
/// the protocol there, so it never plays and does not count against a quota.
pub const INVALID: &str = "invalid";

/// Whether a version of this status never plays.
pub fn never_plays(status: &str) -> bool {
    status == FAILED || status == INVALID
}
