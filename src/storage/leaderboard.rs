//! Standings: mean score (a did-not-finish, `aborted` included, counts as 1000), finish
//! rate, mean ratio of score to the maze's optimum, matches played.

use sqlx::FromRow;

use super::{Result, Storage};
use crate::engine::score::DNF_SCORE;
use crate::ranking::mean::{DNF_THIRTIETHS, ratio_3dp};
use crate::ranking::{Mean, Sample, Uncertainty};

impl Standing {
    /// The exact mean score.
    pub fn mean(&self) -> Mean {
        Mean::new(self.score_sum30, self.played)
    }
}

/// Which matches a leaderboard counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// One tournament's matches, per bot version in it.
    Tournament(i64),
    /// Each bot's latest version, on hidden (ranking) mazes: the default competition
    /// (matches of other competitions do not count).
    Ranking,
    /// Each bot's latest version, on every maze (outside competitions).
    All,
}

/// One bot's line (also the API's and the CLI's JSON shape).
#[derive(Debug, Clone, PartialEq, FromRow, serde::Serialize, utoipa::ToSchema)]
pub struct Standing {
    /// 1 for the best mean score.
    #[sqlx(skip)]
    pub rank: i64,
    /// Bot id.
    pub bot_id: i64,
    /// Bot name.
    pub name: String,
    /// The version counted.
    pub version: i64,
    /// Matches counted.
    pub played: i64,
    /// Matches finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000, rounded to 3 decimals (ranks and
    /// ties come from the exact sum, `score_sum30`).
    #[sqlx(skip)]
    pub mean_score: f64,
    /// Sum of the scores in thirtieths of a step (a did-not-finish: 30,000): the exact
    /// mean is `score_sum30 / (30 x played)`.
    pub score_sum30: i64,
    /// finished / played, rounded to 3 decimals.
    #[sqlx(skip)]
    pub finish_rate: f64,
    /// Mean of score / optimum (over mazes with a known optimum). The API leaves it out
    /// for non-admins when `hidden_played > 0`: over one hidden maze it gives the
    /// maze's optimum away.
    pub mean_ratio: Option<f64>,
    /// How many of the matches counted were on hidden mazes (not serialized).
    #[serde(skip)]
    pub hidden_played: i64,
    /// How sure the rank is (filled by [`crate::registry::rankings`]).
    #[sqlx(skip)]
    pub uncertainty: Uncertainty,
}

impl Storage {
    /// The bot versions (bot id, version) with a match on a hidden maze outside the
    /// competitions still queued or running: their standings move with each such match
    /// as it ends.
    ///
    /// # Errors
    /// Database failures.
    pub async fn versions_pending_on_hidden_mazes(&self) -> Result<Vec<(i64, i64)>> {
        Ok(sqlx::query_as(
            "select distinct v.bot_id, v.version from match m
             join maze z on z.maze_id = m.maze_id
             join bot_version v on v.bot_version_id = m.bot_version_id
             where z.hidden = 1 and m.status in ('queued', 'running')
                 and not exists (select 1 from tournament t
                                 where t.tournament_id = m.tournament_id and t.competition_id is not null)",
        )
        .fetch_all(self.pool())
        .await?)
    }

    /// The standings, best mean score first (ties: higher finish rate, then name), read
    /// from the running sums of the `standing` table (kept by triggers on `match`): two
    /// rows per bot version (hidden and public mazes) for the whole ranking, a few per
    /// tournament, however many matches and tournaments there are.
    ///
    /// # Errors
    /// Database failures.
    pub async fn leaderboard(&self, scope: Scope) -> Result<Vec<Standing>> {
        let filter = match scope {
            Scope::Tournament(_) => "s.tournament_id = $1",
            // The ranking's own sums (tournament -1: every match outside a
            // competition's tournaments, migration 0014): a few rows per bot version,
            // however many tournaments there are.
            Scope::Ranking => {
                "s.tournament_id = -1 and s.hidden = 1 and cast($1 as bigint) is null and v.version = b.latest"
            }
            Scope::All => {
                "s.tournament_id = -1 and cast($1 as bigint) is null and v.version = b.latest"
            }
        };
        let sql = format!(
            "select b.bot_id, b.name, v.version, cast(sum(s.played) as bigint) as played,
                 cast(sum(s.finished) as bigint) as finished,
                 cast(sum(s.score_sum30) as bigint) as score_sum30,
                 cast(case when sum(s.ratio_count) > 0 then sum(s.ratio_sum) / sum(s.ratio_count) end
                      as double precision) as mean_ratio,
                 cast(sum(s.played * s.hidden) as bigint) as hidden_played
             from standing s
             join bot_version v on v.bot_version_id = s.bot_version_id
             join (select bot_id, name, (select max(version) from bot_version x where x.bot_id = bot.bot_id) as latest
                   from bot) b on b.bot_id = v.bot_id
             where s.played > 0 and {filter}
             group by v.bot_version_id, b.bot_id, b.name, v.version
             order by 1.0 * sum(s.score_sum30) / sum(s.played) asc,
                 1.0 * sum(s.finished) / sum(s.played) desc, b.name asc"
        );
        self.standings(&sql, scope).await
    }

