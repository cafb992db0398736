//! The match queue: matches are rows; workers claim them with a lease, and write the
//! record in one transaction only while they still hold the lease.
//! A match whose lease expired (its server died while it ran) is retried a bounded
//! number of times ([`super::retries`]).

use sqlx::FromRow;

use super::{Backend, Result, Storage, StorageError, now_ms, records};
use crate::engine::{Maze, mazefile};
use crate::runner::MatchRecord;
use crate::runner::outcome::{MatchState, MatchStatus, MatchSummary};

/// Priority of single matches: they run before tournament matches.
pub const PRIORITY_SINGLE: i64 = 0;
/// Priority of tournament matches.
pub const PRIORITY_TOURNAMENT: i64 = 1;

/// A stored match (without its trace).
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct MatchRow {
    /// Id.
    pub match_id: i64,
    /// The bot version that plays.
    pub bot_version_id: i64,
    /// Its bot.
    pub bot_id: i64,
    /// The bot's name.
    pub bot_name: String,
    /// The bot version's number.
    pub version: i64,
    /// The maze.
    pub maze_id: i64,
    /// The maze's name.
    pub maze_name: String,
    /// Whether the maze is hidden.
    #[sqlx(try_from = "super::Flag")]
    pub maze_hidden: bool,
    /// SHA-256 of the maze's canonical text.
    pub maze_hash: String,
    /// The maze's side.
    pub maze_dim: i64,
    /// The seed sent to the bot.
    pub seed: i64,
    /// The tournament, if any.
    pub tournament_id: Option<i64>,
    /// Repetition index within the tournament.
    pub repeat: Option<i64>,
    /// Queued, running, or its final status.
    #[sqlx(try_from = "String")]
    pub status: MatchState,
    /// How many times a worker started it.
    pub attempts: i64,
    /// How many times its lease expired while it ran (its server died).
    pub lease_expiries: i64,
    /// Score when finished.
    pub score: Option<f64>,
    /// Run-0 steps.
    pub run0_steps: Option<i64>,
    /// Run-1 steps.
    pub run1_steps: Option<i64>,
    /// The step counter at the end.
    pub total_steps: Option<i64>,
    /// The record without its trace (JSON), once played.
    pub record: Option<String>,
    /// Queued at (unix ms).
    pub created_at: i64,
    /// Last started at (unix ms).
    pub started_at: Option<i64>,
    /// Finished at (unix ms).
    pub finished_at: Option<i64>,
    /// When its stored replay was removed to save space (an old practice match; none:
    /// never).
    pub record_pruned_at: Option<i64>,
    /// Whether its tournament is sealed (a competition's private set before the close,
    /// its final run before the results): for the admin and organisers only.
    #[sqlx(try_from = "super::Flag")]
    pub sealed: bool,
}

impl MatchRow {
    /// The row as anyone but the admin may see it: on a hidden maze, whether it finished
    /// and else the kind of failure (its status), nothing more: no score, no steps, no
    /// failure step or text, no start or end time (each of these could carry a few bits
    /// of the maze, chosen by the bot). A public maze's row is unchanged.
    pub fn redacted(mut self) -> MatchRow {
        if self.maze_hidden {
            self.score = None;
            self.run0_steps = None;
            self.run1_steps = None;
            self.total_steps = None;
            self.started_at = None;
            self.finished_at = None;
            if let Some(summary) = self
                .record
                .as_deref()
                .and_then(|r| serde_json::from_str::<crate::runner::outcome::MatchSummary>(r).ok())
            {
                let kept = crate::runner::outcome::MatchSummary {
                    engine_version: summary.engine_version,
                    limits: summary.limits,
                    status: summary.status,
                    ..Default::default()
                };
                self.record = serde_json::to_string(&kept).ok();
            }
        }
        self
    }

    /// Whether its stored replay was removed to save space (an old practice match,
    /// pruned): only then, not for a match that ended before its bot's first move.
    pub fn trace_removed(&self) -> bool {
        self.record_pruned_at.is_some()
    }

    /// The row's summary of the record (empty while the match is not played; a summary
    /// that cannot be read counts as empty).
    pub fn summary(&self) -> MatchSummary {
        self.record
            .as_deref()
            .and_then(|r| serde_json::from_str(r).ok())
            .unwrap_or_default()
    }
}

/// The order in which queued matches are played ([`Storage::claim_next`]): the next
/// match is the first waiting match of the lane least recently served, in the class of
/// lanes least recently served (table `queue_lane`). A lane is one owner's single matches,
/// one tournament, or one competition's tournaments; the classes are single matches and tournaments. So while both
/// wait, tournaments get every other match whatever is queued, and among single matches
/// the owners take turns: a single match that is first in its owner's lane is played
/// after at most one match of each other owner's lane and as many tournament matches,
/// however much anyone queues.
const FAIR_ORDER: &str = "
    with heads as (
        -- Single matches: each owner's first ready one (a partial index holds only the
        -- waiting single matches, a few per owner).
        select coalesce('e:' || cast(b.entrant_id as text), 'o:' || b.owner_token_hash) as lane,
            'class:s' as class,
            min(m.match_id) as match_id
        from match m
        join bot_version v on v.bot_version_id = m.bot_version_id
        join bot b on b.bot_id = v.bot_id
        where m.status = 'queued' and m.tournament_id is null
            and b.paused_at is null and v.build_status = 'ready'
            and cast($4 as bigint) is null
        group by coalesce('e:' || cast(b.entrant_id as text), 'o:' || b.owner_token_hash)
        union all
        -- Tournaments: each one's first ready waiting match (an index seek each). The
        -- tournaments of one competition share its lane.
        select coalesce('c:' || cast(t.competition_id as text), 't:' || cast(t.tournament_id as text)),
            'class:t',
            (select m.match_id from match m
             join bot_version v on v.bot_version_id = m.bot_version_id
             join bot b on b.bot_id = v.bot_id
             where m.tournament_id = t.tournament_id and m.status = 'queued'
                 and b.paused_at is null and v.build_status = 'ready'
             order by m.match_id limit 1)
        from tournament t
    )
    select m.match_id from heads h
    join match m on m.match_id = h.match_id
    left join queue_lane c on c.lane = h.class
    left join queue_lane l on l.lane = h.lane
    where m.status = 'queued'
    order by coalesce(c.served, 0), h.class, coalesce(l.served, 0), h.match_id";

