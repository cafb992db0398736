//! Bots and their versions, and pausing: a bot whose matches keep aborting (see
//! [`super::retries::PAUSE_AFTER_ABORTS`]) is paused until an admin resumes it or a new
//! version is uploaded.

use sqlx::FromRow;

pub use super::build_status;
use super::matches::failure_record;
use super::owners::{self, OwnerLimits, OwnerQuotaKind, OwnerUsage};
use super::{Result, Storage, StorageError, is_unique_violation, now_ms};
use crate::runner::outcome::MatchStatus;

/// A bot with its latest version.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct BotRow {
    /// Id.
    pub bot_id: i64,
    /// Unique name.
    pub name: String,
    /// When it was registered (unix ms).
    pub created_at: i64,
    /// The latest version number.
    pub version: i64,
    /// The latest version's id.
    pub bot_version_id: i64,
    /// The latest version's command.
    pub command: String,
    /// Why the bot is paused; `None` while it is not.
    pub paused_reason: Option<String>,
    /// When it was paused (unix ms).
    pub paused_at: Option<i64>,
    /// The latest version's build status: `ready`, `building` or `build_failed`.
    pub build_status: String,
}

impl BotRow {
    /// Whether the bot is paused: its matches are not played.
    pub fn is_paused(&self) -> bool {
        self.paused_at.is_some()
    }
}

/// One stored version of a bot.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct BotVersionRow {
    /// Id.
    pub bot_version_id: i64,
    /// The bot.
    pub bot_id: i64,
    /// 1, 2, ...
    pub version: i64,
    /// The command line.
    pub command: String,
    /// Where its files are.
    pub dir: String,
    /// Content hash of the files.
    pub files_sha256: String,
    /// Number of files.
    pub file_count: i64,
    /// When it was stored (unix ms).
    pub created_at: i64,
    /// The build command run once before it plays, if any.
    pub build_command: Option<String>,
    /// `ready` (plays), `building`, or `build_failed` (never plays).
    pub build_status: String,
    /// The end of the build's output.
    pub build_log: Option<String>,
    /// When its build ended (unix ms).
    pub built_at: Option<i64>,
    /// Environment variables declared for the bot: a JSON object of strings.
    pub env: String,
    /// The stored bundle of its files as uploaded (`files_sha256`); `None` for a bot
    /// registered from a local folder, which plays from [`BotVersionRow::dir`].
    pub bundle_sha256: Option<String>,
    /// The stored bundle of its folder after its build, once built.
    pub built_sha256: Option<String>,
    /// How many times its build has been claimed (a claim whose worker died counts).
    #[sqlx(default)]
    pub build_attempts: i64,
    /// The runtime it wants first on its `PATH`, by name (`GET /api/runtimes`).
    pub runtime: Option<String>,
    /// `mms` for a mouse of the mms simulator; `None` for protocol v1.
    #[sqlx(default)]
    pub protocol: Option<String>,
    /// How long its build and validation match took (ms), once they ended.
    #[sqlx(default)]
    pub build_ms: Option<i64>,
}

impl BotVersionRow {
    /// The declared environment variables as pairs (an unreadable value: none).
    pub fn env_pairs(&self) -> Vec<(String, String)> {
        env_pairs(&self.env)
    }
}

/// Environment pairs from their stored JSON object (anything else: none).
pub fn env_pairs(json: &str) -> Vec<(String, String)> {
    serde_json::from_str::<std::collections::BTreeMap<String, String>>(json)
        .map(|m| m.into_iter().collect())
        .unwrap_or_default()
}

/// Stored JSON of environment pairs.
pub fn env_json(pairs: &[(String, String)]) -> String {
    let map: std::collections::BTreeMap<&str, &str> = pairs
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    serde_json::to_string(&map).unwrap_or_else(|_| "{}".into())
}

