//! The queue: matches queued within their owners' limits, claimed fairly across
//! lanes (each owner's single matches, each tournament), leased, released, failed and
//! given back when a lease expires.

use sqlx::FromRow;

use super::{PRIORITY_SINGLE, SAME_OWNER, failure_record};
use crate::runner::outcome::MatchStatus;
use crate::storage::{Backend, Result, Storage, now_ms};

impl Storage {
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
                crate::storage::competitions::PRACTICE_MATCHES
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