/// The work waiting for match workers, in seconds of a worker slot, for an autoscaler of
/// workers: the pieces of work (the queued matches a worker may claim now, the condition
/// of [`Storage::claim_next`]: the version is built and ready, the bot is not paused; the
/// matches being played; the versions waiting for or in their build) times the mean time
/// of the last 200 matches played (start to record; 1 s while none is known, at least
/// 0.1 s), rounded up. Queued matches that cannot be claimed (a paused bot, a version
/// still building) are not counted: more workers would not play them sooner. In seconds
/// rather than matches, so that a field of slow bots (each match up to the time bank)
/// asks for more workers than the same number of quick matches.
///
/// KEDA's PostgreSQL scaler runs exactly this statement
/// (`deploy/kubernetes/worker-scaler.yaml`; a test checks that the two are the same and
/// runs the manifest's copy on PostgreSQL). Its counts are index seeks (`match_status`,
/// `bot_version_build`) and the mean reads the newest 200 rows by primary key: it stays
/// cheap on a database of millions of finished matches. Integer arithmetic only, so both
/// backends give the same number.
pub const WORK_FOR_WORKERS: &str = "with recent as (
  select coalesce(cast(sum(finished_at - started_at) as bigint) / count(*), 1000) as ms
  from (select finished_at, started_at from match
        where finished_at is not null and started_at is not null
        order by match_id desc limit 200) last_played
), pieces as (
  select
    (select count(*) from match m
       join bot_version v on v.bot_version_id = m.bot_version_id
       join bot b on b.bot_id = v.bot_id
     where m.status = 'queued' and b.paused_at is null and v.build_status = 'ready')
    + (select count(*) from match where status = 'running')
    + (select count(*) from bot_version where build_status = 'building') as n
)
select (n * (case when ms < 100 then 100 else ms end) + 999) / 1000 from pieces, recent";

/// Bot `b` has the same owner as bot `$1`: the same entrant, or (for bots of no
/// entrant) the same owner token.
const SAME_OWNER: &str = "b.bot_id in (
    select o.bot_id from bot o, bot x where x.bot_id = $1 and (
        (x.entrant_id is not null and o.entrant_id = x.entrant_id)
        or (x.entrant_id is null and o.entrant_id is null
            and o.owner_token_hash = x.owner_token_hash)))";

/// Inserts a queued single match (not a tournament's), played under `limits` (JSON, as
/// a tournament's; `None`: the worker's); its id.
async fn insert_single(
    conn: &mut sqlx::AnyConnection,
    bot_version_id: i64,
    maze_id: i64,
    seed: i64,
    limits: Option<&str>,
) -> Result<i64> {
    Ok(sqlx::query_scalar(
        "insert into match (bot_version_id, maze_id, seed, priority, created_at, limits)
         values ($1, $2, $3, $4, $5, $6) returning match_id",
    )
    .bind(bot_version_id)
    .bind(maze_id)
    .bind(seed)
    .bind(PRIORITY_SINGLE)
    .bind(now_ms())
    .bind(limits)
    .fetch_one(conn)
    .await?)
}

/// What a single match must hold to be queued ([`Storage::queue_match_within`]).
#[derive(Debug, Clone, Default)]
pub struct QueueLimits {
    /// The bot whose owner's matches are counted.
    pub bot_id: i64,
    /// The most matches its owner may have waiting (`None`: no limit).
    pub most_queued: Option<i64>,
    /// The practice quotas of the competitions whose practice maze it is.
    pub practice: Vec<PracticeQuota>,
    /// The limits it plays under (JSON, [`crate::competition::Limits`]): a competition's
    /// practice match plays under that competition's; `None`: the worker's.
    pub match_limits: Option<String>,
}

/// A competition's practice quota: at most `limit` practice matches of entrant
/// `entrant_id` on competition `competition_id`'s practice mazes queued after `since`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PracticeQuota {
    /// The competition.
    pub competition_id: i64,
    /// The entrant whose matches are counted.
    pub entrant_id: i64,
    /// The most matches.
    pub limit: i64,
    /// Matches queued after this time (unix ms) count.
    pub since: i64,
}

/// Why [`Storage::queue_match_within`] did not queue a match.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QueueRefusal {
    /// The owner has this many matches waiting, its limit or more.
    Queued(i64),
    /// This practice quota is used up.
    Practice(PracticeQuota),
}

