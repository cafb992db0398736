//! The build worker of a match-worker pool: claims the uploaded versions that have a
//! build command (one build at a time per pool; a claim is a lease in the database, so
//! each version is built once, by one worker of one machine), runs the build in the
//! sandbox (`runner::build`) in a fresh folder holding the version's bundle, stores the
//! built folder as a bundle of its own, plays the version's **validation match** (short
//! matches on public mazes, like a validation episode), and records the result: `ready`
//! versions play from the built bundle on every worker, `build_failed` and `invalid`
//! ones never play (nor count against a quota), and their owner reads why in the build
//! log. By the competition's rule ([`Validation`]): with `start` (the default, and
//! outside competitions) a version is invalid only when it fails before its first move
//! on every maze it is tried on, a failure no maze causes (it does not start, needs
//! another runtime or protocol); a failure on one maze, or after the first move, is a
//! warning in the log and the version plays. With `match` any failure on the first
//! practice maze makes it invalid; `off` plays no validation match. Versions uploaded
//! without a build command are only validated. A build whose worker died is claimed
//! again once its lease expires.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::Notify;
use tokio_util::sync::CancellationToken;

use crate::competition::Validation;
use crate::registry::{self, RegistryError};
use crate::runner::{BotSpec, Limits, MatchStatus, Sandbox, build};
use crate::storage::Storage;
use crate::storage::bots::{BotVersionRow, build_status};
use crate::storage::builds::{MAX_BUILD_ATTEMPTS, build_retries_exhausted};

/// How often the queue of builds is looked at when nothing wakes the builder.
const POLL: Duration = Duration::from_secs(2);

/// The validation match's steps: enough for a bot to start and make its first moves
/// (running out of them is no fault), few enough that the builder, which plays one at a
/// time, is not held long by a slow bot.
const VALIDATION_STEPS: u32 = 20;

/// The size of the validation maze of a protocol-v1 bot outside competitions (an mms
/// mouse's is 16x16, the size such mice are written for).
const VALIDATION_DIM: u32 = 12;

/// The seed of the generated validation mazes (public, the same for every version).
const VALIDATION_SEED: u64 = 20_260_101;

/// What a pool's builder needs.
#[derive(Debug, Clone)]
pub struct Builder {
    /// The database.
    pub storage: Storage,
    /// How builds are isolated.
    pub sandbox: Sandbox,
    /// A local folder for build folders.
    pub scratch: PathBuf,
    /// The bound of each build's writable area, in bytes.
    pub write_limit: u64,
    /// The claimer's name (the pool's lease owner).
    pub owner: Arc<str>,
    /// The lease on a claimed build, renewed every third of it.
    pub lease: Duration,
    /// Play each version's validation match (`serve --no-validation`: not).
    pub validate: bool,
}

/// How a claimed build ended.
enum Ended {
    /// Record it, with the log: `ready` with its built bundle, or `build_failed` or
    /// `invalid`.
    Done {
        status: &'static str,
        built: Option<String>,
        log: String,
    },
    /// Not recorded (the lease was lost, or the database or disk failed): the build is
    /// claimed again once its lease expires.
    Dropped,
}

impl Builder {
    /// Builds waiting versions one at a time until `stop`; `wake` is notified on uploads,
    /// and notified again after each build so match workers look for newly ready versions.
    pub async fn run(self, wake: Arc<Notify>, stop: CancellationToken) {
        let lease_ms = self.lease.as_millis() as i64;
        loop {
            if stop.is_cancelled() {
                return;
            }
            let woken = wake.notified();
            let next = match self.storage.claim_build(&self.owner, lease_ms).await {
                Ok(next) => next,
                Err(e) => {
                    tracing::warn!(error = %e, "cannot read the build queue");
                    None
                }
            };
            let Some(version) = next else {
                tokio::select! {
                    _ = stop.cancelled() => return,
                    _ = woken => {}
                    _ = tokio::time::sleep(POLL) => {}
                }
                continue;
            };
            let id = version.bot_version_id;
            let started = std::time::Instant::now();
            let ended = tokio::select! {
                // Dropped: the build is killed and claimed again after its lease.
                _ = stop.cancelled() => return,
                ended = self.build_renewing(&version) => ended,
            };
            if let Ended::Done { status, built, log } = ended {
                // Spent from its owner's daily build time, whatever the outcome.
                let took_ms = started.elapsed().as_millis() as i64;
                tracing::info!(bot_version_id = id, status, took_ms, "build ended");
                match self
                    .storage
                    .finish_build(id, &self.owner, status, built.as_deref(), &log, took_ms)
                    .await
                {
                    Ok(true) => {}
                    Ok(false) => {
                        tracing::warn!(bot_version_id = id, "build claim lost; not recorded")
                    }
                    Err(e) => tracing::warn!(error = %e, "cannot record a build"),
                }
                wake.notify_waiters();
            }
        }
    }

