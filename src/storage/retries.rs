//! Retries of matches whose server died while they ran, and pausing the bots whose
//! matches keep dying with their server: a match is re-queued after an expired lease
//! at most [`MAX_MATCH_RETRIES`] times (or as [`Storage::with_max_retries`] says), then
//! recorded as `aborted`, so a bot that brings
//! its server down (a poison pill) is not re-run forever; a bot with
//! [`PAUSE_AFTER_ABORTS`] such matches of one version is paused (`bots.rs`).

use super::matches::failure_record;
use super::{Result, Storage, now_ms};
use crate::runner::outcome::MatchStatus;

/// How many times a match whose lease expired while it ran (its server died) is put
/// back in the queue. The next expiry, attempt `MAX_MATCH_RETRIES + 1`, records it as
/// `aborted`: a bot that brings its server down would otherwise be re-run after every
/// restart, forever. A graceful shutdown's release ([`Storage::release_match`]) is not
/// the bot's doing and does not count.
pub const MAX_MATCH_RETRIES: i64 = 2;

/// Aborted matches (retries used up) of one bot version, since the bot was last
/// resumed, that pause the bot: its queued matches are aborted and no new ones are
/// accepted until an admin resumes it or a new version is uploaded.
pub const PAUSE_AFTER_ABORTS: i64 = 2;

/// The reason recorded with a match that used up its `retries`.
pub fn retries_exhausted_reason(retries: i64) -> String {
    format!(
        "the match was running each time the server stopped ({} attempts); it is not retried",
        retries + 1
    )
}

/// What [`Storage::reap_expired`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Reaped {
    /// Matches put back in the queue.
    pub requeued: Vec<i64>,
    /// Matches recorded as `aborted` (their retries were used up).
    pub aborted: Vec<i64>,
    /// Bots paused because of these aborts.
    pub paused_bots: Vec<i64>,
}

impl Storage {
    /// Every running match whose lease has expired (its server died) goes back to the
    /// queue, at most [`MAX_MATCH_RETRIES`] times; the next time it is recorded as
    /// `aborted`. A bot with [`PAUSE_AFTER_ABORTS`] such matches of one version since it
    /// was last resumed is paused, and its queued matches are aborted. One transaction.
    ///
    /// # Errors
    /// Database failures.
    pub async fn reap_expired(&self) -> Result<Reaped> {
        let now = now_ms();
        let retries = self.max_retries();
        let aborted_record =
            failure_record(MatchStatus::Aborted, &retries_exhausted_reason(retries))?;
        let mut tx = self.begin_write().await?;
        // Write first, so the transaction holds the write lock from its start. In an
        // update every expression reads the row as it was before it.
        let rows: Vec<(i64, String, i64)> = sqlx::query_as(
            "update match set lease_expiries = lease_expiries + 1,
                 status = case when lease_expiries + 1 > $1 then 'aborted' else 'queued' end,
                 record = case when lease_expiries + 1 > $1 then $2 else record end,
                 finished_at = case when lease_expiries + 1 > $1 then $3 else finished_at end,
                 lease_owner = null, lease_expires_at = null
             where status = 'running' and lease_expires_at < $3
             returning match_id, status, bot_version_id",
        )
        .bind(retries)
        .bind(&aborted_record)
        .bind(now)
        .fetch_all(&mut *tx)
        .await?;
        let mut reaped = Reaped::default();
        let mut versions = Vec::new();
        for (match_id, status, bot_version_id) in rows {
            if status == MatchStatus::Aborted.as_str() {
                reaped.aborted.push(match_id);
                if !versions.contains(&bot_version_id) {
                    versions.push(bot_version_id);
                }
            } else {
                reaped.requeued.push(match_id);
            }
        }
        for bot_version_id in versions {
            if let Some(bot_id) = pause_if_aborting(&mut tx, bot_version_id, now, retries).await? {
                reaped.paused_bots.push(bot_id);
            }
        }
        tx.commit().await?;
        reaped.requeued.sort_unstable();
        reaped.aborted.sort_unstable();
        Ok(reaped)
    }
}