/// A new version's details.
#[derive(Debug, Clone)]
pub struct NewVersion<'a> {
    /// The command line.
    pub command: &'a str,
    /// Where its files are (absolute) for a bot registered from a local folder; empty
    /// for a stored bundle.
    pub dir: &'a str,
    /// Content hash of the files (the bundle hash of `botfiles`).
    pub files_sha256: &'a str,
    /// The stored bundle the version plays from (its hash is `files_sha256`); `None`
    /// for a local folder.
    pub bundle_sha256: Option<&'a str>,
    /// Number of files.
    pub file_count: i64,
    /// A build command: the version is `building` until it has run. A version whose
    /// files are stored (`bundle_sha256`) is `building` too, until the builder has
    /// played its validation match.
    pub build_command: Option<&'a str>,
    /// Declared environment variables (checked by `runner::botenv::check`).
    pub env: &'a [(String, String)],
    /// The runtime it wants first on its `PATH`, by name.
    pub runtime: Option<&'a str>,
    /// `mms` for a mouse of the mms simulator; `None` for protocol v1.
    pub protocol: Option<&'a str>,
}

const BOT_WITH_LATEST: &str =
    "select b.bot_id, b.name, b.created_at, v.version, v.bot_version_id, v.command,
         b.paused_reason, b.paused_at, v.build_status
     from bot b join bot_version v on v.bot_id = b.bot_id
     where v.version = (select max(version) from bot_version where bot_id = b.bot_id)";

impl Storage {
    /// Registers a bot with its first version, in one transaction.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the name is taken.
    pub async fn create_bot(
        &self,
        name: &str,
        owner_token_hash: &str,
        first: &NewVersion<'_>,
    ) -> Result<BotVersionRow> {
        let mut tx = self.begin_write().await?;
        let bot_id = insert_bot(&mut tx, name, owner_token_hash, None).await?;
        let row = insert_version(&mut tx, bot_id, first).await?;
        tx.commit().await?;
        Ok(row)
    }

    /// Registers a bot as [`Storage::create_bot`] does, the bot of `entrant` if given
    /// (entered in competition `enter` too, if given), unless `owner`'s quotas are used
    /// up (counted in the same transaction under the owner's lock): then nothing is
    /// written and the refusal is returned.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the name is taken; database failures.
    pub async fn create_bot_within(
        &self,
        name: &str,
        owner_token_hash: &str,
        entrant: Option<i64>,
        first: &NewVersion<'_>,
        owner: Option<&OwnerLimits>,
        enter: Option<i64>,
    ) -> Result<std::result::Result<BotVersionRow, VersionRefusal>> {
        let mut tx = self.begin_write().await?;
        if let Some(limits) = owner
            && let Some((kind, usage)) = owners::hold_in(&mut tx, self.backend(), limits).await?
        {
            tx.rollback().await?;
            return Ok(Err(VersionRefusal::Owner(kind, usage)));
        }
        let bot_id = insert_bot(&mut tx, name, owner_token_hash, entrant).await?;
        let row = insert_version(&mut tx, bot_id, first).await?;
        // Entered in the same transaction: the builder never sees the version without
        // its competition (whose rule and practice mazes validate it).
        if let (Some(competition_id), Some(entrant_id)) = (enter, entrant) {
            sqlx::query(
                "insert into competition_entry (competition_id, bot_id, entrant_id, first_version_id, entered_at)
                 values ($1, $2, $3, $4, $5)",
            )
            .bind(competition_id)
            .bind(bot_id)
            .bind(entrant_id)
            .bind(row.bot_version_id)
            .bind(now_ms())
            .execute(&mut *tx)
            .await
            .map_err(|e| {
                if is_unique_violation(&e) {
                    StorageError::Conflict(
                        "this entrant has a bot in this competition already (one bot per entrant)"
                            .into(),
                    )
                } else {
                    e.into()
                }
            })?;
        }
        tx.commit().await?;
        Ok(Ok(row))
    }

    /// Adds a new version to a bot, and resumes the bot if it was paused (the new
    /// version has no aborted matches).
    ///
    /// # Errors
    /// Database failures.
    pub async fn add_bot_version(
        &self,
        bot_id: i64,
        new: &NewVersion<'_>,
    ) -> Result<BotVersionRow> {
        let mut tx = self.begin_write().await?;
        let row = insert_version(&mut tx, bot_id, new).await?;
        resume_in(&mut tx, bot_id).await?;
        tx.commit().await?;
        Ok(row)
    }