    /// The same standings as [`Storage::leaderboard`], computed from the match table
    /// itself: the slow way, kept to check the running sums against. (Before release
    /// 0.2 this was the leaderboard, with one flaw: a did-not-finish was written as the
    /// integer 1000, so its ratio to the optimum was an integer division.)
    ///
    /// # Errors
    /// Database failures.
    pub async fn leaderboard_recount(&self, scope: Scope) -> Result<Vec<Standing>> {
        let filter = match_filter(scope);
        let sql = format!(
            "select b.bot_id, b.name, v.version, count(*) as played,
                 cast(sum(case when m.status = 'finished' then 1 else 0 end) as bigint) as finished,
                 cast(sum(case when m.status = 'finished' then cast(round(m.score * 30) as bigint)
                          else {DNF_THIRTIETHS} end) as bigint) as score_sum30,
                 cast(avg((case when m.status = 'finished' then m.score else {DNF_SCORE:.1} end) / z.optimum)
                      as double precision) as mean_ratio,
                 cast(sum(z.hidden) as bigint) as hidden_played
             from match m
             join bot_version v on v.bot_version_id = m.bot_version_id
             join bot b on b.bot_id = v.bot_id
             join maze z on z.maze_id = m.maze_id
             where m.status not in ('queued', 'running') and {filter}
             group by v.bot_version_id, b.bot_id, b.name, v.version
             order by 1.0 * sum(case when m.status = 'finished' then cast(round(m.score * 30) as bigint)
                          else {DNF_THIRTIETHS} end) / count(*) asc,
                 1.0 * sum(case when m.status = 'finished' then 1 else 0 end) / count(*) desc, b.name asc"
        );
        self.standings(&sql, scope).await
    }

    /// Every played match a standing of `scope` counts, as (bot id, version, sample):
    /// the data of its intervals and tie groups ([`crate::ranking`]). The same matches
    /// as [`Storage::leaderboard_recount`].
    ///
    /// # Errors
    /// Database failures.
    pub async fn standing_samples(&self, scope: Scope) -> Result<Vec<(i64, i64, Sample)>> {
        let filter = match_filter(scope);
        // One row per (version, maze, seed): several runs on one seed are averaged
        // (as the ranking does), so a standing counted many times over reads few rows.
        let sql = format!(
            "select v.bot_id, v.version, m.maze_id, m.seed,
                 cast(avg(case when m.status = 'finished' then m.score else {DNF_SCORE:.1} end) as double precision)
             from match m
             join bot_version v on v.bot_version_id = m.bot_version_id
             join maze z on z.maze_id = m.maze_id
             where m.status not in ('queued', 'running') and {filter}
             group by v.bot_id, v.version, m.maze_id, m.seed"
        );
        let rows: Vec<(i64, i64, i64, i64, f64)> = sqlx::query_as(&sql)
            .bind(tournament_of(scope))
            .fetch_all(self.pool())
            .await?;
        Ok(rows
            .into_iter()
            .map(|(bot, version, maze, seed, score)| (bot, version, Sample { maze, seed, score }))
            .collect())
    }

    async fn standings(&self, sql: &str, scope: Scope) -> Result<Vec<Standing>> {
        let mut rows: Vec<Standing> = sqlx::query_as(sql)
            .bind(tournament_of(scope))
            .fetch_all(self.pool())
            .await?;
        for (i, row) in rows.iter_mut().enumerate() {
            row.rank = i as i64 + 1;
            row.mean_score = row.mean().rounded();
            row.finish_rate = ratio_3dp(row.finished, row.played);
            row.mean_ratio = row.mean_ratio.map(crate::ranking::mean::round_3dp);
        }
        Ok(rows)
    }
}

/// The `where` clause over `match m` (joined to `bot_version v` and `maze z`) of the
/// matches a standing of `scope` counts, the tournament bound as `$1`
/// ([`tournament_of`]): the slow recount's and the intervals' (the running sums of
/// [`Storage::leaderboard`] hold the same matches).
fn match_filter(scope: Scope) -> &'static str {
    match scope {
        Scope::Tournament(_) => "m.tournament_id = $1",
        Scope::Ranking => {
            "z.hidden = 1 and cast($1 as bigint) is null and v.version = (select max(version) from bot_version where bot_id = v.bot_id)
             and not exists (select 1 from tournament t where t.tournament_id = m.tournament_id and t.competition_id is not null)"
        }
        Scope::All => {
            "cast($1 as bigint) is null and v.version = (select max(version) from bot_version where bot_id = v.bot_id)
             and not exists (select 1 from tournament t where t.tournament_id = m.tournament_id and t.competition_id is not null)"
        }
    }
}

