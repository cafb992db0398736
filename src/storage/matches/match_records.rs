//! Match records: written once by the lease holder (compressed, the trace kept as the
//! answers), read back replayed, and old practice records pruned.

use sqlx::FromRow;

use crate::engine::{Maze, mazefile};
use crate::runner::MatchRecord;
use crate::storage::{Result, Storage, StorageError, now_ms, records};

use super::SAME_OWNER;

impl Storage {
    /// Moves the records that earlier versions stored inline in the match row (with
    /// the trace as JSON) to `match_record`, a batch at a time, each batch in one
    /// transaction. Returns how many were moved.
    ///
    /// # Errors
    /// Database failures. A stored record that cannot be read is left as it was.
    pub(in crate::storage) async fn convert_inline_records(&self) -> Result<u64> {
        const BATCH: i64 = 200;
        let mut moved = 0u64;
        let mut after = 0i64;
        loop {
            let rows: Vec<(i64, Option<String>, String, String)> = sqlx::query_as(
                "select m.match_id, m.record, m.trace, z.layout from match m
                 join maze z on z.maze_id = m.maze_id
                 where m.trace is not null and m.match_id > $1 order by m.match_id limit $2",
            )
            .bind(after)
            .bind(BATCH)
            .fetch_all(self.pool())
            .await?;
            let Some(last) = rows.last() else {
                break;
            };
            after = last.0;
            let mut tx = self.begin_write().await?;
            for (match_id, record, trace, layout) in rows {
                let whole = record
                    .as_deref()
                    .and_then(|r| serde_json::from_str::<MatchRecord>(r).ok())
                    .zip(serde_json::from_str::<Vec<crate::runner::TraceStep>>(&trace).ok())
                    .map(|(mut r, t)| {
                        r.trace = t;
                        r
                    });
                let maze = mazefile::numeric::parse(layout.as_bytes()).ok();
                let (Some(whole), Some(maze)) = (whole, maze) else {
                    tracing::warn!(
                        match_id,
                        "a stored match record cannot be read; it is left as it was"
                    );
                    continue;
                };
                let Ok(stored) = StoredRecord::encode(match_id, &whole, &maze) else {
                    continue;
                };
                stored.put(&mut tx).await?;
                sqlx::query("update match set record = $1, trace = null where match_id = $2")
                    .bind(&stored.summary)
                    .bind(match_id)
                    .execute(&mut *tx)
                    .await?;
                moved += 1;
            }
            tx.commit().await?;
        }
        if moved > 0 {
            tracing::info!(moved, "moved match records to their compact storage");
        }
        Ok(moved)
    }