    /// Builds `version`, renewing its lease meanwhile.
    async fn build_renewing(&self, version: &BotVersionRow) -> Ended {
        let lease_ms = self.lease.as_millis() as i64;
        let mut renew = tokio::time::interval(self.lease / 3);
        renew.tick().await;
        let work = self.build(version);
        tokio::pin!(work);
        loop {
            tokio::select! {
                ended = &mut work => return ended,
                _ = renew.tick() => {
                    match self.storage.renew_build_lease(version.bot_version_id, &self.owner, lease_ms).await {
                        Ok(true) => {}
                        Ok(false) => {
                            tracing::warn!(bot_version_id = version.bot_version_id, "build claim lost; stopping the build");
                            return Ended::Dropped;
                        }
                        Err(e) => tracing::warn!(error = %e, "could not renew a build's lease"),
                    }
                }
            }
        }
    }

    async fn build(&self, version: &BotVersionRow) -> Ended {
        if version.build_attempts > MAX_BUILD_ATTEMPTS {
            tracing::warn!(
                bot_version_id = version.bot_version_id,
                attempts = version.build_attempts,
                "a build kept outliving its worker; recorded as failed"
            );
            return Ended::Done {
                status: build_status::FAILED,
                built: None,
                log: build_retries_exhausted(version.build_attempts - 1),
            };
        }
        if version.build_command.is_none() && !self.validate {
            // Nothing to build or play: ready as uploaded.
            return Ended::Done {
                status: build_status::READY,
                built: None,
                log: String::new(),
            };
        }
        let Some(sha) = &version.bundle_sha256 else {
            return Ended::Done {
                status: build_status::FAILED,
                built: None,
                log: "the version's files are not stored in the database (an old data folder \
                      that could not be moved): upload it again"
                    .into(),
            };
        };
        let area = match build::BuildArea::new(&self.scratch, self.write_limit) {
            Ok(a) => a,
            Err(e) => {
                tracing::error!(cause = %e, dir = %self.scratch.display(), "cannot make a build folder");
                return Ended::Dropped;
            }
        };
        let dir = area.work().to_path_buf();
        match registry::bundles::unpack_stored(&self.storage, sha, &dir).await {
            Ok(_) => {}
            // Missing or damaged in the database: building again cannot help.
            Err(e) if e.is_permanent() => {
                tracing::error!(cause = %e, bot_version_id = version.bot_version_id, "a version's stored files cannot be used; its build failed");
                return Ended::Done {
                    status: build_status::FAILED,
                    built: None,
                    log: format!(
                        "the server could not use the version's stored files: {e}; upload it again"
                    ),
                };
            }
            // The database or this machine's disk: built again after the lease.
            Err(e) => {
                tracing::error!(cause = %e, bot_version_id = version.bot_version_id, "cannot fetch a version's files to build them");
                return Ended::Dropped;
            }
        }
        let Some(command) = version.build_command.clone() else {
            // Nothing to build: the uploaded files play as they are, once validated.
            let (status, log) = self.validate(version, &dir, String::new()).await;
            return Ended::Done {
                status,
                built: None,
                log,
            };
        };
        tracing::info!(bot_version_id = version.bot_version_id, %command, "building");
        let (ok, mut log) =
            match build::build_logged(&command, &area, &self.sandbox, version.runtime.as_deref())
                .await
            {
                Ok(o) => {
                    let mut log = o.log;
                    if !o.ok {
                        log.push_str(&format!("\n[build {}]", o.status));
                    }
                    (o.ok, log)
                }
                Err(e) => (false, e.to_string()),
            };
        if !ok {
            return Ended::Done {
                status: build_status::FAILED,
                built: None,
                log,
            };
        }
        match registry::bundles::store_dir(&self.storage, &dir, &self.scratch).await {
            Ok(summary) => {
                let (status, log) = self.validate(version, &dir, log).await;
                Ended::Done {
                    status,
                    built: (status == build_status::READY).then_some(summary.sha256),
                    log,
                }
            }
            Err(RegistryError::Bundle(e)) if e.is_client_error() => {
                log.push_str(&format!("\n[the built folder cannot be stored: {e}]"));
                Ended::Done {
                    status: build_status::FAILED,
                    built: None,
                    log,
                }
            }
            Err(e) => {
                tracing::error!(cause = %e, bot_version_id = version.bot_version_id, "cannot store a built folder");
                Ended::Dropped
            }
        }
    }
}

