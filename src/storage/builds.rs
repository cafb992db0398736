//! Builds of uploaded bot versions: a version with a build command is `building` until
//! a worker has claimed it and run it once in the sandbox; then it is `ready` (it plays) or
//! `build_failed` (it never plays, and its queued matches are recorded as `crashed`
//! with the build's failure as the reason).

use super::bots::{BotVersionRow, build_status};
use super::matches::failure_record;
use super::{Backend, Result, Storage, now_ms};
use crate::runner::outcome::MatchStatus;

/// How much of a build's output is kept for its owner: the last 64 KiB.
pub const BUILD_LOG_BYTES: usize = 64 * 1024;

/// How many times a build is claimed at most: a build whose worker died while it ran
/// (its lease expired) is claimed again, and the claim after the last is recorded as
/// `build_failed` ([`build_retries_exhausted`]) instead of running it, as matches are.
pub const MAX_BUILD_ATTEMPTS: i64 = 3;

/// The log of a build that used up its attempts.
pub fn build_retries_exhausted(attempts: i64) -> String {
    format!(
        "the build was running each time its worker stopped ({attempts} attempts); it is not \
         tried again: a build must not bring its worker down (memory, disk, time)"
    )
}

/// The order in which versions are built ([`Storage::claim_build`]). First the versions
/// a closed competition waits for before its selection (each entered bot's newest
/// version uploaded before the close: [`Storage::competition_work_left`]), so that a
/// close never waits behind other builds; then the rest. In each class, the oldest
/// waiting version of the owner least recently served (table `queue_lane`, lanes
/// `build:` and the owner: an entrant, all its bots together, or the owner token of a
/// bot of no entrant). So a version waits behind at most one build of each other owner
/// that has versions waiting, however many one owner uploads. `$3` is `building`, `$4`
/// now: a version whose build's lease is held is not waiting.
pub const FAIR_BUILD_ORDER: &str = "
    with waiting as (
        select v.bot_version_id,
            'build:' || coalesce('e:' || cast(b.entrant_id as text), 'o:' || b.owner_token_hash) as lane,
            case when exists (
                select 1 from competition_entry e
                join competition c on c.competition_id = e.competition_id
                where e.bot_id = v.bot_id and c.kind = 'competition' and c.state is null
                    and c.closes_at <= $4 and v.bot_version_id >= e.first_version_id
                    and v.created_at < c.closes_at
                    and v.bot_version_id = (select max(w.bot_version_id) from bot_version w
                                            where w.bot_id = v.bot_id and w.created_at < c.closes_at)
            ) then 0 else 1 end as class
        from bot_version v join bot b on b.bot_id = v.bot_id
        where v.build_status = $3
            and (v.build_lease_expires_at is null or v.build_lease_expires_at < $4)
    ), heads as (
        select lane, class, min(bot_version_id) as bot_version_id
        from waiting group by lane, class
    )
    select v.bot_version_id from heads h
    join bot_version v on v.bot_version_id = h.bot_version_id
    left join queue_lane l on l.lane = h.lane
    order by h.class, coalesce(l.served, 0), h.bot_version_id";

/// Marks the owner of the version `$1` as served last by the builders.
const MARK_BUILD_SERVED: &str = "
    insert into queue_lane (lane, served)
    select 'build:' || coalesce('e:' || cast(b.entrant_id as text), 'o:' || b.owner_token_hash),
        (select coalesce(max(served), 0) + 1 from queue_lane)
    from bot_version v join bot b on b.bot_id = v.bot_id
    where v.bot_version_id = $1
    on conflict (lane) do update set served = excluded.served";

