//! Tests of the competitions' operations.

use crate::competition::selection::Rule;
use crate::competition::{Limits, MazeSets, MazeText, Quota, Spec, Timestamp};
use crate::storage::Storage;
use crate::storage::competitions::{CompetitionRow, ResultRow};

use super::*;
use crate::engine::generator::generate;
use crate::engine::mazefile::numeric;
use crate::storage::now_ms;
use crate::storage::test_support::{backends, plain_version};

fn maze(seed: u64) -> MazeText {
    MazeText {
        name: format!("m{seed}"),
        layout: numeric::write(&generate(12, seed).unwrap()),
    }
}

fn spec(now: i64) -> Spec<MazeText> {
    Spec {
        name: "c".into(),
        title: "C".into(),
        description: String::new(),
        rules: String::new(),
        opens_at: Timestamp(now - 1000),
        closes_at: Timestamp(now + 3_600_000),
        freeze_hours: None,
        repeats: 2,
        final_repeats: 1,
        versions_per_day: 5,
        practice_per_day: 5,
        selection: Rule::Latest,
        max_selected: 1,
        reveal_private_mazes: true,
        hold_results: false,
        limits: Limits::default(),
        validation: Default::default(),
        mazes: MazeSets {
            practice: vec![maze(7001)],
            public: vec![maze(7002)],
            private: vec![maze(7003), maze(7004)],
        },
    }
}

/// A version that failed its validation match (`invalid`) gives its quota back, as
/// one that failed to build does.
#[tokio::test]
async fn an_invalid_version_does_not_count_against_the_quota() {
    use crate::storage::bots::build_status;
    for (db, _guard) in backends().await {
        let now = now_ms();
        let c = create(&db, spec(now), None).await.unwrap();
        let (e, v) = entered_bot(&db, &c).await;
        let used = |q: Quota| q.used;
        let before = used(
            version_quota(&db, &c, e.entrant_id, now_ms())
                .await
                .unwrap(),
        );
        db.add_bot_version(v.bot_id, &crate::storage::test_support::with_build())
            .await
            .unwrap();
        let claimed = db.claim_build("w", 60_000).await.unwrap().unwrap();
        let counted = used(
            version_quota(&db, &c, e.entrant_id, now_ms())
                .await
                .unwrap(),
        );
        assert_eq!(counted, before + 1);
        assert!(
            db.finish_build(
                claimed.bot_version_id,
                "w",
                build_status::INVALID,
                None,
                "crashed",
                1_000
            )
            .await
            .unwrap()
        );
        let after = used(
            version_quota(&db, &c, e.entrant_id, now_ms())
                .await
                .unwrap(),
        );
        assert_eq!(after, before, "the invalid version still counts");
        let row = db
            .get_bot_version(claimed.bot_version_id)
            .await
            .unwrap()
            .unwrap();
        assert_eq!(row.build_status, build_status::INVALID);
    }
}

/// A close moved earlier never freezes the public board in the past: moved to now,
/// the board shows what it showed (no freeze before the close); a board frozen
/// already stays frozen from the same instant.
#[tokio::test]
async fn shortening_a_competition_never_freezes_its_board_retroactively() {
    for (db, _guard) in backends().await {
        let now = now_ms();
        let mut s = spec(now);
        s.closes_at = Timestamp(now + 48 * 3_600_000);
        s.freeze_hours = Some(24.0);
        let c = create(&db, s, None).await.unwrap();
        let frozen_from = |c: &CompetitionRow| timeline(c).and_then(|t| t.frozen_from());
        assert_eq!(frozen_from(&c), Some(now + 24 * 3_600_000));
        let patch = Patch {
            closes_at: Some(Timestamp(now)),
            ..Patch::default()
        };
        let closed = edit(&db, c.clone(), patch, now).await.unwrap();
        assert_eq!(closed.closes_at, Some(now));
        assert!(frozen_from(&closed).unwrap() >= now, "{closed:?}");
        // Frozen already (the close 12 hours away, frozen for 12): closing in an
        // hour keeps the freeze where it was.
        let later = now + 36 * 3_600_000;
        let patch = Patch {
            closes_at: Some(Timestamp(later + 3_600_000)),
            ..Patch::default()
        };
        let moved = edit(&db, c, patch, later).await.unwrap();
        assert_eq!(frozen_from(&moved), Some(now + 24 * 3_600_000));
    }
}

