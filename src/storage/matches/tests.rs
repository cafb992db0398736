//! Tests of the module's operations.

use super::lists::*;
use super::queue::*;
use super::*;
use crate::runner::MatchRecord;
use crate::runner::outcome::{MatchState, MatchStatus};
use crate::storage::Storage;
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
