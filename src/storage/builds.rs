//! Builds of uploaded bot versions: a version with a build command is `building` until
//! a server has run it once in the sandbox; then it is `ready` (it plays) or
//! `build_failed` (it never plays, and its queued matches are recorded as `crashed`
//! with the build's failure as the reason).

use super::bots::{BotVersionRow, build_status};
use super::matches::failure_record;
use super::{Result, Storage, now_ms};
use crate::runner::outcome::MatchStatus;

/// How much of a build's output is kept for its owner: the last 64 KiB.
pub const BUILD_LOG_BYTES: usize = 64 * 1024;

impl Storage {
    /// The oldest version waiting for its build, if any. One server builds at a time;
    /// a build cut short by a restart is simply run again.
    ///
    /// # Errors
    /// Database failures.
    pub async fn next_build(&self) -> Result<Option<BotVersionRow>> {
        Ok(sqlx::query_as(
            "select * from bot_version where build_status = $1 order by bot_version_id limit 1",
        )
        .bind(build_status::BUILDING)
        .fetch_optional(self.pool())
        .await?)
    }

    /// Records a build's end: `ready`, or `build_failed` with its queued matches
    /// recorded as crashed ("the build failed: ..."), in one transaction.
    ///
    /// # Errors
    /// Database failures.
    pub async fn finish_build(&self, bot_version_id: i64, ok: bool, log: &str) -> Result<()> {
        let mut log = log.to_string();
        if log.len() > BUILD_LOG_BYTES {
            let mut cut = log.len() - BUILD_LOG_BYTES;
            while !log.is_char_boundary(cut) {
                cut += 1;
            }
            log = format!("[... {cut} earlier bytes not kept]\n{}", &log[cut..]);
        }
        let status = if ok {
            build_status::READY
        } else {
            build_status::FAILED
        };
        let now = now_ms();
        let mut tx = self.pool().begin().await?;
        sqlx::query(
            "update bot_version set build_status = $1, build_log = $2, built_at = $3
             where bot_version_id = $4",
        )
        .bind(status)
        .bind(&log)
        .bind(now)
        .bind(bot_version_id)
        .execute(&mut *tx)
        .await?;
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
                &format!("the bot version's build failed: {tail}"),
            )?)
            .bind(now)
            .bind(bot_version_id)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::storage::bots::{NewVersion, build_status};
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn versions_with_a_build_wait_for_it_and_a_failed_build_fails_their_matches() {
        for (db, _guard) in backends().await {
            let v = db
                .create_bot(
                    "c-bot",
                    "h",
                    &NewVersion {
                        command: "./bot",
                        dir: "/x",
                        files_sha256: "s",
                        file_count: 1,
                        build_command: Some("make"),
                        env: &[],
                    },
                )
                .await
                .unwrap();
            assert_eq!(v.build_status, build_status::BUILDING);
            let maze = crate::storage::test_support::bot_and_maze(&db).await.1;
            let m = db.queue_match(v.bot_version_id, maze, 1).await.unwrap();
            // Not claimed while building.
            let claimed = db.claim_next("w", 1000, None).await.unwrap();
            assert!(claimed.is_none_or(|c| c.match_id != m));
            assert_eq!(
                db.next_build().await.unwrap().unwrap().bot_version_id,
                v.bot_version_id
            );
            db.finish_build(v.bot_version_id, false, "cc: error: no such file\n")
                .await
                .unwrap();
            assert!(db.next_build().await.unwrap().is_none());
            let row = db.get_match(m).await.unwrap().unwrap();
            assert_eq!(row.status, "crashed");
            assert!(row.record.unwrap().contains("build failed: cc: error"));
            let v = db.get_bot_version(v.bot_version_id).await.unwrap().unwrap();
            assert_eq!(v.build_status, build_status::FAILED);
            assert!(v.build_log.unwrap().contains("no such file"));
        }
    }
}