/// Plays every waiting match of the competition's tournaments by hand: finished,
/// score `score`.
async fn play_all(db: &Storage, score: f64) {
    db.run_sql_for_tests(&format!(
        "update match set status = 'finished', score = {score}, total_steps = 10
         where status = 'queued' and tournament_id is not null"
    ))
    .await;
}

/// An entrant ("e") with a bot ("b") entered in `c`.
async fn entered_bot(
    db: &Storage,
    c: &CompetitionRow,
) -> (
    crate::storage::entrants::EntrantRow,
    crate::storage::bots::BotVersionRow,
) {
    let e = db.create_entrant("e", "[]", "k", None).await.unwrap();
    let v = db.create_bot("b", "h", &plain_version()).await.unwrap();
    db.set_bot_entrant(v.bot_id, e.entrant_id).await.unwrap();
    db.enter_competition(c.competition_id, v.bot_id, e.entrant_id)
        .await
        .unwrap();
    (e, v)
}

/// A close waits for each entered bot's newest version uploaded before it, built
/// before anyone else's builds (a flood of uploads outside the competition waits),
/// and not for the older versions it supersedes.
#[tokio::test]
async fn a_close_waits_for_one_build_per_entrant_built_first() {
    use crate::storage::bots::build_status;
    use crate::storage::test_support::with_build;
    for (db, _guard) in backends().await {
        let now = now_ms();
        let c = create(&db, spec(now), None).await.unwrap();
        let (_, v) = entered_bot(&db, &c).await;
        // Someone floods the builder with bots in no competition first.
        for i in 0..3 {
            db.create_bot(&format!("flood-{i}"), "flooder", &with_build())
                .await
                .unwrap();
        }
        // The entrant uploads three versions just before the close.
        let mut uploaded = Vec::new();
        for _ in 0..3 {
            uploaded.push(db.add_bot_version(v.bot_id, &with_build()).await.unwrap());
        }
        tokio::time::sleep(std::time::Duration::from_millis(5)).await;
        let closed = close_now(&db, c, now_ms()).await;
        // Only the newest holds the close.
        assert_eq!(db.competition_work_left(&closed).await.unwrap(), 1);
        // It is built first, ahead of the flood and of the entrant's older ones.
        let first = db.claim_build("w", 60_000).await.unwrap().unwrap();
        assert_eq!(first.bot_version_id, uploaded[2].bot_version_id);
        assert!(
            db.finish_build(first.bot_version_id, "w", build_status::READY, None, "", 5)
                .await
                .unwrap()
        );
        assert_eq!(db.competition_work_left(&closed).await.unwrap(), 0);
        // Then the others take turns as usual.
        let next = db.claim_build("w", 60_000).await.unwrap().unwrap();
        assert_ne!(
            next.bot_id, v.bot_id,
            "the flooder was served least recently"
        );
    }
}

/// `c` closed at `now`.
async fn close_now(db: &Storage, c: CompetitionRow, now: i64) -> CompetitionRow {
    let patch = Patch {
        closes_at: Some(Timestamp(now)),
        ..Patch::default()
    };
    edit(db, c, patch, now).await.unwrap()
}

async fn sealed(db: &Storage, t: Option<i64>) -> bool {
    db.get_tournament(t.unwrap()).await.unwrap().unwrap().sealed
}

