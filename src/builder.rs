//! The build worker: runs the build command of each uploaded bot version that has one,
//! once, in the sandbox (`runner::build`), and records the result: `ready` versions
//! play, `build_failed` ones never do, and their owner reads the build log.

use std::sync::Arc;
use std::time::Duration;

use tokio::sync::Notify;
use tokio_util::sync::CancellationToken;

use crate::runner::{Sandbox, build};
use crate::storage::Storage;

/// How often the queue of builds is looked at when nothing wakes the builder.
const POLL: Duration = Duration::from_secs(2);

/// Builds waiting versions one at a time until `stop`; `wake` is notified on uploads,
/// and notified again after each build so match workers look for newly ready versions.
pub async fn run_builds(
    storage: Storage,
    sandbox: Sandbox,
    wake: Arc<Notify>,
    stop: CancellationToken,
) {
    loop {
        if stop.is_cancelled() {
            return;
        }
        let next = match storage.next_build().await {
            Ok(next) => next,
            Err(e) => {
                tracing::warn!(error = %e, "cannot read the build queue");
                None
            }
        };
        let Some(version) = next else {
            tokio::select! {
                _ = stop.cancelled() => return,
                _ = wake.notified() => {}
                _ = tokio::time::sleep(POLL) => {}
            }
            continue;
        };
        let command = version.build_command.clone().unwrap_or_default();
        let dir = std::path::PathBuf::from(&version.dir);
        tracing::info!(bot_version_id = version.bot_version_id, %command, "building");
        let (ok, log) = tokio::select! {
            _ = stop.cancelled() => return, // dropped: killed; built again next start
            outcome = build::build_logged(&command, &dir, &sandbox) => match outcome {
                Ok(o) => {
                    let mut log = o.log;
                    if !o.ok {
                        log.push_str(&format!("\n[build {}]", o.status));
                    }
                    (o.ok, log)
                }
                Err(e) => (false, e.to_string()),
            },
        };
        tracing::info!(bot_version_id = version.bot_version_id, ok, "build ended");
        if let Err(e) = storage.finish_build(version.bot_version_id, ok, &log).await {
            tracing::warn!(error = %e, "cannot record a build");
        }
        wake.notify_waiters();
    }
}
