//! Storage: the only code with SQL. A SQLite database through sqlx, its schema in
//! `migrations/` (embedded, applied at open). The API, the CLI and the workers call the
//! typed functions of the submodules; nothing else writes SQL.
//!
//! The functions take plain values and return plain rows, so that another backend
//! (PostgreSQL, for workers on several machines) can be added behind the same calls.

pub mod bots;
pub mod builds;
pub mod leaderboard;
pub mod matches;
pub mod mazes;
pub mod records;
pub mod retries;
pub mod tournaments;

use std::str::FromStr;
use std::time::Duration;

use sqlx::SqlitePool;
use sqlx::sqlite::{SqliteConnectOptions, SqliteJournalMode, SqlitePoolOptions, SqliteSynchronous};

/// How long a statement waits for another connection's write lock before failing.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(10);

/// Why a storage call failed.
#[derive(Debug, thiserror::Error)]
pub enum StorageError {
    /// The database URL is malformed.
    #[error("invalid database URL {url:?}: {source}")]
    Url {
        /// The URL given.
        url: String,
        /// What sqlx said.
        source: sqlx::Error,
    },
    /// A unique key clash: the thing exists already.
    #[error("{0}")]
    Conflict(String),
    /// The database itself failed.
    #[error("database error: {0}")]
    Database(#[from] sqlx::Error),
    /// The schema could not be applied.
    #[error("database migration failed: {0}")]
    Migrate(#[from] sqlx::migrate::MigrateError),
    /// A value could not be encoded for storing.
    #[error("cannot encode {what}: {message}")]
    Encode {
        /// What was being encoded.
        what: &'static str,
        /// What serde said.
        message: String,
    },
    /// A match record could not be encoded, or a stored one read.
    #[error("match {match_id}: {message}")]
    Record {
        /// The match.
        match_id: i64,
        /// What went wrong.
        message: String,
    },
}

/// Result alias for storage calls.
pub type Result<T, E = StorageError> = std::result::Result<T, E>;

/// A handle on the database; cheap to clone.
#[derive(Debug, Clone)]
pub struct Storage {
    pool: SqlitePool,
    /// SQLite lets one connection write at a time, and a writer that finds the database
    /// busy sleeps (1, 2, 5 ms and on) before it tries again. The match workers' writes
    /// (claims, leases, records) queue here instead, so no worker sleeps on the
    /// database while its core idles.
    writes: std::sync::Arc<tokio::sync::Mutex<()>>,
}

impl Storage {
    /// Opens (creating it if missing) the SQLite database at `url`, e.g.
    /// `sqlite://mazearena.db`, in WAL mode with foreign keys on, and applies the
    /// migrations.
    ///
    /// # Errors
    /// A malformed URL, a file that cannot be opened, or a failed migration.
    pub async fn open(url: &str) -> Result<Storage> {
        let options = SqliteConnectOptions::from_str(url)
            .map_err(|source| StorageError::Url {
                url: url.to_string(),
                source,
            })?
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .foreign_keys(true)
            .busy_timeout(BUSY_TIMEOUT);
        let pool = SqlitePoolOptions::new()
            .max_connections(8)
            .acquire_timeout(Duration::from_secs(30))
            .connect_with(options)
            .await?;
        sqlx::migrate!().run(&pool).await?;
        let storage = Storage {
            pool,
            writes: std::sync::Arc::default(),
        };
        storage.convert_inline_records().await?;
        Ok(storage)
    }

    /// The connection pool (for the submodules).
    pub(crate) fn pool(&self) -> &SqlitePool {
        &self.pool
    }

    /// Waits for this process's turn to write (see [`Storage::writes`]); the turn lasts
    /// as long as the guard.
    pub(crate) async fn write_turn(&self) -> tokio::sync::MutexGuard<'_, ()> {
        self.writes.lock().await
    }

    /// Checks that the database answers.
    ///
    /// # Errors
    /// When it does not.
    pub async fn ping(&self) -> Result<()> {
        sqlx::query("select 1").execute(&self.pool).await?;
        Ok(())
    }

    /// Closes the pool, waiting for connections to be returned.
    pub async fn close(&self) {
        self.pool.close().await;
    }
}

/// Now, in unix milliseconds.
pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as i64)
}

/// Whether an error is a unique-constraint violation.
pub(crate) fn is_unique_violation(e: &sqlx::Error) -> bool {
    matches!(e, sqlx::Error::Database(db) if db.is_unique_violation())
}

#[cfg(test)]
pub(crate) mod test_support {
    use super::Storage;

    /// A fresh database in a temporary directory (kept alive by the returned guard).
    pub async fn fresh() -> (Storage, tempfile::TempDir) {
        let dir = tempfile::tempdir().unwrap();
        let url = format!("sqlite://{}", dir.path().join("test.db").display());
        (Storage::open(&url).await.unwrap(), dir)
    }

    /// The layout of the maze of [`bot_and_maze`].
    const MAZE: &str = "2\n3,6\n9,12\n";

    /// The maze of [`bot_and_maze`], parsed.
    pub fn maze() -> crate::engine::Maze {
        crate::engine::mazefile::numeric::parse(MAZE.as_bytes()).unwrap()
    }

    /// A bot "b" (owner token hash "h") with one version, and a public 2x2 maze "m":
    /// the version's and the maze's ids.
    pub async fn bot_and_maze(db: &Storage) -> (i64, i64) {
        let v = db
            .create_bot(
                "b",
                "h",
                &crate::storage::bots::NewVersion {
                    command: "python3 b.py",
                    dir: "/x",
                    files_sha256: "s",
                    file_count: 1,
                    build_command: None,
                    env: &[],
                },
            )
            .await
            .unwrap();
        let z = db
            .insert_maze(&crate::storage::mazes::NewMaze {
                name: "m",
                hash: "hash",
                dim: 2,
                layout: MAZE,
                hidden: false,
                optimum: Some(1),
            })
            .await
            .unwrap();
        (v.bot_version_id, z.maze_id)
    }
}