#[test]
fn the_csv_quotes_what_it_must_and_no_name_is_a_formula() {
    let row = |entrant: &str, bot: &str| ResultRow {
        rank: 1,
        entrant_id: 1,
        entrant_name: entrant.into(),
        bot_id: 1,
        bot_name: bot.into(),
        bot_version_id: 1,
        version: 2,
        played: 4,
        finished: 3,
        mean_score: 260.5,
        score_sum30: 31260,
        finish_rate: 0.75,
        manifest: r#"{"bundle_sha256":"abc"}"#.into(),
        uncertainty: crate::ranking::Uncertainty {
            low: 250.0,
            high: 270.0,
            rank_range: "1-2".into(),
            tie_group: 1,
            ..Default::default()
        },
    };
    let csv = results_csv(&[row("team, \"a\"", "=cmd|' /c calc'!A1"), row("b", "@sum")]);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "rank,rank_range,tie_group,entrant,bot,version,played,finished,mean_score,score_low,score_high,finish_rate,score_sum30,bundle_sha256"
    );
    assert_eq!(
        lines[1],
        r#"1,1-2,1,"team, ""a""",'=cmd|' /c calc'!A1,2,4,3,260.500,250.000,270.000,0.750,31260,abc"#
    );
    assert_eq!(
        lines[2],
        "1,1-2,1,b,'@sum,2,4,3,260.500,250.000,270.000,0.750,31260,abc"
    );
}

/// The close is one instant: a version whose upload passed every check before the
/// close but reaches the database after it is not stored (the clock would never
/// rank it), and one stored before it is ranked.
#[tokio::test]
async fn a_version_that_loses_the_race_with_the_close_is_not_stored() {
    for (db, _guard) in backends().await {
        let now = now_ms();
        let c = create(&db, spec(now), None).await.unwrap();
        let (e, v) = entered_bot(&db, &c).await;
        // Checked while open (no refusal), then the close passes before it is stored.
        let checked = check_upload(&db, v.bot_id, now).await.unwrap().unwrap();
        let stored = db
            .add_bot_version_within(v.bot_id, &plain_version(), &checked, None)
            .await
            .unwrap();
        assert!(stored.is_ok(), "{stored:?}");
        close_now(&db, c, now).await;
        let late = db
            .add_bot_version_within(v.bot_id, &plain_version(), &checked, None)
            .await
            .unwrap();
        assert!(
            matches!(&late, Err(crate::storage::bots::VersionRefusal::Closed { name, .. }) if name == "c"),
            "{late:?}"
        );
        let versions = db
            .submissions(
                &db.get_competition("c").await.unwrap().unwrap(),
                e.entrant_id,
            )
            .await
            .unwrap();
        assert_eq!(
            versions.len(),
            2,
            "the late one was not stored: {versions:?}"
        );
    }
}