/// Marks the lane and class of claimed match `$1` as served last.
const MARK_SERVED: &str = "
    insert into queue_lane (lane, served)
    select x.lane, (select coalesce(max(served), 0) + 1 from queue_lane)
    from (
        select case when m.tournament_id is null
                then coalesce('e:' || cast(b.entrant_id as text), 'o:' || b.owner_token_hash)
                else coalesce((select 'c:' || cast(t.competition_id as text) from tournament t
                               where t.tournament_id = m.tournament_id),
                              't:' || cast(m.tournament_id as text)) end as lane
        from match m join bot b on b.bot_id = m.bot_id where m.match_id = $1
        union all
        select case when m.tournament_id is null then 'class:s' else 'class:t' end
        from match m where m.match_id = $1
    ) x
    where true
    on conflict (lane) do update set served = excluded.served";

/// A match a worker has claimed, with what it needs to play it.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct ClaimedMatch {
    /// Id.
    pub match_id: i64,
    /// The seed.
    pub seed: i64,
    /// The bot's command.
    pub command: String,
    /// The bot's directory, for a bot registered from a local folder.
    pub dir: String,
    /// The stored bundle of the bot's files, if it has one.
    pub bundle_sha256: Option<String>,
    /// The stored bundle of the bot's folder after its build, if it has one.
    pub built_sha256: Option<String>,
    /// The maze's canonical numeric text.
    pub layout: String,
    /// The tournament, if any.
    pub tournament_id: Option<i64>,
    /// Environment variables declared for the bot version (JSON object).
    pub env: String,
    /// The runtime the version wants first on its `PATH`, by name.
    pub runtime: Option<String>,
    /// `mms` for a mouse of the mms simulator; `None` for protocol v1.
    #[sqlx(default)]
    pub protocol: Option<String>,
    /// The match's own limits (a competition's practice match) or its tournament's
    /// (JSON, [`crate::competition::Limits`]), if it has its own.
    pub limits: Option<String>,
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

/// Which matches [`Storage::list_matches`] returns.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MatchFilter {
    /// Only this bot's (any version).
    pub bot_id: Option<i64>,
    /// Only this tournament's.
    pub tournament_id: Option<i64>,
    /// Only this maze's.
    pub maze_id: Option<i64>,
    /// Only matches in this state.
    pub status: Option<MatchState>,
    /// Only matches older than this one (smaller ids): the page after a page that ends
    /// with it. Unlike an offset, it costs the same however deep the page.
    pub before: Option<i64>,
    /// Leave out the matches of sealed tournaments (for anyone but the admin and the
    /// organisers).
    pub hide_sealed: bool,
}

/// How many matches pass a filter, counted up to [`COUNT_CAP`] so that a count costs
/// the same at a million matches as at a thousand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MatchCount {
    /// The number counted (at most [`COUNT_CAP`]).
    pub total: i64,
    /// False when more pass than were counted.
    pub exact: bool,
}

/// The most matches a list counts.
pub const COUNT_CAP: i64 = 10_000;

/// One page of a list: at most `limit` rows after skipping `offset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Page {
    /// Rows to skip.
    pub offset: i64,
    /// Rows to return.
    pub limit: i64,
}

/// A match's columns with its names (for [`Storage::match_select`]).
const MATCH_COLUMNS: &str = "m.match_id, m.bot_version_id, v.bot_id, b.name as bot_name, v.version, m.maze_id,
        z.name as maze_name, z.hidden as maze_hidden, z.hash as maze_hash, z.dim as maze_dim, m.seed, m.tournament_id, m.repeat, m.status, m.attempts, m.lease_expiries, m.score,
        m.run0_steps, m.run1_steps, m.total_steps, m.record, m.created_at, m.started_at, m.finished_at,
        m.record_pruned_at, coalesce((select t.sealed from tournament t where t.tournament_id = m.tournament_id), 0) as sealed";

impl Storage {
    /// The select of a match with its names, for a where clause on `match m` to follow.
    /// The match table leads: on SQLite, `cross join` keeps the planner from starting
    /// elsewhere, so that a filtered list walks the filter's index.
    fn match_select(&self) -> String {
        let join = match self.backend() {
            Backend::Sqlite => "cross join",
            Backend::Postgres => "join",
        };
        format!(
            "select {MATCH_COLUMNS}
             from match m {join} bot_version v on v.bot_version_id = m.bot_version_id
             {join} bot b on b.bot_id = v.bot_id
             {join} maze z on z.maze_id = m.maze_id"
        )
    }

    /// Queues a single match.
    ///
    /// # Errors
    /// Database failures (including unknown bot version or maze ids).
    pub async fn queue_match(&self, bot_version_id: i64, maze_id: i64, seed: i64) -> Result<i64> {
        let mut conn = self.pool().acquire().await?;
        insert_single(&mut conn, bot_version_id, maze_id, seed, None).await
    }