    /// Removes the stored records (trace, stderr, debug drawing) of the practice
    /// matches (single matches, not in a tournament) that ended before `before_ms`,
    /// keeping their rows: status, score, steps and summary stay, and so does every
    /// standing (kept from the rows). Returns how many records and compressed bytes went.
    ///
    /// # Errors
    /// Database failures.
    pub async fn prune_practice_records(&self, before_ms: i64) -> Result<(i64, i64)> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let (count, bytes): (i64, Option<i64>) = sqlx::query_as(
            "select count(*), cast(sum(length(r.data)) as bigint) from match_record r
             join match m on m.match_id = r.match_id
             where m.tournament_id is null and m.finished_at < $1",
        )
        .bind(before_ms)
        .fetch_one(&mut *tx)
        .await?;
        sqlx::query(
            "update match set record_pruned_at = $2
             where tournament_id is null and finished_at < $1 and record_pruned_at is null
               and match_id in (select match_id from match_record)",
        )
        .bind(before_ms)
        .bind(now_ms())
        .execute(&mut *tx)
        .await?;
        sqlx::query(
            "delete from match_record where match_id in (
                 select m.match_id from match m
                 where m.tournament_id is null and m.finished_at < $1)",
        )
        .bind(before_ms)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok((count, bytes.unwrap_or(0)))
    }

    /// The compressed bytes of the stored records of every match of the owner of bot
    /// `bot_id` (its owner token, over every bot registered with it).
    ///
    /// # Errors
    /// Database failures.
    pub async fn stored_bytes_of_owner_of(&self, bot_id: i64) -> Result<i64> {
        let bytes: Option<i64> = sqlx::query_scalar(&format!(
            "select cast(sum(length(r.data)) as bigint) from match_record r
             join match m on m.match_id = r.match_id
             join bot b on b.bot_id = m.bot_id
             where {SAME_OWNER}"
        ))
        .bind(bot_id)
        .fetch_one(self.pool())
        .await?;
        Ok(bytes.unwrap_or(0))
    }

    /// Writes a played match's record, in one transaction, if `owner` still holds it:
    /// its summary in the match row, the whole record compactly in `match_record` (see
    /// [`crate::storage::records`]). Returns false (and writes nothing) when the lease was lost
    /// meanwhile.
    ///
    /// `maze` is the maze it was played on.
    ///
    /// # Errors
    /// Database failures, or a record that cannot be encoded.
    pub async fn complete_match(
        &self,
        match_id: i64,
        owner: &str,
        record: &MatchRecord,
        maze: &Maze,
    ) -> Result<bool> {
        let stored = StoredRecord::encode(match_id, record, maze)?;
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let done = sqlx::query(
            "update match set status = $1, score = $2, run0_steps = $3, run1_steps = $4, total_steps = $5,
                 record = $6, trace = null, finished_at = $7, lease_owner = null, lease_expires_at = null
             where match_id = $8 and lease_owner = $9 and status = 'running'",
        )
        .bind(record.status.as_str())
        .bind(record.score)
        .bind(record.run0_steps.map(i64::from))
        .bind(record.run1_steps.map(i64::from))
        .bind(i64::from(record.total_steps))
        .bind(&stored.summary)
        .bind(now_ms())
        .bind(match_id)
        .bind(owner)
        .execute(&mut *tx)
        .await?;
        if done.rows_affected() == 1 {
            stored.put(&mut tx).await?;
        }
        tx.commit().await?;
        Ok(done.rows_affected() == 1)
    }

    /// A played match's whole record with its trace (an earlier version's record that
    /// could not be converted: without it); `None` for a match not played (queued,
    /// running, or ended by the server without playing it) or no such match.
    ///
    /// # Errors
    /// Database failures, or a stored record that cannot be read.
    pub async fn get_record(&self, match_id: i64) -> Result<Option<MatchRecord>> {
        let row: Option<StoredRecordRow> = sqlx::query_as(
            "select m.record as summary, r.encoding, r.data, z.layout from match m
             join maze z on z.maze_id = m.maze_id
             left join match_record r on r.match_id = m.match_id
             where m.match_id = $1",
        )
        .bind(match_id)
        .fetch_optional(self.pool())
        .await?;
        let Some(StoredRecordRow {
            summary,
            encoding,
            data,
            layout,
        }) = row
        else {
            return Ok(None);
        };
        let fail = |message: String| StorageError::Record { match_id, message };
        match (encoding, data) {
            (Some(encoding), Some(data)) => {
                let maze = mazefile::numeric::parse(layout.as_bytes())
                    .map_err(|e| fail(format!("its stored maze is invalid: {e}")))?;
                records::decode(encoding, &data, summary.as_deref().unwrap_or(""), &maze)
                    .map(Some)
                    .map_err(fail)
            }
            _ => Ok(summary.and_then(|s| serde_json::from_str(&s).ok())),
        }
    }
}

/// A record ready to be written: the row's summary (JSON) and the compact record.
struct StoredRecord {
    match_id: i64,
    summary: String,
    encoding: i64,
    data: Vec<u8>,
}

impl StoredRecord {
    /// Encodes `record` of match `match_id`, played on `maze`.
    fn encode(match_id: i64, record: &MatchRecord, maze: &Maze) -> Result<StoredRecord> {
        let fail = |message: String| StorageError::Record { match_id, message };
        let (encoding, data) = records::encode(record, maze).map_err(fail)?;
        let summary = serde_json::to_string(&records::summary(record))
            .map_err(|e| fail(format!("cannot encode the record's summary: {e}")))?;
        Ok(StoredRecord {
            match_id,
            summary,
            encoding,
            data,
        })
    }

    /// Writes the compact record (the caller writes the summary with its row).
    async fn put(&self, tx: &mut sqlx::AnyConnection) -> Result<()> {
        sqlx::query(
            "insert into match_record (match_id, encoding, data) values ($1, $2, $3)
             on conflict (match_id) do update set encoding = excluded.encoding, data = excluded.data",
        )
        .bind(self.match_id)
        .bind(self.encoding)
        .bind(&self.data)
        .execute(tx)
        .await?;
        Ok(())
    }
}

/// What [`Storage::get_record`] reads.
#[derive(FromRow)]
struct StoredRecordRow {
    summary: Option<String>,
    encoding: Option<i64>,
    data: Option<Vec<u8>>,
    layout: String,
}
