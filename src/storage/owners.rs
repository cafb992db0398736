//! What one owner has used of the quotas held on its uploads: its versions waiting for
//! their build, its versions of bots outside competitions, and its build time. An owner
//! is an entrant (all its bots together) or, for a bot of no entrant, its owner token
//! (the fair queue's lanes are the same owners). The rules (sizes, messages) are
//! [`crate::registry::owners`].

use super::build_status;
use super::{Backend, Result, Storage};

/// Whose quota: an entrant, or the owner token of bots of no entrant (by its hash).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Owner {
    /// An entrant: all its bots.
    Entrant(i64),
    /// The bots of no entrant registered with one owner token (its SHA-256).
    Token(String),
}

impl Owner {
    /// Bot `b` is this owner's (`$1` is [`Owner::bind_value`]).
    fn condition(&self) -> &'static str {
        match self {
            Owner::Entrant(_) => "b.entrant_id = cast($1 as bigint)",
            Owner::Token(_) => "b.entrant_id is null and b.owner_token_hash = $1",
        }
    }

    /// The value bound as `$1` in [`Owner::condition`], as text.
    fn bind_value(&self) -> String {
        match self {
            Owner::Entrant(id) => id.to_string(),
            Owner::Token(hash) => hash.clone(),
        }
    }

    /// The key of its lock (PostgreSQL) and of its lane in the build queue.
    pub fn key(&self) -> String {
        match self {
            Owner::Entrant(id) => format!("e:{id}"),
            Owner::Token(hash) => format!("o:{hash}"),
        }
    }
}

/// What an owner has used, counted at one moment.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct OwnerUsage {
    /// Its versions waiting for or in their build (bot name, version), oldest first.
    pub pending: Vec<(String, i64)>,
    /// Its versions of bots entered in no competition uploaded since the window's start,
    /// failed builds and invalid versions left out.
    pub versions_outside: i64,
    /// When the oldest of those was uploaded (unix ms).
    pub oldest_outside_at: Option<i64>,
    /// The build time its versions' builds that ended since the window's start took
    /// (ms, failed and invalid ones included).
    pub build_ms: i64,
    /// When the oldest of those builds ended (unix ms).
    pub oldest_build_at: Option<i64>,
}

/// Bot `b` is entered in no competition (the default ranking is none).
const OUTSIDE_COMPETITIONS: &str = "not exists (
    select 1 from competition_entry e join competition c on c.competition_id = e.competition_id
    where e.bot_id = b.bot_id and c.kind = 'competition')";

impl Storage {
    /// The owner of bot `bot_id`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn owner_of_bot(&self, bot_id: i64) -> Result<Option<Owner>> {
        let row: Option<(Option<i64>, String)> =
            sqlx::query_as("select entrant_id, owner_token_hash from bot where bot_id = $1")
                .bind(bot_id)
                .fetch_optional(self.pool())
                .await?;
        Ok(row.map(|(entrant, token)| entrant.map_or(Owner::Token(token), Owner::Entrant)))
    }

    /// What `owner` has used since `since` (unix ms).
    ///
    /// # Errors
    /// Database failures.
    pub async fn owner_usage(&self, owner: &Owner, since: i64) -> Result<OwnerUsage> {
        let mut conn = self.pool().acquire().await?;
        owner_usage_in(&mut conn, owner, since).await
    }
}

/// Takes `owner`'s lock for the caller's transaction (PostgreSQL: uploads of one owner
/// are counted one after the other; SQLite's writers are one at a time already).
pub(super) async fn lock_owner(
    tx: &mut sqlx::AnyConnection,
    backend: Backend,
    owner: &Owner,
) -> Result<()> {
    if backend == Backend::Postgres {
        sqlx::query("select pg_advisory_xact_lock(hashtextextended($1, 0))")
            .bind(format!("owner {}", owner.key()))
            .execute(tx)
            .await?;
    }
    Ok(())
}

