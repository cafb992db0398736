//! Rankings that state their uncertainty (pure; no I/O): each bot's mean score with a
//! 95% interval, its rank as a range where intervals overlap, and tie groups of bots
//! whose difference is not significant.
//!
//! The rules, the same on every surface (API, pages, `tournament` table, CSV):
//! - **Order and rank.** Lower mean score first. Means are exact ([`Mean`]: sums of
//!   scores in whole thirtieths of a step), so bots whose mean scores are equal share
//!   a rank, as in 1, 1, 3, and are listed by name, however their scores were added
//!   up. Means and interval ends are shown rounded to 3 decimals.
//! - **Interval.** The 95% percentile interval of the mean from a bootstrap that keeps
//!   the mazes and resamples each maze's runs (one per seed), with a fixed seed
//!   ([`bootstrap`]). It measures the luck of the seeds: a bot that scores the same on
//!   every seed of a maze has a zero-width interval. With one run per maze nothing is
//!   measured (`runs_per_maze` says so).
//! - **Rank range.** Best: 1 + the bots whose interval lies wholly below this bot's
//!   (surely better). Worst: 1 + the bots of another mean whose interval starts below
//!   this bot's upper end (possibly better). Shown as "2-4", or "3" when both ends
//!   agree.
//! - **Tie groups.** Going down the table, a bot joins the group above when its
//!   difference from that group's first bot is not significant: the 95% interval of the
//!   mean difference over the mazes and seeds both played (the same bootstrap, paired)
//!   holds 0. Bots with equal means always share a group. Without common mazes and
//!   seeds, bots differ when their intervals do not overlap.
//! - **Hidden matches.** Where a line counts matches on a hidden maze and the caller may
//!   not see those matches' scores, none of the above is shown ([`withheld`]): with one
//!   hidden maze and two runs, the interval's ends are the two runs' scores, and with
//!   few matches any spread, rank range or significance test says something of single
//!   matches. Such a line shows its mean and its rank; its interval is the mean alone,
//!   its rank range its rank, and it shares a tie group only with equal means.

pub mod bootstrap;
pub mod mean;

use bootstrap::Cells;
pub use mean::{Mean, same_mean};

/// One match of a bot: its maze, its seed and its score (a did-not-finish as 1000).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The maze (any id that is the same for every bot).
    pub maze: i64,
    /// The seed.
    pub seed: i64,
    /// The score, 1000 for a match that did not finish.
    pub score: f64,
}

/// A bot's line of a standing, as ranked: its place and how sure it is.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, utoipa::ToSchema)]
pub struct Uncertainty {
    /// Lower end of the 95% interval of the mean score.
    pub low: f64,
    /// Upper end of the 95% interval of the mean score.
    pub high: f64,
    /// The best rank the intervals allow.
    pub rank_best: i64,
    /// The worst rank the intervals allow.
    pub rank_worst: i64,
    /// `rank_best` and `rank_worst` as text: "2-4", or "3" when they agree.
    pub rank_range: String,
    /// The tie group, 1 for the leader's: bots of a group are not significantly
    /// different from its first bot.
    pub tie_group: i64,
    /// Whether another bot shares the tie group.
    pub tied: bool,
    /// The fewest runs (seeds) the bot has on any one maze; with 1 the intervals
    /// measure nothing (0 when withheld).
    pub runs_per_maze: i64,
    /// True when the interval, rank range and tie group are withheld because they would
    /// tell something of single hidden matches ([`withheld`]): the interval is then the
    /// mean, the rank range the rank, and the tie group that of equal means only.
    pub withheld: bool,
}

/// A bot to rank: its mean score (as the standings show it) and its matches.
#[derive(Debug, Clone, Copy)]
pub struct Entry<'a> {
    /// Mean score, exact.
    pub mean: Mean,
    /// Its matches.
    pub samples: &'a [Sample],
}