    /// Queues a single match as [`Storage::queue_match`] does, unless it would go over
    /// one of `limits` (counted again here, so that requests sent at once cannot all
    /// pass the caller's own check and then all be queued): then nothing is written.
    /// The counting and the insert are one owner's at a time (PostgreSQL: a
    /// transaction-long lock on the bot's owner; SQLite: this process's write turn).
    ///
    /// # Errors
    /// Database failures.
    pub async fn queue_match_within(
        &self,
        bot_version_id: i64,
        maze_id: i64,
        seed: i64,
        limits: &QueueLimits,
    ) -> Result<std::result::Result<i64, QueueRefusal>> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        if self.backend() == super::Backend::Postgres {
            sqlx::query(
                "select pg_advisory_xact_lock(hashtextextended((
                     select coalesce('entrant ' || entrant_id, 'owner ' || owner_token_hash)
                     from bot where bot_id = $1), 0))",
            )
            .bind(limits.bot_id)
            .execute(&mut *tx)
            .await?;
        }
        if let Some(most) = limits.most_queued {
            let waiting: i64 = sqlx::query_scalar(&format!(
                "select cast(count(*) as bigint) from match m join bot b on b.bot_id = m.bot_id
                 where m.status = 'queued' and {SAME_OWNER}"
            ))
            .bind(limits.bot_id)
            .fetch_one(&mut *tx)
            .await?;
            if waiting >= most {
                tx.rollback().await?;
                return Ok(Err(QueueRefusal::Queued(waiting)));
            }
        }
        for q in &limits.practice {
            let played: i64 = sqlx::query_scalar(&format!(
                "select cast(count(*) as bigint) {}",
                super::competitions::PRACTICE_MATCHES
            ))
            .bind(q.competition_id)
            .bind(q.entrant_id)
            .bind(q.since)
            .fetch_one(&mut *tx)
            .await?;
            if played >= q.limit {
                tx.rollback().await?;
                return Ok(Err(QueueRefusal::Practice(*q)));
            }
        }
        let match_id = insert_single(
            &mut tx,
            bot_version_id,
            maze_id,
            seed,
            limits.match_limits.as_deref(),
        )
        .await?;
        tx.commit().await?;
        Ok(Ok(match_id))
    }

    /// The work waiting for match workers now, in seconds of a worker slot, as
    /// [`WORK_FOR_WORKERS`] counts it (the number an autoscaler of workers reads).
    ///
    /// # Errors
    /// Database failures.
    pub async fn work_for_workers(&self) -> Result<i64> {
        Ok(sqlx::query_scalar(WORK_FOR_WORKERS)
            .fetch_one(self.pool())
            .await?)
    }

    /// The number of matches waiting to be played.
    ///
    /// # Errors
    /// Database failures.
    pub async fn queued_count(&self) -> Result<i64> {
        Ok(
            sqlx::query_scalar("select count(*) from match where status = 'queued'")
                .fetch_one(self.pool())
                .await?,
        )
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

    /// How many matches of the owner of bot `bot_id` (its owner token, over every bot
    /// registered with it) are waiting in the queue.
    ///
    /// # Errors
    /// Database failures.
    pub async fn queued_for_owner_of(&self, bot_id: i64) -> Result<i64> {
        Ok(sqlx::query_scalar(&format!(
            "select count(*) from match m join bot b on b.bot_id = m.bot_id
             where m.status = 'queued' and {SAME_OWNER}"
        ))
        .bind(bot_id)
        .fetch_one(self.pool())
        .await?)
    }

    /// Claims the next queued match in the fair order (`FAIR_ORDER`) for `owner` until
    /// `now + lease_ms`, in one statement. With `tournament`, only that tournament's, in
    /// order. Matches of a paused bot are never claimed.
    ///
    /// # Errors
    /// Database failures.
    pub async fn claim_next(
        &self,
        owner: &str,
        lease_ms: i64,
        tournament: Option<i64>,
    ) -> Result<Option<ClaimedMatch>> {
        let turn = self.write_turn().await;
        let now = now_ms();
        // PostgreSQL: a claim skips the rows other workers are claiming at that moment
        // (each worker locks the row it takes), so any number claim at once without
        // waiting on each other. SQLite has one writer at a time.
        let lock = match self.backend() {
            Backend::Sqlite => "",
            Backend::Postgres => "for update of m skip locked",
        };
        let next = match tournament {
            // One tournament's matches (a local tournament): one lane, in order.
            Some(_) => format!(
                "select m.match_id from match m
                 join bot_version v on v.bot_version_id = m.bot_version_id
                 join bot b on b.bot_id = v.bot_id
                 where m.status = 'queued' and b.paused_at is null and v.build_status = 'ready'
                     and m.tournament_id = $4
                 order by m.match_id limit 1 {lock}"
            ),
            None => format!("{FAIR_ORDER} limit 1 {lock}"),
        };
        let id: Option<i64> = sqlx::query_scalar(&format!(
            "update match set status = 'running', lease_owner = $1, lease_expires_at = $2,
                 attempts = attempts + 1, started_at = $3
             where match_id = ({next})
             returning match_id"
        ))
        .bind(owner)
        .bind(now + lease_ms)
        .bind(now)
        .bind(tournament)
        .fetch_optional(self.pool())
        .await?;
        if let (Some(id), None) = (id, tournament) {
            sqlx::query(MARK_SERVED)
                .bind(id)
                .execute(self.pool())
                .await?;
        }
        drop(turn);
        let Some(id) = id else { return Ok(None) };
        Ok(sqlx::query_as(
            "select m.match_id, m.seed, v.command, v.dir, v.bundle_sha256, v.built_sha256,
                 z.layout, m.tournament_id, v.env, v.runtime, v.protocol,
                 coalesce(m.limits,
                     (select t.limits from tournament t where t.tournament_id = m.tournament_id)) as limits
             from match m join bot_version v on v.bot_version_id = m.bot_version_id
             join maze z on z.maze_id = m.maze_id where m.match_id = $1",
        )
        .bind(id)
        .fetch_optional(self.pool())
        .await?)
    }

    /// Extends `owner`'s lease on a running match. Returns false if the lease was lost.
    ///
    /// # Errors
    /// Database failures.
    pub async fn renew_lease(&self, match_id: i64, owner: &str, lease_ms: i64) -> Result<bool> {
        let _turn = self.write_turn().await;
        let done = sqlx::query(
            "update match set lease_expires_at = $1
             where match_id = $2 and lease_owner = $3 and status = 'running'",
        )
        .bind(now_ms() + lease_ms)
        .bind(match_id)
        .bind(owner)
        .execute(self.pool())
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Writes a played match's record, in one transaction, if `owner` still holds it:
    /// its summary in the match row, the whole record compactly in `match_record` (see
    /// [`super::records`]). Returns false (and writes nothing) when the lease was lost
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

    /// Moves the records that earlier versions stored inline in the match row (with
    /// the trace as JSON) to `match_record`, a batch at a time, each batch in one
    /// transaction. Returns how many were moved.
    ///
    /// # Errors
    /// Database failures. A stored record that cannot be read is left as it was.
    pub(super) async fn convert_inline_records(&self) -> Result<u64> {
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

    /// Marks a match `owner` holds as crashed without a bot record (our own fault,
    /// e.g. a stored maze that no longer parses), so it is not retried forever.
    ///
    /// # Errors
    /// Database failures.
    pub async fn fail_match(&self, match_id: i64, owner: &str, reason: &str) -> Result<bool> {
        let record = failure_record(MatchStatus::Crashed, reason)?;
        let _turn = self.write_turn().await;
        let done = sqlx::query(
            "update match set status = 'crashed', record = $1, finished_at = $2,
                 lease_owner = null, lease_expires_at = null
             where match_id = $3 and lease_owner = $4 and status = 'running'",
        )
        .bind(record)
        .bind(now_ms())
        .bind(match_id)
        .bind(owner)
        .execute(self.pool())
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Puts a match `owner` holds back in the queue (a worker that stops before the end,
    /// e.g. on a graceful shutdown). This is not counted against the match's retries:
    /// the server chose to stop, the bot did nothing wrong.
    ///
    /// # Errors
    /// Database failures.
    pub async fn release_match(&self, match_id: i64, owner: &str) -> Result<bool> {
        let _turn = self.write_turn().await;
        let done = sqlx::query(
            "update match set status = 'queued', lease_owner = null, lease_expires_at = null
             where match_id = $1 and lease_owner = $2 and status = 'running'",
        )
        .bind(match_id)
        .bind(owner)
        .execute(self.pool())
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Deals with every running match whose lease has expired (its worker died) and
    /// returns how many there were: re-queued, or aborted when their retries are used
    /// up; see [`Storage::reap_expired`].
    ///
    /// # Errors
    /// Database failures.
    pub async fn requeue_expired(&self) -> Result<u64> {
        let reaped = self.reap_expired().await?;
        Ok((reaped.requeued.len() + reaped.aborted.len()) as u64)
    }

    /// A match by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_match(&self, match_id: i64) -> Result<Option<MatchRow>> {
        Ok(
            sqlx::query_as(&format!("{} where m.match_id = $1", self.match_select()))
                .bind(match_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// One page of the matches that pass `filter`, newest first, and how many pass it
    /// (without its `before`).
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_matches(
        &self,
        filter: &MatchFilter,
        page: Page,
    ) -> Result<(Vec<MatchRow>, MatchCount)> {
        let (clause, values) = filter_clause(filter, true);
        let n = values.len();
        let sql = format!(
            "{}{clause} order by m.match_id desc limit ${} offset ${}",
            self.match_select(),
            n + 1,
            n + 2
        );
        let mut rows = sqlx::query_as(&sql);
        for value in &values {
            rows = match value {
                FilterValue::Id(id) => rows.bind(*id),
                FilterValue::Text(text) => rows.bind(*text),
            };
        }
        let rows = rows
            .bind(page.limit)
            .bind(page.offset)
            .fetch_all(self.pool())
            .await?;
        let (clause, values) = filter_clause(filter, false);
        let sql = format!(
            "select count(*) from (select 1 from match m{clause} limit ${}) as counted",
            values.len() + 1
        );
        let mut count = sqlx::query_scalar(&sql);
        for value in &values {
            count = match value {
                FilterValue::Id(id) => count.bind(*id),
                FilterValue::Text(text) => count.bind(*text),
            };
        }
        let counted: i64 = count.bind(COUNT_CAP + 1).fetch_one(self.pool()).await?;
        Ok((
            rows,
            MatchCount {
                total: counted.min(COUNT_CAP),
                exact: counted <= COUNT_CAP,
            },
        ))
    }

    /// Matches of a tournament, by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_matches(&self, tournament_id: i64) -> Result<Vec<MatchRow>> {
        Ok(sqlx::query_as(&format!(
            "{} where m.tournament_id = $1 order by m.match_id",
            self.match_select()
        ))
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The number of matches in each status.
    ///
    /// # Errors
    /// Database failures.
    pub async fn count_by_status(&self) -> Result<Vec<(String, i64)>> {
        Ok(
            sqlx::query_as("select status, count(*) from match group by status order by status")
                .fetch_all(self.pool())
                .await?,
        )
    }
}

/// A value [`filter_clause`] binds.
enum FilterValue {
    Id(i64),
    Text(&'static str),
}

/// `filter` as the where clause of a query on `match m`, with its parameters numbered
/// from `$1`, and their values in order: only the conditions it sets, so that the
/// database can use the index each one has (`before` only if `keyset`).
fn filter_clause(filter: &MatchFilter, keyset: bool) -> (String, Vec<FilterValue>) {
    let mut clause = String::from(" where 1 = 1");
    let mut values = Vec::new();
    let mut add = |column: &str, op: &str, value: FilterValue| {
        values.push(value);
        clause.push_str(&format!(" and m.{column} {op} ${}", values.len()));
    };
    if let Some(bot_id) = filter.bot_id {
        add("bot_id", "=", FilterValue::Id(bot_id));
    }
    if let Some(tournament_id) = filter.tournament_id {
        add("tournament_id", "=", FilterValue::Id(tournament_id));
    }
    if let Some(maze_id) = filter.maze_id {
        add("maze_id", "=", FilterValue::Id(maze_id));
    }
    if let Some(status) = filter.status {
        add("status", "=", FilterValue::Text(status.as_str()));
    }
    if let Some(before) = filter.before.filter(|_| keyset) {
        add("match_id", "<", FilterValue::Id(before));
    }
    if filter.hide_sealed {
        clause.push_str(
            " and not exists (select 1 from tournament t where t.tournament_id = m.tournament_id and t.sealed = 1)",
        );
    }
    (clause, values)
}

/// The summary (JSON, for the row) of a match the server ended without playing it.
pub(super) fn failure_record(status: MatchStatus, reason: &str) -> Result<String> {
    serde_json::to_string(&MatchSummary::unplayed(status, reason)).map_err(|e| {
        StorageError::Encode {
            what: "a match summary",
            message: e.to_string(),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::leaderboard::Scope;
    use crate::storage::test_support::{backends, bot_and_maze, maze};

    fn record(status: crate::runner::MatchStatus) -> MatchRecord {
        serde_json::from_value(serde_json::json!({
            "engine_version": "t", "protocol": 1, "maze_hash": "hash", "maze_dim": 2, "seed": 1,
            "limits": {"max_steps": 1000, "startup_timeout_ms": null, "move_timeout_ms": null, "memory_limit_mb": null},
            "status": status, "score": 1.1, "run0_steps": 3, "run1_steps": 1, "total_steps": 4,
            "warnings": [], "error": null, "stderr_tail": "", "timings": {"wall_ms": 1, "bot_cpu_ms": null, "max_answer_us": 1, "mean_answer_us": 1}
        }))
        .unwrap()
    }

    /// The scaler's count: claimable queued matches, running ones and builds, times the
    /// mean time of the matches played last; never the matches of a paused bot or of a
    /// version still building, nor finished ones.
    #[tokio::test]
    async fn the_work_for_workers_counts_what_a_worker_could_take() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            assert_eq!(db.work_for_workers().await.unwrap(), 0);
            for seed in 0..3 {
                db.queue_match(v, z, seed).await.unwrap();
            }
            // No match played yet: 1 s each.
            assert_eq!(db.work_for_workers().await.unwrap(), 3, "three queued");
            let claimed = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert_eq!(
                db.work_for_workers().await.unwrap(),
                3,
                "two queued, one running"
            );
            db.release_match(claimed.match_id, "w").await.unwrap();
            assert_eq!(
                db.work_for_workers().await.unwrap(),
                3,
                "released: queued again"
            );
            let claimed = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            db.complete_match(
                claimed.match_id,
                "w",
                &record(crate::runner::MatchStatus::Finished),
                &maze(),
            )
            .await
            .unwrap();
            // The match played took 5 s: two left, 10 s.
            db.run_sql_for_tests(&format!(
                "update match set started_at = 1000, finished_at = 6000 where match_id = {}",
                claimed.match_id
            ))
            .await;
            assert_eq!(db.work_for_workers().await.unwrap(), 10, "one finished");
            // A paused bot's queued matches wait for nothing a worker can do.
            let paused = db
                .create_bot("p", "h2", &crate::storage::test_support::plain_version())
                .await
                .unwrap();
            db.queue_match(paused.bot_version_id, z, 0).await.unwrap();
            assert_eq!(db.work_for_workers().await.unwrap(), 15);
            db.pause_bot(paused.bot_id, "test").await.unwrap();
            assert_eq!(
                db.work_for_workers().await.unwrap(),
                10,
                "paused: not counted"
            );
            // A version waiting for its build is one piece of work, its matches none yet.
            let built = db
                .create_bot("c", "h3", &crate::storage::test_support::with_build())
                .await
                .unwrap();
            db.queue_match(built.bot_version_id, z, 0).await.unwrap();
            assert_eq!(
                db.work_for_workers().await.unwrap(),
                15,
                "the build, not its match"
            );
            // Quick matches count at least 0.1 s each, rounded up to whole seconds.
            db.run_sql_for_tests(&format!(
                "update match set finished_at = 1001 where match_id = {}",
                claimed.match_id
            ))
            .await;
            assert_eq!(
                db.work_for_workers().await.unwrap(),
                1,
                "3 x 0.1 s, rounded up"
            );
        }
    }

    /// Two processes on one SQLite file (two storages: each has its own write turn)
    /// queue matches at once. A transaction that counts and then inserts, begun
    /// deferred, failed at its insert ("database is locked", SQLITE_BUSY_SNAPSHOT)
    /// whenever the other had written since its count: a 500 for `POST /api/matches`.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn two_processes_on_one_sqlite_file_queue_matches_at_once_without_a_busy_error() {
        let (a, dir) = crate::storage::test_support::fresh().await;
        let url = format!("sqlite://{}", dir.path().join("test.db").display());
        let b = Storage::open(&url).await.unwrap();
        let (v, z) = bot_and_maze(&a).await;
        let bot_id: i64 =
            sqlx::query_scalar("select bot_id from bot_version where bot_version_id = $1")
                .bind(v)
                .fetch_one(a.pool())
                .await
                .unwrap();
        let limits = QueueLimits {
            bot_id,
            most_queued: Some(1_000),
            practice: Vec::new(),
            match_limits: None,
        };
        let tasks: Vec<_> = (0..60)
            .map(|i| {
                let db = if i % 2 == 0 { a.clone() } else { b.clone() };
                let limits = limits.clone();
                tokio::spawn(async move { db.queue_match_within(v, z, i, &limits).await })
            })
            .collect();
        for task in tasks {
            let queued = task.await.unwrap();
            assert!(matches!(queued, Ok(Ok(_))), "{queued:?}");
        }
        assert_eq!(a.queued_count().await.unwrap(), 60);
    }

    #[tokio::test]
    async fn single_matches_are_claimed_first_when_neither_class_was_served() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let t = db.create_tournament("t", &[v], &[z], 2).await.unwrap();
            assert_eq!((t.total, t.done), (2, 0));
            let single = db.queue_match(v, z, 9).await.unwrap();
            assert_eq!(db.queued_count().await.unwrap(), 3);
            let first = db.claim_next("w1", 60_000, None).await.unwrap().unwrap();
            assert_eq!(first.match_id, single);
            assert_eq!(first.seed, 9);
            let second = db.claim_next("w1", 60_000, None).await.unwrap().unwrap();
            assert_eq!(second.tournament_id, Some(t.tournament_id));
            // Only that tournament's matches when asked.
            let third = db
                .claim_next("w2", 60_000, Some(t.tournament_id + 1))
                .await
                .unwrap();
            assert!(third.is_none());
        }
    }

    #[tokio::test]
    async fn a_flooding_owner_delays_another_owner_and_a_tournament_by_a_bounded_number() {
        for (db, _guard) in backends().await {
            let (flooder, z) = bot_and_maze(&db).await;
            let honest = db
                .create_bot(
                    "honest",
                    "another owner",
                    &crate::storage::test_support::plain_version(),
                )
                .await
                .unwrap()
                .bot_version_id;
            let t = db.create_tournament("t", &[honest], &[z], 6).await.unwrap();
            for seed in 0..40 {
                db.queue_match(flooder, z, seed).await.unwrap();
            }
            let mine = db.queue_match(honest, z, 99).await.unwrap();
            let mut order = Vec::new();
            while let Some(c) = db.claim_next("w", 60_000, None).await.unwrap() {
                order.push(c);
            }
            assert_eq!(order.len(), 47);
            // The honest owner's one match, queued after 40 of the flooder's and a
            // tournament of 6: before it at most one match of the flooder's lane and one
            // of the tournaments' class.
            let at = order.iter().position(|c| c.match_id == mine).unwrap();
            assert!(
                at <= 3,
                "the honest match came {}th: {:?}",
                at + 1,
                order
                    .iter()
                    .map(|c| (c.match_id, c.tournament_id))
                    .collect::<Vec<_>>()
            );
            // The tournament gets every other claim while singles wait: all of its 6
            // matches within the first 13.
            let last_t = order
                .iter()
                .rposition(|c| c.tournament_id == Some(t.tournament_id))
                .unwrap();
            assert!(
                last_t < 13,
                "the tournament's last match came {}th",
                last_t + 1
            );
        }
    }

    #[tokio::test]
    async fn pruning_old_practice_records_keeps_rows_and_every_standing() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let t = db.create_tournament("t", &[v], &[z], 1).await.unwrap();
            let single = db.queue_match(v, z, 3).await.unwrap();
            while let Some(c) = db.claim_next("w", 60_000, None).await.unwrap() {
                let status = if c.match_id == single {
                    MatchStatus::Finished
                } else {
                    MatchStatus::Timeout
                };
                let mut r = record(status);
                r.stderr_tail = "kept until pruned".into();
                assert!(
                    db.complete_match(c.match_id, "w", &r, &maze())
                        .await
                        .unwrap()
                );
            }
            let boards = || async {
                let mut all = Vec::new();
                for scope in [
                    Scope::All,
                    Scope::Ranking,
                    Scope::Tournament(t.tournament_id),
                ] {
                    all.push(format!("{:?}", db.leaderboard(scope).await.unwrap()));
                }
                all
            };
            let before = boards().await;
            let row_before = db.get_match(single).await.unwrap().unwrap();
            assert_eq!(
                db.get_record(single).await.unwrap().unwrap().stderr_tail,
                "kept until pruned"
            );
            // Nothing is old enough yet.
            assert_eq!(db.prune_practice_records(0).await.unwrap().0, 0);
            let (count, bytes) = db.prune_practice_records(i64::MAX).await.unwrap();
            assert_eq!(count, 1, "only the practice match's record goes");
            assert!(bytes > 0);
            assert_eq!(boards().await, before, "a standing changed");
            assert!(!row_before.trace_removed());
            let row_after = db.get_match(single).await.unwrap().unwrap();
            assert!(
                row_after.trace_removed(),
                "the row says its replay was removed"
            );
            assert_eq!(
                MatchRow {
                    record_pruned_at: None,
                    ..row_after
                },
                row_before
            );
            let left = db.get_record(single).await.unwrap();
            assert!(
                left.as_ref().is_none_or(|r| r.stderr_tail.is_empty()),
                "{left:?}"
            );
            // The tournament's match keeps its record.
            let tm = db
                .tournament_matches(t.tournament_id)
                .await
                .unwrap()
                .remove(0)
                .match_id;
            assert!(db.get_record(tm).await.unwrap().is_some());
        }
    }

    #[tokio::test]
    async fn a_record_is_written_once_and_only_by_the_lease_holder() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let id = db.queue_match(v, z, 1).await.unwrap();
            db.claim_next("w1", 60_000, None).await.unwrap().unwrap();
            let finished = crate::runner::MatchStatus::Finished;
            assert!(
                !db.complete_match(id, "w2", &record(finished), &maze())
                    .await
                    .unwrap()
            );
            assert!(
                db.complete_match(id, "w1", &record(finished), &maze())
                    .await
                    .unwrap()
            );
            assert!(
                !db.complete_match(id, "w1", &record(finished), &maze())
                    .await
                    .unwrap()
            );
            let row = db.get_match(id).await.unwrap().unwrap();
            assert_eq!(row.status, "finished");
            assert_eq!(row.score, Some(1.1));
            assert_eq!(row.attempts, 1);
            assert!(db.claim_next("w1", 60_000, None).await.unwrap().is_none());
        }
    }

    #[tokio::test]
    async fn expired_leases_go_back_to_the_queue() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let id = db.queue_match(v, z, 1).await.unwrap();
            db.claim_next("dead", -1, None).await.unwrap().unwrap();
            assert!(!db.renew_lease(id, "other", 1000).await.unwrap());
            assert_eq!(db.requeue_expired().await.unwrap(), 1);
            let again = db.claim_next("w2", 60_000, None).await.unwrap().unwrap();
            assert_eq!(again.match_id, id);
            // The dead worker can no longer write.
            let status = crate::runner::MatchStatus::Crashed;
            assert!(
                !db.complete_match(id, "dead", &record(status), &maze())
                    .await
                    .unwrap()
            );
            assert!(db.renew_lease(id, "w2", 1000).await.unwrap());
            assert!(db.release_match(id, "w2").await.unwrap());
            assert_eq!(db.get_match(id).await.unwrap().unwrap().attempts, 2);
            assert_eq!(db.queued_count().await.unwrap(), 1);
        }
    }

    #[tokio::test]
    async fn the_leaderboard_counts_a_dnf_as_1000() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let t = db.create_tournament("t", &[v], &[z], 2).await.unwrap();
            let a = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            db.complete_match(
                a.match_id,
                "w",
                &record(crate::runner::MatchStatus::Finished),
                &maze(),
            )
            .await
            .unwrap();
            let b = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            db.complete_match(
                b.match_id,
                "w",
                &record(crate::runner::MatchStatus::Timeout),
                &maze(),
            )
            .await
            .unwrap();
            let board = db
                .leaderboard(Scope::Tournament(t.tournament_id))
                .await
                .unwrap();
            assert_eq!(board.len(), 1);
            let s = &board[0];
            assert_eq!((s.rank, s.played, s.finished), (1, 2, 1));
            assert!((s.mean_score - (1.1 + 1000.0) / 2.0).abs() < 1e-9);
            assert!((s.finish_rate - 0.5).abs() < 1e-9);
            assert!((s.mean_ratio.unwrap() - (1.1 + 1000.0) / 2.0).abs() < 1e-9);
            // The maze is public: the ranking board is empty, the all-mazes board is not.
            assert!(db.leaderboard(Scope::Ranking).await.unwrap().is_empty());
            assert_eq!(db.leaderboard(Scope::All).await.unwrap().len(), 1);
            assert_eq!(
                db.get_tournament(t.tournament_id)
                    .await
                    .unwrap()
                    .unwrap()
                    .done,
                2
            );
        }
    }

    #[tokio::test]
    async fn lists_page_by_the_last_match_shown_and_count_up_to_a_cap() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let bot = db.get_bot_version(v).await.unwrap().unwrap().bot_id;
            let mut ids = Vec::new();
            for seed in 0..5 {
                ids.push(db.queue_match(v, z, seed).await.unwrap());
            }
            let page = Page {
                offset: 0,
                limit: 2,
            };
            let list = |filter: MatchFilter| {
                let db = db.clone();
                async move {
                    let (rows, count) = db.list_matches(&filter, page).await.unwrap();
                    (rows.iter().map(|r| r.match_id).collect::<Vec<_>>(), count)
                }
            };
            let exact = |total| MatchCount { total, exact: true };
            assert_eq!(
                list(MatchFilter::default()).await,
                (vec![ids[4], ids[3]], exact(5))
            );
            // The next page starts before the last match shown; the count is the list's.
            let older = MatchFilter {
                before: Some(ids[3]),
                ..MatchFilter::default()
            };
            assert_eq!(list(older).await, (vec![ids[2], ids[1]], exact(5)));
            // Each row knows its bot (the filter's index), whoever wrote it.
            let of = |bot_id| MatchFilter {
                bot_id: Some(bot_id),
                status: Some(MatchState::Queued),
                ..MatchFilter::default()
            };
            assert_eq!(list(of(bot)).await.1, exact(5));
            assert_eq!(list(of(bot + 1)).await, (vec![], exact(0)));
            // Past the cap, the count says so instead of counting on.
            sqlx::query(
                "with recursive n(i) as (select 1 union all select i + 1 from n where i < $1)
             insert into match (bot_version_id, maze_id, seed, priority, created_at)
             select $2, $3, i, 0, 0 from n",
            )
            .bind(COUNT_CAP)
            .bind(v)
            .bind(z)
            .execute(db.pool())
            .await
            .unwrap();
            let (rows, count) = list(of(bot)).await;
            assert_eq!(rows.len(), 2);
            assert_eq!(
                count,
                MatchCount {
                    total: COUNT_CAP,
                    exact: false
                }
            );
        }
    }
}
