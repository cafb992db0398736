//! Storage: the only code with SQL. One set of typed functions over two backends, chosen
//! by the database URL at open: SQLite (`sqlite://...`, the embedded default) and
//! PostgreSQL (`postgres://...`, for servers and workers on several machines). Both go
//! through sqlx's runtime-chosen driver; each has its schema in `migrations/sqlite` and
//! `migrations/postgres` (embedded, applied at open), migration for migration in step.
//! The API, the CLI and the workers call the functions of the submodules; nothing else
//! writes SQL.
//!
//! The SQL is written once for both where it can be (numbered `$1` parameters, which
//! SQLite reads too; explicit casts where PostgreSQL's types would differ); the few
//! statements that must differ ask [`Storage::backend`].

pub mod bots;
pub mod budgets;
pub mod build_status;
pub mod builds;
pub mod bundles;
pub mod competitions;
pub mod entrants;
pub mod leaderboard;
pub mod matches;
pub mod mazes;
pub mod owners;
pub mod records;
pub mod rejudges;
pub mod retries;
pub mod sessions;
pub mod tournaments;
pub mod workers;

use std::str::FromStr;
use std::time::Duration;

use sqlx::any::{AnyConnectOptions, AnyPoolOptions};
use sqlx::{AnyPool, Executor};

/// How long a process that starts waits for PostgreSQL to answer before it gives up.
pub const CONNECT_PATIENCE: Duration = Duration::from_secs(30);