    /// Adds a version to bot `bot_id` as [`Storage::add_bot_version`] does, unless it
    /// would go over one of `quotas`, or a competition the bot is entered in has closed
    /// by the time it is stored: then nothing is written and the refusal is returned.
    /// Each quota's entrant row is taken for the transaction first, so two uploads of
    /// one entrant at once are counted one after the other: the second waits for the
    /// first to commit, then counts its version. The bot's competitions' rows are taken
    /// too, and their close compared with the clock after that, in the transaction that
    /// stores the version: the close's selection (which updates those rows) comes after
    /// a version stored before the close, and a version that loses the race is not
    /// stored at all.
    ///
    /// # Errors
    /// Database failures.
    pub async fn add_bot_version_within(
        &self,
        bot_id: i64,
        new: &NewVersion<'_>,
        quotas: &[VersionQuota],
        owner: Option<&OwnerLimits>,
    ) -> Result<std::result::Result<BotVersionRow, VersionRefusal>> {
        let mut quotas = quotas.to_vec();
        // One order for the locks, so two uploads never wait for each other.
        quotas.sort_by_key(|q| (q.entrant_id, q.competition_id));
        let mut tx = self.begin_write().await?;
        if let Some(limits) = owner
            && let Some((kind, usage)) = owners::hold_in(&mut tx, self.backend(), limits).await?
        {
            tx.rollback().await?;
            return Ok(Err(VersionRefusal::Owner(kind, usage)));
        }
        for q in &quotas {
            sqlx::query("update entrant set created_at = created_at where entrant_id = $1")
                .bind(q.entrant_id)
                .execute(&mut *tx)
                .await?;
            let counted = Storage::count_counted_versions_in(
                &mut tx,
                q.competition_id,
                q.entrant_id,
                q.since,
            )
            .await?;
            if counted >= q.limit {
                tx.rollback().await?;
                return Ok(Err(VersionRefusal::Quota(*q)));
            }
        }
        let row = insert_version(&mut tx, bot_id, new).await?;
        sqlx::query(
            "update competition set closes_at = closes_at where kind = 'competition' and competition_id in
                 (select competition_id from competition_entry where bot_id = $1)",
        )
        .bind(bot_id)
        .execute(&mut *tx)
        .await?;
        let closed: Option<(String, i64)> = sqlx::query_as(
            "select name, closes_at from competition where kind = 'competition' and closes_at <= $2
                 and competition_id in (select competition_id from competition_entry where bot_id = $1)
             order by closes_at limit 1",
        )
        .bind(bot_id)
        .bind(now_ms().max(row.created_at))
        .fetch_optional(&mut *tx)
        .await?;
        if let Some((name, closes_at)) = closed {
            tx.rollback().await?;
            return Ok(Err(VersionRefusal::Closed { name, closes_at }));
        }
        resume_in(&mut tx, bot_id).await?;
        tx.commit().await?;
        Ok(Ok(row))
    }

    /// Pauses a bot with `reason` and records its queued matches as `aborted` ("bot
    /// paused: reason"), in one transaction. Returns false if it was paused already
    /// (the first reason is kept) or does not exist.
    ///
    /// # Errors
    /// Database failures.
    pub async fn pause_bot(&self, bot_id: i64, reason: &str) -> Result<bool> {
        let mut tx = self.begin_write().await?;
        let paused = pause_bot_in(&mut tx, bot_id, reason, now_ms()).await?;
        tx.commit().await?;
        Ok(paused)
    }

    /// Resumes a paused bot: its matches are accepted and played again, and the matches
    /// aborted so far no longer count towards pausing it. Returns false if it was not
    /// paused.
    ///
    /// # Errors
    /// Database failures.
    pub async fn resume_bot(&self, bot_id: i64) -> Result<bool> {
        let mut tx = self.begin_write().await?;
        let resumed = resume_in(&mut tx, bot_id).await?;
        tx.commit().await?;
        Ok(resumed)
    }