impl Storage {
    /// Claims the next version waiting for its build in the fair order
    /// ([`FAIR_BUILD_ORDER`]: owners take turns), for `owner` until `lease_ms` from now:
    /// no other worker builds it meanwhile. A build whose worker died (its lease
    /// expired) is claimed again; each claim counts in `build_attempts`, and the claimer
    /// records a claim past [`MAX_BUILD_ATTEMPTS`] as failed.
    ///
    /// # Errors
    /// Database failures.
    pub async fn claim_build(&self, owner: &str, lease_ms: i64) -> Result<Option<BotVersionRow>> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        // PostgreSQL: a claim skips the versions other builders are claiming at that
        // moment, so builders of several machines never wait on each other.
        let lock = match self.backend() {
            Backend::Sqlite => "",
            Backend::Postgres => "for update of v skip locked",
        };
        let claimed: Option<BotVersionRow> = sqlx::query_as(&format!(
            "update bot_version set build_owner = $1, build_lease_expires_at = $2,
                 build_attempts = build_attempts + 1
             where bot_version_id = ({FAIR_BUILD_ORDER} limit 1 {lock})
                 and build_status = $3
             returning *"
        ))
        .bind(owner)
        .bind(now + lease_ms)
        .bind(build_status::BUILDING)
        .bind(now)
        .fetch_optional(self.pool())
        .await?;
        if let Some(v) = &claimed {
            sqlx::query(MARK_BUILD_SERVED)
                .bind(v.bot_version_id)
                .execute(self.pool())
                .await?;
        }
        Ok(claimed)
    }

    /// Extends `owner`'s claim on a build. Returns false if the claim was lost.
    ///
    /// # Errors
    /// Database failures.
    pub async fn renew_build_lease(
        &self,
        bot_version_id: i64,
        owner: &str,
        lease_ms: i64,
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let done = sqlx::query(
            "update bot_version set build_lease_expires_at = $1
             where bot_version_id = $2 and build_owner = $3 and build_status = $4",
        )
        .bind(now_ms() + lease_ms)
        .bind(bot_version_id)
        .bind(owner)
        .bind(build_status::BUILDING)
        .execute(self.pool())
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Records a build's end by `owner` (who claimed it), which took `build_ms` (spent
    /// from its owner's daily build time): `ready` (`ok`) with `built`
    /// (the stored bundle of the built folder), or `build_failed` with its queued matches
    /// recorded as crashed ("the build failed: ..."), in one transaction. Returns false,
    /// writing nothing, if `owner` no longer holds the build.
    ///
    /// # Errors
    /// Database failures.
    pub async fn finish_build(
        &self,
        bot_version_id: i64,
        owner: &str,
        status: &str,
        built: Option<&str>,
        log: &str,
        build_ms: i64,
    ) -> Result<bool> {
        let ok = status == build_status::READY;
        let mut log = log.to_string();
        if log.len() > BUILD_LOG_BYTES {
            let mut cut = log.len() - BUILD_LOG_BYTES;
            while !log.is_char_boundary(cut) {
                cut += 1;
            }
            log = format!("[... {cut} earlier bytes not kept]\n{}", &log[cut..]);
        }
        let now = now_ms();
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let done = sqlx::query(
            "update bot_version set build_status = $1, build_log = $2, built_at = $3,
                 built_sha256 = $4, build_owner = null, build_lease_expires_at = null,
                 build_ms = $8
             where bot_version_id = $5 and build_owner = $6 and build_status = $7",
        )
        .bind(status)
        .bind(&log)
        .bind(now)
        .bind(built)
        .bind(bot_version_id)
        .bind(owner)
        .bind(build_status::BUILDING)
        .bind(build_ms.max(0))
        .execute(&mut *tx)
        .await?;
        if done.rows_affected() == 0 {
            return Ok(false);
        }
        if !ok {
            let tail: String = log
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("no output")
                .chars()
                .take(300)
                .collect();
            sqlx::query(
                "update match set status = 'crashed', record = $1, finished_at = $2
                 where status = 'queued' and bot_version_id = $3",
            )
            .bind(failure_record(
                MatchStatus::Crashed,
                &if status == build_status::INVALID {
                    format!("the bot version failed its validation match: {tail}")
                } else {
                    format!("the bot version's build failed: {tail}")
                },
            )?)
            .bind(now)
            .bind(bot_version_id)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use crate::storage::bots::build_status;
    use crate::storage::test_support::{backends, with_build};

    #[tokio::test]
    async fn versions_with_a_build_wait_for_it_and_a_failed_build_fails_their_matches() {
        for (db, _guard) in backends().await {
            let v = db.create_bot("c-bot", "h", &with_build()).await.unwrap();
            assert_eq!(v.build_status, build_status::BUILDING);
            let maze = crate::storage::test_support::bot_and_maze(&db).await.1;
            let m = db.queue_match(v.bot_version_id, maze, 1).await.unwrap();
            // Not claimed while building.
            let claimed = db.claim_next("w", 1000, None).await.unwrap();
            assert!(claimed.is_none_or(|c| c.match_id != m));
            let claimed = db.claim_build("w1", 60_000).await.unwrap().unwrap();
            assert_eq!(claimed.bot_version_id, v.bot_version_id);
            // Claimed: nobody else builds it until the claim expires.
            assert!(db.claim_build("w2", 60_000).await.unwrap().is_none());
            assert!(
                !db.renew_build_lease(v.bot_version_id, "w2", 1)
                    .await
                    .unwrap()
            );
            assert!(
                db.renew_build_lease(v.bot_version_id, "w1", -1)
                    .await
                    .unwrap()
            );
            // w1's claim has expired: w2 takes the build over and w1 can no longer end it.
            let again = db.claim_build("w2", 60_000).await.unwrap().unwrap();
            assert_eq!(again.bot_version_id, v.bot_version_id);
            assert_eq!((claimed.build_attempts, again.build_attempts), (1, 2));
            assert!(
                !db.finish_build(
                    v.bot_version_id,
                    "w1",
                    build_status::FAILED,
                    None,
                    "late",
                    0
                )
                .await
                .unwrap()
            );
            assert!(
                db.finish_build(
                    v.bot_version_id,
                    "w2",
                    build_status::FAILED,
                    None,
                    "cc: error: no such file\n",
                    2_500
                )
                .await
                .unwrap()
            );
            assert!(db.claim_build("w3", 60_000).await.unwrap().is_none());
            let row = db.get_match(m).await.unwrap().unwrap();
            assert_eq!(row.status, "crashed");
            assert!(row.record.unwrap().contains("build failed: cc: error"));
            let v = db.get_bot_version(v.bot_version_id).await.unwrap().unwrap();
            assert_eq!(v.build_status, build_status::FAILED);
            assert!(v.build_log.unwrap().contains("no such file"));

            // A build that worked: the version plays from its built bundle.
            let v2 = db.add_bot_version(v.bot_id, &with_build()).await.unwrap();
            let m2 = db.queue_match(v2.bot_version_id, maze, 1).await.unwrap();
            db.claim_build("w1", 60_000).await.unwrap().unwrap();
            db.put_bundle(&crate::storage::bundles::NewBundle {
                sha256: "b1",
                archive: b"tgz",
                files: 1,
                bytes: 3,
            })
            .await
            .unwrap();
            assert!(
                db.finish_build(
                    v2.bot_version_id,
                    "w1",
                    build_status::READY,
                    Some("b1"),
                    "ok",
                    1_500
                )
                .await
                .unwrap()
            );
            let claimed = db.claim_next("w", 1000, None).await.unwrap().unwrap();
            assert_eq!(claimed.match_id, m2);
            assert_eq!(claimed.built_sha256.as_deref(), Some("b1"));
            let v2 = db
                .get_bot_version(v2.bot_version_id)
                .await
                .unwrap()
                .unwrap();
            assert_eq!(v2.build_status, build_status::READY);
        }
    }

    #[tokio::test]
    async fn owners_take_turns_at_the_builder_however_many_one_uploads() {
        for (db, _guard) in backends().await {
            // A floods six versions (two bots of one owner token), then B and C upload one.
            let a = db.create_bot("a1", "ha", &with_build()).await.unwrap();
            let a2 = db.create_bot("a2", "ha", &with_build()).await.unwrap();
            for _ in 0..2 {
                db.add_bot_version(a.bot_id, &with_build()).await.unwrap();
                db.add_bot_version(a2.bot_id, &with_build()).await.unwrap();
            }
            let b = db.create_bot("b", "hb", &with_build()).await.unwrap();
            let c = db.create_bot("c", "hc", &with_build()).await.unwrap();
            let mut order = Vec::new();
            while let Some(v) = db.claim_build("w", 60_000).await.unwrap() {
                let who = match v.bot_id {
                    id if id == b.bot_id => "b",
                    id if id == c.bot_id => "c",
                    _ => "a",
                };
                order.push(who);
                assert!(
                    db.finish_build(v.bot_version_id, "w", build_status::READY, None, "", 10)
                        .await
                        .unwrap()
                );
            }
            // B and C wait behind one build of A's, not six.
            assert_eq!(order, ["a", "b", "c", "a", "a", "a", "a", "a"]);
            // A newcomer after that is next, ahead of A's next upload.
            db.add_bot_version(a.bot_id, &with_build()).await.unwrap();
            let d = db.create_bot("d", "hd", &with_build()).await.unwrap();
            let first = db.claim_build("w", 60_000).await.unwrap().unwrap();
            assert_eq!(first.bot_id, d.bot_id);
        }
    }
}