#[tokio::test]
async fn each_step_of_the_clock_happens_once_and_the_results_equal_a_recount() {
    for (db, _guard) in backends().await {
        let now = now_ms();
        let c = create(&db, spec(now), None).await.unwrap();
        assert!(sealed(&db, c.private_tournament_id).await);
        assert!(!sealed(&db, c.public_tournament_id).await);
        // A ranking maze must not be public, a practice maze not hidden.
        let mut bad = spec(now);
        bad.name = "d".into();
        bad.mazes.public = vec![maze(7001)];
        let err = create(&db, bad, None).await.unwrap_err();
        assert!(err.to_string().contains("must be hidden"), "{err}");
        let (_, v) = entered_bot(&db, &c).await;
        // Ranked once: 1 public maze x 2 repeats, every seed secret; no private match
        // before the close.
        assert_eq!(tick(&db, now).await.unwrap().ranked, 1);
        assert_eq!(tick(&db, now).await.unwrap(), TickReport::default());
        let seeds = c.seed_list();
        let queued = db
            .tournament_matches(c.public_tournament_id.unwrap())
            .await
            .unwrap();
        assert_eq!(queued.len(), 2);
        assert_eq!(
            queued.iter().map(|m| m.seed).collect::<Vec<_>>(),
            seeds[..2].to_vec()
        );
        let private_matches = db
            .tournament_matches(c.private_tournament_id.unwrap())
            .await
            .unwrap();
        assert!(private_matches.is_empty(), "{private_matches:?}");
        play_all(&db, 20.0).await;
        let public = board(&db, &c, BoardKind::Public, false, now).await.unwrap();
        assert_eq!(public.standings.len(), 1);
        for organiser in [false, true] {
            let private = board(&db, &c, BoardKind::Private, organiser, now)
                .await
                .unwrap();
            assert!(private.sealed && private.standings.is_empty());
            assert_eq!(private.final_run, None);
        }
        // Closed: the private set unsealed, the selection and final run made once.
        let c = close_now(&db, c, now).await;
        let later = now + 1;
        assert_eq!(tick(&db, later).await.unwrap().selected, 1);
        assert!(!sealed(&db, c.private_tournament_id).await);
        let c = db.get_competition("c").await.unwrap().unwrap();
        assert!(
            !db.start_final(&c, &[v.bot_version_id], &[], 7)
                .await
                .unwrap()
        );
        assert!(sealed(&db, c.final_tournament_id).await);
        // The final run: 2 private mazes x 1 repeat, with seeds of its own.
        let final_matches = db
            .tournament_matches(c.final_tournament_id.unwrap())
            .await
            .unwrap();
        assert_eq!(final_matches.len(), 2);
        assert!(final_matches.iter().all(|m| m.seed == seeds[2]));
        assert!(!seeds[..2].contains(&seeds[2]));
        assert_eq!(
            tick(&db, later).await.unwrap(),
            TickReport {
                closing: 1,
                ..TickReport::default()
            },
            "the final run waits"
        );
        let private = board(&db, &c, BoardKind::Private, true, later)
            .await
            .unwrap();
        assert!(private.sealed);
        assert_eq!(
            private.final_run,
            Some(RunProgress {
                played: 0,
                total: 2
            })
        );
        play_all(&db, 30.0).await;
        // Played: its organisers see it, nobody else until the results.
        let private = board(&db, &c, BoardKind::Private, true, later)
            .await
            .unwrap();
        assert!(!private.sealed);
        assert_eq!(private.standings[0].played, 2);
        let private = board(&db, &c, BoardKind::Private, false, later)
            .await
            .unwrap();
        assert!(private.sealed && private.standings.is_empty());
        assert_eq!(
            (private.final_run, private.final_run_playing),
            (None, true),
            "only the organisers see how far the final run has played"
        );
        assert_eq!(tick(&db, later).await.unwrap().finalized, 1);
        assert_eq!(tick(&db, later).await.unwrap(), TickReport::default());
        let c = db.get_competition("c").await.unwrap().unwrap();
        assert!(
            !db.write_results(&c, &[], &[]).await.unwrap(),
            "written once"
        );
        let results = db.competition_results(c.competition_id).await.unwrap();
        assert_eq!(results.len(), 1);
        assert_eq!((results[0].played, results[0].mean_score), (2, 30.0));
        assert!(recount_differences(&db, &c).await.unwrap().is_empty());
        assert!(!sealed(&db, c.final_tournament_id).await);
        // Revealed: the private mazes are public now.
        for m in db.competition_mazes(c.competition_id).await.unwrap() {
            let row = db.get_maze(m.maze_id).await.unwrap().unwrap();
            assert_eq!(row.hidden, m.maze_set == "public", "{}", m.name);
        }
        // A changed match record shows as a difference from the snapshot.
        db.run_sql_for_tests("update match set score = 31.0 where tournament_id is not null")
            .await;
        assert_eq!(recount_differences(&db, &c).await.unwrap().len(), 1);
    }
}