    /// A bot and its latest version.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_bot(&self, bot_id: i64) -> Result<Option<BotRow>> {
        Ok(
            sqlx::query_as(&format!("{BOT_WITH_LATEST} and b.bot_id = $1"))
                .bind(bot_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// A bot by name.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_bot_by_name(&self, name: &str) -> Result<Option<BotRow>> {
        Ok(
            sqlx::query_as(&format!("{BOT_WITH_LATEST} and b.name = $1"))
                .bind(name)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// Every bot with its latest version, by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_bots(&self) -> Result<Vec<BotRow>> {
        Ok(
            sqlx::query_as(&format!("{BOT_WITH_LATEST} order by b.bot_id"))
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// Every version of a bot, oldest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn bot_versions(&self, bot_id: i64) -> Result<Vec<BotVersionRow>> {
        Ok(
            sqlx::query_as("select * from bot_version where bot_id = $1 order by version")
                .bind(bot_id)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// One version by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_bot_version(&self, bot_version_id: i64) -> Result<Option<BotVersionRow>> {
        Ok(
            sqlx::query_as("select * from bot_version where bot_version_id = $1")
                .bind(bot_version_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// The bots (id, name) whose owner token or entrant's key has hash `token_hash`, by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn bots_owned_by(&self, token_hash: &str) -> Result<Vec<(i64, String)>> {
        Ok(sqlx::query_as(
            "select b.bot_id, b.name from bot b left join entrant e on e.entrant_id = b.entrant_id
             where b.owner_token_hash = $1 or e.key_hash = $1 order by b.bot_id",
        )
        .bind(token_hash)
        .fetch_all(self.pool())
        .await?)
    }

    /// Whether `token_hash` is the hash of `bot_id`'s owner token or of the key of the
    /// entrant it belongs to.
    ///
    /// # Errors
    /// Database failures.
    pub async fn is_bot_owner(&self, bot_id: i64, token_hash: &str) -> Result<bool> {
        // The bot's own owner token, or the key of the entrant it belongs to.
        let found: Option<i64> = sqlx::query_scalar(
            "select b.bot_id from bot b left join entrant e on e.entrant_id = b.entrant_id
             where b.bot_id = $1 and (b.owner_token_hash = $2 or e.key_hash = $2)",
        )
        .bind(bot_id)
        .bind(token_hash)
        .fetch_optional(self.pool())
        .await?;
        Ok(found.is_some())
    }
}

/// See [`Storage::pause_bot`]; inside the caller's transaction.
pub(super) async fn pause_bot_in(
    tx: &mut sqlx::AnyConnection,
    bot_id: i64,
    reason: &str,
    now: i64,
) -> Result<bool> {
    let done = sqlx::query(
        "update bot set paused_reason = $1, paused_at = $2 where bot_id = $3 and paused_at is null",
    )
    .bind(reason)
    .bind(now)
    .bind(bot_id)
    .execute(&mut *tx)
    .await?;
    if done.rows_affected() == 0 {
        return Ok(false);
    }
    sqlx::query(
        "update match set status = 'aborted', record = $1, finished_at = $2
         where status = 'queued'
             and bot_version_id in (select bot_version_id from bot_version where bot_id = $3)",
    )
    .bind(failure_record(
        MatchStatus::Aborted,
        &format!("bot paused: {reason}"),
    )?)
    .bind(now)
    .bind(bot_id)
    .execute(&mut *tx)
    .await?;
    Ok(true)
}

/// See [`Storage::resume_bot`]; inside the caller's transaction.
/// A competition's version quota, held when a version is added
/// ([`Storage::add_bot_version_within`]): at most `limit` versions of entrant
/// `entrant_id` in competition `competition_id` uploaded after `since` that count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VersionQuota {
    /// The competition.
    pub competition_id: i64,
    /// The entrant whose versions are counted.
    pub entrant_id: i64,
    /// The most versions that count.
    pub limit: i64,
    /// Versions uploaded after this time (unix ms) count.
    pub since: i64,
}

/// Why [`Storage::add_bot_version_within`] stored nothing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum VersionRefusal {
    /// The quota is used up.
    Quota(VersionQuota),
    /// One of the owner's quotas is used up (what it had used).
    Owner(OwnerQuotaKind, OwnerUsage),
    /// A competition the bot is entered in closed (its name and close, unix ms) before
    /// the version could be stored.
    Closed {
        /// The competition's name.
        name: String,
        /// Its close (unix ms).
        closes_at: i64,
    },
}

async fn resume_in(tx: &mut sqlx::AnyConnection, bot_id: i64) -> Result<bool> {
    let done = sqlx::query(
        "update bot set paused_reason = null, paused_at = null, resumed_at = $1
         where bot_id = $2 and paused_at is not null",
    )
    .bind(now_ms())
    .bind(bot_id)
    .execute(tx)
    .await?;
    Ok(done.rows_affected() == 1)
}

/// Inserts bot `name` (of `entrant`, if given); its id. A taken name is a
/// [`StorageError::Conflict`].
async fn insert_bot(
    tx: &mut sqlx::AnyConnection,
    name: &str,
    owner_token_hash: &str,
    entrant: Option<i64>,
) -> Result<i64> {
    sqlx::query_scalar(
        "insert into bot (name, owner_token_hash, created_at, entrant_id)
         values ($1, $2, $3, $4) returning bot_id",
    )
    .bind(name)
    .bind(owner_token_hash)
    .bind(now_ms())
    .bind(entrant)
    .fetch_one(tx)
    .await
    .map_err(|e| {
        if is_unique_violation(&e) {
            StorageError::Conflict(format!(
                "a bot named {name:?} exists already (names that differ only in case are one name)"
            ))
        } else {
            e.into()
        }
    })
}

async fn insert_version(
    tx: &mut sqlx::AnyConnection,
    bot_id: i64,
    new: &NewVersion<'_>,
) -> Result<BotVersionRow> {
    let status = if new.build_command.is_some() || new.bundle_sha256.is_some() {
        build_status::BUILDING
    } else {
        build_status::READY
    };
    Ok(sqlx::query_as(
        "insert into bot_version (bot_id, version, command, dir, files_sha256, file_count, created_at,
             build_command, build_status, env, bundle_sha256, runtime, protocol)
         values ($1, (select coalesce(max(version), 0) + 1 from bot_version where bot_id = $2), $3, $4, $5, $6, $7,
             $8, $9, $10, $11, $12, $13)
         returning *",
    )
    .bind(bot_id)
    .bind(bot_id)
    .bind(new.command)
    .bind(new.dir)
    .bind(new.files_sha256)
    .bind(new.file_count)
    .bind(now_ms())
    .bind(new.build_command)
    .bind(status)
    .bind(env_json(new.env))
    .bind(new.bundle_sha256)
    .bind(new.runtime)
    .bind(new.protocol)
    .fetch_one(tx)
    .await?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::{backends, plain_version};

    fn version<'a>(command: &'a str) -> NewVersion<'a> {
        NewVersion {
            command,
            dir: "/bots/x",
            files_sha256: "abc",
            file_count: 1,
            build_command: None,
            ..plain_version()
        }
    }

    #[tokio::test]
    async fn bots_get_versions_and_owners() {
        for (db, _guard) in backends().await {
            let v1 = db
                .create_bot("alpha", "h1", &version("python3 a.py"))
                .await
                .unwrap();
            assert_eq!(v1.version, 1);
            let v2 = db
                .add_bot_version(v1.bot_id, &version("python3 b.py"))
                .await
                .unwrap();
            assert_eq!(v2.version, 2);
            let bot = db.get_bot(v1.bot_id).await.unwrap().unwrap();
            assert_eq!((bot.version, bot.command.as_str()), (2, "python3 b.py"));
            assert_eq!(db.bot_versions(v1.bot_id).await.unwrap().len(), 2);
            assert!(db.is_bot_owner(v1.bot_id, "h1").await.unwrap());
            assert!(!db.is_bot_owner(v1.bot_id, "h2").await.unwrap());
            assert_eq!(
                db.get_bot_by_name("alpha").await.unwrap().unwrap().bot_id,
                v1.bot_id
            );
            assert!(db.get_bot(999).await.unwrap().is_none());
            let clash = db.create_bot("alpha", "h3", &version("x")).await;
            assert!(matches!(clash, Err(StorageError::Conflict(_))));
            assert_eq!(db.list_bots().await.unwrap().len(), 1);
        }
    }
}