/// One validation match played: where, and how it ended.
struct Tried {
    /// The maze in words.
    place: String,
    /// The record.
    record: crate::runner::MatchRecord,
}

impl Tried {
    /// Whether the bot played without a fault (the steps ran out or it finished).
    fn passed(&self) -> bool {
        matches!(
            self.record.status,
            MatchStatus::Finished | MatchStatus::StepLimit
        )
    }

    /// Whether it failed before its first move (the first step asked and not answered,
    /// or before it: it never made a move).
    fn failed_before_first_move(&self) -> bool {
        !self.passed()
            && self
                .record
                .error
                .as_ref()
                .and_then(|e| e.step)
                .is_none_or(|step| step <= 1)
    }

    /// What happened, for the owner: where, the status and reason, the end of its
    /// stderr (a traceback), and a hint.
    fn told(&self, command: &str) -> String {
        let status = self.record.status;
        let reason = self
            .record
            .error
            .as_ref()
            .map_or_else(|| status.to_string(), |e| e.reason.clone());
        let mut text = format!("[validation match on {}: {status}: {reason}]\n", self.place);
        let tail = self.record.stderr_tail.trim_end();
        if !tail.is_empty() {
            text.push_str(&format!("--- the end of its stderr ---\n{tail}\n"));
        }
        if let Some(hint) = validation_hint(command, tail) {
            text.push_str(&format!("hint: {hint}\n"));
        }
        text
    }
}

impl Builder {
    /// Validates `version` from its folder `dir` as its competition (or the server)
    /// says ([`Validation`]): `ready`, or `invalid`, with `log` and what happened added
    /// to it (the reason, the end of its stderr, a hint; a warning for a failure that
    /// does not make it invalid).
    async fn validate(
        &self,
        version: &BotVersionRow,
        dir: &std::path::Path,
        mut log: String,
    ) -> (&'static str, String) {
        if !self.validate {
            return (build_status::READY, log);
        }
        let Some(plan) = self.validation_plan(version).await else {
            return (build_status::READY, log);
        };
        if plan.mode == Validation::Off {
            return (build_status::READY, log);
        }
        if !log.is_empty() && !log.ends_with('\n') {
            log.push('\n');
        }
        let mut tried: Vec<Tried> = Vec::new();
        for (maze, place) in plan.mazes {
            let Some(record) = self.play_validation(version, dir, maze, plan.limits).await else {
                // The server could not play it (logged): the version is not held up.
                return (build_status::READY, log);
            };
            let t = Tried { place, record };
            let done =
                t.passed() || !t.failed_before_first_move() || plan.mode == Validation::Match;
            tried.push(t);
            if done {
                break;
            }
        }
        let Some(last) = tried.last() else {
            return (build_status::READY, log);
        };
        if last.passed() {
            for t in &tried[..tried.len() - 1] {
                log.push_str(&t.told(&version.command));
            }
            if tried.len() > 1 {
                log.push_str("warning: it failed before its first move on the mazes above, but played on the next: it is ready and plays; it may fail the same way on some of the mazes it plays.\n");
            }
            log.push_str(&format!(
                "[validation match: played {} steps on {} without a fault]",
                last.record.total_steps, last.place
            ));
            return (build_status::READY, log);
        }
        for t in &tried {
            log.push_str(&t.told(&version.command));
        }
        if plan.mode == Validation::Start && !last.failed_before_first_move() {
            log.push_str("warning: it failed on that maze after its first move (an error inside the bot on that maze, not one at its start): it is ready and plays, and it may fail the same way on other mazes.");
            return (build_status::READY, log);
        }
        if plan.mode == Validation::Start {
            log.push_str("It failed before its first move on every maze it was tried on (it does not start, or needs another runtime or protocol). ");
        }
        log.push_str(
            "This version is invalid: it will not play, and it does not count against your quota.",
        );
        (build_status::INVALID, log)
    }