/// Ranks `entries`, given best first (ascending mean): each one's rank (shared by equal
/// means) and its [`Uncertainty`], by the rules in the module's documentation.
pub fn assess(entries: &[Entry]) -> Vec<(i64, Uncertainty)> {
    let cells: Vec<Cells> = entries.iter().map(|e| Cells::new(e.samples)).collect();
    let intervals: Vec<(f64, f64)> = entries
        .iter()
        .zip(&cells)
        .map(|(e, c)| {
            let mean = e.mean.rounded();
            if c.is_empty() {
                (mean, mean)
            } else {
                let (low, high) = c.interval();
                if low == high {
                    // No spread: the mean itself (as the standings add it up).
                    (mean, mean)
                } else {
                    (
                        mean::round_3dp(low).min(mean),
                        mean::round_3dp(high).max(mean),
                    )
                }
            }
        })
        .collect();
    let mut out = Vec::with_capacity(entries.len());
    let mut group = 0i64;
    let mut leader = 0usize;
    for (i, e) in entries.iter().enumerate() {
        let rank = 1 + entries.iter().filter(|o| o.mean < e.mean).count() as i64;
        let (low, high) = intervals[i];
        let best = 1 + intervals.iter().filter(|(_, h)| *h < low).count() as i64;
        let worst = 1 + entries
            .iter()
            .zip(&intervals)
            .filter(|(o, (l, _))| *l < high && o.mean != e.mean)
            .count() as i64;
        let joins = i > 0
            && (same_mean(entries[i - 1].mean, e.mean)
                || !differ(&cells[leader], &cells[i], intervals[leader], intervals[i]));
        if !joins {
            group += 1;
            leader = i;
        }
        out.push((
            rank,
            Uncertainty {
                low,
                high,
                rank_best: best.min(rank),
                rank_worst: worst.max(rank),
                rank_range: String::new(),
                tie_group: group,
                tied: false,
                runs_per_maze: cells[i].runs_per_maze() as i64,
                withheld: false,
            },
        ));
    }
    for i in 0..out.len() {
        let g = out[i].1.tie_group;
        let tied = out.iter().filter(|(_, u)| u.tie_group == g).count() > 1;
        let u = &mut out[i].1;
        u.tied = tied;
        u.rank_range = if u.rank_best == u.rank_worst {
            u.rank_best.to_string()
        } else {
            format!("{}-{}", u.rank_best, u.rank_worst)
        };
    }
    out
}

/// The uncertainty shown for lines, given best first as (rank, mean), whose matches
/// must not be told apart: nothing but what the means say. The interval is the mean,
/// the rank range the rank, and lines share a tie group only when their means are equal
/// ([`same_mean`]).
pub fn withheld(lines: &[(i64, Mean)]) -> Vec<Uncertainty> {
    let mut out: Vec<Uncertainty> = Vec::with_capacity(lines.len());
    let mut group = 0;
    for (i, &(rank, mean)) in lines.iter().enumerate() {
        if i == 0 || !same_mean(lines[i - 1].1, mean) {
            group += 1;
        }
        out.push(Uncertainty {
            low: mean.rounded(),
            high: mean.rounded(),
            rank_best: rank,
            rank_worst: rank,
            rank_range: rank.to_string(),
            tie_group: group,
            tied: false,
            runs_per_maze: 0,
            withheld: true,
        });
    }
    for i in 0..out.len() {
        let g = out[i].tie_group;
        out[i].tied = out.iter().filter(|u| u.tie_group == g).count() > 1;
    }
    out
}