/// [`Storage::owner_usage`] on `conn` (inside the caller's transaction).
pub(super) async fn owner_usage_in(
    conn: &mut sqlx::AnyConnection,
    owner: &Owner,
    since: i64,
) -> Result<OwnerUsage> {
    let who = owner.condition();
    let value = owner.bind_value();
    let pending: Vec<(String, i64)> = sqlx::query_as(&format!(
        "select b.name, v.version from bot_version v join bot b on b.bot_id = v.bot_id
         where {who} and v.build_status = $2 order by v.bot_version_id"
    ))
    .bind(&value)
    .bind(build_status::BUILDING)
    .fetch_all(&mut *conn)
    .await?;
    let (versions_outside, oldest_outside_at): (i64, Option<i64>) = sqlx::query_as(&format!(
        "select cast(count(*) as bigint), min(v.created_at)
         from bot_version v join bot b on b.bot_id = v.bot_id
         where {who} and v.created_at > $2 and v.build_status not in ($3, $4)
             and {OUTSIDE_COMPETITIONS}"
    ))
    .bind(&value)
    .bind(since)
    .bind(build_status::FAILED)
    .bind(build_status::INVALID)
    .fetch_one(&mut *conn)
    .await?;
    let (build_ms, oldest_build_at): (Option<i64>, Option<i64>) = sqlx::query_as(&format!(
        "select cast(sum(v.build_ms) as bigint), min(v.built_at)
         from bot_version v join bot b on b.bot_id = v.bot_id
         where {who} and v.built_at > $2 and v.build_ms is not null"
    ))
    .bind(&value)
    .bind(since)
    .fetch_one(&mut *conn)
    .await?;
    Ok(OwnerUsage {
        pending,
        versions_outside,
        oldest_outside_at,
        build_ms: build_ms.unwrap_or(0),
        oldest_build_at,
    })
}

/// An owner's quotas, held when a version is added ([`Storage::add_bot_version_within`],
/// [`Storage::create_bot_within`]): counted again in the transaction that adds it,
/// under the owner's lock, so that uploads sent at once cannot all pass.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnerLimits {
    /// Whose.
    pub owner: Owner,
    /// The window's start (unix ms): versions and builds after it count.
    pub since: i64,
    /// The most versions waiting for their build at once.
    pub most_pending: Option<i64>,
    /// The most versions of bots outside competitions in the window (only for a bot
    /// outside competitions).
    pub most_versions_outside: Option<i64>,
    /// The most build time (ms) in the window.
    pub most_build_ms: Option<i64>,
}

/// Which of an owner's quotas is used up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OwnerQuotaKind {
    /// Versions waiting for their build.
    Pending,
    /// Versions of bots outside competitions in the window.
    VersionsOutside,
    /// Build time in the window.
    BuildTime,
}

impl OwnerLimits {
    /// The first quota that `usage` leaves no room in for one more version.
    pub fn refusal(&self, usage: &OwnerUsage) -> Option<OwnerQuotaKind> {
        if self
            .most_pending
            .is_some_and(|m| usage.pending.len() as i64 >= m)
        {
            return Some(OwnerQuotaKind::Pending);
        }
        if self
            .most_versions_outside
            .is_some_and(|m| usage.versions_outside >= m)
        {
            return Some(OwnerQuotaKind::VersionsOutside);
        }
        if self.most_build_ms.is_some_and(|m| usage.build_ms >= m) {
            return Some(OwnerQuotaKind::BuildTime);
        }
        None
    }
}

