//! Standings ranked with their uncertainty: the rules of [`crate::ranking`] applied to
//! the lines a caller is shown (after any line is left out, so the ranks are among the
//! lines shown), with the matches of the standing's scope.
//!
//! The running sums make a standing cheap; its intervals need every match, so a
//! [`Ranker`] keeps the last tables it made, keyed by the standing's own numbers (a
//! match that ends changes them), and makes a table once however many requests ask for
//! it at the same time.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use crate::ranking::{self, Entry, Mean, Sample, Uncertainty};
use crate::storage::leaderboard::{Scope, Standing};
use crate::storage::{Result, Storage};

/// Puts `lines` best first: lower mean first (exactly, [`Mean`]), equal means by name.
pub fn order_lines<T>(lines: &mut [T], mean: impl Fn(&T) -> Mean, name: impl Fn(&T) -> &str) {
    lines.sort_by(|a, b| mean(a).cmp(&mean(b)).then_with(|| name(a).cmp(name(b))));
}

/// Ranks `lines` (any order) by mean score with [`ranking::assess`]: puts them best
/// first ([`order_lines`]), and hands each its rank and [`Uncertainty`]. `key` is a
/// line's (bot id, version) in `samples`.
pub fn rank_lines<T>(
    lines: &mut [T],
    samples: &[(i64, i64, Sample)],
    mean: impl Fn(&T) -> Mean,
    name: impl Fn(&T) -> &str,
    key: impl Fn(&T) -> (i64, i64),
    mut set: impl FnMut(&mut T, i64, Uncertainty),
) {
    order_lines(lines, &mean, &name);
    let mut by_version: HashMap<(i64, i64), Vec<Sample>> = HashMap::new();
    for (bot, version, s) in samples {
        by_version.entry((*bot, *version)).or_default().push(*s);
    }
    let entries: Vec<Entry> = lines
        .iter()
        .map(|l| Entry {
            mean: mean(l),
            samples: by_version.get(&key(l)).map_or(&[], Vec::as_slice),
        })
        .collect();
    let assessed = ranking::assess(&entries);
    for (line, (rank, u)) in lines.iter_mut().zip(assessed) {
        set(line, rank, u);
    }
}

/// Replaces the uncertainty of `lines` (ranked, best first) by what their means alone
/// say ([`ranking::withheld`]): for lines over hidden matches whose scores the caller
/// may not see.
pub fn withhold_lines<T>(
    lines: &mut [T],
    rank: impl Fn(&T) -> i64,
    mean: impl Fn(&T) -> Mean,
    mut set: impl FnMut(&mut T, Uncertainty),
) {
    let shown: Vec<(i64, Mean)> = lines.iter().map(|l| (rank(l), mean(l))).collect();
    for (line, u) in lines.iter_mut().zip(ranking::withheld(&shown)) {
        set(line, u);
    }
}

/// Ranks `lines` (any order) by mean score as [`rank_lines`] does, with the uncertainty
/// withheld ([`ranking::withheld`]): no match is read and nothing is bootstrapped, since
/// nothing of it would be shown.
pub fn rank_lines_withheld<T>(
    lines: &mut [T],
    mean: impl Fn(&T) -> Mean,
    name: impl Fn(&T) -> &str,
    mut set: impl FnMut(&mut T, i64, Uncertainty),
) {
    order_lines(lines, &mean, &name);
    let means: Vec<Mean> = lines.iter().map(&mean).collect();
    let shown: Vec<(i64, Mean)> = means
        .iter()
        .map(|&m| {
            let better = means.iter().filter(|&&o| o < m).count();
            (1 + better as i64, m)
        })
        .collect();
    for ((line, u), (rank, _)) in lines.iter_mut().zip(ranking::withheld(&shown)).zip(&shown) {
        set(line, *rank, u);
    }
}

/// A standing's own numbers, best first: (bot, version, played, finished, sum of scores).
type Key = (Scope, Vec<(i64, i64, i64, i64, i64)>);

/// A table: each line's rank and uncertainty, in the standing's order.
type Table = Arc<Vec<(i64, Uncertainty)>>;

/// How many tables a [`Ranker`] keeps.
const KEPT: usize = 32;

/// Ranks standings, keeping the last `KEPT` tables it made.
#[derive(Default)]
pub struct Ranker {
    kept: Mutex<Vec<(Key, Table)>>,
    making: tokio::sync::Mutex<()>,
}

impl std::fmt::Debug for Ranker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ranker").finish_non_exhaustive()
    }
}

impl Ranker {
    fn find(&self, key: &Key) -> Option<Table> {
        let kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.iter().find(|(k, _)| k == key).map(|(_, t)| t.clone())
    }