/// Whether two bots differ significantly: paired over the mazes and seeds both played,
/// or by their intervals when they share none.
fn differ(a: &Cells, b: &Cells, ia: (f64, f64), ib: (f64, f64)) -> bool {
    let d = a.differences(b);
    if d.is_empty() {
        return ia.1 < ib.0 || ib.1 < ia.0;
    }
    if d.all_zero() {
        return false;
    }
    let (low, high) = d.interval();
    low > 0.0 || high < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With one to five hidden matches per bot, no number of a withheld line but its
    /// mean and rank depends on the matches: the same mean from other matches gives the
    /// same line, and a single match's score is never among its numbers unless it equals
    /// the mean.
    #[test]
    fn a_withheld_line_tells_nothing_the_mean_does_not() {
        let sets: [&[f64]; 5] = [
            &[24.4],
            &[24.4, 29.0666],
            &[20.0, 30.0, 1000.0],
            &[18.5, 18.5, 40.0, 41.0],
            &[10.0, 20.0, 30.0, 40.0, 1000.0],
        ];
        for scores in sets {
            let samples: Vec<Sample> = scores
                .iter()
                .enumerate()
                .map(|(i, &score)| Sample {
                    maze: 1,
                    seed: i as i64,
                    score,
                })
                .collect();
            let m = mean(&samples);
            let shown = withheld(&[(1, m)]);
            let u = &shown[0];
            let shown_mean = m.rounded();
            assert_eq!(
                (u.low, u.high, u.rank_best, u.rank_worst),
                (shown_mean, shown_mean, 1, 1)
            );
            assert_eq!((u.runs_per_maze, u.tied, u.withheld), (0, false, true));
            // Another set of matches with the same mean shows the same line.
            let other = withheld(&[(1, m)]);
            assert_eq!(&other[0], u);
            for s in scores.iter().filter(|&&s| Mean::of_scores([s]) != m) {
                for n in [u.low, u.high] {
                    assert!(
                        Mean::of_scores([n]) != Mean::of_scores([*s]),
                        "{scores:?}: {n} shows a match"
                    );
                }
            }
        }
        let table = withheld(&[
            (1, Mean::new(1200, 2)),
            (1, Mean::new(600, 1)),
            (3, Mean::new(750, 1)),
        ]);
        assert_eq!(
            table
                .iter()
                .map(|u| (u.tie_group, u.tied))
                .collect::<Vec<_>>(),
            vec![(1, true), (1, true), (2, false)]
        );
    }

    fn runs(maze_scores: &[(i64, &[f64])]) -> Vec<Sample> {
        let mut out = Vec::new();
        for (maze, scores) in maze_scores {
            for (seed, score) in scores.iter().enumerate() {
                out.push(Sample {
                    maze: *maze,
                    seed: seed as i64,
                    score: *score,
                });
            }
        }
        out
    }

    fn mean(s: &[Sample]) -> Mean {
        Mean::of_scores(s.iter().map(|x| x.score))
    }

    fn table(bots: &[Vec<Sample>]) -> Vec<(i64, Uncertainty)> {
        let entries: Vec<Entry> = bots
            .iter()
            .map(|s| Entry {
                mean: mean(s),
                samples: s,
            })
            .collect();
        assess(&entries)
    }

    /// The case worked by hand in docs/RANKINGS.md: five deterministic or nearly
    /// deterministic bots on two mazes, two seeds each.
    #[test]
    fn the_hand_computed_case() {
        // A and B: the same records (two names for one bot). C: 1 point worse on
        // every cell (a real difference, however small). D: C's mean, but seed luck
        // on maze 2 (18 or 22 around C's 20). E: far behind.
        let a = runs(&[(1, &[10.0, 10.0]), (2, &[19.0, 19.0])]);
        let b = a.clone();
        let c = runs(&[(1, &[11.0, 11.0]), (2, &[20.0, 20.0])]);
        let d = runs(&[(1, &[11.0, 11.0]), (2, &[18.0, 22.0])]);
        let e = runs(&[(1, &[40.0, 40.0]), (2, &[40.0, 40.0])]);
        let t = table(&[a, b, c, d, e]);
        let ranks: Vec<i64> = t.iter().map(|(r, _)| *r).collect();
        // A and B share rank 1; C and D have equal means (15.5) and share rank 3.
        assert_eq!(ranks, vec![1, 1, 3, 3, 5]);
        // Intervals: A, B, C, E are deterministic (zero width). D's maze-2 runs are 18
        // and 22: each replicate draws two of them, so its maze-2 sum is 36, 40 or 44
        // (probabilities 1/4, 1/2, 1/4) and its mean over 4 runs is 14.5, 15.5 or
        // 16.5; the 2.5% and 97.5% percentiles are 14.5 and 16.5.
        let iv: Vec<(f64, f64)> = t.iter().map(|(_, u)| (u.low, u.high)).collect();
        assert_eq!(
            iv,
            vec![
                (14.5, 14.5),
                (14.5, 14.5),
                (15.5, 15.5),
                (14.5, 16.5),
                (40.0, 40.0)
            ]
        );
        // Rank ranges: only D's interval is wide. A and B: nothing surely or possibly
        // better (D starts at their 14.5, which is a tie at best): "1". C: A and B surely
        // better, D equal: "3". D: nothing surely better (best 1), A and B possibly
        // (they start below 16.5; C is equal): worst 3. E: 5.
        let rr: Vec<&str> = t.iter().map(|(_, u)| u.rank_range.as_str()).collect();
        assert_eq!(rr, vec!["1", "1", "3", "1-3", "5"]);
        // Tie groups: {A, B} (identical); C differs from A on every cell by exactly 1
        // (paired interval [1, 1] excludes 0): a new group; D equal to C: C's group; E
        // a group of its own.
        let groups: Vec<(i64, bool)> = t.iter().map(|(_, u)| (u.tie_group, u.tied)).collect();
        assert_eq!(
            groups,
            vec![(1, true), (1, true), (2, true), (2, true), (3, false)]
        );
        assert!(t.iter().all(|(_, u)| u.runs_per_maze == 2));
    }

    #[test]
    fn a_difference_inside_the_luck_of_the_seeds_is_a_tie_and_a_clear_one_is_not() {
        let noisy = |offset: f64| -> Vec<Sample> {
            let scores: Vec<f64> = (0..12)
                .map(|k| 20.0 + offset + if k % 2 == 0 { -5.0 } else { 5.0 } * ((k % 3) as f64))
                .collect();
            runs(&[(1, &scores)])
        };
        // Paired: the same seeds give the same luck, so a constant 0.5 is significant.
        let t = table(&[noisy(0.0), noisy(0.5)]);
        assert_eq!((t[0].1.tie_group, t[1].1.tie_group), (1, 2));
        // Luck that does not pair up (another bot's seed order): a 0.5 gap is a tie.
        let mut shuffled = noisy(0.5);
        let n = shuffled.len() as i64;
        for s in &mut shuffled {
            s.seed = (s.seed * 5 + 1) % n;
        }
        let t = table(&[noisy(0.0), shuffled]);
        assert_eq!((t[0].1.tie_group, t[1].1.tie_group), (1, 1));
        assert_eq!(t[1].1.rank_range, "1-2");
        assert!(t[0].1.low < t[0].1.high);
    }

    #[test]
    fn bots_without_common_cells_differ_only_when_their_intervals_do_not_meet() {
        let a = runs(&[(1, &[10.0, 10.0])]);
        let b = runs(&[(2, &[12.0, 12.0])]);
        let t = table(&[a, b]);
        assert_eq!(t[1].1.tie_group, 2);
        assert_eq!(t[1].1.rank_range, "2");
    }

    #[test]
    fn the_same_records_give_the_same_table() {
        let bots: Vec<Vec<Sample>> = (0..4)
            .map(|b| {
                let s: Vec<f64> = (0..6)
                    .map(|k| 20.0 + ((k * 7 + b * 3) % 5) as f64)
                    .collect();
                runs(&[(1, &s), (2, &s)])
            })
            .collect();
        let mut sorted = bots.clone();
        sorted.sort_by_key(|x| mean(x));
        assert_eq!(table(&sorted), table(&sorted));
    }
}