/// Counts `limits`' owner's usage under its lock in the caller's transaction: the
/// refusal, if a quota is used up.
pub(super) async fn hold_in(
    tx: &mut sqlx::AnyConnection,
    backend: Backend,
    limits: &OwnerLimits,
) -> Result<Option<(OwnerQuotaKind, OwnerUsage)>> {
    lock_owner(&mut *tx, backend, &limits.owner).await?;
    let usage = owner_usage_in(tx, &limits.owner, limits.since).await?;
    Ok(limits.refusal(&usage).map(|kind| (kind, usage)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::bots::VersionRefusal;
    use crate::storage::bots::{BotVersionRow, NewVersion};
    use crate::storage::test_support::{backends, plain_version, with_build};

    /// Adds `version` to bot `bot` within `limits`: the version, or why it was refused.
    async fn add(
        db: &Storage,
        bot: i64,
        version: &NewVersion<'_>,
        limits: &OwnerLimits,
    ) -> std::result::Result<BotVersionRow, VersionRefusal> {
        db.add_bot_version_within(bot, version, &[], Some(limits))
            .await
            .unwrap()
    }

    #[tokio::test]
    async fn an_owners_quotas_are_counted_where_the_version_is_stored() {
        for (db, _guard) in backends().await {
            let now = crate::storage::now_ms();
            let owner = Owner::Token("ho".into());
            let limits = OwnerLimits {
                owner: owner.clone(),
                since: now - 86_400_000,
                most_pending: Some(2),
                most_versions_outside: Some(4),
                most_build_ms: Some(60_000),
            };
            let first = db
                .create_bot_within("o", "ho", None, &with_build(), Some(&limits), None)
                .await
                .unwrap()
                .unwrap();
            add(&db, first.bot_id, &with_build(), &limits)
                .await
                .unwrap();
            // Two waiting for their build: a third is refused, and stores nothing.
            let refused = add(&db, first.bot_id, &with_build(), &limits)
                .await
                .unwrap_err();
            let VersionRefusal::Owner(OwnerQuotaKind::Pending, usage) = refused else {
                panic!("{refused:?}")
            };
            assert_eq!(usage.pending, [("o".to_string(), 1), ("o".to_string(), 2)]);
            // Both built (20 s each, one failed): two versions count, 40 s spent.
            for status in [build_status::READY, build_status::FAILED] {
                let v = db.claim_build("w", 60_000).await.unwrap().unwrap();
                db.finish_build(v.bot_version_id, "w", status, None, "", 20_000)
                    .await
                    .unwrap();
            }
            // Another owner is not held by it.
            db.create_bot_within("x", "hx", None, &with_build(), Some(&limits), None)
                .await
                .unwrap()
                .unwrap();
            let usage = db.owner_usage(&owner, limits.since).await.unwrap();
            assert_eq!(usage.versions_outside, 1, "the failed build does not count");
            assert_eq!(usage.build_ms, 40_000);
            assert!(usage.pending.is_empty());
            // Versions without a build are not pending: up to the daily quota of 4.
            for _ in 0..3 {
                add(&db, first.bot_id, &plain_version(), &limits)
                    .await
                    .unwrap();
            }
            let refused = add(&db, first.bot_id, &plain_version(), &limits)
                .await
                .unwrap_err();
            assert!(
                matches!(
                    refused,
                    VersionRefusal::Owner(OwnerQuotaKind::VersionsOutside, _)
                ),
                "{refused:?}"
            );
            // Build time: past a minute, refused whatever else is left.
            let roomy = OwnerLimits {
                most_versions_outside: None,
                most_build_ms: Some(40_000),
                ..limits.clone()
            };
            let refused = add(&db, first.bot_id, &plain_version(), &roomy)
                .await
                .unwrap_err();
            assert!(
                matches!(refused, VersionRefusal::Owner(OwnerQuotaKind::BuildTime, _)),
                "{refused:?}"
            );
            // An entrant's bots count together.
            let e = db.create_entrant("team", "[]", "hk", None).await.unwrap();
            let mine = OwnerLimits {
                owner: Owner::Entrant(e.entrant_id),
                most_pending: Some(1),
                ..limits.clone()
            };
            db.create_bot_within(
                "e1",
                "he1",
                Some(e.entrant_id),
                &with_build(),
                Some(&mine),
                None,
            )
            .await
            .unwrap()
            .unwrap();
            let refused = db
                .create_bot_within(
                    "e2",
                    "he2",
                    Some(e.entrant_id),
                    &with_build(),
                    Some(&mine),
                    None,
                )
                .await
                .unwrap()
                .unwrap_err();
            assert!(matches!(
                refused,
                VersionRefusal::Owner(OwnerQuotaKind::Pending, _)
            ));
            assert!(db.get_bot_by_name("e2").await.unwrap().is_none());
        }
    }
}