/// The value bound as `$1` in a standing's query: its tournament, if any.
fn tournament_of(scope: Scope) -> Option<i64> {
    match scope {
        Scope::Tournament(id) => Some(id),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::{MatchRecord, MatchStatus};
    use crate::storage::test_support::{backends, bot_and_maze, maze};

    fn record(status: MatchStatus, score: Option<f64>) -> MatchRecord {
        serde_json::from_value(serde_json::json!({
            "engine_version": "t", "protocol": 1, "maze_hash": "hash", "maze_dim": 2, "seed": 1,
            "limits": {"max_steps": 1000, "startup_timeout_ms": null, "move_timeout_ms": null, "memory_limit_mb": null},
            "status": status, "score": score, "run0_steps": 3, "run1_steps": 1, "total_steps": 4,
            "warnings": [], "error": null, "stderr_tail": "", "timings": {"wall_ms": 1, "bot_cpu_ms": null, "max_answer_us": 1, "mean_answer_us": 1}
        }))
        .unwrap()
    }

    async fn same_as_recount(db: &Storage, scope: Scope) -> Vec<Standing> {
        let kept = db.leaderboard(scope).await.unwrap();
        let counted = db.leaderboard_recount(scope).await.unwrap();
        assert_eq!(kept.len(), counted.len(), "{kept:?} {counted:?}");
        for (k, c) in kept.iter().zip(&counted) {
            assert_eq!(
                (k.bot_id, k.played, k.finished),
                (c.bot_id, c.played, c.finished)
            );
            assert_eq!(k.score_sum30, c.score_sum30, "{k:?} {c:?}");
            assert_eq!(
                k.mean_score.to_bits(),
                c.mean_score.to_bits(),
                "{k:?} {c:?}"
            );
            assert_eq!(
                k.finish_rate.to_bits(),
                c.finish_rate.to_bits(),
                "{k:?} {c:?}"
            );
            assert_eq!(k.mean_ratio.is_some(), c.mean_ratio.is_some());
        }
        kept
    }

    #[tokio::test]
    async fn the_running_sums_follow_every_way_a_match_gets_or_loses_its_status() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            assert!(db.leaderboard(Scope::All).await.unwrap().is_empty());
            let t = db.create_tournament("t", &[v], &[z], 3).await.unwrap();
            // Finished (score 1.1), crashed by the worker, and one left queued.
            let a = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert!(
                db.complete_match(
                    a.match_id,
                    "w",
                    &record(MatchStatus::Finished, Some(1.1)),
                    &maze()
                )
                .await
                .unwrap()
            );
            let b = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert!(db.fail_match(b.match_id, "w", "ours").await.unwrap());
            let board = same_as_recount(&db, Scope::Tournament(t.tournament_id)).await;
            assert_eq!((board[0].played, board[0].finished), (2, 1));
            assert!((board[0].mean_score - (1.1 + DNF_SCORE) / 2.0).abs() < 1e-9);
            assert!((board[0].mean_ratio.unwrap() - (1.1 + DNF_SCORE) / 2.0).abs() < 1e-9);
            same_as_recount(&db, Scope::All).await;
            // A single match outside the tournament counts in `All`, not in the tournament.
            let single = db.queue_match(v, z, 5).await.unwrap();
            let c = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            assert_eq!(c.match_id, single);
            db.complete_match(
                c.match_id,
                "w",
                &record(MatchStatus::Timeout, None),
                &maze(),
            )
            .await
            .unwrap();
            assert_eq!(same_as_recount(&db, Scope::All).await[0].played, 3);
            assert_eq!(
                same_as_recount(&db, Scope::Tournament(t.tournament_id)).await[0].played,
                2
            );
            // Rows that change or vanish by other statements are followed too.
            sqlx::query("update match set status = 'finished', score = 2.0 where match_id = $1")
                .bind(b.match_id)
                .execute(db.pool())
                .await
                .unwrap();
            assert_eq!(same_as_recount(&db, Scope::All).await[0].finished, 2);
            sqlx::query("delete from match where match_id = $1")
                .bind(a.match_id)
                .execute(db.pool())
                .await
                .unwrap();
            let all = same_as_recount(&db, Scope::All).await;
            assert_eq!((all[0].played, all[0].finished), (2, 1));
            // No hidden maze: no ranking.
            assert!(same_as_recount(&db, Scope::Ranking).await.is_empty());
        }
    }
}