    /// Plays one validation match of `version` on `maze` (at most [`VALIDATION_STEPS`]
    /// steps under `limits`); `None` if the server could not play it (logged).
    async fn play_validation(
        &self,
        version: &BotVersionRow,
        dir: &std::path::Path,
        maze: crate::engine::Maze,
        limits: Limits,
    ) -> Option<crate::runner::MatchRecord> {
        let bot = BotSpec {
            command: version.command.clone(),
            dir: dir.to_path_buf(),
            env: version.env_pairs(),
            echo_stderr: false,
            runtime: version.runtime.clone(),
            protocol: crate::runner::BotProtocol::of_stored(version.protocol.as_deref()),
        };
        let limits = Limits {
            max_steps: VALIDATION_STEPS,
            ..limits
        };
        // On a thread of its own, as the workers play matches: its waits on the bot's
        // pipes must not hold up the server's runtime.
        let sandbox = self.sandbox.clone();
        let played = tokio::task::spawn_blocking(move || {
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()?;
            Ok::<_, std::io::Error>(rt.block_on(crate::runner::run_match(
                &bot,
                &maze,
                0,
                limits,
                &sandbox,
                |_| {},
            )))
        })
        .await;
        match played {
            Ok(Ok(r)) => Some(r),
            Ok(Err(e)) => {
                tracing::error!(cause = %e, "cannot play a validation match");
                None
            }
            Err(e) => {
                tracing::error!(cause = %e, "a validation match failed");
                None
            }
        }
    }
}

/// How a version is validated: the rule, the mazes in the order they are tried, the
/// limits.
struct Plan {
    mode: Validation,
    mazes: Vec<(crate::engine::Maze, String)>,
    limits: Limits,
}

/// A generated public validation maze of size `dim`, and its description.
fn generated(dim: u32) -> Option<(crate::engine::Maze, String)> {
    crate::engine::generator::generate(dim, VALIDATION_SEED)
        .map(|m| (m, format!("a public generated {dim}x{dim} maze")))
        .map_err(|e| tracing::error!(cause = %e, "cannot make a validation maze"))
        .ok()
}

/// The size of another generated maze after a failure on mazes of size `dim`.
fn other_size(dim: u32) -> u32 {
    if dim == 16 { 12 } else { 16 }
}

impl Builder {
    /// Where and how `version` is validated: for a bot entered in a competition, by the
    /// competition's rule, on its practice mazes (public; with `match`, the first only)
    /// and then a generated maze of another size, under its limits; otherwise by
    /// `start` on a generated maze of the size its protocol plays (16x16 for an mms
    /// mouse, 12x12 else) and then one of the other size, under the server's limits.
    /// `None` if no maze can be had (the generator failed: a bug, logged, and the
    /// version is not held up by it).
    async fn validation_plan(&self, version: &BotVersionRow) -> Option<Plan> {
        let protocol = crate::runner::BotProtocol::of_stored(version.protocol.as_deref());
        let dim = if protocol == crate::runner::BotProtocol::Mms {
            16
        } else {
            VALIDATION_DIM
        };
        let competitions = self
            .storage
            .competitions_of_bot(version.bot_id)
            .await
            .unwrap_or_default();
        if let Some(c) = competitions.iter().find(|c| c.kind != "default") {
            let mode = Validation::parse(&c.validation);
            let limits = c.limit_set().apply(Limits::default());
            let mut mazes = Vec::new();
            for m in self
                .storage
                .competition_mazes(c.competition_id)
                .await
                .unwrap_or_default()
                .iter()
                .filter(|m| m.maze_set == "practice")
            {
                if let Ok(Some(row)) = self.storage.get_maze(m.maze_id).await
                    && !row.hidden
                    && let Ok(maze) = crate::engine::mazefile::parse(row.layout.as_bytes())
                {
                    let place = format!("the practice maze {} of competition {}", row.name, c.name);
                    mazes.push((maze, place));
                }
            }
            if mazes.is_empty() {
                mazes.extend(generated(dim));
            }
            if mode == Validation::Match {
                mazes.truncate(1);
            } else if let Some(first) = mazes.first().map(|(m, _)| m.dim()) {
                mazes.extend(generated(other_size(first)));
            }
            return (!mazes.is_empty()).then_some(Plan {
                mode,
                mazes,
                limits,
            });
        }
        let mut mazes: Vec<_> = generated(dim).into_iter().collect();
        mazes.extend(generated(other_size(dim)));
        (!mazes.is_empty()).then_some(Plan {
            mode: Validation::Start,
            mazes,
            limits: Limits::default(),
        })
    }
}