/// Pauses the bot of `bot_version_id` when that version has [`PAUSE_AFTER_ABORTS`]
/// aborted matches (retries used up) since the bot was last resumed, and it is not
/// paused already. Returns the bot's id when it paused it.
async fn pause_if_aborting(
    tx: &mut sqlx::AnyConnection,
    bot_version_id: i64,
    now: i64,
    retries: i64,
) -> Result<Option<i64>> {
    let (bot_id, version, paused_at): (i64, i64, Option<i64>) = sqlx::query_as(
        "select b.bot_id, v.version, b.paused_at
         from bot_version v join bot b on b.bot_id = v.bot_id where v.bot_version_id = $1",
    )
    .bind(bot_version_id)
    .fetch_one(&mut *tx)
    .await?;
    if paused_at.is_some() {
        return Ok(None);
    }
    let aborted: Vec<i64> = sqlx::query_scalar(
        "select m.match_id from match m join bot_version v on v.bot_version_id = m.bot_version_id
         join bot b on b.bot_id = v.bot_id
         where m.bot_version_id = $1 and m.status = 'aborted' and m.lease_expiries > $2
             and m.finished_at > coalesce(b.resumed_at, 0)
         order by m.match_id",
    )
    .bind(bot_version_id)
    .bind(retries)
    .fetch_all(&mut *tx)
    .await?;
    if (aborted.len() as i64) < PAUSE_AFTER_ABORTS {
        return Ok(None);
    }
    let ids: Vec<String> = aborted.iter().map(i64::to_string).collect();
    let reason = format!(
        "{} matches of version {version} were aborted (matches {}): the server stopped each time they ran",
        aborted.len(),
        ids.join(", ")
    );
    super::bots::pause_bot_in(tx, bot_id, &reason, now).await?;
    Ok(Some(bot_id))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::bots::NewVersion;
    use crate::storage::leaderboard::Scope;
    use crate::storage::test_support::{backends, bot_and_maze, plain_version};

    /// Claims the next match with a lease that has already expired, as a server that
    /// died while playing it would leave it, then reaps.
    async fn die_while_running(db: &Storage) -> (i64, Reaped) {
        let claimed = db.claim_next("dead", -1, None).await.unwrap().unwrap();
        (claimed.match_id, db.reap_expired().await.unwrap())
    }

    #[tokio::test]
    async fn an_expired_lease_counts_and_the_third_expiry_aborts_the_match() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let id = db.queue_match(v, z, 1).await.unwrap();
            for expiry in 1..=MAX_MATCH_RETRIES {
                let (claimed, reaped) = die_while_running(&db).await;
                assert_eq!(claimed, id);
                assert_eq!(reaped.requeued, vec![id]);
                let row = db.get_match(id).await.unwrap().unwrap();
                assert_eq!(
                    (row.status.as_str(), row.lease_expiries),
                    ("queued", expiry)
                );
            }
            let (_, reaped) = die_while_running(&db).await;
            assert_eq!(
                (reaped.requeued.len(), reaped.aborted.clone()),
                (0, vec![id])
            );
            assert!(reaped.paused_bots.is_empty(), "one abort does not pause");
            let row = db.get_match(id).await.unwrap().unwrap();
            assert_eq!((row.status.as_str(), row.attempts), ("aborted", 3));
            assert!(row.finished_at.is_some());
            let record: serde_json::Value = serde_json::from_str(&row.record.unwrap()).unwrap();
            assert_eq!(record["status"], "aborted");
            assert_eq!(
                record["error"]["reason"],
                "the match was running each time the server stopped (3 attempts); it is not retried"
            );
            assert!(db.claim_next("w", 60_000, None).await.unwrap().is_none());
            // An aborted match is a did-not-finish and a played match of its tournament.
            assert_eq!(
                db.leaderboard(Scope::All).await.unwrap()[0].mean_score,
                1000.0
            );
        }
    }

    #[tokio::test]
    async fn a_graceful_release_is_not_counted_against_the_retries() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let id = db.queue_match(v, z, 1).await.unwrap();
            for _ in 0..5 {
                db.claim_next("w", 60_000, None).await.unwrap().unwrap();
                assert!(db.release_match(id, "w").await.unwrap());
            }
            let row = db.get_match(id).await.unwrap().unwrap();
            assert_eq!((row.status.as_str(), row.lease_expiries), ("queued", 0));
            assert_eq!(row.attempts, 5);
            let (_, reaped) = die_while_running(&db).await;
            assert_eq!(reaped.requeued, vec![id]);
        }
    }

    #[tokio::test]
    async fn a_bot_with_two_aborted_matches_is_paused_and_its_queue_aborted() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let first = db.queue_match(v, z, 1).await.unwrap();
            let second = db.queue_match(v, z, 2).await.unwrap();
            let waiting = db.queue_match(v, z, 3).await.unwrap();
            // Both running matches die with their server three times.
            let mut last = Reaped::default();
            for _ in 0..=MAX_MATCH_RETRIES {
                db.claim_next("dead", -1, None).await.unwrap().unwrap();
                db.claim_next("dead", -1, None).await.unwrap().unwrap();
                last = db.reap_expired().await.unwrap();
            }
            assert_eq!(last.aborted, vec![first, second]);
            let bot = db.get_bot_by_name("b").await.unwrap().unwrap();
            assert_eq!(last.paused_bots, vec![bot.bot_id]);
            assert!(bot.is_paused());
            let reason = bot.paused_reason.unwrap();
            assert!(
                reason.contains(&format!("matches {first}, {second}")),
                "{reason}"
            );
            // Its queued match is aborted, naming the pause.
            let row = db.get_match(waiting).await.unwrap().unwrap();
            assert_eq!((row.status.as_str(), row.lease_expiries), ("aborted", 0));
            let record: serde_json::Value = serde_json::from_str(&row.record.unwrap()).unwrap();
            let why = record["error"]["reason"].as_str().unwrap();
            assert_eq!(why, format!("bot paused: {reason}"));
            // After a resume, the old aborts no longer count: one more does not pause.
            assert!(db.resume_bot(bot.bot_id).await.unwrap());
            db.queue_match(v, z, 4).await.unwrap();
            for _ in 0..=MAX_MATCH_RETRIES {
                last = die_while_running(&db).await.1;
            }
            assert_eq!(last.aborted.len(), 1);
            assert!(last.paused_bots.is_empty());
            assert!(!db.get_bot(bot.bot_id).await.unwrap().unwrap().is_paused());
        }
    }

    #[tokio::test]
    async fn a_paused_bots_matches_are_not_claimed() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let other = db
                .create_bot(
                    "other",
                    "h2",
                    &NewVersion {
                        command: "python3 o.py",
                        dir: "/o",
                        files_sha256: "o",
                        file_count: 1,
                        build_command: None,
                        ..plain_version()
                    },
                )
                .await
                .unwrap();
            let bot_id = db.get_bot_by_name("b").await.unwrap().unwrap().bot_id;
            assert!(db.pause_bot(bot_id, "testing").await.unwrap());
            assert!(!db.pause_bot(bot_id, "again").await.unwrap());
            // A match queued after the pause waits: it is not claimed, others are.
            let paused_match = db.queue_match(v, z, 1).await.unwrap();
            let others = db.queue_match(other.bot_version_id, z, 1).await.unwrap();
            let claimed = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert_eq!(claimed.match_id, others);
            assert!(db.claim_next("w", 60_000, None).await.unwrap().is_none());
            // A new version resumes the bot; its waiting match is claimed.
            let v2 = NewVersion {
                command: "python3 b2.py",
                dir: "/y",
                files_sha256: "t",
                file_count: 1,
                build_command: None,
                ..plain_version()
            };
            db.add_bot_version(bot_id, &v2).await.unwrap();
            let bot = db.get_bot(bot_id).await.unwrap().unwrap();
            assert_eq!((bot.is_paused(), bot.paused_reason), (false, None));
            let claimed = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert_eq!(claimed.match_id, paused_match);
        }
    }
}
