//! The processes that play matches, as they report themselves: each `mazearena serve`
//! with match workers and each `mazearena worker`, on any machine, writes a row when it
//! starts and refreshes it while it runs, so that health, metrics and pages show them all.

use serde::Serialize;
use sqlx::FromRow;

use super::{Result, Storage, now_ms};

/// A worker process as it reported itself.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, FromRow, utoipa::ToSchema)]
pub struct WorkerRow {
    /// Its lease owner name: unique per process start.
    pub worker_id: String,
    /// `serve` or `worker`.
    pub role: String,
    /// The machine's host name.
    pub host: String,
    /// Its process id on that machine.
    pub pid: i64,
    /// How many matches it plays at once.
    pub jobs: i64,
    /// The sandbox level its bots run at.
    pub sandbox: String,
    /// Matches it has recorded since it started.
    pub matches_done: i64,
    /// When it started (unix ms).
    pub started_at: i64,
    /// Its last report (unix ms).
    pub last_seen: i64,
    /// When it stopped gracefully (unix ms), if it did.
    pub stopped_at: Option<i64>,
}

/// What a worker says of itself when it starts.
#[derive(Debug, Clone)]
pub struct NewWorker<'a> {
    /// Its lease owner name.
    pub worker_id: &'a str,
    /// `serve` or `worker`.
    pub role: &'a str,
    /// The machine's host name.
    pub host: &'a str,
    /// Its process id.
    pub pid: i64,
    /// Matches at once.
    pub jobs: i64,
    /// Its sandbox level.
    pub sandbox: &'a str,
}

impl Storage {
    /// Records a worker that starts.
    ///
    /// # Errors
    /// Database failures.
    pub async fn register_worker(&self, w: &NewWorker<'_>) -> Result<()> {
        let now = now_ms();
        sqlx::query(
            "insert into worker (worker_id, role, host, pid, jobs, sandbox, started_at, last_seen)
             values ($1, $2, $3, $4, $5, $6, $7, $7)
             on conflict (worker_id) do update set last_seen = excluded.last_seen, stopped_at = null",
        )
        .bind(w.worker_id)
        .bind(w.role)
        .bind(w.host)
        .bind(w.pid)
        .bind(w.jobs)
        .bind(w.sandbox)
        .bind(now)
        .execute(self.pool())
        .await?;
        Ok(())
    }

    /// A running worker's report: it is alive and has recorded `matches_done` matches.
    /// False when the worker has no row (its registration never got through).
    ///
    /// # Errors
    /// Database failures.
    pub async fn worker_seen(&self, worker_id: &str, matches_done: i64) -> Result<bool> {
        let done =
            sqlx::query("update worker set last_seen = $1, matches_done = $2 where worker_id = $3")
                .bind(now_ms())
                .bind(matches_done)
                .bind(worker_id)
                .execute(self.pool())
                .await?;
        Ok(done.rows_affected() > 0)
    }

    /// Records that a worker stopped gracefully.
    ///
    /// # Errors
    /// Database failures.
    pub async fn worker_stopped(&self, worker_id: &str, matches_done: i64) -> Result<()> {
        let now = now_ms();
        sqlx::query(
            "update worker set last_seen = $1, stopped_at = $1, matches_done = $2
             where worker_id = $3",
        )
        .bind(now)
        .bind(matches_done)
        .bind(worker_id)
        .execute(self.pool())
        .await?;
        Ok(())
    }

    /// The workers seen within `within_ms` and not stopped, by start time.
    ///
    /// # Errors
    /// Database failures.
    pub async fn live_workers(&self, within_ms: i64) -> Result<Vec<WorkerRow>> {
        Ok(sqlx::query_as(
            "select * from worker where last_seen >= $1 and stopped_at is null
             order by started_at, worker_id",
        )
        .bind(now_ms() - within_ms)
        .fetch_all(self.pool())
        .await?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn workers_report_themselves_and_leave() {
        for (db, _guard) in backends().await {
            let w = NewWorker {
                worker_id: "w1",
                role: "worker",
                host: "h",
                pid: 7,
                jobs: 2,
                sandbox: "full",
            };
            assert!(!db.worker_seen("w1", 4).await.unwrap(), "no row yet");
            db.register_worker(&w).await.unwrap();
            assert!(db.worker_seen("w1", 5).await.unwrap());
            let live = db.live_workers(60_000).await.unwrap();
            assert_eq!(live.len(), 1);
            assert_eq!((live[0].jobs, live[0].matches_done), (2, 5));
            assert!(live[0].last_seen >= live[0].started_at);
            db.worker_stopped("w1", 6).await.unwrap();
            assert!(db.live_workers(60_000).await.unwrap().is_empty());
            // A worker not seen within the window is not live either.
            db.register_worker(&NewWorker {
                worker_id: "w2",
                ..w
            })
            .await
            .unwrap();
            assert_eq!(db.live_workers(60_000).await.unwrap().len(), 1);
            assert!(db.live_workers(-1000).await.unwrap().is_empty());
        }
    }
}