/// A hint for a version that failed its validation match, from its command and the end
/// of its stderr.
pub fn validation_hint(command: &str, stderr: &str) -> Option<&'static str> {
    let python = command
        .split_whitespace()
        .next()
        .is_some_and(|w| w.contains("python"));
    let python2 = stderr.contains("SyntaxError")
        && (stderr.contains("print ")
            || stderr.contains("Missing parentheses in call to 'print'")
            || stderr.contains("except ")
            || stderr.contains("xrange"));
    if python && (python2 || (stderr.contains("SyntaxError") && !command.contains("2.7"))) {
        return Some(
            "is this Python 2? Python 3 cannot read it: choose a Python 2.7 runtime (GET \
             /api/runtimes lists the server's; README \"A Python 2.7 runtime\") or port it to Python 3",
        );
    }
    if stderr.contains("ModuleNotFoundError") || stderr.contains("ImportError") {
        return Some(
            "a module is missing: upload it with your files, or choose a runtime that has it \
             (GET /api/runtimes lists the server's)",
        );
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_python_2_syntax_error_gets_the_runtime_hint() {
        let stderr = "  File \"robot.py\", line 12\n    print \"hello\"\n          ^\nSyntaxError: Missing parentheses in call to 'print'. Did you mean print(...)?";
        assert!(
            validation_hint("python3 udacity_adapter.py", stderr)
                .unwrap()
                .contains("Python 2")
        );
        assert!(validation_hint("./bot", stderr).is_none());
        assert!(
            validation_hint(
                "python3 b.py",
                "ModuleNotFoundError: No module named 'numpy'"
            )
            .unwrap()
            .contains("module")
        );
    }

    #[tokio::test]
    async fn a_build_that_kept_outliving_its_worker_is_failed_not_run_again() {
        for (db, _guard) in crate::storage::test_support::backends().await {
            let v = db
                .create_bot("b", "h", &crate::storage::test_support::with_build())
                .await
                .unwrap();
            let scratch = tempfile::tempdir().unwrap();
            let builder = Builder {
                storage: db.clone(),
                sandbox: Sandbox::None,
                scratch: scratch.path().to_path_buf(),
                write_limit: 1 << 20,
                owner: "w".into(),
                lease: Duration::from_secs(60),
                validate: true,
            };
            // Each claim's worker dies: its lease runs out and the build is claimed again.
            let mut row = None;
            for _ in 0..=MAX_BUILD_ATTEMPTS {
                row = db.claim_build("w", -1).await.unwrap();
            }
            let row = row.unwrap();
            assert_eq!(row.bot_version_id, v.bot_version_id);
            assert_eq!(row.build_attempts, MAX_BUILD_ATTEMPTS + 1);
            let Ended::Done { built, log, .. } = builder.build(&row).await else {
                panic!("the build was dropped again");
            };
            assert_eq!(built, None);
            assert!(log.contains("(3 attempts)"), "{log}");
            // Before its attempts ran out, the same version is built (and, with its
            // files missing, fails for that reason instead).
            let mut fresh = row.clone();
            fresh.build_attempts = MAX_BUILD_ATTEMPTS;
            let Ended::Done { log, .. } = builder.build(&fresh).await else {
                panic!("dropped");
            };
            assert!(log.contains("upload it again"), "{log}");
        }
    }
}
