//! The build worker of a match-worker pool: claims the uploaded versions that have a
//! build command (one build at a time per pool; a claim is a lease in the database, so
//! each version is built once, by one worker of one machine), runs the build in the
//! sandbox (`runner::build`) in a fresh folder holding the version's bundle, stores the
//! built folder as a bundle of its own, and records the result: `ready` versions play
//! from the built bundle on every worker, `build_failed` ones never play, and their
//! owner reads the build log. A build whose worker died is claimed again once its lease
//! expires.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::Notify;
use tokio_util::sync::CancellationToken;

use crate::registry::{self, RegistryError};
use crate::runner::{Sandbox, build};
use crate::storage::Storage;
use crate::storage::bots::BotVersionRow;
use crate::storage::builds::{MAX_BUILD_ATTEMPTS, build_retries_exhausted};

/// How often the queue of builds is looked at when nothing wakes the builder.
const POLL: Duration = Duration::from_secs(2);

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
}

/// How a claimed build ended.
enum Ended {
    /// Record it, with the log: `ready` with its built bundle, else `build_failed`.
    Done { built: Option<String>, log: String },
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
            let ended = tokio::select! {
                // Dropped: the build is killed and claimed again after its lease.
                _ = stop.cancelled() => return,
                ended = self.build_renewing(&version) => ended,
            };
            if let Ended::Done { built, log } = ended {
                let ok = built.is_some();
                tracing::info!(bot_version_id = id, ok, "build ended");
                match self
                    .storage
                    .finish_build(id, &self.owner, ok, built.as_deref(), &log)
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
                built: None,
                log: build_retries_exhausted(version.build_attempts - 1),
            };
        }
        let command = version.build_command.clone().unwrap_or_default();
        let Some(sha) = &version.bundle_sha256 else {
            return Ended::Done {
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
            return Ended::Done { built: None, log };
        }
        match registry::bundles::store_dir(&self.storage, &dir, &self.scratch).await {
            Ok(summary) => Ended::Done {
                built: Some(summary.sha256),
                log,
            },
            Err(RegistryError::Bundle(e)) if e.is_client_error() => {
                log.push_str(&format!("\n[the built folder cannot be stored: {e}]"));
                Ended::Done { built: None, log }
            }
            Err(e) => {
                tracing::error!(cause = %e, bot_version_id = version.bot_version_id, "cannot store a built folder");
                Ended::Dropped
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            };
            // Each claim's worker dies: its lease runs out and the build is claimed again.
            let mut row = None;
            for _ in 0..=MAX_BUILD_ATTEMPTS {
                row = db.claim_build("w", -1).await.unwrap();
            }
            let row = row.unwrap();
            assert_eq!(row.bot_version_id, v.bot_version_id);
            assert_eq!(row.build_attempts, MAX_BUILD_ATTEMPTS + 1);
            let Ended::Done { built, log } = builder.build(&row).await else {
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