    /// Ranks the standings `rows` of `scope` (see [`rank_lines`]).
    ///
    /// # Errors
    /// Database failures.
    pub async fn rank(
        &self,
        storage: &Storage,
        scope: Scope,
        mut rows: Vec<Standing>,
    ) -> Result<Vec<Standing>> {
        if rows.is_empty() {
            return Ok(rows);
        }
        order_lines(&mut rows, Standing::mean, |r| r.name.as_str());
        let key: Key = (
            scope,
            rows.iter()
                .map(|r| (r.bot_id, r.version, r.played, r.finished, r.score_sum30))
                .collect(),
        );
        let table = match self.find(&key) {
            Some(t) => t,
            None => {
                let _one_at_a_time = self.making.lock().await;
                match self.find(&key) {
                    Some(t) => t,
                    None => {
                        let samples = storage.standing_samples(scope).await?;
                        struct Line {
                            at: usize,
                            mean: Mean,
                            name: String,
                            key: (i64, i64),
                            rank: i64,
                            u: Uncertainty,
                        }
                        let mut lines: Vec<Line> = rows
                            .iter()
                            .enumerate()
                            .map(|(at, r)| Line {
                                at,
                                mean: r.mean(),
                                name: r.name.clone(),
                                key: (r.bot_id, r.version),
                                rank: 0,
                                u: Uncertainty::default(),
                            })
                            .collect();
                        rank_lines(
                            &mut lines,
                            &samples,
                            |l| l.mean,
                            |l| l.name.as_str(),
                            |l| l.key,
                            |l, rank, u| {
                                l.rank = rank;
                                l.u = u;
                            },
                        );
                        // Same order as `rows` (already ordered): keep it by index.
                        lines.sort_by_key(|l| l.at);
                        let t = Arc::new(lines.into_iter().map(|l| (l.rank, l.u)).collect());
                        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
                        if kept.len() >= KEPT {
                            kept.remove(0);
                        }
                        kept.push((key, Arc::clone(&t)));
                        t
                    }
                }
            }
        };
        for (row, (rank, u)) in rows.iter_mut().zip(table.iter()) {
            row.rank = *rank;
            row.uncertainty = u.clone();
        }
        Ok(rows)
    }

    /// The standings of `scope`, ranked.
    ///
    /// # Errors
    /// Database failures.
    pub async fn leaderboard(&self, storage: &Storage, scope: Scope) -> Result<Vec<Standing>> {
        let rows = storage.leaderboard(scope).await?;
        self.rank(storage, scope, rows).await
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::MatchRecord;
    use crate::storage::test_support::{backends, bot_and_maze, maze};

    fn finished(score: f64) -> MatchRecord {
        serde_json::from_value(serde_json::json!({
            "engine_version": "t", "protocol": 1, "maze_hash": "hash", "maze_dim": 2, "seed": 1,
            "limits": {"max_steps": 1000, "startup_timeout_ms": null, "move_timeout_ms": null, "memory_limit_mb": null},
            "status": "finished", "score": score, "run0_steps": 3, "run1_steps": 1, "total_steps": 4,
            "warnings": [], "error": null, "stderr_tail": "", "timings": {"wall_ms": 1, "bot_cpu_ms": null, "max_answer_us": 1, "mean_answer_us": 1}
        }))
        .unwrap()
    }

    #[tokio::test]
    async fn a_ranker_makes_a_new_table_when_a_match_ends_and_keeps_it_otherwise() {
        for (db, _guard) in backends().await {
            let (v, z) = bot_and_maze(&db).await;
            let t = db.create_tournament("t", &[v], &[z], 2).await.unwrap();
            let scope = Scope::Tournament(t.tournament_id);
            let ranker = Ranker::default();
            let a = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            db.complete_match(a.match_id, "w", &finished(10.0), &maze())
                .await
                .unwrap();
            let one = ranker.leaderboard(&db, scope).await.unwrap();
            assert_eq!(
                (one[0].uncertainty.low, one[0].uncertainty.high),
                (10.0, 10.0)
            );
            assert_eq!(ranker.leaderboard(&db, scope).await.unwrap(), one);
            // The second seed scores 20: two runs, 10 and 20, on one maze; a replicate's
            // mean is 10, 15 or 20 (1/4, 1/2, 1/4): the interval is [10, 20].
            let b = db.claim_next("w", 60_000, None).await.unwrap().unwrap();
            db.complete_match(b.match_id, "w", &finished(20.0), &maze())
                .await
                .unwrap();
            let two = ranker.leaderboard(&db, scope).await.unwrap();
            assert_eq!(two[0].mean_score, 15.0);
            assert_eq!(
                (two[0].uncertainty.low, two[0].uncertainty.high),
                (10.0, 20.0)
            );
            assert_eq!(two[0].uncertainty.runs_per_maze, 2);
        }
    }

    #[test]
    fn lines_are_ordered_by_mean_then_by_name_when_means_are_equal() {
        // 3 over 1 match and 6 over 2 are the same mean: equal, so by name.
        let mut lines = vec![
            (Mean::new(90, 1), "b"),
            (Mean::new(30, 1), "z"),
            (Mean::new(180, 2), "a"),
            (Mean::new(60, 1), "c"),
        ];
        order_lines(&mut lines, |l| l.0, |l| l.1);
        let names: Vec<&str> = lines.iter().map(|l| l.1).collect();
        assert_eq!(names, vec!["z", "c", "a", "b"]);
    }
}