/// Tries `attempt` again, a second apart, until it succeeds or [`CONNECT_PATIENCE`]
/// has passed since the first try: start-up work on PostgreSQL, which may be starting
/// or restarting, waits for it a while rather than exit at once.
///
/// # Errors
/// The last attempt's.
pub async fn with_patience<T, E, F>(mut attempt: impl FnMut() -> F) -> Result<T, E>
where
    E: std::fmt::Display,
    F: std::future::Future<Output = Result<T, E>>,
{
    let since = std::time::Instant::now();
    loop {
        match attempt().await {
            Err(e) if since.elapsed() < CONNECT_PATIENCE => {
                tracing::warn!(
                    cause = format!("{e:#}"),
                    "PostgreSQL is not ready yet; trying again"
                );
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
            done => return done,
        }
    }
}

/// How long a statement waits for another connection's write lock before failing.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(10);

/// Why a storage call failed.
#[derive(Debug, thiserror::Error)]
pub enum StorageError {
    /// The database URL is malformed.
    #[error("invalid database URL {url:?}: {source}")]
    Url {
        /// The URL given, without its password.
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

/// Which database a [`Storage`] talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// SQLite: one file, one machine.
    Sqlite,
    /// PostgreSQL: many servers and workers on one database.
    Postgres,
}

impl Backend {
    /// The backend a database URL names, if any.
    pub fn of_url(url: &str) -> Option<Backend> {
        if url.starts_with("sqlite:") {
            Some(Backend::Sqlite)
        } else if url.starts_with("postgres://") || url.starts_with("postgresql://") {
            Some(Backend::Postgres)
        } else {
            None
        }
    }
}

/// A handle on the database; cheap to clone.
#[derive(Debug, Clone)]
pub struct Storage {
    pool: AnyPool,
    backend: Backend,
    /// SQLite lets one connection write at a time, and a writer that finds the database
    /// busy sleeps (1, 2, 5 ms and on) before it tries again. The match workers' writes
    /// (claims, leases, records) queue here instead, so no worker sleeps on the
    /// database while its core idles. (PostgreSQL writers do not wait on each other.)
    writes: std::sync::Arc<tokio::sync::Mutex<()>>,
    /// See [`Storage::with_max_retries`].
    max_retries: i64,
    /// How the pool's connections are opened (see [`Storage::for_this_thread`]).
    options: AnyConnectOptions,
}

/// A database `url` without its password, for messages: a log (a pod's, a Job's) is read
/// by more people than the Secret the URL comes from.
pub fn redacted_url(url: &str) -> String {
    let mut out = match (url.find("://"), url.rfind('@')) {
        (Some(scheme), Some(at)) if at > scheme => match url[scheme + 3..at].split_once(':') {
            Some((user, _)) => format!("{}{user}:***{}", &url[..scheme + 3], &url[at..]),
            None => url.to_string(),
        },
        _ => url.to_string(),
    };
    // A password given as a parameter: `?password=...` or `&password=...`.
    if let Some((base, query)) = out.split_once('?') {
        let query: Vec<String> = query
            .split('&')
            .map(|pair| match pair.split_once('=') {
                Some((key, _)) if key.eq_ignore_ascii_case("password") => format!("{key}=***"),
                _ => pair.to_string(),
            })
            .collect();
        out = format!("{base}?{}", query.join("&"));
    }
    out
}

impl Storage {
    /// Opens the database at `url` and applies the migrations: `sqlite://FILE` (made if
    /// missing; WAL mode, foreign keys on) or `postgres://USER@HOST/DB`.
    ///
    /// # Errors
    /// A malformed or unknown URL, a database that cannot be reached or opened, or a
    /// failed migration.
    pub async fn open(url: &str) -> Result<Storage> {
        sqlx::any::install_default_drivers();
        let bad_url = |source: sqlx::Error| StorageError::Url {
            url: redacted_url(url),
            source,
        };
        let backend = Backend::of_url(url).ok_or_else(|| {
            bad_url(sqlx::Error::Configuration(
                "the database URL must start with sqlite:// or postgres://".into(),
            ))
        })?;
        match backend {
            Backend::Sqlite => {
                // Made if missing, unless the URL says otherwise.
                let url = if url.contains("mode=") {
                    url.to_string()
                } else if url.contains('?') {
                    format!("{url}&mode=rwc")
                } else {
                    format!("{url}?mode=rwc")
                };
                let options = AnyConnectOptions::from_str(&url).map_err(bad_url)?;
                let pool = sqlite_pool(8).connect_with(options.clone()).await?;
                sqlx::migrate!("migrations/sqlite").run(&pool).await?;
                Storage::ready(pool, backend, options).await
            }
            Backend::Postgres => {
                let options = AnyConnectOptions::from_str(url).map_err(bad_url)?;
                // A server or worker may start while PostgreSQL does (or restarts, even
                // between the connection and the last start-up statement).
                with_patience(|| Storage::open_postgres(&options)).await
            }
        }
    }

    /// One attempt at [`Storage::open`] on PostgreSQL: connect, migrate, convert.
    async fn open_postgres(options: &AnyConnectOptions) -> Result<Storage> {
        let pool = AnyPoolOptions::new()
            .max_connections(16)
            .acquire_timeout(Duration::from_secs(30))
            .connect_with(options.clone())
            .await?;
        sqlx::migrate!("migrations/postgres").run(&pool).await?;
        Storage::ready(pool, Backend::Postgres, options.clone()).await
    }

    /// The storage on a migrated `pool`, once records of earlier releases are converted.
    async fn ready(pool: AnyPool, backend: Backend, options: AnyConnectOptions) -> Result<Storage> {
        let storage = Storage {
            pool,
            backend,
            writes: std::sync::Arc::default(),
            max_retries: retries::MAX_MATCH_RETRIES,
            options,
        };
        storage.convert_inline_records().await?;
        Ok(storage)
    }

    /// This storage with `retries` re-queues of a match whose lease expired (instead of
    /// [`retries::MAX_MATCH_RETRIES`]) before its next expiry records it as `aborted`:
    /// more for a deployment whose workers are often stopped without a graceful
    /// shutdown (the match was not the cause), fewer to give up on a poison pill sooner.
    pub fn with_max_retries(mut self, retries: i64) -> Storage {
        self.max_retries = retries.max(0);
        self
    }

    /// This storage (the same database, write turn and settings) with a connection of
    /// its own for the calling thread.
    ///
    /// A SQLite connection does its work on a thread of its own, and a new thread starts
    /// with the CPU affinity of the thread that made it. A match worker pinned to a core
    /// calls this after pinning itself, so its claims and record writes run on its own
    /// core, which idles while it waits for them, instead of taking turns on the other
    /// core with the match played there. The connection is opened on first use, from
    /// the task that uses it, and kept (no idle or lifetime limit). PostgreSQL does its
    /// work in its own server processes: the storage is returned as it is.
    pub fn for_this_thread(&self) -> Storage {
        match self.backend {
            Backend::Postgres => self.clone(),
            Backend::Sqlite => Storage {
                pool: sqlite_pool(1)
                    .min_connections(0)
                    .idle_timeout(None)
                    .max_lifetime(None)
                    .connect_lazy_with(self.options.clone()),
                ..self.clone()
            },
        }
    }

    /// How many times a match whose lease expired is re-queued.
    pub fn max_retries(&self) -> i64 {
        self.max_retries
    }

    /// The connection pool (for the submodules).
    pub(crate) fn pool(&self) -> &AnyPool {
        &self.pool
    }

    /// The database this storage talks to.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Waits for this process's turn to write (see [`Storage::writes`]); the turn lasts
    /// as long as the guard. PostgreSQL needs no turn.
    pub(crate) async fn write_turn(&self) -> Option<tokio::sync::MutexGuard<'_, ()>> {
        match self.backend {
            Backend::Sqlite => Some(self.writes.lock().await),
            Backend::Postgres => None,
        }
    }

    /// Begins a transaction that writes. With SQLite it takes the database's write lock
    /// at once (`BEGIN IMMEDIATE`, waiting up to [`BUSY_TIMEOUT`] for it): a deferred
    /// transaction that reads first and then writes fails at once ("database is
    /// locked", `SQLITE_BUSY_SNAPSHOT`) when another connection has written since its
    /// read, as another process on the same file, or a write of this one outside
    /// [`Storage::write_turn`], may have.
    ///
    /// # Errors
    /// Database failures.
    pub(crate) async fn begin_write(&self) -> Result<sqlx::Transaction<'static, sqlx::Any>> {
        Ok(match self.backend {
            Backend::Sqlite => self.pool.begin_with("begin immediate").await?,
            Backend::Postgres => self.pool.begin().await?,
        })
    }

    /// The tables of the schema and the columns of each, sorted (for comparing the two
    /// backends' schemas).
    ///
    /// # Errors
    /// Database failures.
    pub async fn schema_columns(&self) -> Result<Vec<(String, String)>> {
        let sql = match self.backend {
            Backend::Sqlite => {
                "select m.name, p.name from sqlite_master m, pragma_table_info(m.name) p
                 where m.type = 'table' and m.name not like 'sqlite_%' and m.name not like '_sqlx%'
                 order by 1, 2"
            }
            Backend::Postgres => {
                "select table_name::text, column_name::text from information_schema.columns
                 where table_schema = 'public' and table_name not like '_sqlx%'
                 order by 1, 2"
            }
        };
        Ok(sqlx::query_as(sql).fetch_all(&self.pool).await?)
    }

    /// Checks that the database answers.
    ///
    /// # Errors
    /// When it does not.
    pub async fn ping(&self) -> Result<()> {
        sqlx::query("select 1").execute(&self.pool).await?;
        Ok(())
    }

    /// The schema's version (the latest migration applied) and how many migrations
    /// are applied.
    ///
    /// # Errors
    /// Database failures.
    pub async fn schema_version(&self) -> Result<(i64, i64)> {
        Ok(sqlx::query_as(
            "select coalesce(max(version), 0), count(*) from _sqlx_migrations where success",
        )
        .fetch_one(&self.pool)
        .await?)
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

/// A flag column (0 or 1: both backends store flags as integers), read as a `bool` with
/// `#[sqlx(try_from = "Flag")]`.
pub(crate) struct Flag(bool);

impl sqlx::Type<sqlx::Any> for Flag {
    fn type_info() -> sqlx::any::AnyTypeInfo {
        <i64 as sqlx::Type<sqlx::Any>>::type_info()
    }

    fn compatible(ty: &sqlx::any::AnyTypeInfo) -> bool {
        <i64 as sqlx::Type<sqlx::Any>>::compatible(ty)
    }
}

impl<'r> sqlx::Decode<'r, sqlx::Any> for Flag {
    fn decode(value: sqlx::any::AnyValueRef<'r>) -> Result<Flag, sqlx::error::BoxDynError> {
        Ok(Flag(<i64 as sqlx::Decode<sqlx::Any>>::decode(value)? != 0))
    }
}

impl From<Flag> for bool {
    fn from(flag: Flag) -> bool {
        flag.0
    }
}

/// The options of a SQLite pool of at most `connections`; each connection starts with
/// [`sqlite_pragmas`].
fn sqlite_pool(connections: u32) -> AnyPoolOptions {
    AnyPoolOptions::new()
        .max_connections(connections)
        .acquire_timeout(Duration::from_secs(30))
        .after_connect(|conn, _| {
            Box::pin(async move {
                conn.execute(sqlite_pragmas().as_str()).await?;
                Ok(())
            })
        })
}

/// The settings each SQLite connection starts with.
fn sqlite_pragmas() -> String {
    format!(
        "pragma journal_mode = wal; pragma synchronous = normal; pragma foreign_keys = on;
         pragma busy_timeout = {};",
        BUSY_TIMEOUT.as_millis()
    )
}

/// The most rows one multi-row insert carries (7 parameters a row at most: well under
/// either database's limit on parameters).
pub(crate) const ROWS_PER_INSERT: usize = 200;

/// `rows` groups of `columns` numbered placeholders: `($1, $2), ($3, $4)`.
pub(crate) fn placeholders(rows: usize, columns: usize) -> String {
    (0..rows)
        .map(|r| {
            let row: Vec<String> = (1..=columns)
                .map(|c| format!("${}", r * columns + c))
                .collect();
            format!("({})", row.join(", "))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether an error is a unique-constraint violation.
pub(crate) fn is_unique_violation(e: &sqlx::Error) -> bool {
    matches!(e, sqlx::Error::Database(db) if db.is_unique_violation())
}

#[cfg(test)]
mod tests {
    use super::test_support::backends;

    /// The threads of this process and the cores each may run on.
    fn threads() -> Vec<(String, String, String)> {
        let mut found = Vec::new();
        for task in std::fs::read_dir("/proc/self/task").unwrap().flatten() {
            let status = std::fs::read_to_string(task.path().join("status")).unwrap_or_default();
            let field = |name: &str| {
                status
                    .lines()
                    .find_map(|l| l.strip_prefix(name))
                    .map(|v| v.trim().to_string())
                    .unwrap_or_default()
            };
            found.push((
                task.file_name().to_string_lossy().into_owned(),
                field("Name:"),
                field("Cpus_allowed_list:"),
            ));
        }
        found
    }

    #[test]
    fn a_thread_s_own_sqlite_connection_works_on_the_thread_s_core() {
        let dir = tempfile::tempdir().unwrap();
        let url = format!("sqlite://{}", dir.path().join("t.db").display());
        let runtime = tokio::runtime::Runtime::new().unwrap();
        let storage = runtime.block_on(super::Storage::open(&url)).unwrap();
        let core = *crate::runner::affinity::allowed_cores().last().unwrap();
        let shared = storage.clone();
        let opened_before = storage.pool().size();
        let row = std::thread::spawn(move || {
            crate::runner::affinity::pin_current_thread(core).unwrap();
            let before: Vec<String> = threads().into_iter().map(|t| t.0).collect();
            let local = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
                .unwrap();
            let own = shared.for_this_thread();
            let row = local.block_on(async {
                own.ping().await.unwrap();
                assert_eq!(own.count_mazes().await.unwrap(), 0);
                let m = crate::storage::test_support::maze();
                own.insert_maze(&crate::storage::mazes::NewMaze {
                    name: "m",
                    hash: &m.hash(),
                    dim: 2,
                    layout: "2\n3,6\n9,12\n",
                    hidden: false,
                    optimum: None,
                })
                .await
                .unwrap()
            });
            // One connection of its own, started from this thread: its thread keeps to
            // this thread's core.
            assert_eq!(own.pool().size(), 1);
            let started: Vec<_> = threads()
                .into_iter()
                .filter(|t| !before.contains(&t.0) && t.1.starts_with("sqlx-sqlite"))
                .collect();
            assert!(
                started.iter().any(|t| t.2 == core.to_string()),
                "no SQLite thread on core {core} among those started: {started:?}"
            );
            row
        })
        .join()
        .unwrap();
        // The shared pool opened nothing for that work, and sees its write.
        assert_eq!(storage.pool().size(), opened_before);
        let seen = runtime.block_on(storage.get_maze(row.maze_id)).unwrap();
        assert_eq!(seen, Some(row));
    }

    #[tokio::test]
    async fn both_backends_have_the_same_tables_and_columns() {
        let all = backends().await;
        let mut schemas = Vec::new();
        for (db, _guard) in &all {
            schemas.push(db.schema_columns().await.unwrap());
        }
        assert!(schemas[0].len() > 40, "{:?}", schemas[0]);
        for other in &schemas[1..] {
            assert_eq!(&schemas[0], other);
        }
    }
}

#[cfg(test)]
mod url_tests {
    use super::redacted_url;

    #[test]
    fn a_password_never_reaches_the_log() {
        assert_eq!(
            redacted_url("postgres://maze:s3cret@db.example:5432/arena"),
            "postgres://maze:***@db.example:5432/arena"
        );
        assert_eq!(
            redacted_url("sqlite:///var/db.sqlite"),
            "sqlite:///var/db.sqlite"
        );
        assert_eq!(
            redacted_url("postgres://maze@db/arena"),
            "postgres://maze@db/arena",
            "no password: nothing to hide"
        );
        assert_eq!(
            redacted_url("postgres://db/arena?user=maze&password=s3cret&sslmode=require"),
            "postgres://db/arena?user=maze&password=***&sslmode=require"
        );
    }
}

#[cfg(test)]
pub(crate) mod test_support {
    use super::Storage;
    use super::bots::NewVersion;

    /// A version from a local folder, ready to play.
    pub fn plain_version() -> NewVersion<'static> {
        NewVersion {
            command: "python3 b.py",
            dir: "/x",
            files_sha256: "s",
            file_count: 1,
            build_command: None,
            env: &[],
            bundle_sha256: None,
            runtime: None,
            protocol: None,
        }
    }

    /// A version with a build command (`make`), its files not stored.
    pub fn with_build() -> NewVersion<'static> {
        NewVersion {
            command: "./bot",
            dir: "",
            files_sha256: "s",
            file_count: 1,
            build_command: Some("make"),
            env: &[],
            bundle_sha256: None,
            runtime: None,
            protocol: None,
        }
    }

    impl Storage {
        /// Runs `sql` (a test's way of playing or changing matches by hand).
        pub async fn run_sql_for_tests(&self, sql: &str) {
            sqlx::query(sql).execute(self.pool()).await.unwrap();
        }
    }

    /// A fresh SQLite database in a temporary directory (kept alive by the guard).
    pub async fn fresh() -> (Storage, tempfile::TempDir) {
        let dir = tempfile::tempdir().unwrap();
        let url = format!("sqlite://{}", dir.path().join("test.db").display());
        (Storage::open(&url).await.unwrap(), dir)
    }

    /// A fresh database on each backend, for a test to run on both: SQLite, then
    /// PostgreSQL (a new database in the cluster `MAZEARENA_TEST_POSTGRES` names; see
    /// `.ci/postgres.sh`). Without that cluster the PostgreSQL half is skipped with a
    /// printed reason, except in CI (`CI=true`), where it fails.
    pub async fn backends() -> Vec<(Storage, Option<tempfile::TempDir>)> {
        let (sqlite, dir) = fresh().await;
        let mut all = vec![(sqlite, Some(dir))];
        match std::env::var("MAZEARENA_TEST_POSTGRES") {
            Ok(url) => all.push((fresh_postgres(&url).await, None)),
            Err(_) if std::env::var("CI").is_ok_and(|v| v == "true") => {
                panic!("CI=true but MAZEARENA_TEST_POSTGRES is not set: .ci/run starts PostgreSQL")
            }
            Err(_) => eprintln!(
                "skipping the PostgreSQL half: MAZEARENA_TEST_POSTGRES is not set \
                 (eval \"$(.ci/postgres.sh start /tmp/mazearena-pg)\" starts a cluster)"
            ),
        }
        all
    }

    /// A new, empty database in the PostgreSQL cluster at `url`, opened.
    pub async fn fresh_postgres(url: &str) -> Storage {
        use sqlx::Connection;
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        sqlx::any::install_default_drivers();
        let name = format!(
            "unit_{}_{}_{}",
            std::process::id(),
            super::now_ms(),
            NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        );
        let mut admin = sqlx::AnyConnection::connect(url).await.unwrap();
        sqlx::query(&format!("create database {name}"))
            .execute(&mut admin)
            .await
            .unwrap();
        admin.close().await.unwrap();
        let (base, _) = url.rsplit_once('/').unwrap();
        Storage::open(&format!("{base}/{name}")).await.unwrap()
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
        let v = db.create_bot("b", "h", &plain_version()).await.unwrap();
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
