//! Prometheus metrics: matches by status, queue depth and the live workers on every
//! machine (read from the database at scrape time, so they survive restarts and agree
//! across servers) and a histogram of this process's match durations.

use std::sync::Arc;
use std::time::Duration;

use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;

use crate::runner::MatchState;
use crate::storage::Storage;

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct StatusLabel {
    status: String,
}

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct WorkerLabel {
    worker: String,
    role: String,
    host: String,
    sandbox: String,
}

/// The server's metrics; cheap to clone.
#[derive(Debug, Clone)]
pub struct Metrics {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    registry: Registry,
    matches: Family<StatusLabel, Gauge>,
    queue_depth: Gauge,
    worker_jobs: Family<WorkerLabel, Gauge>,
    worker_matches: Family<WorkerLabel, Gauge>,
    duration: Histogram,
}

impl Default for Metrics {
    fn default() -> Self {
        Metrics::new()
    }
}

impl Metrics {
    /// A fresh registry with the mazearena metrics.
    pub fn new() -> Metrics {
        let mut registry = Registry::with_prefix("mazearena");
        let matches = Family::<StatusLabel, Gauge>::default();
        registry.register(
            "matches",
            "Matches in the database, by status",
            matches.clone(),
        );
        let queue_depth = Gauge::default();
        registry.register(
            "queue_depth",
            "Matches waiting to be played",
            queue_depth.clone(),
        );
        let worker_jobs = Family::<WorkerLabel, Gauge>::default();
        registry.register(
            "worker_jobs",
            "Matches each live worker plays at once (workers seen in the last 30 s)",
            worker_jobs.clone(),
        );
        let worker_matches = Family::<WorkerLabel, Gauge>::default();
        registry.register(
            "worker_matches_done",
            "Matches each live worker has recorded since it started",
            worker_matches.clone(),
        );
        // 0.05 s .. ~100 s
        let duration = Histogram::new(exponential_buckets(0.05, 2.0, 12));
        registry.register(
            "match_duration_seconds",
            "Wall time of played matches, from claim to record",
            duration.clone(),
        );
        Metrics {
            inner: Arc::new(Inner {
                registry,
                matches,
                queue_depth,
                worker_jobs,
                worker_matches,
                duration,
            }),
        }
    }

    /// Records a played match's duration.
    pub fn observe_match(&self, elapsed: Duration) {
        self.inner.duration.observe(elapsed.as_secs_f64());
    }

    /// The metrics in the Prometheus text format, with counts read from `storage`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn render(&self, storage: &Storage) -> Result<String, crate::storage::StorageError> {
        let counts = storage.count_by_status().await?;
        for state in MatchState::ALL {
            let status = state.as_str();
            let n = counts
                .iter()
                .find(|(s, _)| s == status)
                .map_or(0, |(_, n)| *n);
            self.inner
                .matches
                .get_or_create(&StatusLabel {
                    status: status.to_string(),
                })
                .set(n);
            if state == MatchState::Queued {
                self.inner.queue_depth.set(n);
            }
        }
        let workers = storage.live_workers(LIVE_WINDOW.as_millis() as i64).await?;
        self.inner.worker_jobs.clear();
        self.inner.worker_matches.clear();
        for w in workers {
            let label = WorkerLabel {
                worker: w.worker_id,
                role: w.role,
                host: w.host,
                sandbox: w.sandbox,
            };
            self.inner.worker_jobs.get_or_create(&label).set(w.jobs);
            self.inner
                .worker_matches
                .get_or_create(&label)
                .set(w.matches_done);
        }
        let mut out = String::new();
        // Writing into a String cannot fail.
        let _ = prometheus_client::encoding::text::encode(&mut out, &self.inner.registry);
        Ok(out)
    }
}

/// A worker not seen for this long is no longer shown as live.
pub const LIVE_WINDOW: std::time::Duration = std::time::Duration::from_secs(30);
